//! Diagnostic probe (not part of the API): `gauss-map-adaptive` on area-uniform tori of
//! growing density, to tell resolution-dependent behaviour from bugs (docs/methods/
//! features.md, "Adaptive on curved shapes"). Prints first-pass share, survivors,
//! re-tests and phase times.
//!
//! `cargo run --release -p reconbench-tools --bin probe_adaptive [N ...]`

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_features::{GaussMap, GaussMapAdaptive, GaussMapAdaptiveParams, GaussMapParams};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, FeatureDetector, RunCtx};

/// Area-uniform samples of the torus (R, r) by rejection on the area element.
fn torus(n: usize, big: f64, r: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let u = rng.random::<f64>() * std::f64::consts::TAU;
        let v = rng.random::<f64>() * std::f64::consts::TAU;
        if rng.random::<f64>() * (big + r) <= big + r * v.cos() {
            let w = big + r * v.cos();
            out.push(DVec3::new(w * u.cos(), w * u.sin(), r * v.sin()));
        }
    }
    out
}

fn num(d: &reconbench_geom::method::Diagnostics, k: &str) -> f64 {
    match d.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        _ => f64::NAN,
    }
}

fn main() {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![3000, 12000, 48000]
    } else {
        sizes
    };
    for &n in &sizes {
        let pts = torus(n, 2.0, 1.0, 1);
        let cloud = PointCloud::new(pts).unwrap();
        let spacing_kappa = (4.0 * std::f64::consts::PI.powi(2) * 2.0 / n as f64).sqrt();
        for fms in [0.0, 0.2] {
            let d = GaussMapAdaptive::new(GaussMapAdaptiveParams {
                flat_min_sine: fms,
                ..Default::default()
            });
            let mut ctx = RunCtx::new(1);
            let t = std::time::Instant::now();
            let out = d.detect(&cloud, &mut ctx).unwrap();
            let wall = t.elapsed().as_secs_f64();
            let dg = &out.diagnostics;
            println!(
                "adaptive torus n={n} spacing*kappa_max={spacing_kappa:.3} flat_min_sine={fms}: first-pass share {:.3}, features {} ({:.1} %), retests {}, skipped {}, isolated {}, passes {}, wall {wall:.2} s ({:.0} us/point), phases {:?}",
                num(dg, "first_pass_share"),
                num(dg, "features"),
                100.0 * num(dg, "features") / n as f64,
                num(dg, "retests"),
                num(dg, "retests_skipped"),
                num(dg, "isolated_removed"),
                num(dg, "passes"),
                1e6 * wall / n as f64,
                ctx.phases()
            );
            let g = GaussMap::new(GaussMapParams {
                flat_min_sine: fms,
                ..Default::default()
            });
            let out = g.detect(&cloud, &mut RunCtx::new(1)).unwrap();
            println!(
                "  gauss-map (16, 0.6): features {}, clustered {}",
                num(&out.diagnostics, "features"),
                num(&out.diagnostics, "candidates")
            );
        }
    }
}
