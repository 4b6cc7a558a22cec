//! Runs `ufm` on a synthetic shape and prints the diagnostics and the time split.
//!
//! `cargo run --release -p reconbench-tools --bin ufm_run -- SHAPE N [SAMPLER] [PERTURB]`
//! e.g. `-- torus-knot 50000 blue-noise`, `-- torus 3600 grid`,
//! `-- sphere 20000 uniform ball:radius=0.3,rel=spacing`.

use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::{Ufm, UfmParams};
use reconbench_synth::{DatasetSpec, Density};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let shape = args.first().map_or("torus-knot", String::as_str);
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(50_000);
    let sampler = args.get(2).map_or("blue-noise", String::as_str);
    let perturbations = match args.get(3) {
        Some(p) => vec![p.parse().expect("perturbation spec")],
        None => Vec::new(),
    };
    let spec = DatasetSpec {
        shape: shape.parse().expect("shape spec"),
        sampler: sampler.parse().expect("sampler spec"),
        density: Density::Count(n),
        perturbations,
        scan: None,
    };
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let g = reconbench_synth::generate(&spec, seed).expect("data");
    let genus = Some(spec.shape.build().expect("shape").info().genus);
    let cloud = PointCloud::new(g.positions).expect("finite");
    // Extra parameters as JSON in UFM_PARAMS, e.g. '{"lock_matched": false}'.
    let mut params: UfmParams = match std::env::var("UFM_PARAMS") {
        Ok(j) => serde_json::from_str(&j).expect("UFM_PARAMS: UfmParams JSON"),
        Err(_) => UfmParams::default(),
    };
    params.genus = genus;
    let ufm = Ufm::new(params).expect("params");
    let mut ctx = RunCtx::new(1);
    let t = std::time::Instant::now();
    let r = ufm.reconstruct(&cloud, &mut ctx).expect("ufm");
    let total = t.elapsed().as_secs_f64();
    for (k, v) in &r.diagnostics {
        match v {
            Diagnostic::Number(x) => println!("{k:22} {x}"),
            Diagnostic::Series(s) if s.len() > 12 => {
                println!("{k:22} {:?} ... {:?}", &s[..6], &s[s.len() - 3..])
            }
            Diagnostic::Series(s) => println!("{k:22} {s:?}"),
            Diagnostic::Text(s) => println!("{k:22} {s}"),
        }
    }
    for (name, s) in &ctx.phases() {
        println!("phase {name:16} {s:.3} s");
    }
    let rep = analyze(&r.mesh);
    let sizes: Vec<usize> = rep.component_details.iter().map(|c| c.faces).collect();
    println!("component faces {sizes:?}");
    println!(
        "points {} faces {} watertight {} genus {:?} (expected {:?}) components {} total {total:.3} s",
        cloud.len(),
        rep.faces,
        rep.watertight,
        rep.genus,
        genus,
        rep.components
    );
}
