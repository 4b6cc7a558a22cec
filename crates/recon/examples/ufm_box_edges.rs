//! Sharp-feature reproduction of Algorithm C (chapter 5, NVC filtering) on a box
//! `[-1, 1]^3`: jittered-grid samples on the six faces (spacing `h`) plus, unless
//! `EDGES=0`, samples exactly on the 12 edges (spacing `h`) and the 8 corners — the
//! thesis's CAD data are mesh vertices, so its edges are sampled *on* the edge.
//! Runs `ufm` with the parameter sets given as JSON arguments (default: off, generic,
//! flatness) and prints, per run: matching %, boundary loops, non-manifold edges,
//! `edge_recovery` (share of the segments between consecutive edge samples that are mesh
//! edges), the mean dihedral angle at those mesh edges (90° = the box edge kept), and
//! `bevel_faces` (faces with corners on two different faces and not all on an edge: the
//! edge cut off).
//!
//! `EDGE_DENSE=k` (default 1): edge spacing `h / k`. `MARGIN=` (default 0.25): face samples keep this share of a cell from the cell
//! border (0.5 = cell centres, no jitter).
//!
//! `cargo run --release -p reconbench-recon --example ufm_box_edges -- 0.06
//! '{}' '{"nvc": "flatness"}'`; `SEED=` jitter seed (default 1).

use std::collections::{HashMap, HashSet};

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, Reconstructor, RunCtx};
use reconbench_recon::{Ufm, UfmParams};

