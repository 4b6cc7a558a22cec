//! `pf` with k = 16 on N random torus-surface points (issue target: 1M points in under
//! 1 s on 2 cores). N from `RECONBENCH_BENCH_POINTS` (default 1,000,000).

use std::f64::consts::TAU;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{NormalEstimator, RunCtx};
use reconbench_normals::{Jet, JetParams, PlaneFit, PlaneFitParams};

fn torus_points(n: usize) -> Vec<DVec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..n)
        .map(|_| {
            let (u, v): (f64, f64) = (rng.random_range(0.0..TAU), rng.random_range(0.0..TAU));
            let c = 1.0 + 0.4 * v.cos();
            DVec3::new(c * u.cos(), c * u.sin(), 0.4 * v.sin())
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let n = std::env::var("RECONBENCH_BENCH_POINTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let cloud = PointCloud::new(torus_points(n)).expect("finite points");
    let mut g = c.benchmark_group("normals");
    g.sample_size(10);
    let pf = PlaneFit {
        params: PlaneFitParams { k: 16, orient_k: 0 },
    };
    g.bench_function(format!("pf_k16_{n}"), |b| {
        b.iter(|| pf.estimate(&cloud, &mut RunCtx::new(0)).expect("pf runs"))
    });
    let jet = Jet {
        params: JetParams { k: 18, orient_k: 0 },
    };
    g.bench_function(format!("jet_k18_{n}"), |b| {
        b.iter(|| jet.estimate(&cloud, &mut RunCtx::new(0)).expect("jet runs"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
