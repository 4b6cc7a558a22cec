//! Inside-out regions (IMPL-CHOICE I19, not in the paper; issue 20; `inside_out_min_faces`).
//!
//! Growth can turn over at a crease: the faces stay consistently wound, but a whole
//! sheet behind the turn (on the real fandisk the bottom face, on mechpart a box side)
//! is meshed with its normals pointing into the solid. Where that sheet meets the
//! rightly grown mesh again the fronts cannot glue, so the run ends with a long open
//! seam or a fold along it, often with a false handle. Winding cannot show such a
//! region (it agrees with its neighbours), but the ray parity can: a ray leaving a face
//! on its normal side crosses the surface an even number of times when that side is
//! the outside. Each face votes with one ray, and a face against its piece's majority
//! is confirmed with five; the confirmed faces, in edge-connected regions of at least
//! `min_faces`, are removed with the faces touching them, their points become Free,
//! and the growth resumes from the new border (the same growth, from rightly wound
//! fronts). The result is kept only when it leaves fewer open boundary edges.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::TriMesh;
use reconbench_geom::method::{MethodError, RunCtx};
use reconbench_geom::spatial::MeshBvh;

use super::complete::VertexFaces;
use super::cross::plane_basis;
use super::peel::PeelMesh;
use super::regrow::{Regrow, regrow_without};
use crate::hc_it::cluster::UnionFind;

/// Rays per face; a face is inside-out when most of them cross the surface an odd number
/// of times.
const RAYS: usize = 5;

/// Crossings after which a ray is given up (a ray grazing a fold can hit it repeatedly).
const MAX_HITS: usize = 64;

/// Removes the inside-out regions of at least `min_faces` faces and regrows their area
/// (see the module doc). Returns the number of faces removed (0 when nothing changed).
pub(super) fn regrow_inside_out(
    g: &Regrow,
    mesh: PeelMesh,
    min_faces: usize,
    ctx: &RunCtx,
) -> Result<usize, MethodError> {
    if min_faces == 0 || mesh.loops.is_empty() || mesh.tris.len() < 2 * min_faces {
        return Ok(0);
    }
    let n = g.pts.len();
    let against = against_majority(g.pts, mesh.tris, g.cfg.r);
    let region = large_regions(mesh.tris, &against, min_faces, n);
    if !region.iter().any(|&r| r) {
        return Ok(0);
    }
    // The region and every face touching it (the fold along the seam).
    let mut touched = vec![false; n];
    for (t, _) in mesh.tris.iter().zip(&region).filter(|(_, r)| **r) {
        for &v in t {
            touched[v as usize] = true;
        }
    }
    regrow_without(g, mesh, &touched, ctx)
}

/// Per face: whether its ray-parity side (see [`outward`]) differs from the majority of
/// the decided faces of its piece (component by shared vertices). One ray per face
/// decides the majorities and the candidates; a candidate is confirmed with all
/// [`RAYS`] rays (most faces cost one ray).
fn against_majority(pts: &[DVec3], tris: &[[u32; 3]], r: f64) -> Vec<bool> {
    let Ok(bvh) = TriMesh::new(pts.to_vec(), tris.to_vec()).and_then(|m| MeshBvh::new(&m)) else {
        return vec![false; tris.len()];
    };
    let eps = 1e-5 * r;
    let corners = |t: &[u32; 3]| t.map(|v| pts[v as usize]);
    let side: Vec<Option<bool>> = tris
        .par_iter()
        .map(|t| outward(&bvh, corners(t), eps, 1))
        .collect();
    let mut uf = UnionFind::new(pts.len());
    for t in tris {
        uf.union(t[0], t[1]);
        uf.union(t[0], t[2]);
    }
    // Per piece root: decided faces facing out minus those facing in.
    let mut balance = vec![0i64; pts.len()];
    for (t, s) in tris.iter().zip(&side) {
        if let Some(out) = s {
            balance[uf.find(t[0]) as usize] += if *out { 1 } else { -1 };
        }
    }
    let majority: Vec<bool> = tris
        .iter()
        .map(|t| balance[uf.find(t[0]) as usize] >= 0)
        .collect();
    tris.par_iter()
        .zip(&side)
        .zip(&majority)
        .map(|((t, s), &maj)| {
            s.is_some_and(|out| out != maj)
                && outward(&bvh, corners(t), eps, RAYS).is_some_and(|out| out != maj)
        })
        .collect()
}

