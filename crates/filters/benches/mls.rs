//! `mls-sharp` and `mls` on a noisy 100k-point box (k = 20): the speed target of issue
//! 23 is `mls-sharp` under 2 s on 2 cores. The box is the grid of 129 intervals per
//! edge (99 848 points) with ball noise of 0.1 spacings; its feature channel holds the
//! ground-truth edge samples (a detector's labels cost the same per feature point and
//! are benchmarked in `reconbench-features`).
//!
//! Run with `cargo bench -p reconbench-filters --bench mls`.

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_filters::{Mls, MlsParams, MlsSharp, MlsSharpParams};
use reconbench_geom::method::{Describe, FEATURE_CHANNEL, Filter, RunCtx};
use reconbench_geom::{Channel, PointCloud};
use reconbench_testkit::feature_fixtures::{add_noise, grid_box};

fn noisy_box() -> PointCloud {
    let t = grid_box(1.0, 129);
    let labels: Vec<i64> = t
        .points
        .iter()
        .map(|&p| i64::from(t.edge_distance(p) < 1e-9))
        .collect();
    let mut cloud = PointCloud::new(add_noise(&t.points, 0.1 * t.spacing, 1)).unwrap();
    cloud
        .set_channel(FEATURE_CHANNEL, Channel::Label(labels))
        .unwrap();
    cloud
}

fn bench(c: &mut Criterion) {
    let cloud = noisy_box();
    let mut g = c.benchmark_group("mls_box_100k");
    g.sample_size(10);
    let sharp = MlsSharp::from_params(MlsSharpParams::default()).unwrap();
    g.bench_function("mls-sharp_k20", |b| {
        b.iter(|| sharp.filter(&cloud, &mut RunCtx::new(1)).unwrap())
    });
    let smooth = Mls::from_params(MlsParams::default()).unwrap();
    g.bench_function("mls_k20", |b| {
        b.iter(|| smooth.filter(&cloud, &mut RunCtx::new(1)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
