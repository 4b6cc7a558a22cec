//! Prints the local state of unmatched umbrellas after a UFM run (debugging aid).
//! `cargo run --release -p reconbench-recon --example ufm_debug -- SHAPE N SAMPLER [COUNT]`

use reconbench_geom::method::RunCtx;
use reconbench_recon::ufm::engine;
use reconbench_recon::ufm::{UfmParams, run_ufm};
use reconbench_synth::{DatasetSpec, Density};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = DatasetSpec {
        shape: args[0].parse().expect("shape"),
        sampler: args[2].parse().expect("sampler"),
        density: Density::Count(args[1].parse().expect("n")),
        perturbations: Vec::new(),
        scan: None,
    };
    let count: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let pts = reconbench_synth::generate(&spec, seed)
        .expect("data")
        .positions;
    let st = run_ufm(&pts, &UfmParams::default(), &mut RunCtx::new(1)).expect("ufm");
    let cx = &st.cx;
    let g = engine::grades(cx, &st.inu, &st.m);
    let facets = cx.facets();
    let member = |w: u32, f: u32| -> bool {
        let k = facets[f as usize].v.iter().position(|&x| x == w).unwrap();
        st.inu[cx.slot[f as usize][k] as usize]
    };
    let mut shown = 0;
    let extra: Vec<usize> = args.iter().skip(4).map(|s| s.parse().unwrap()).collect();
    for v in 0..cx.n_vertices() {
        if !extra.contains(&v) && (g[v] || shown >= count) {
            continue;
        }
        shown += 1;
        println!("vertex {v}: |DT_v| = {}", cx.row(v).len());
        for &f in cx.row(v) {
            let fv = facets[f as usize].v;
            let mem: Vec<bool> = fv.iter().map(|&w| member(w, f)).collect();
            if st.m[f as usize] == 0 {
                continue;
            }
            let gr: Vec<bool> = fv.iter().map(|&w| g[w as usize]).collect();
            println!(
                "  f{f} {:?} m={} member={:?} full={:?} gabriel={} rank={}",
                fv, st.m[f as usize], mem, gr, cx.gabriel[f as usize], cx.rank_init[f as usize]
            );
        }
    }
}
