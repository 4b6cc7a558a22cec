//! Runs `hc-it` on a cloud file or on the criterion bench's inputs and prints the phase
//! times, the diagnostics and a hash of the faces (in order), so a change can be checked
//! to give the same mesh bit for bit.
//!
//! `cargo run --release -p reconbench-tools --bin hcit_run -- INPUT [REPEAT]`, INPUT a
//! cloud file (`hf.ply`) or `sheet:N` / `sphere:N` / `hf:N` (the bench's jittered wavy
//! sheet, golden-spiral sphere and noisy height field, the last the points of
//! `reconbench gen height-field --points N --sampler grid --noise ma-uniform:level=0.3
//! --seed 1`). Parameters as JSON in `HCIT_PARAMS`, e.g.
//! `HCIT_PARAMS='{"rho": 2, "closure": "none"}'`. For instruction counts run the built
//! binary under `valgrind --tool=callgrind`.

use reconbench_geom::PointCloud;
use reconbench_geom::io::{fnv1a64, read_cloud};
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_recon::{HcIt, HcItParams};
use reconbench_testkit::hc_it_inputs::{golden_spiral_sphere, noisy_height_field, wavy_sheet};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let input = args.first().map_or("sheet:100000", String::as_str);
    let repeat: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let cloud = match input.split_once(':') {
        Some(("sheet", n)) => PointCloud::new(wavy_sheet(n.parse().expect("N"))).expect("cloud"),
        Some(("sphere", n)) => {
            PointCloud::new(golden_spiral_sphere(n.parse().expect("N"))).expect("cloud")
        }
        Some(("hf", n)) => {
            PointCloud::new(noisy_height_field(n.parse().expect("N"))).expect("cloud")
        }
        _ => read_cloud(input).expect("cloud file"),
    };
    let params: HcItParams = match std::env::var("HCIT_PARAMS") {
        Ok(j) => serde_json::from_str(&j).expect("HCIT_PARAMS: HcItParams JSON"),
        Err(_) => HcItParams::default(),
    };
    let m = HcIt { params };
    for run in 0..repeat.max(1) {
        let mut ctx = RunCtx::new(1);
        let t = std::time::Instant::now();
        let r = m.reconstruct(&cloud, &mut ctx).expect("hc-it");
        let total = t.elapsed().as_secs_f64();
        for (name, s) in &ctx.phases() {
            println!("phase {name:16} {s:.3} s");
        }
        let bytes: Vec<u8> = r
            .mesh
            .faces()
            .iter()
            .flat_map(|f| f.iter().flat_map(|v| v.to_le_bytes()))
            .collect();
        println!(
            "points {} faces {} face-hash {:016x} total {total:.3} s",
            cloud.len(),
            r.mesh.faces().len(),
            fnv1a64(&bytes)
        );
        if run + 1 == repeat.max(1) && std::env::var("HCIT_DIAG").is_ok() {
            for (k, v) in &r.diagnostics {
                if let Diagnostic::Number(x) = v {
                    println!("{k:24} {x}");
                }
            }
        }
    }
}
