//! Prints the local state of unmatched umbrellas after a UFM run (debugging aid).
//! `cargo run --release -p reconbench-tools --bin ufm_debug -- SHAPE N SAMPLER [COUNT]`

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
    let params: UfmParams = match std::env::var("UFM_PARAMS") {
        Ok(j) => serde_json::from_str(&j).expect("UFM_PARAMS: UfmParams JSON"),
        Err(_) => UfmParams::default(),
    };
    let st = run_ufm(&pts, &params, &mut RunCtx::new(1)).expect("ufm");
    let cx = &st.cx;
    let g = engine::grades(cx, &st.inu, &st.m);
    let facets = cx.facets();
    let member = |w: u32, f: u32| -> bool {
        let k = facets[f as usize].v.iter().position(|&x| x == w).unwrap();
        st.inu[cx.slot[f as usize][k] as usize]
    };
    if std::env::var("FOLDS").is_ok() {
        // Histogram of the maximum fold angle per umbrella, split by grade.
        let pts = cx.dt.vertices();
        let mut g_link = reconbench_recon::ufm::umbrella::LinkGraph::default();
        let (mut fs, mut ring, mut ang) = (Vec::new(), Vec::new(), Vec::new());
        let mut hist = [[0usize; 18]; 2];
        for v in 0..cx.n_vertices() {
            cx.prepare(v, &mut g_link);
            let base = cx.off[v] as usize;
            g_link.cycle(|i| st.inu[base + i], &mut fs, &mut ring);
            reconbench_recon::ufm::geometry::fold_angles(pts, v as u32, &ring, &mut ang);
            let mx = ang.iter().copied().fold(0.0f64, f64::max).to_degrees();
            hist[g[v] as usize][((mx / 10.0) as usize).min(17)] += 1;
        }
        println!("max fold per umbrella, 10-degree bins 0..180: [unmatched, matched]");
        for b in 0..18 {
            println!(
                "{:3}-{:3}: {:6} {:6}",
                b * 10,
                b * 10 + 10,
                hist[0][b],
                hist[1][b]
            );
        }
        return;
    }
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
