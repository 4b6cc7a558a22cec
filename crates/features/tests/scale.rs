//! Scale robustness: every detector labels a cloud multiplied by a power of two exactly
//! as the original, at any representable scale, and runs at decimal extremes.

use reconbench_features::{GaussMap, GaussMapAdaptive, PcaVariation};
use reconbench_geom::method::{FeatureClass, FeatureDetector, RunCtx};
use reconbench_geom::{DVec3, PointCloud};
use reconbench_testkit::feature_fixtures::grid_box;

fn detectors() -> Vec<Box<dyn FeatureDetector>> {
    vec![
        Box::new(GaussMap::default()),
        Box::new(GaussMapAdaptive::default()),
        Box::new(PcaVariation::default()),
    ]
}

fn labels(d: &dyn FeatureDetector, pts: Vec<DVec3>) -> Vec<FeatureClass> {
    let cloud = PointCloud::new(pts).unwrap();
    d.detect(&cloud, &mut RunCtx::new(7))
        .unwrap_or_else(|e| panic!("{}: {e}", d.name()))
        .labels
}

fn times_pow2(p: DVec3, e: i32) -> DVec3 {
    let h = e / 2;
    p * 2f64.powi(h) * 2f64.powi(e - h)
}

#[test]
fn power_of_two_scaled_boxes_get_identical_labels() {
    // Side 1, 8 cells: every coordinate a multiple of 1/8, exact under any 2^e used here.
    let base = grid_box(1.0, 8).cloud().positions().to_vec();
    for d in detectors() {
        let want = labels(d.as_ref(), base.clone());
        assert!(
            want.iter().any(|c| *c != FeatureClass::None),
            "{}",
            d.name()
        );
        for e in [-1060, -532, -199, 266, 664, 1020] {
            let pts = base.iter().map(|&p| times_pow2(p, e)).collect();
            assert_eq!(labels(d.as_ref(), pts), want, "{} at 2^{e}", d.name());
        }
    }
}

#[test]
fn decimal_extremes_run_and_find_features() {
    let base = grid_box(1.0, 8).cloud().positions().to_vec();
    for d in detectors() {
        for f in [1e-300, 1e-160, 1e200, 1e300] {
            let got = labels(d.as_ref(), base.iter().map(|&p| p * f).collect());
            assert!(
                got.iter().any(|c| *c != FeatureClass::None),
                "{} at {f:e}",
                d.name()
            );
        }
    }
}
