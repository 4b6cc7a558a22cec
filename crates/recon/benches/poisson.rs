//! Criterion bench of `poisson` (screened, depth 8 by default) on a torus with exact
//! normals.
//!
//! Input: the PLY file named by `RECON_BENCH_PLY` (with normals; e.g. the file
//! `reconbench gen torus --points 100000 -o /tmp/torus100k.ply` writes), else a uniform
//! sample of `RECON_BENCH_POINTS` points (default 100000) on the torus (1, 0.35) with
//! exact normals. Depth via `RECON_BENCH_DEPTH` (default 8), threads via
//! `RECON_BENCH_THREADS` (default 2). Figures: docs/methods/poisson.md.
//!
//! `cargo bench -p reconbench-recon --bench poisson`

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::{Poisson, PoissonParams};
use reconbench_testkit::surfaces::Surface;

fn env_usize(k: &str, d: usize) -> usize {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn input() -> (String, PointCloud) {
    if let Ok(path) = std::env::var("RECON_BENCH_PLY") {
        let c = reconbench_geom::io::read_cloud(&path).expect("readable cloud");
        assert!(c.normals().is_some(), "{path}: no normals");
        let name = std::path::Path::new(&path)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        return (name, c);
    }
    let n = env_usize("RECON_BENCH_POINTS", 100_000);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pts = Surface::Torus(1.0, 0.35).sample_uniform(n, &mut rng);
    let nrm = pts
        .iter()
        .map(|&p| (p - DVec3::new(p.x, p.y, 0.0).normalize()).normalize())
        .collect();
    let c = PointCloud::new(pts)
        .and_then(|c| c.with_normals(nrm))
        .expect("finite points");
    (format!("torus_uniform_{n}"), c)
}

fn bench(c: &mut Criterion) {
    let threads = env_usize("RECON_BENCH_THREADS", 2);
    let depth = env_usize("RECON_BENCH_DEPTH", 8);
    let (name, cloud) = input();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let poisson = Poisson::new(PoissonParams {
        depth,
        ..Default::default()
    })
    .expect("valid parameters");
    let mut g = c.benchmark_group("poisson");
    g.sample_size(10);
    g.bench_function(format!("{name}_d{depth}_t{threads}"), |b| {
        b.iter(|| {
            pool.install(|| {
                let mut ctx = RunCtx::new(1);
                poisson
                    .reconstruct(&cloud, &mut ctx)
                    .expect("reconstruction")
            })
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
