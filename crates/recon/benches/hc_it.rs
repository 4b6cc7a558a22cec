//! Criterion bench of `hc-it` in its default mode (the sweep and the closure pass) on a
//! jittered 316 x 316 grid (about 100k points) over a wavy height field, on a 100k
//! golden-spiral sphere (a closed surface that folds back in x), and on the issue's
//! noisy height field (`reconbench gen height-field --points 100000 --sampler grid
//! --noise ma-uniform:level=0.3 --seed 1`, the same points), there also in the literal
//! mode (`closure = "none"`). `RECON_BENCH_POINTS` changes the size. The issue-24
//! target: 100k points under 2 s on 2 cores,
//! `RAYON_NUM_THREADS=2 cargo bench -p reconbench-recon --bench hc_it`. Figures are in
//! docs/methods/hc_it.md.

use criterion::{Criterion, criterion_group, criterion_main};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::hc_it::Closure;
use reconbench_recon::{HcIt, HcItParams};
use reconbench_testkit::hc_it_inputs::{golden_spiral_sphere, noisy_height_field, wavy_sheet};

fn size() -> usize {
    std::env::var("RECON_BENCH_POINTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000)
}

fn bench(c: &mut Criterion) {
    let n = size();
    let mut g = c.benchmark_group("hc_it");
    g.sample_size(10);
    let literal = HcIt {
        params: HcItParams {
            closure: Closure::None,
            ..HcItParams::default()
        },
    };
    let hf = noisy_height_field(n);
    for (name, pts, m) in [
        ("sheet", wavy_sheet(n), HcIt::default()),
        ("sphere", golden_spiral_sphere(n), HcIt::default()),
        ("noisy_height_field", hf.clone(), HcIt::default()),
        ("noisy_height_field_literal", hf, literal),
    ] {
        let cloud = PointCloud::new(pts).expect("cloud");
        g.bench_function(format!("{name}_{n}"), |b| {
            b.iter(|| {
                m.reconstruct(&cloud, &mut RunCtx::new(1))
                    .expect("reconstruct")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
