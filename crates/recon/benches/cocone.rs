//! Criterion bench of `tight-cocone` and `cocone` against the Delaunay tetrahedralization
//! they start from, on 100k blue-noise points of the synth torus (target: Tight Cocone
//! within 2x of the Delaunay time on 2 cores; size via `COCONE_BENCH_POINTS`), and on the
//! vendored Stanford bunny's 35,947 vertices.

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_delaunay::Delaunay;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::{Cocone, TightCocone};
use reconbench_synth::{DatasetSpec, Density};

fn bench(c: &mut Criterion) {
    let n = std::env::var("COCONE_BENCH_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000);
    let spec = DatasetSpec {
        shape: "torus".parse().expect("shape"),
        sampler: "blue-noise".parse().expect("sampler"),
        density: Density::Count(n),
        perturbations: Vec::new(),
        scan: None,
    };
    let pts = reconbench_synth::generate(&spec, 1)
        .expect("data")
        .positions;
    let bunny =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/real/bunny.ply");
    let bunny = reconbench_geom::io::read_mesh(bunny)
        .expect("vendored bunny")
        .vertices()
        .to_vec();
    let mut g = c.benchmark_group("cocone");
    g.sample_size(10);
    for (name, pts) in [(format!("torus_{n}"), pts), ("bunny_35947".into(), bunny)] {
        let cloud = PointCloud::new(pts.clone()).expect("finite points");
        g.bench_function(format!("delaunay_{name}"), |b| {
            b.iter(|| {
                let dt = Delaunay::new(&pts).expect("triangulation");
                dt.facets().len()
            })
        });
        g.bench_function(format!("tight_cocone_{name}"), |b| {
            b.iter(|| {
                TightCocone::default()
                    .reconstruct(&cloud, &mut RunCtx::new(1))
                    .expect("reconstruction")
            })
        });
        g.bench_function(format!("cocone_{name}"), |b| {
            b.iter(|| {
                Cocone::default()
                    .reconstruct(&cloud, &mut RunCtx::new(1))
                    .expect("reconstruction")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
