//! Criterion bench of `ufm` end to end (Delaunay + UFM) on blue-noise points of the
//! synth torus knot (issue 7 target: 50k points under 1.5 s on 2 cores).
//! Size via `UFM_BENCH_POINTS` (default 50000).

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::{Ufm, UfmParams};
use reconbench_synth::{DatasetSpec, Density};

fn bench(c: &mut Criterion) {
    let n = std::env::var("UFM_BENCH_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(50_000);
    let spec = DatasetSpec {
        shape: "torus-knot".parse().expect("shape"),
        sampler: "blue-noise".parse().expect("sampler"),
        density: Density::Count(n),
        perturbations: Vec::new(),
        scan: None,
    };
    let pts = reconbench_synth::generate(&spec, 1)
        .expect("data")
        .positions;
    let cloud = PointCloud::new(pts).expect("finite points");
    let ufm = Ufm::new(UfmParams::default()).expect("valid params");
    let mut g = c.benchmark_group("ufm");
    g.sample_size(10);
    g.bench_function(format!("torus_knot_blue_{n}"), |b| {
        b.iter(|| {
            let mut ctx = RunCtx::new(1);
            ufm.reconstruct(&cloud, &mut ctx).expect("reconstruction")
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
