//! Criterion bench of `ufm` end to end (Delaunay + UFM + closure) on blue-noise points of
//! the synth torus knot (target: 50k points under 1.5 s on 2 cores; size via
//! `UFM_BENCH_POINTS`, default 50000) and on the vendored Stanford bunny's 35,947
//! vertices, closed mode and literal (target: under 2 s on 2 cores).

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::ufm::Mode;
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
    let bunny =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/real/bunny.ply");
    let bunny = reconbench_geom::io::read_mesh(bunny).expect("vendored bunny");
    let bunny = PointCloud::new(bunny.vertices().to_vec()).expect("finite points");
    for mode in [Mode::Closed, Mode::Literal] {
        let ufm = Ufm::new(UfmParams {
            mode,
            ..Default::default()
        })
        .expect("valid params");
        g.bench_function(format!("bunny_35947_{mode:?}").to_lowercase(), |b| {
            b.iter(|| {
                let mut ctx = RunCtx::new(1);
                ufm.reconstruct(&bunny, &mut ctx).expect("reconstruction")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
