//! Diagnostic probe (not part of the API): one `gauss-map` (k = 16, sigma = 0.6) run on
//! the bench's 100k-point random box; run under `/usr/bin/time` to get CPU seconds,
//! which are less sensitive to a shared machine's load than wall time.
//!
//! `cargo build --release -p reconbench-tools --bin probe_bench &&
//!  /usr/bin/time -f "%U s user %e s wall" target/release/probe_bench`

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reconbench_features::{GaussMap, GaussMapAdaptive};
use reconbench_geom::PointCloud;
use reconbench_geom::method::{FeatureDetector, RunCtx};

fn main() {
    let n = 100_000;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let pts: Vec<DVec3> = (0..n)
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
    let cloud = PointCloud::new(pts).unwrap();
    let adaptive = std::env::args().any(|a| a == "adaptive");
    let mut ctx = RunCtx::new(0);
    let t = std::time::Instant::now();
    let out = if adaptive {
        GaussMapAdaptive::default().detect(&cloud, &mut ctx)
    } else {
        GaussMap::default().detect(&cloud, &mut ctx)
    }
    .unwrap();
    println!(
        "{}: {:.2} s wall, features {:?}, phases {:?}",
        if adaptive { "adaptive" } else { "gauss-map" },
        t.elapsed().as_secs_f64(),
        out.diagnostics.get("features"),
        ctx.phases()
    );
}
