//! `blend` on the 10k-point grid cube (40 intervals per edge, 9 602 points; the thesis's
//! cube has 10 250) with a tube of radius 0.1 diagonals on its top face: the blending
//! steps alone (`reconstruct = none`) and with the sharp MLS of the union (`sharp`, k =
//! 20; the feature channel holds the ground-truth edge samples).
//!
//! Run with `cargo bench -p reconbench-filters --bench blend`.

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_filters::blend::{Blend, BlendParams, Reconstruct};
use reconbench_geom::method::{Describe, FEATURE_CHANNEL, Filter, RunCtx};
use reconbench_geom::{Channel, PointCloud};
use reconbench_testkit::feature_fixtures::grid_box;

fn cube() -> PointCloud {
    let t = grid_box(1.0, 40);
    let labels: Vec<i64> = t
        .points
        .iter()
        .map(|&p| i64::from(t.edge_distance(p) < 1e-9))
        .collect();
    let mut cloud = t.cloud();
    cloud
        .set_channel(FEATURE_CHANNEL, Channel::Label(labels))
        .unwrap();
    cloud
}

fn bench(c: &mut Criterion) {
    let cloud = cube();
    let mut g = c.benchmark_group("blend_cube_10k");
    g.sample_size(10);
    for (name, reconstruct) in [("none", Reconstruct::None), ("sharp", Reconstruct::Sharp)] {
        let f = Blend::from_params(BlendParams {
            reconstruct,
            radius_rel: 0.1,
            length_rel: 0.2,
            ..BlendParams::default()
        })
        .unwrap();
        g.bench_function(name, |b| {
            b.iter(|| f.filter(&cloud, &mut RunCtx::new(1)).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
