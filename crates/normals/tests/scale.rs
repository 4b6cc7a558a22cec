//! Scale robustness: every estimator gives the same unit normals on a cloud multiplied
//! by a power of two, at any representable scale, and nearly the same at decimal scales.

use std::f64::consts::TAU;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{NormalEstimator, RunCtx};
use reconbench_normals::*;

fn estimators() -> Vec<Box<dyn NormalEstimator>> {
    vec![
        Box::new(PlaneFit {
            params: PlaneFitParams { k: 12, orient_k: 8 },
        }),
        Box::new(WeightedPlaneFit {
            params: WeightedPlaneFitParams {
                k: 12,
                orient_k: 8,
                ..Default::default()
            },
        }),
        Box::new(Jet {
            params: JetParams { k: 18, orient_k: 8 },
        }),
        Box::new(LvmApprox {
            params: LvmApproxParams { k: 15, orient_k: 8 },
        }),
    ]
}

/// 400 random points on the unit sphere, snapped to the dyadic grid 2^-40 so that every
/// scaling by 2^e down to e = -1030 is exact.
fn sphere() -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let g = 2f64.powi(40);
    (0..400)
        .map(|_| {
            let z: f64 = rng.random_range(-1.0..1.0);
            let t: f64 = rng.random_range(0.0..TAU);
            let r = (1.0 - z * z).sqrt();
            (DVec3::new(r * t.cos(), r * t.sin(), z) * g).round() / g
        })
        .collect()
}

fn normals(e: &dyn NormalEstimator, pts: Vec<DVec3>) -> Vec<DVec3> {
    let cloud = PointCloud::new(pts).unwrap();
    let n = e.estimate(&cloud, &mut RunCtx::new(0));
    n.unwrap_or_else(|err| panic!("{}: {err}", e.name()))
        .normals
}

fn times_pow2(p: DVec3, e: i32) -> DVec3 {
    let h = e / 2;
    p * 2f64.powi(h) * 2f64.powi(e - h)
}

#[test]
fn power_of_two_scaled_clouds_give_identical_normals() {
    let base = sphere();
    for est in estimators() {
        let want = normals(est.as_ref(), base.clone());
        assert!(want.iter().all(|n| (n.length() - 1.0).abs() < 1e-9));
        for e in [-1030, -997, -532, -199, 266, 664, 996, 1022] {
            let pts = base.iter().map(|&p| times_pow2(p, e)).collect();
            let got = normals(est.as_ref(), pts);
            assert_eq!(got, want, "{} at 2^{e}", est.name());
        }
    }
}

#[test]
fn decimal_scales_give_unit_normals_close_to_the_unscaled_ones() {
    let base = sphere();
    for est in estimators() {
        let want = normals(est.as_ref(), base.clone());
        for f in [1e-300, 1e-160, 1e-60, 1e80, 1e200, 1e300] {
            let pts = base.iter().map(|&p| p * f).collect();
            let got = normals(est.as_ref(), pts);
            for (g, w) in got.iter().zip(&want) {
                assert!((g.length() - 1.0).abs() < 1e-9, "{} at {f:e}", est.name());
                assert!(g.dot(*w).abs() > 1.0 - 1e-6, "{} at {f:e}", est.name());
            }
        }
    }
}