/// splitmix64 in [0, 1).
fn rnd(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Points and, per point, the face id (0..6) or `None` for edge / corner samples.
fn box_points(h: f64, edges: bool, dense: usize, seed: u64) -> (Vec<DVec3>, Vec<Option<u8>>) {
    let n = (2.0 / h).round().max(2.0) as usize;
    let step = 2.0 / n as f64;
    let mut s = seed;
    let (mut pts, mut face) = (Vec::new(), Vec::new());
    // Faces: one jittered sample per grid cell; with edge samples the jitter keeps
    // `MARGIN` cells (default 0.25) away from the cell border (no near-duplicates of
    // edge samples; 0.5 = the regular grid of cell centres).
    let margin = if edges {
        std::env::var("MARGIN")
            .ok()
            .and_then(|m| m.parse().ok())
            .unwrap_or(0.25f64)
            .clamp(0.0, 0.5)
    } else {
        0.0
    };
    for f in 0..6u8 {
        let (axis, sign) = ((f / 2) as usize, if f % 2 == 0 { -1.0 } else { 1.0 });
        for i in 0..n {
            for j in 0..n {
                let u = -1.0 + step * (i as f64 + margin + (1.0 - 2.0 * margin) * rnd(&mut s));
                let v = -1.0 + step * (j as f64 + margin + (1.0 - 2.0 * margin) * rnd(&mut s));
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                pts.push(DVec3::from_array(p));
                face.push(Some(f));
            }
        }
    }
    if edges {
        for axis in 0..3 {
            for (sa, sb) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                for k in 1..n * dense {
                    let mut p = [0.0; 3];
                    p[axis] = -1.0 + step / dense as f64 * k as f64;
                    p[(axis + 1) % 3] = sa;
                    p[(axis + 2) % 3] = sb;
                    pts.push(DVec3::from_array(p));
                    face.push(None);
                }
            }
        }
        for c in 0..8 {
            let b = |k: u32| if c >> k & 1 == 1 { 1.0 } else { -1.0 };
            pts.push(DVec3::new(b(0), b(1), b(2)));
            face.push(None);
        }
    }
    (pts, face)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let h: f64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(0.06);
    let edges = std::env::var("EDGES").map_or(true, |v| v != "0");
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let mut sets: Vec<String> = args.iter().skip(1).cloned().collect();
    if sets.is_empty() {
        sets = vec![
            "{}".into(),
            r#"{"nvc": "generic"}"#.into(),
            r#"{"nvc": "flatness"}"#.into(),
        ];
    }
    let dense: usize = std::env::var("EDGE_DENSE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1usize)
        .clamp(1, 16);
    let (pts, face) = box_points(h, edges, dense, seed);
    // Ground-truth edge segments: consecutive edge samples along each box edge (the
    // samples are generated in order; corners close the ends).
    let on_edge: Vec<usize> = (0..pts.len()).filter(|&i| face[i].is_none()).collect();
    let mut segs: Vec<(u32, u32)> = Vec::new();
    if edges {
        let idx: HashMap<[i64; 3], u32> = on_edge
            .iter()
            .map(|&i| ((pts[i] * 1e6).round().as_i64vec3().to_array(), i as u32))
            .collect();
        let n = (2.0 / h).round().max(2.0) as i64;
        let step = 2.0 / (n * dense as i64) as f64;
        for &i in &on_edge {
            for axis in 0..3 {
                let mut q = pts[i];
                q[axis] += step;
                if let Some(&j) = idx.get(&(q * 1e6).round().as_i64vec3().to_array()) {
                    // Both on the same box edge: the other two coordinates are ±1.
                    let same = (0..3)
                        .filter(|&a| a != axis)
                        .all(|a| pts[i][a].abs() == 1.0);
                    if same {
                        segs.push((i as u32, j));
                    }
                }
            }
        }
    }
    println!(
        "box h = {h}, {} points ({} on edges/corners), {} edge segments",
        pts.len(),
        on_edge.len(),
        segs.len()
    );
    let cloud = PointCloud::new(pts.clone()).expect("finite");
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
        let faces = r.mesh.faces();
        let mut edge_faces: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                edge_faces.entry((a.min(b), a.max(b))).or_default().push(fi);
            }
        }
        let normal = |fi: usize| {
            let [a, b, c] = faces[fi].map(|x| pts[x as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        };
        let (mut found, mut dsum, mut dn) = (0usize, 0.0, 0usize);
        for &(a, b) in &segs {
            if let Some(fs) = edge_faces.get(&(a.min(b), a.max(b))) {
                found += 1;
                if fs.len() == 2 {
                    // Oriented output: the unsigned normal deviation is the dihedral.
                    let d = normal(fs[0]).dot(normal(fs[1])).clamp(-1.0, 1.0).acos();
                    dsum += d.to_degrees();
                    dn += 1;
                }
            }
        }
        let bevel = faces
            .iter()
            .filter(|f| {
                let fs: HashSet<u8> = f.iter().filter_map(|&x| face[x as usize]).collect();
                fs.len() >= 2
            })
            .count();
        // Vertices on a hole (boundary edge) or unreferenced, by where they are: on an
        // edge, within 2h of an edge, farther.
        let mut open = vec![true; pts.len()];
        for f in faces {
            for &x in f {
                open[x as usize] = false;
            }
        }
        for (&(a, b), fs) in &edge_faces {
            if fs.len() == 1 {
                open[a as usize] = true;
                open[b as usize] = true;
            }
        }
        let near = |p: DVec3| {
            let mut c = [p.x.abs(), p.y.abs(), p.z.abs()];
            c.sort_by(f64::total_cmp);
            // Distance to the nearest box edge ~ distance of the 2nd largest to 1.
            1.0 - c[1] < 2.0 * h
        };
        let (mut o_edge, mut o_near, mut o_far) = (0, 0, 0);
        for i in (0..pts.len()).filter(|&i| open[i]) {
            if face[i].is_none() {
                o_edge += 1;
            } else if near(pts[i]) {
                o_near += 1;
            } else {
                o_far += 1;
            }
        }
        println!("{set:50} open vertices: on edge {o_edge}, within 2h {o_near}, farther {o_far}");
        println!(
            "{set:50} matching {:7.3} loops {:3} nme {} edge_recovery {:.4} dihedral_mean {:6.2} bevel_faces {} nvc_flat_points {}",
            num("matching"),
            num("boundary_loops"),
            num("non_manifold_edges"),
            if segs.is_empty() {
                f64::NAN
            } else {
                found as f64 / segs.len() as f64
            },
            if dn > 0 { dsum / dn as f64 } else { f64::NAN },
            bevel,
            num("nvc_flat_points"),
        );
    }
}
