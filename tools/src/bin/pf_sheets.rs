//! `priority-front` on two parallel blue-noise sheets 1 x 1 a small gap apart: faces
//! joining the sheets and the topology (issue 20, close sheets;
//! `docs/methods/priority_front.md`, "Real data").
//!
//! `cargo run --release -p reconbench-tools --bin pf_sheets -- [gap] [points] [threads]`
//! (default 0.016, 8000, 1). Environment: `RECON_PARAMS` (JSON parameters),
//! `RECON_CTX_SEED` (default 5), `RECON_SAMPLE_SEED` (default 5).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::{PriorityFront, PriorityFrontParams};
use reconbench_testkit::surfaces::Surface;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let gap: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(0.016);
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(8000);
    let threads: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let env_u64 = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let mut rng = ChaCha8Rng::seed_from_u64(env_u64("RECON_SAMPLE_SEED", 5));
    let pts = Surface::TwoSheets { gap }.sample_blue_noise(n, &mut rng);
    let mut params = PriorityFrontParams::default();
    if let Ok(j) = std::env::var("RECON_PARAMS") {
        params = serde_json::from_str(&j).expect("RECON_PARAMS must be a JSON params object");
    }
    params.threads = threads;
    let pf = PriorityFront::new(params).expect("params");
    let cloud = PointCloud::new(pts).expect("finite");
    let rec = pf
        .reconstruct(&cloud, &mut RunCtx::new(env_u64("RECON_CTX_SEED", 5)))
        .expect("reconstruction");
    let v = rec.mesh.vertices();
    let bridging = rec
        .mesh
        .faces()
        .iter()
        .filter(|f| {
            let up = f.iter().filter(|&&i| v[i as usize].z > gap / 2.0).count();
            up != 0 && up != 3
        })
        .count();
    let mut hist = [0usize; 10];
    for f in rec.mesh.faces() {
        let up = f.iter().filter(|&&i| v[i as usize].z > gap / 2.0).count();
        if up != 0 && up != 3 {
            let c = f.iter().map(|&i| v[i as usize]).sum::<glam::DVec3>() / 3.0;
            hist[((c.x + 0.5) * 10.0).clamp(0.0, 9.0) as usize] += 1;
        }
    }
    println!("faces joining the sheets by x in tenths of the sheet: {hist:?}");
    let t = analyze(&rec.mesh);
    let rho = match rec.diagnostics.get("rho") {
        Some(Diagnostic::Number(x)) => *x,
        _ => f64::NAN,
    };
    println!(
        "gap {gap} ({:.2} rho), {n} points, {threads} thread(s): {} faces, {bridging} joining the sheets; genus {:?}, components {}, boundary loops {}, refused {}",
        gap / rho,
        rec.mesh.n_faces(),
        t.genus,
        t.components,
        t.n_boundary_loops(),
        rec.refused.len()
    );
}
