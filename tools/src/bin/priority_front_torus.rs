//! Prints the triangle rate of `priority-front` on a blue-noise torus.
//!
//! `cargo run --release -p reconbench-tools --bin priority_front_torus -- [points]
//! [threads] [shape]` with shape `torus` (default), `sphere`, `sheet` or `two-sheets`.
//! Environment: `RECON_PARAMS` (JSON parameters), `RECON_OUTLIERS` (fraction of uniform
//! outliers), `RECON_SAMPLE_SEED` / `RECON_CTX_SEED` (default 7 / 1), `RECON_DUMP`
//! (OBJ-like dump with `r` lines for refused points), `RECON_TOPOLOGY` (print topology).

use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::{PriorityFront, PriorityFrontParams};
use reconbench_testkit::surfaces::Surface;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let shape = args.get(3).map(String::as_str).unwrap_or("torus");
    let surf = match shape {
        "sphere" => Surface::Sphere(1.0),
        "sheet" => Surface::Sheet {
            size: 4.0,
            amp: 0.3,
        },
        "two-sheets" => Surface::TwoSheets { gap: 0.05 },
        "plane" => Surface::Sheet {
            size: 1.0,
            amp: 0.0,
        },
        _ => Surface::Torus(1.0, 0.35),
    };
    let t0 = Instant::now();
    let env_u64 = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let mut rng = ChaCha8Rng::seed_from_u64(env_u64("RECON_SAMPLE_SEED", 7));
    let pts = surf.sample_blue_noise(n, &mut rng);
    let mut pts = pts;
    let n_clean = pts.len();
    if let Some(f) = std::env::var("RECON_OUTLIERS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
    {
        let out = reconbench_testkit::surfaces::uniform_outliers(
            &pts,
            (f * n_clean as f64) as usize,
            &mut rng,
        );
        pts.extend(out);
    }
    let n = pts.len();
    eprintln!(
        "sampled {n} blue-noise points in {:.2} s",
        t0.elapsed().as_secs_f64()
    );
    let cloud = PointCloud::new(pts).expect("finite");
    let mut params = PriorityFrontParams {
        threads,
        ..Default::default()
    };
    if let Ok(j) = std::env::var("RECON_PARAMS") {
        params = serde_json::from_str(&j).expect("RECON_PARAMS must be a JSON params object");
        params.threads = threads;
    }
    let pf = PriorityFront::new(params).expect("params");
    let mut ctx = RunCtx::new(env_u64("RECON_CTX_SEED", 1));
    let cpu0 = process_cpu_seconds();
    let t1 = Instant::now();
    let rec = pf.reconstruct(&cloud, &mut ctx).expect("reconstruction");
    let secs = t1.elapsed().as_secs_f64();
    if let (Some(c0), Some(c1)) = (cpu0, process_cpu_seconds()) {
        println!(
            "  reconstruct CPU time (all threads): {:.3} s = {:.0} triangles per CPU-second",
            c1 - c0,
            rec.mesh.n_faces() as f64 / (c1 - c0).max(1e-9)
        );
    }
    let nf = rec.mesh.n_faces();
    println!(
        "{shape}: {n} points, {threads} thread(s): {nf} triangles in {secs:.3} s = {:.0} triangles/s",
        nf as f64 / secs
    );
    if n > n_clean {
        let r = rec
            .refused
            .iter()
            .filter(|&&i| i as usize >= n_clean)
            .count();
        println!(
            "  outliers: {} of {} refused; clean points refused: {}",
            r,
            n - n_clean,
            rec.refused.len() - r
        );
    }
    for (k, v) in &ctx.phases() {
        println!("  phase {k}: {v:.3} s");
    }
    for (k, v) in &rec.diagnostics {
        match v {
            Diagnostic::Number(x) => println!("  {k} = {x}"),
            Diagnostic::Series(s) if s.len() <= 12 => println!("  {k} = {s:?}"),
            Diagnostic::Series(s) => println!("  {k} = [{} values]", s.len()),
            Diagnostic::Text(t) => println!("  {k} = {t}"),
        }
    }
    if let Ok(path) = std::env::var("RECON_DUMP") {
        use std::io::Write;
        let mut f = std::io::BufWriter::new(std::fs::File::create(path).expect("dump file"));
        for v in rec.mesh.vertices() {
            writeln!(f, "v {} {} {}", v.x, v.y, v.z).expect("write");
        }
        for t in rec.mesh.faces() {
            writeln!(f, "f {} {} {}", t[0], t[1], t[2]).expect("write");
        }
        for r in &rec.refused {
            writeln!(f, "r {r}").expect("write");
        }
    }
    if std::env::var("RECON_TOPOLOGY").is_ok() {
        let t = analyze(&rec.mesh);
        println!(
            "  topology: watertight={} genus={:?} boundary_loops={} non_manifold_edges={} non_manifold_vertices={} consistently_oriented={} components={}",
            t.watertight,
            t.genus,
            t.n_boundary_loops(),
            t.non_manifold_edges,
            t.non_manifold_vertices,
            t.consistently_oriented,
            t.components
        );
    }
}

/// User + system CPU time of this process (all threads) from `/proc/self/stat`, in
/// seconds (Linux; `None` elsewhere). Assumes the usual 100 clock ticks per second.
fn process_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14, 15.
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ut: f64 = f.get(11)?.parse().ok()?;
    let st: f64 = f.get(12)?.parse().ok()?;
    Some((ut + st) / 100.0)
}
