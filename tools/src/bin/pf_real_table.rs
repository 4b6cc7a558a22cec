//! `priority-front` on the vertices of the issue-20 real sets: one line per set, thread
//! count and ctx seed with genus, components, boundary loops, refused on-surface points,
//! self-intersecting face pairs and the method's wall time (issue 20's before / after
//! table, `docs/methods/priority_front.md`, "Real data").
//!
//! `cargo run --release -p reconbench-tools --bin pf_real_table -- [SET ...]` (default:
//! fandisk rocker-arm 3holes mechpart golf-club bunny, from `datasets/real/`; an
//! argument ending in `.ply` is read as the path of a mesh).
//! Environment: `PF_THREADS` (comma list, default `1,2`), `PF_SEEDS` (comma list,
//! default `1,2,3`), `RECON_PARAMS` (JSON parameters; `threads` is overridden),
//! `PF_NOSELF` (skip the self-intersection count, which dominates the probe's time),
//! `PF_DETAIL` (also print each component's faces, genus and loops, and each boundary
//! loop's edges, length and centroid).

use reconbench_geom::PointCloud;
use reconbench_geom::method::{Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::{PriorityFront, PriorityFrontParams};

/// A comma list of integers from the environment, or `default`.
fn env_list(key: &str, default: &[u64]) -> Vec<u64> {
    match std::env::var(key) {
        Ok(s) => s
            .split(',')
            .map(|x| {
                x.trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("{key}: not an integer: {x}"))
            })
            .collect(),
        Err(_) => default.to_vec(),
    }
}

/// Parameters from `RECON_PARAMS` (or the defaults) with `threads` set.
fn params(threads: usize) -> PriorityFrontParams {
    let mut p = match std::env::var("RECON_PARAMS") {
        Ok(j) => serde_json::from_str(&j).expect("RECON_PARAMS must be a JSON params object"),
        Err(_) => PriorityFrontParams::default(),
    };
    p.threads = threads;
    p
}

fn main() {
    let mut sets: Vec<String> = std::env::args().skip(1).collect();
    if sets.is_empty() {
        sets = [
            "fandisk",
            "rocker-arm",
            "3holes",
            "mechpart",
            "golf-club",
            "bunny",
        ]
        .map(String::from)
        .to_vec();
    }
    let threads = env_list("PF_THREADS", &[1, 2]);
    let seeds = env_list("PF_SEEDS", &[1, 2, 3]);
    let selfx = std::env::var("PF_NOSELF").is_err();
    println!(
        "set threads seed | genus comp loops bnd_edges | refused on_surface | self_pairs | faces reversed s"
    );
    for name in &sets {
        let path = if name.ends_with(".ply") {
            name.clone()
        } else {
            format!("datasets/real/{name}.ply")
        };
        let mesh = reconbench_geom::io::read_mesh(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let mut used = vec![false; mesh.n_vertices()];
        for f in mesh.faces() {
            for &i in f {
                used[i as usize] = true;
            }
        }
        let cloud = PointCloud::new(mesh.vertices().to_vec()).expect("finite points");
        let truth_normals = vertex_normals(&mesh);
        for &t in &threads {
            let pf = PriorityFront::new(params(t as usize)).expect("valid params");
            for &s in &seeds {
                let t0 = std::time::Instant::now();
                let rec = pf
                    .reconstruct(&cloud, &mut RunCtx::new(s))
                    .expect("reconstruction");
                let secs = t0.elapsed().as_secs_f64();
                let topo = analyze(&rec.mesh);
                let on = rec.refused.iter().filter(|&&i| used[i as usize]).count();
                let pairs = if selfx {
                    reconbench_metrics::topology::self_intersecting_pairs(&rec.mesh)
                        .len()
                        .to_string()
                } else {
                    "-".to_string()
                };
                let reversed = reversed_faces(&rec.mesh, &truth_normals);
                println!(
                    "{name} {t} {s} | {} {} {} {} | {} {on} | {pairs} | {} {reversed} {secs:.3}",
                    topo.genus.map_or("-".to_string(), |g| g.to_string()),
                    topo.components,
                    topo.n_boundary_loops(),
                    topo.boundary_edges,
                    rec.refused.len(),
                    rec.mesh.n_faces(),
                );
                if std::env::var("PF_DETAIL").is_ok() {
                    print_detail(&rec.mesh, &topo);
                }
            }
        }
    }
}

/// Area-weighted vertex normals of the reference mesh.
fn vertex_normals(mesh: &reconbench_geom::TriMesh) -> Vec<glam::DVec3> {
    let v = mesh.vertices();
    let mut n = vec![glam::DVec3::ZERO; v.len()];
    for f in mesh.faces() {
        let [a, b, c] = f.map(|i| v[i as usize]);
        let fn_ = (b - a).cross(c - a);
        for &i in f {
            n[i as usize] += fn_;
        }
    }
    n
}

/// Output faces whose normal points against the reference normals at their corners
/// (a piece grown with the wrong orientation).
fn reversed_faces(mesh: &reconbench_geom::TriMesh, truth: &[glam::DVec3]) -> usize {
    let v = mesh.vertices();
    mesh.faces()
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|i| v[i as usize]);
            let sum: glam::DVec3 = f.iter().map(|&i| truth[i as usize]).sum();
            (b - a).cross(c - a).dot(sum) < 0.0
        })
        .count()
}

/// Each component's faces, genus and loops; each boundary loop's edges, length and the
/// centroid of its vertices.
fn print_detail(mesh: &reconbench_geom::TriMesh, topo: &reconbench_geom::topology::TopologyReport) {
    for (i, c) in topo.component_details.iter().enumerate() {
        println!(
            "  component {i}: {} faces, genus {:?}, {} loops",
            c.faces, c.genus, c.boundary_loops
        );
    }
    let v = mesh.vertices();
    let mut count = std::collections::HashMap::<(u32, u32), u32>::new();
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    for l in &topo.boundary_loops {
        println!(
            "  loop: {} edges, length {:.4}, component {}",
            l.edges, l.length, l.component
        );
    }
    let bnd: Vec<glam::DVec3> = count
        .iter()
        .filter(|(_, c)| **c == 1)
        .map(|((a, _), _)| v[*a as usize])
        .collect();
    if !bnd.is_empty() {
        println!(
            "  boundary vertices (first 20): {:?}",
            &bnd[..bnd.len().min(20)]
        );
    }
}
