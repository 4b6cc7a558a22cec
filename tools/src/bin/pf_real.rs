//! `priority-front` on the vertices of a mesh (a real set): topology of the output and
//! where it departs from the mesh (issue 20, `docs/methods/priority_front.md`, "Real
//! data").
//!
//! `cargo run --release -p reconbench-tools --bin pf_real -- datasets/real/fandisk.ply
//! [threads]`. Environment: `RECON_PARAMS` (JSON parameters), `RECON_CTX_SEED`
//! (default 1), `PF_STRETCH` (default 3), `PF_LIST` (bridges / refused points to list,
//! default 8).
//!
//! Prints: ρ, R and the mesh's edge lengths in units of ρ; the output's topology and
//! diagnostics; *bridges* = output edges whose endpoints are farther apart along the
//! input mesh's edges than `PF_STRETCH` times their distance plus 2 ρ (an edge across two sheets or a notch, the cause of a
//! false handle), with their length and position; refused points that the mesh uses
//! (on-surface) and how far their nearest mesh neighbour is; the boundary loops.

use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_geom::topology::analyze;
use reconbench_recon::{PriorityFront, PriorityFrontParams};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: pf_real MESH.ply [threads]");
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let env_usize = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let list = env_usize("PF_LIST", 8);
    let mesh = reconbench_geom::io::read_mesh(path).expect("mesh");
    let v = mesh.vertices().to_vec();
    let n = v.len();
    // Mesh adjacency.
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n];
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if !nb[a as usize].contains(&b) {
                nb[a as usize].push(b);
                nb[b as usize].push(a);
            }
        }
    }
    // Area-weighted vertex normals of the mesh.
    let mut vn = vec![glam::DVec3::ZERO; n];
    for f in mesh.faces() {
        let p = f.map(|i| v[i as usize]);
        let c = (p[1] - p[0]).cross(p[2] - p[0]);
        for &i in f {
            vn[i as usize] += c;
        }
    }
    let vn: Vec<glam::DVec3> = vn.iter().map(|x| x.normalize_or_zero()).collect();
    let cloud = PointCloud::new(v.clone()).expect("finite");
    let mut params = PriorityFrontParams {
        threads,
        ..Default::default()
    };
    if let Ok(j) = std::env::var("RECON_PARAMS") {
        params = serde_json::from_str(&j).expect("RECON_PARAMS must be a JSON params object");
        params.threads = threads;
    }
    let pf = PriorityFront::new(params).expect("params");
    let mut ctx = RunCtx::new(env_usize("RECON_CTX_SEED", 1) as u64);
    let t0 = std::time::Instant::now();
    let rec = pf.reconstruct(&cloud, &mut ctx).expect("reconstruction");
    let secs = t0.elapsed().as_secs_f64();
    let num = |k: &str| match rec.diagnostics.get(k) {
        Some(Diagnostic::Number(x)) => *x,
        _ => f64::NAN,
    };
    let rho = num("rho");
    let r = num("radius");
    // Mesh edge lengths in units of rho.
    let mut el: Vec<f64> = Vec::new();
    for (a, l) in nb.iter().enumerate() {
        for &b in l {
            if (a as u32) < b {
                el.push((v[a] - v[b as usize]).length() / rho);
            }
        }
    }
    el.sort_by(f64::total_cmp);
    let q = |p: f64| el[((el.len() - 1) as f64 * p) as usize];
    println!(
        "{path}: {n} points, rho {rho:.5}, R {r:.5} ({:.2} rho); mesh edges / rho: p50 {:.2} p90 {:.2} p99 {:.2} max {:.2}; {:.2} % longer than R",
        r / rho,
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0),
        100.0 * el.iter().filter(|&&x| x > r / rho).count() as f64 / el.len() as f64
    );
    let t = analyze(&rec.mesh);
    println!(
        "threads {threads}: {} faces in {secs:.3} s; genus {:?}, components {}, boundary loops {}, boundary edges {}, watertight {}, non-manifold edges {}",
        rec.mesh.n_faces(),
        t.genus,
        t.components,
        t.n_boundary_loops(),
        t.boundary_edges,
        t.watertight,
        t.non_manifold_edges
    );
    for (k, d) in &rec.diagnostics {
        match d {
            Diagnostic::Number(x) => print!("{k}={x} "),
            Diagnostic::Series(s) if s.len() <= 16 => print!("{k}={s:?} "),
            _ => {}
        }
    }
    println!();
    // Bridges: bounded Dijkstra on the mesh's edge graph.
    let stretch = std::env::var("PF_STRETCH")
        .ok()
        .and_then(|x| x.parse().ok())
        .unwrap_or(3.0);
    let mut dist = vec![f64::INFINITY; n];
    let mut touched: Vec<u32> = Vec::new();
    let mut heap = std::collections::BinaryHeap::new();
    let mut within = |a: u32, b: u32| -> Option<f64> {
        let lim = stretch * (v[a as usize] - v[b as usize]).length() + 2.0 * rho;
        for &i in &touched {
            dist[i as usize] = f64::INFINITY;
        }
        touched.clear();
        heap.clear();
        dist[a as usize] = 0.0;
        touched.push(a);
        heap.push((std::cmp::Reverse(0u64), a));
        while let Some((std::cmp::Reverse(dk), x)) = heap.pop() {
            let d = f64::from_bits(dk);
            if d > dist[x as usize] {
                continue;
            }
            if x == b {
                return Some(d);
            }
            for &y in &nb[x as usize] {
                let nd = d + (v[x as usize] - v[y as usize]).length();
                if nd <= lim && nd < dist[y as usize] {
                    if dist[y as usize].is_infinite() {
                        touched.push(y);
                    }
                    dist[y as usize] = nd;
                    heap.push((std::cmp::Reverse(nd.to_bits()), y));
                }
            }
        }
        None
    };
    let mut bridges = Vec::new();
    let mut done = std::collections::HashSet::new();
    for f in rec.mesh.faces() {
        for k in 0..3 {
            let (a, b) = (f[k].min(f[(k + 1) % 3]), f[k].max(f[(k + 1) % 3]));
            if done.insert((a, b))
                && !nb[a as usize].is_empty()
                && !nb[b as usize].is_empty()
                && within(a, b).is_none()
            {
                bridges.push((a, b));
            }
        }
    }
    println!(
        "bridges (output edges whose mesh path is longer than {stretch} x + 2 rho): {} of {} edges",
        bridges.len(),
        done.len()
    );
    for &(a, b) in bridges.iter().take(list) {
        let (pa, pb) = (v[a as usize], v[b as usize]);
        println!(
            "  bridge {a}-{b}: length {:.2} rho, mesh normals dot {:.2} at ({:.4}, {:.4}, {:.4})",
            (pa - pb).length() / rho,
            vn[a as usize].dot(vn[b as usize]),
            (pa.x + pb.x) / 2.0,
            (pa.y + pb.y) / 2.0,
            (pa.z + pb.z) / 2.0
        );
    }
    // Self-intersecting face pairs and the shape of the faces involved.
    if std::env::var("PF_SELF").is_ok() {
        let pairs = reconbench_metrics::topology::self_intersecting_pairs(&rec.mesh);
        let mut inv = std::collections::BTreeSet::new();
        for &(f, g) in &pairs {
            inv.insert(f);
            inv.insert(g);
        }
        let faces = rec.mesh.faces();
        let mut hist = [0usize; 6];
        let mut aniso = [0usize; 6];
        for &f in &inv {
            let t = faces[f as usize];
            let l = (0..3)
                .map(|k| (v[t[k] as usize] - v[t[(k + 1) % 3] as usize]).length() / rho)
                .fold(0.0, f64::max);
            hist[(l as usize).min(5)] += 1;
            // Anisotropy of the input mesh at the face's vertices: longest over shortest
            // mesh edge at a vertex.
            let an = t
                .iter()
                .map(|&i| {
                    let ls: Vec<f64> = nb[i as usize]
                        .iter()
                        .map(|&j| (v[i as usize] - v[j as usize]).length())
                        .collect();
                    let mx = ls.iter().copied().fold(0.0, f64::max);
                    let mn = ls.iter().copied().fold(f64::INFINITY, f64::min);
                    mx / mn
                })
                .fold(0.0, f64::max);
            aniso[((an.log2()) as usize).min(5)] += 1;
        }
        let mut all_an = [0usize; 6];
        for (i, l) in nb.iter().enumerate() {
            if l.is_empty() {
                continue;
            }
            let ls: Vec<f64> = l.iter().map(|&j| (v[i] - v[j as usize]).length()).collect();
            let mx = ls.iter().copied().fold(0.0, f64::max);
            let mn = ls.iter().copied().fold(f64::INFINITY, f64::min);
            all_an[(((mx / mn).log2()) as usize).min(5)] += 1;
        }
        println!(
            "self-intersecting pairs {}, faces {}; their longest edge / rho [0,1) .. [5,inf): {hist:?}; input anisotropy (longest / shortest mesh edge at a vertex, log2 bins) at their vertices {aniso:?}, at all vertices {all_an:?}",
            pairs.len(),
            inv.len()
        );
    }
    // Refused points used by the mesh.
    let on: Vec<u32> = rec
        .refused
        .iter()
        .copied()
        .filter(|&i| !nb[i as usize].is_empty())
        .collect();
    println!(
        "refused {} ({} on the surface = used by a mesh face)",
        rec.refused.len(),
        on.len()
    );
    let mut nn: Vec<f64> = on
        .iter()
        .map(|&i| {
            nb[i as usize]
                .iter()
                .map(|&j| (v[i as usize] - v[j as usize]).length() / rho)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nn.sort_by(f64::total_cmp);
    if !nn.is_empty() {
        println!(
            "  refused on-surface: nearest mesh neighbour / rho p10 {:.2} p50 {:.2} p90 {:.2}",
            nn[nn.len() / 10],
            nn[nn.len() / 2],
            nn[nn.len() * 9 / 10]
        );
    }
    for &i in on.iter().take(list) {
        let p = v[i as usize];
        println!("  refused {i} at ({:.4}, {:.4}, {:.4})", p.x, p.y, p.z);
    }
    let paths = reconbench_geom::topology::MeshTopology::new(&rec.mesh).boundary_loops();
    for (k, l) in paths.iter().enumerate().take(list) {
        let c = l
            .vertices
            .iter()
            .fold(glam::DVec3::ZERO, |s, &i| s + v[i as usize])
            / l.vertices.len().max(1) as f64;
        println!(
            "  loop {k}: {} edges at ({:.4}, {:.4}, {:.4})",
            l.vertices.len(),
            c.x,
            c.y,
            c.z
        );
    }
}
