//! Diagnostic probe (not part of the API): `gauss-map-adaptive` on a noisy random box:
//! first-pass and final precision (at 2 grid-equivalent spacings) against the noise.
//!
//! `cargo run --release -p reconbench-tools --bin probe_noise`

use reconbench_testkit::feature_fixtures as common;

use reconbench_features::{GaussMap, GaussMapAdaptive, GaussMapAdaptiveParams, GaussMapParams};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{FeatureDetector, RunCtx};

fn main() {
    let t = common::random_box(1.0, 6000, 3);
    for rel in [0.0, 0.1, 0.2, 0.4, 0.6] {
        let noisy = common::add_noise(&t.points, rel * t.spacing, 9);
        let cloud = PointCloud::new(noisy).unwrap();
        for fms in [0.0, 0.2] {
            let g = GaussMap::new(GaussMapParams {
                k: 20,
                sigma: 0.1,
                flat_min_sine: fms,
                ..Default::default()
            })
            .detect(&cloud, &mut RunCtx::new(1))
            .unwrap();
            println!(
                "noise {rel} first pass flat_min_sine {fms}: flat {:?} clustered {:?} features {:?}",
                g.diagnostics.get("flat"),
                g.diagnostics.get("candidates"),
                g.diagnostics.get("features")
            );
        }
        let g = GaussMap::new(GaussMapParams {
            k: 20,
            sigma: 0.1,
            ..Default::default()
        })
        .detect(&cloud, &mut RunCtx::new(1))
        .unwrap();
        let sg = common::score(&t, &g.labels, 2.0 * t.spacing);
        for iso in [true, false] {
            let a = GaussMapAdaptive::new(GaussMapAdaptiveParams {
                isolated_rule: iso,
                ..Default::default()
            })
            .detect(&cloud, &mut RunCtx::new(1))
            .unwrap();
            let sa = common::score(&t, &a.labels, 2.0 * t.spacing);
            println!(
                "noise {rel} spacing: first pass det {} P {:.2} | adaptive iso {iso}: det {} P {:.2} cov {:.2} | {:?} {:?}",
                sg.detected,
                sg.precision,
                sa.detected,
                sa.precision,
                sa.coverage,
                a.diagnostics.get("removed_per_pass"),
                a.diagnostics.get("isolated_removed")
            );
        }
    }
}
