//! Sharp-feature reproduction of Algorithm C (chapter 5, NVC filtering) on a box
//! `[-1, 1]^3`: jittered-grid samples on the six faces (spacing `h`) plus, unless
//! `EDGES=0`, samples exactly on the 12 edges and the 8 corners — the thesis's CAD data
//! are mesh vertices, so its edges are sampled *on* the edge. Runs `ufm` with the
//! parameter sets given as JSON arguments (default: off, generic, flatness, flat-only)
//! and prints, per run: matching %, boundary loops, non-manifold edges,
//! `edge_recovery` (share of the segments between consecutive edge samples that are
//! mesh edges), `bevel_faces` (faces with corners on two different box faces, edge
//! samples not counted: the edge cut off) and the open (hole or unreferenced) vertices
//! on an edge / within 2h of one / farther. Generator and measures:
//! `reconbench_testkit::box_edges`.
//!
//! `EDGE_DENSE=k` (default 2): edge spacing `h / k`. `MARGIN=` (default 0.25): face
//! samples keep this share of a cell from the cell border. `SEED=` (default 1).
//!
//! `EDGE_DENSE=2 cargo run --release -p reconbench-tools --bin ufm_box_edges --
//! 0.06 '{"max_fold": 90, "escapes": 20}' '{"max_fold": 90, "escapes": 20, "nvc":
//! "flat-only"}'`

use reconbench_testkit::box_edges;

use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_recon::{Ufm, UfmParams};

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(d)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let h: f64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(0.06);
    let edges = env("EDGES", 1u32) != 0;
    let mut sets: Vec<String> = args.iter().skip(1).cloned().collect();
    if sets.is_empty() {
        sets = [
            "{}",
            r#"{"nvc": "generic"}"#,
            r#"{"nvc": "flatness"}"#,
            r#"{"nvc": "flat-only"}"#,
        ]
        .map(String::from)
        .to_vec();
    }
    let b = box_edges::box_samples(
        h,
        edges,
        env("EDGE_DENSE", 2),
        env("MARGIN", 0.25),
        env("SEED", 1),
    );
    println!(
        "box h = {h}, {} points ({} on edges/corners), {} edge segments",
        b.pts.len(),
        b.face.iter().filter(|f| f.is_none()).count(),
        b.segs.len()
    );
    let cloud = PointCloud::new(b.pts.clone()).expect("finite");
    for set in &sets {
        let mut p: UfmParams = serde_json::from_str(set).expect("UfmParams JSON");
        p.genus = Some(0);
        let r = Ufm::new(p)
            .expect("params")
            .reconstruct(&cloud, &mut RunCtx::new(1))
            .expect("ufm");
        let num = |k: &str| match r.diagnostics.get(k) {
            Some(Diagnostic::Number(x)) => *x,
            _ => f64::NAN,
        };
        let e = box_edges::edge_stats(&b, r.mesh.faces(), h);
        println!(
            "{set:50} matching {:7.3} loops {:3} nme {} edge_recovery {:.4} bevel_faces {} open(edge/near/far) {:?} nvc_flat_points {}",
            num("matching"),
            num("boundary_loops"),
            num("non_manifold_edges"),
            e.recovery,
            e.bevel_faces,
            e.open,
            num("nvc_flat_points"),
        );
    }
}