/// Whether the normal side of triangle `p` is outside the mesh: most of the first
/// `rays` of [`RAYS`] rays from its centroid (along the normal, then tilted 30 degrees
/// from it) cross the mesh an even number of times. `None` for a degenerate triangle or
/// when a ray is given up.
fn outward(bvh: &MeshBvh, p: [DVec3; 3], eps: f64, rays: usize) -> Option<bool> {
    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
    if n == DVec3::ZERO {
        return None;
    }
    let c = (p[0] + p[1] + p[2]) / 3.0;
    let (u, v) = plane_basis(n);
    let tilt = 0.577; // tan 30 degrees
    let dirs = [n, n + tilt * u, n - tilt * u, n + tilt * v, n - tilt * v];
    let mut odd = 0;
    for d in &dirs[..rays.min(RAYS)] {
        let d = d.normalize();
        let mut o = c + eps * d;
        let mut hits = 0;
        loop {
            match bvh.ray_cast(o, d, f64::INFINITY) {
                Ok(Some(h)) => {
                    hits += 1;
                    if hits > MAX_HITS {
                        return None;
                    }
                    o = h.point + eps * d;
                }
                Ok(None) => break,
                Err(_) => return None,
            }
        }
        odd += hits % 2;
    }
    Some(2 * odd < rays.min(RAYS))
}

/// Faces flagged in `flag` that belong to an edge-connected region of flagged faces of
/// at least `min_faces`.
fn large_regions(tris: &[[u32; 3]], flag: &[bool], min_faces: usize, n: usize) -> Vec<bool> {
    let vf = VertexFaces::new(n, tris);
    let mut uf = UnionFind::new(tris.len());
    for (f, t) in tris.iter().enumerate().filter(|(f, _)| flag[*f]) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            for &g in vf.of(a) {
                if g as usize != f && flag[g as usize] && tris[g as usize].contains(&b) {
                    uf.union(f as u32, g);
                }
            }
        }
    }
    (0..tris.len())
        .map(|f| {
            let root = uf.find(f as u32);
            flag[f] && uf.size(root) as usize >= min_faces
        })
        .collect()
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::priority_front::regrow::simple_cut;

    /// A closed unit sphere: `m` rings of `2 m` vertices between two poles, wound
    /// outward.
    pub(in crate::priority_front) fn sphere(m: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let k = 2 * m;
        let mut pts = vec![DVec3::Z, -DVec3::Z];
        for i in 0..m {
            let th = std::f64::consts::PI * (i as f64 + 1.0) / (m as f64 + 1.0);
            for j in 0..k {
                let ph = std::f64::consts::TAU * j as f64 / k as f64;
                pts.push(DVec3::new(
                    th.sin() * ph.cos(),
                    th.sin() * ph.sin(),
                    th.cos(),
                ));
            }
        }
        let at = |i: u32, j: u32| 2 + i * k + j % k;
        let mut tris = Vec::new();
        for j in 0..k {
            tris.push([0, at(0, j), at(0, j + 1)]);
            tris.push([1, at(m - 1, j + 1), at(m - 1, j)]);
            for i in 0..m - 1 {
                tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        (pts, tris)
    }

    /// The sphere is wound outward (positive volume), so the fixture is what it says.
    #[test]
    fn sphere_fixture_is_closed_and_outward() {
        let (pts, tris) = sphere(8);
        let vol: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| pts[v as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(vol > 3.5, "{vol}");
        let none = vec![false; pts.len()];
        assert!(simple_cut(&tris, &none, 0, pts.len()).unwrap().1.is_empty());
    }

    /// Ray parity flags exactly the faces wound into the solid: none on the outward
    /// sphere; on the sphere with its top cap reversed, the cap and nothing else, even
    /// when the cap is the majority of its own patch of faces.
    #[test]
    fn ray_parity_flags_exactly_the_reversed_cap() {
        let (pts, mut tris) = sphere(10);
        assert!(!against_majority(&pts, &tris, 0.1).iter().any(|&a| a));
        let cap: Vec<bool> = tris
            .iter()
            .map(|t| t.iter().map(|&v| pts[v as usize].z).sum::<f64>() / 3.0 > 0.5)
            .collect();
        for (t, &c) in tris.iter_mut().zip(&cap) {
            if c {
                t.swap(1, 2);
            }
        }
        let n_cap = cap.iter().filter(|&&c| c).count();
        assert!(n_cap > 20 && 2 * n_cap < tris.len(), "{n_cap}");
        assert_eq!(against_majority(&pts, &tris, 0.1), cap);
        // Regions: the cap is one edge-connected region.
        assert_eq!(large_regions(&tris, &cap, n_cap, pts.len()), cap);
        assert!(
            !large_regions(&tris, &cap, n_cap + 1, pts.len())
                .iter()
                .any(|&r| r)
        );
    }
}
