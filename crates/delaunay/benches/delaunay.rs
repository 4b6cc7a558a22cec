//! Construction benchmarks: `cargo bench -p reconbench-delaunay`.

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_delaunay::Delaunay;
use reconbench_testkit::points as samples;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("delaunay");
    g.sample_size(10);
    let torus = samples::torus_surface(100_000, 1);
    g.bench_function("torus_100k", |b| {
        b.iter(|| Delaunay::new(&torus).unwrap().n_tets())
    });
    let cube = samples::uniform_cube(1_000_000, 2);
    g.bench_function("uniform_cube_1m", |b| {
        b.iter(|| Delaunay::new(&cube).unwrap().n_tets())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
