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

use std::f64::consts::PI;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::io::{fnv1a64, read_cloud};
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_recon::{HcIt, HcItParams};
use reconbench_synth::{DatasetSpec, Density};

/// The bench's jittered m x m grid over [0, 1]^2 lifted by a wavy height.
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

/// The bench's golden-spiral samples of the unit sphere.
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

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let input = args.first().map_or("sheet:100000", String::as_str);
    let repeat: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let cloud = match input.split_once(':') {
        Some(("sheet", n)) => PointCloud::new(sheet(n.parse().expect("N"))).expect("cloud"),
        Some(("sphere", n)) => PointCloud::new(sphere(n.parse().expect("N"))).expect("cloud"),
        Some(("hf", n)) => {
            let spec = DatasetSpec {
                shape: "height-field".parse().expect("shape"),
                sampler: "grid".parse().expect("sampler"),
                density: Density::Count(n.parse().expect("N")),
                perturbations: vec!["ma-uniform:level=0.3".parse().expect("noise")],
                scan: None,
            };
            let g = reconbench_synth::generate(&spec, 1).expect("height field");
            PointCloud::new(g.positions).expect("cloud")
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
