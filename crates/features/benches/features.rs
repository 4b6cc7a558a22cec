//! Gauss-map detection, k = 16, on a sampled box surface (and a sphere: the worst case,
//! where curved neighbourhoods fail the flatness pre-test and every point is clustered).
//!
//! `FEATURES_BENCH_N` sets the number of points (default 100 000). Run with
//! `cargo bench -p reconbench-features --bench features`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_features::{GaussMap, GaussMapAdaptive, GaussMapParams, PcaVariation};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{FeatureDetector, RunCtx};

fn n_points() -> usize {
    std::env::var("FEATURES_BENCH_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000)
}

fn random_box(n: usize, seed: u64) -> PointCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pts = (0..n)
        .map(|_| {
            let face: usize = rng.random_range(0..6);
            let (u, v): (f64, f64) = (rng.random(), rng.random());
            let w = if face >= 3 { 1.0 } else { 0.0 };
            match face % 3 {
                0 => DVec3::new(w, u, v),
                1 => DVec3::new(u, w, v),
                _ => DVec3::new(u, v, w),
            }
        })
        .collect();
    PointCloud::new(pts).unwrap()
}

fn sphere(n: usize) -> PointCloud {
    let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let pts = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let t = ga * i as f64;
            DVec3::new(r * t.cos(), r * t.sin(), z)
        })
        .collect();
    PointCloud::new(pts).unwrap()
}

fn report(name: &str, d: &dyn FeatureDetector, cloud: &PointCloud) {
    let mut ctx = RunCtx::new(0);
    let t0 = std::time::Instant::now();
    let out = d.detect(cloud, &mut ctx).unwrap();
    eprintln!(
        "{name}: {} points, {:.3} s total, phases {:?}, diagnostics {:?}",
        cloud.len(),
        t0.elapsed().as_secs_f64(),
        ctx.phases(),
        out.diagnostics
    );
}

fn bench(c: &mut Criterion) {
    let n = n_points();
    let boxc = random_box(n, 1);
    let sph = sphere(n);
    let gm = GaussMap::new(GaussMapParams {
        k: 16,
        ..Default::default()
    });
    eprintln!("rayon threads: {}", rayon::current_num_threads());
    report("gauss-map box", &gm, &boxc);
    report("gauss-map sphere", &gm, &sph);
    report(
        "gauss-map-adaptive box",
        &GaussMapAdaptive::default(),
        &boxc,
    );
    report("pca-variation box", &PcaVariation::default(), &boxc);
    let mut g = c.benchmark_group("features");
    g.sample_size(10);
    g.bench_function(format!("gauss-map k16 box {n}"), |b| {
        b.iter(|| gm.detect(&boxc, &mut RunCtx::new(0)).unwrap())
    });
    g.bench_function(format!("gauss-map k16 sphere {n}"), |b| {
        b.iter(|| gm.detect(&sph, &mut RunCtx::new(0)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
