//! Diagnoses the holes `ufm` leaves on a mesh's vertex set (the seeds' protocol on their
//! real data): how many of the mesh's own faces are Delaunay facets, the matching trace,
//! and, after the Delaunay hole closure, every remaining hole with the reasons its
//! boundary candidates are refused.
//!
//! `cargo run --release -p reconbench-tools --bin ufm_holes -- datasets/real/mechpart.ply`
//! with `UFM_PARAMS='{"close_max_turn_deg": 120}'` (JSON parameters).

use std::collections::HashSet;

use reconbench_geom::method::RunCtx;
use reconbench_recon::UfmParams;
use reconbench_recon::ufm::{closure, output_facets, run_ufm};

fn main() {
    let path = std::env::args().nth(1).expect("usage: ufm_holes MESH");
    let mesh = reconbench_geom::io::read_mesh(&path).expect("mesh");
    let params: UfmParams = match std::env::var("UFM_PARAMS") {
        Ok(j) => serde_json::from_str(&j).expect("UFM_PARAMS: UfmParams JSON"),
        Err(_) => UfmParams::default(),
    };
    // Morton order, as the reconstructor runs it (`reorder = true`).
    let order = reconbench_geom::spatial::morton_order(mesh.vertices());
    let sorted: Vec<glam::DVec3> = order.iter().map(|&i| mesh.vertices()[i as usize]).collect();
    let pts = &sorted[..];
    let mut ctx = RunCtx::new(1);
    let st = run_ufm(pts, &params, &mut ctx).expect("ufm");
    let dt = &st.cx.dt;
    // Which of the mesh's faces are Delaunay facets.
    let dt_faces: HashSet<[u32; 3]> = st
        .cx
        .facets()
        .iter()
        .map(|f| {
            // Back to the mesh's vertex ids (the run is on Morton-ordered points).
            let mut t = f.v.map(|v| order[dt.input_of_vertex(v) as usize]);
            t.sort_unstable();
            t
        })
        .collect();
    let in_dt = mesh
        .faces()
        .iter()
        .filter(|f| {
            let mut t = **f;
            t.sort_unstable();
            dt_faces.contains(&t)
        })
        .count();
    println!(
        "{path}: {} points, {} faces, {} of them Delaunay facets ({:.2} %)",
        pts.len(),
        mesh.n_faces(),
        in_dt,
        100.0 * in_dt as f64 / mesh.n_faces() as f64
    );
    let trace: Vec<String> = st
        .trace
        .iter()
        .map(|x| format!("{:.2}", 100.0 * x))
        .collect();
    println!("matching trace (%): {}", trace.join(" "));
    println!(
        "stop rule: {}, iterations {}",
        st.stop.name(),
        st.iterations
    );
    let out = output_facets(&st, params.output);
    let max_turn = params.close_max_turn.to_radians();
    let (closed, filled, stats) = if max_turn > 0.0 {
        closure::close(&st.cx, dt.vertices(), &out, max_turn)
    } else {
        (out.clone(), Vec::new(), closure::ClosureStats::default())
    };
    println!(
        "loop output {} facets; closure added {}, removed {} at pinches; polygon fill: {} holes, {} triangles",
        out.len(),
        stats.added,
        stats.unpinched_faces,
        stats.filled_holes,
        filled.len()
    );
    let tri = |fs: &[u32]| -> Vec<[u32; 3]> {
        fs.iter().map(|&f| st.cx.facets()[f as usize].v).collect()
    };
    println!("loop output:       {}", summary(dt.vertices(), tri(&out)));
    println!(
        "after growth:      {}",
        summary(dt.vertices(), tri(&closed))
    );
    let mut all = tri(&closed);
    all.extend(filled.iter().copied());
    println!("after fill:        {}", summary(dt.vertices(), all));
    // The holes before the polygon fill, and why no Delaunay triangle closes them.
    let holes = closure::diagnose(&st.cx, dt.vertices(), &closed, max_turn.max(1e-9));
    println!(
        "{} holes (edges: no candidate / refused for turn, size, manifold)",
        holes.len()
    );
    for h in holes.iter().take(40) {
        println!(
            "  {:4} edges: {:3} / {:3} {:3} {:3}",
            h.edges, h.no_candidate, h.turn, h.size, h.manifold
        );
    }
}

/// Topology summary of a face set (DT vertex ids) on the given points.
pub fn summary(pts: &[glam::DVec3], faces: Vec<[u32; 3]>) -> String {
    let m = reconbench_geom::TriMesh::new(pts.to_vec(), faces).expect("mesh");
    let r = reconbench_geom::topology::analyze(&m);
    let topo = reconbench_geom::topology::MeshTopology::new(&m);
    let (nc, comp) = topo.face_components();
    let mut sizes = vec![0usize; nc];
    for &c in &comp {
        if (c as usize) < nc {
            sizes[c as usize] += 1;
        }
    }
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes.truncate(12);
    format!(
        "faces {} components {} {sizes:?} loops {} orientable {} genus {:?} non-manifold v/e {}/{}",
        m.n_faces(),
        r.components,
        r.n_boundary_loops(),
        r.orientable,
        r.genus,
        r.non_manifold_vertices,
        r.non_manifold_edges
    )
}
