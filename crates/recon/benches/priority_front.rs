//! Criterion bench of `priority-front` on a blue-noise torus.
//! Size via `RECON_BENCH_POINTS` (default 100000); threads via `RECON_BENCH_THREADS`
//! (default 1). The issue-8 case (1M points, 2 threads):
//! `RECON_BENCH_POINTS=1000000 RECON_BENCH_THREADS=2 cargo bench -p reconbench-recon
//! --bench priority_front`. Measured figures are in docs/methods/priority_front.md.

use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::{PriorityFront, PriorityFrontParams};
use reconbench_testkit::surfaces::Surface;

fn env_usize(k: &str, d: usize) -> usize {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn bench(c: &mut Criterion) {
    let n = env_usize("RECON_BENCH_POINTS", 100_000);
    let threads = env_usize("RECON_BENCH_THREADS", 1);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pts = Surface::Torus(1.0, 0.35).sample_blue_noise(n, &mut rng);
    let cloud = PointCloud::new(pts).expect("finite points");
    let pf = PriorityFront::new(PriorityFrontParams {
        threads,
        ..Default::default()
    })
    .expect("valid params");
    let mut g = c.benchmark_group("priority_front");
    g.sample_size(10);
    g.bench_function(format!("torus_blue_{n}_t{threads}"), |b| {
        b.iter(|| {
            let mut ctx = RunCtx::new(1);
            pf.reconstruct(&cloud, &mut ctx).expect("reconstruction")
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
