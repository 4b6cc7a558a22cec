//! A box `[-1, 1]^3` sampled like the thesis's CAD meshes (chapter 5): jittered-grid
//! samples on the six faces plus samples exactly on the 12 edges and the 8 corners,
//! and the measures of whether a mesh keeps the box's edges.

use std::collections::{HashMap, HashSet};

use glam::DVec3;

/// The sampled box.
#[derive(Debug)]
pub struct BoxSamples {
    /// Points.
    pub pts: Vec<DVec3>,
    /// Per point: the face id (0..6), or `None` for edge and corner samples.
    pub face: Vec<Option<u8>>,
    /// Ground-truth edge segments: consecutive samples along each box edge.
    pub segs: Vec<(u32, u32)>,
}

/// splitmix64 in [0, 1).
fn rnd(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Face samples: one per cell of an `n × n` grid per face (`n = round(2 / h)`),
/// jittered inside the cell but `margin` cells (in [0, 0.5]) away from its border;
/// with `edges`, also `n · dense - 1` samples on every edge (spacing `h / dense`) and
/// the corners. Deterministic for a given `seed`.
pub fn box_samples(h: f64, edges: bool, dense: usize, margin: f64, seed: u64) -> BoxSamples {
    let n = (2.0 / h).round().clamp(2.0, 1000.0) as usize;
    let dense = dense.clamp(1, 16);
    let margin = if edges { margin.clamp(0.0, 0.5) } else { 0.0 };
    let step = 2.0 / n as f64;
    let mut s = seed;
    let (mut pts, mut face, mut segs) = (Vec::new(), Vec::new(), Vec::new());
    for f in 0..6u8 {
        let (axis, sign) = ((f / 2) as usize, if f % 2 == 0 { -1.0 } else { 1.0 });
        for i in 0..n {
            for j in 0..n {
                let mut jit = |k: usize| {
                    -1.0 + step * (k as f64 + margin + (1.0 - 2.0 * margin) * rnd(&mut s))
                };
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[(axis + 1) % 3] = jit(i);
                p[(axis + 2) % 3] = jit(j);
                pts.push(DVec3::from_array(p));
                face.push(Some(f));
            }
        }
    }
    if edges {
        let corner0 = pts.len() as u32;
        for c in 0..8u32 {
            let b = |k: u32| if c >> k & 1 == 1 { 1.0 } else { -1.0 };
            pts.push(DVec3::new(b(0), b(1), b(2)));
            face.push(None);
        }
        let corner =
            |p: [f64; 3]| corner0 + (0..3).map(|k| ((p[k] > 0.0) as u32) << k).sum::<u32>();
        let m = n * dense;
        for axis in 0..3 {
            for (sa, sb) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                let at = |t: f64| {
                    let mut p = [0.0; 3];
                    p[axis] = t;
                    p[(axis + 1) % 3] = sa;
                    p[(axis + 2) % 3] = sb;
                    p
                };
                let mut prev = corner(at(-1.0));
                for k in 1..m {
                    let i = pts.len() as u32;
                    pts.push(DVec3::from_array(at(-1.0 + 2.0 * k as f64 / m as f64)));
                    face.push(None);
                    segs.push((prev, i));
                    prev = i;
                }
                segs.push((prev, corner(at(1.0))));
            }
        }
    }
    BoxSamples { pts, face, segs }
}

/// Whether a mesh keeps the box's edges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeStats {
    /// Share of the ground-truth edge segments that are mesh edges (NaN without).
    pub recovery: f64,
    /// Faces with corners on two different box faces, not counting edge samples: a
    /// face that cuts an edge off (0 for a mesh that keeps every sampled edge).
    pub bevel_faces: usize,
    /// Points on a hole (boundary edge) or unreferenced: on an edge or corner, within
    /// `2h` of an edge, farther.
    pub open: [usize; 3],
}

/// [`EdgeStats`] of the triangles `faces` (indices into `b.pts`).
pub fn edge_stats(b: &BoxSamples, faces: &[[u32; 3]], h: f64) -> EdgeStats {
    let mut edge_faces: HashMap<(u32, u32), u32> = HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, c) = (f[k], f[(k + 1) % 3]);
            *edge_faces.entry((a.min(c), a.max(c))).or_default() += 1;
        }
    }
    let found = b
        .segs
        .iter()
        .filter(|&&(a, c)| edge_faces.contains_key(&(a.min(c), a.max(c))))
        .count();
    let bevel_faces = faces
        .iter()
        .filter(|f| {
            let fs: HashSet<u8> = f.iter().filter_map(|&x| b.face[x as usize]).collect();
            fs.len() >= 2
        })
        .count();
    let mut open = vec![true; b.pts.len()];
    for f in faces {
        for &x in f {
            open[x as usize] = false;
        }
    }
    for (&(a, c), &n) in &edge_faces {
        if n == 1 {
            open[a as usize] = true;
            open[c as usize] = true;
        }
    }
    let mut counts = [0usize; 3];
    for i in (0..b.pts.len()).filter(|&i| open[i]) {
        let p = b.pts[i];
        let mut c = [p.x.abs(), p.y.abs(), p.z.abs()];
        c.sort_by(f64::total_cmp);
        // The distance to the nearest box edge is about 1 - (second largest |coord|).
        let k = if b.face[i].is_none() {
            0
        } else if 1.0 - c[1] < 2.0 * h {
            1
        } else {
            2
        };
        counts[k] += 1;
    }
    EdgeStats {
        recovery: if b.segs.is_empty() {
            f64::NAN
        } else {
            found as f64 / b.segs.len() as f64
        },
        bevel_faces,
        open: counts,
    }
}
