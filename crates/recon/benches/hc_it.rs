//! Criterion bench of `hc-it` in its default mode (the sweep and the closure pass) on a
//! jittered 316 x 316 grid (about 100k points) over a wavy height field, on a 100k
//! golden-spiral sphere (a closed surface that folds back in x), and on the issue's
//! noisy height field (`reconbench gen height-field --points 100000 --sampler grid
//! --noise ma-uniform:level=0.3 --seed 1`, the same points), there also in the literal
//! mode (`closure = "none"`). `RECON_BENCH_POINTS` changes the size. The issue-24
//! target: 100k points under 2 s on 2 cores,
//! `RAYON_NUM_THREADS=2 cargo bench -p reconbench-recon --bench hc_it`. Figures are in
//! docs/methods/hc_it.md.

use std::f64::consts::PI;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_recon::hc_it::Closure;
use reconbench_recon::{HcIt, HcItParams};
use reconbench_synth::{DatasetSpec, Density};

fn size() -> usize {
    std::env::var("RECON_BENCH_POINTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000)
}

/// A jittered m x m grid over [0, 1]^2 lifted by a wavy height.
fn sheet(n: usize) -> Vec<DVec3> {
    let m = (n as f64).sqrt().round() as usize;
    let mut out = Vec::with_capacity(m * m);
    for i in 0..m {
        for j in 0..m {
            let jx = ((i * 7 + j * 13) as f64 * 0.618_034).fract() - 0.5;
            let jy = ((i * 11 + j * 5) as f64 * 0.414_214).fract() - 0.5;
            let x = (i as f64 + 0.5 + 0.3 * jx) / m as f64;
            let y = (j as f64 + 0.5 + 0.3 * jy) / m as f64;
            out.push(DVec3::new(x, y, 0.1 * (3.0 * x).sin() * y));
        }
    }
    out
}

/// Golden-spiral samples of the unit sphere.
fn sphere(n: usize) -> Vec<DVec3> {
    let ga = PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let phi = ga * i as f64;
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect()
}

/// The CLI's `height-field` grid with `ma-uniform:level=0.3` noise, seed 1.
fn noisy_height_field(n: usize) -> Vec<DVec3> {
    let spec = DatasetSpec {
        shape: "height-field".parse().expect("shape"),
        sampler: "grid".parse().expect("sampler"),
        density: Density::Count(n),
        perturbations: vec!["ma-uniform:level=0.3".parse().expect("noise")],
        scan: None,
    };
    reconbench_synth::generate(&spec, 1)
        .expect("height field")
        .positions
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
        ("sheet", sheet(n), HcIt::default()),
        ("sphere", sphere(n), HcIt::default()),
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
