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
//! `PF_DETAIL` (also print each component's faces, genus and loops, where each piece
//! lies, how far the small pieces are from the largest, the fold edges over 160
//! degrees, and each boundary loop's edges, length and centroid), `PF_REFUSED` (each refused on-surface point: its
//! distance to the output mesh and to the nearest output vertex in rho, whether the
//! output's nearest point is inside a face, boundary vertices within 3 rho, and the
//! largest angle between the reference normals of its faces), `PF_SEAM` (where the faces
//! that point against the reference normals meet the others).

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
                if std::env::var("PF_SEAM").is_ok() {
                    print_seam(&rec.mesh, &truth_normals);
                }
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
                if std::env::var("PF_REFUSED").is_ok() {
                    print_refused(&mesh, &rec, &used);
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
    // Interior edges whose two faces fold back onto each other (over 160 degrees).
    let mut edge_faces = std::collections::HashMap::<(u32, u32), Vec<usize>>::new();
    for (fi, f) in mesh.faces().iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edge_faces.entry((a.min(b), a.max(b))).or_default().push(fi);
        }
    }
    let nrm = |f: [u32; 3]| {
        let [a, b, c] = f.map(|i| v[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    let folds: Vec<glam::DVec3> = edge_faces
        .iter()
        .filter(|(_, fs)| fs.len() == 2)
        .filter(|(_, fs)| nrm(mesh.faces()[fs[0]]).dot(nrm(mesh.faces()[fs[1]])) < -0.94)
        .map(|((a, b), _)| (v[*a as usize] + v[*b as usize]) * 0.5)
        .collect();
    if !folds.is_empty() {
        let c = folds.iter().sum::<glam::DVec3>() / folds.len() as f64;
        println!(
            "  fold edges (> 160 degrees): {}, centroid {c:.4?}",
            folds.len()
        );
    }
    for l in &topo.boundary_loops {
        println!(
            "  loop: {} edges, length {:.4}, component {}",
            l.edges, l.length, l.component
        );
    }
    // Where each piece lies: union-find over face corners, then per root the centroid
    // and box of its vertices and the centroid of its boundary vertices.
    let mut parent: Vec<u32> = (0..v.len() as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for f in mesh.faces() {
        let r = find(&mut parent, f[0]);
        for &x in &f[1..] {
            let q = find(&mut parent, x);
            parent[q as usize] = r;
        }
    }
    let mut pieces = std::collections::BTreeMap::<
        u32,
        (
            usize,
            glam::DVec3,
            glam::DVec3,
            glam::DVec3,
            glam::DVec3,
            usize,
        ),
    >::new();
    let mut seen = vec![false; v.len()];
    for f in mesh.faces() {
        for &x in f {
            if std::mem::replace(&mut seen[x as usize], true) {
                continue;
            }
            let r = find(&mut parent, x);
            let e = pieces.entry(r).or_insert((
                0,
                glam::DVec3::ZERO,
                glam::DVec3::splat(f64::MAX),
                glam::DVec3::splat(f64::MIN),
                glam::DVec3::ZERO,
                0,
            ));
            e.0 += 1;
            e.1 += v[x as usize];
            e.2 = e.2.min(v[x as usize]);
            e.3 = e.3.max(v[x as usize]);
        }
    }
    for ((a, b), c) in &count {
        if *c == 1 {
            for x in [*a, *b] {
                let r = find(&mut parent, x);
                if let Some(e) = pieces.get_mut(&r) {
                    e.4 += v[x as usize];
                    e.5 += 1;
                }
            }
        }
    }
    // Distance of each small piece's vertices from the largest piece's faces.
    let big = pieces.iter().max_by_key(|(_, e)| e.0).map(|(r, _)| *r);
    let big_faces: Vec<[u32; 3]> = mesh
        .faces()
        .iter()
        .filter(|f| Some(find(&mut parent, f[0])) == big)
        .copied()
        .collect();
    let big_mesh = reconbench_geom::TriMesh::new(v.to_vec(), big_faces).expect("mesh");
    let bvh = reconbench_geom::spatial::MeshBvh::new(&big_mesh).expect("bvh");
    let mut far = std::collections::BTreeMap::<u32, f64>::new();
    for (x, &s) in seen.iter().enumerate() {
        let r = find(&mut parent, x as u32);
        if s && Some(r) != big && pieces[&r].0 < 200 {
            let d = bvh.distance(v[x]).expect("distance");
            let e = far.entry(r).or_insert(0.0);
            *e = e.max(d);
        }
    }
    for (r, d) in &far {
        println!(
            "  small piece {r}: {} vertices, farthest {d:.5} from the largest piece",
            pieces[r].0
        );
    }
    for (n, c, lo, hi, bs, bn) in pieces.values() {
        println!(
            "  piece: {n} vertices, centroid {:.4?}, box {:.4?}..{:.4?}, boundary centroid {:.4?}",
            *c / *n as f64,
            lo,
            hi,
            if *bn > 0 {
                *bs / *bn as f64
            } else {
                glam::DVec3::NAN
            }
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

/// One line per refused on-surface point (see the module doc, `PF_REFUSED`).
fn print_refused(
    reference: &reconbench_geom::TriMesh,
    rec: &reconbench_geom::method::Reconstruction,
    used: &[bool],
) {
    use reconbench_geom::method::Diagnostic;
    let rho = match rec.diagnostics.get("rho") {
        Some(Diagnostic::Number(r)) => *r,
        _ => 1.0,
    };
    let out = &rec.mesh;
    if out.n_faces() == 0 {
        return;
    }
    let bvh = reconbench_geom::spatial::MeshBvh::new(out).expect("bvh");
    let ov = out.vertices();
    let mut count = std::collections::HashMap::<(u32, u32), u32>::new();
    for f in out.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let bnd: Vec<glam::DVec3> = count
        .iter()
        .filter(|(_, c)| **c == 1)
        .flat_map(|((a, b), _)| [ov[*a as usize], ov[*b as usize]])
        .collect();
    let rv = reference.vertices();
    let mut fnorm: Vec<Vec<glam::DVec3>> = vec![Vec::new(); rv.len()];
    for f in reference.faces() {
        let [a, b, c] = f.map(|i| rv[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        for &i in f {
            fnorm[i as usize].push(n);
        }
    }
    let used_out: std::collections::HashSet<u32> = out.faces().iter().flatten().copied().collect();
    for &i in &rec.refused {
        if !used[i as usize] {
            continue;
        }
        let p = rv[i as usize];
        let hit = bvh.closest_point(p).expect("closest");
        let f = out.faces()[hit.face as usize];
        let corner = f
            .iter()
            .map(|&v| ov[v as usize].distance(hit.point))
            .fold(f64::INFINITY, f64::min);
        let inside = corner > 1e-9 * rho;
        let dv = used_out
            .iter()
            .map(|&v| ov[v as usize].distance(p))
            .fold(f64::INFINITY, f64::min);
        let nb = bnd.iter().filter(|q| q.distance(p) <= 3.0 * rho).count();
        let ns = &fnorm[i as usize];
        let mut crease: f64 = 0.0;
        for a in ns {
            for b in ns {
                crease = crease.max(a.dot(*b).clamp(-1.0, 1.0).acos().to_degrees());
            }
        }
        println!(
            "  refused {i}: d_mesh {:.3} rho, d_vertex {:.3} rho, on_face {inside}, boundary_near {nb}, crease {crease:.0} deg",
            hit.distance / rho,
            dv / rho
        );
    }
}

/// Where the faces pointing against the reference normals meet the others (`PF_SEAM`):
/// the count of their edges shared with a face that points the right way, binned by
/// the cosine between the two faces' normals, and their boundary edges.
fn print_seam(mesh: &reconbench_geom::TriMesh, truth: &[glam::DVec3]) {
    let v = mesh.vertices();
    let f = mesh.faces();
    let nrm = |t: [u32; 3]| {
        let [a, b, c] = t.map(|i| v[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    let rev: Vec<bool> = f
        .iter()
        .map(|t| nrm(*t).dot(t.iter().map(|&i| truth[i as usize]).sum()) < 0.0)
        .collect();
    let mut edge = std::collections::HashMap::<(u32, u32), Vec<usize>>::new();
    for (i, t) in f.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edge.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    let mut bins = [0usize; 5];
    let mut open = 0;
    for fs in edge.values() {
        match fs.as_slice() {
            [x] if rev[*x] => open += 1,
            [x, y] if rev[*x] != rev[*y] => {
                let c = nrm(f[*x]).dot(nrm(f[*y]));
                let b = if c < -0.9 {
                    0
                } else if c < -0.5 {
                    1
                } else if c < 0.0 {
                    2
                } else if c < 0.5 {
                    3
                } else {
                    4
                };
                bins[b] += 1;
            }
            _ => {}
        }
    }
    println!(
        "  seam: reversed faces {}, their boundary edges {open}, edges to right faces by normal cosine [<-0.9, <-0.5, <0, <0.5, >=0.5]: {bins:?}",
        rev.iter().filter(|&&r| r).count()
    );
}
