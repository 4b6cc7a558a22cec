//! The per-vertex normal fits shared by `ufm-mesh` (Algorithm B) and NVC (Algorithm C):
//! the weighted facet-normal average of an umbrella (Eq. 4.5/4.6) and the weighted plane
//! fit over the points of the matched triangles at a vertex (Eq. 4.7).

use glam::DVec3;
use reconbench_normals::plane_fit::fit_plane_normal;

use super::complex::Complex;

/// WPF of Eq. 4.7 about `pts[c]` over the points `q` (ASSUMPTION B-08:
/// `σ² = d_max² / 3`, `d_max` the distance to the farthest point of `q`).
pub(super) fn wpf(pts: &[DVec3], q: &[u32], c: u32) -> DVec3 {
    let pc = pts[c as usize];
    let d2 = q
        .iter()
        .map(|&j| pts[j as usize].distance_squared(pc))
        .fold(0.0, f64::max);
    if q.len() < 3 || d2 <= 0.0 {
        return DVec3::ZERO;
    }
    let s2 = d2 / 3.0;
    fit_plane_normal(pts, q, |x| (-x.distance_squared(pc) / s2).exp())
}

/// Eq. 4.5/4.6: the weighted average of the umbrella facet normals of the point at
/// `pv` with ring `ring` in cyclic order (facet `j` = `(v, ring[j], ring[j+1])`),
/// weights `w_j = mult(j) · θ_j` (`θ_j` the facet's angle at `v`; Algorithm B:
/// `mult = M_f`, Algorithm C's flat points: `M_f + 1` on shadow facets). `None` when the
/// weights vanish or the average cancels (ASSUMPTION B-03).
pub fn facet_average(
    pts: &[DVec3],
    pv: DVec3,
    ring: &[u32],
    mult: impl Fn(usize) -> f64,
) -> Option<DVec3> {
    let k = ring.len();
    let mut sum = DVec3::ZERO;
    let mut wsum = 0.0;
    for j in 0..k {
        let a = pts[ring[j] as usize] - pv;
        let b = pts[ring[(j + 1) % k] as usize] - pv;
        let nrm = a.cross(b).normalize_or_zero();
        let cos = a.dot(b) / (a.length() * b.length());
        let theta = cos.clamp(-1.0, 1.0).acos();
        // Eq. 4.6: w_i = M_{f_i} θ_i.
        let w = mult(j) * theta;
        sum += w * nrm;
        wsum += w;
    }
    if wsum > 0.0 {
        let nn = sum / wsum;
        if nn.length() >= 1e-12 {
            return Some(nn.normalize());
        }
    }
    None
}

/// Lines 11-12 of Algorithm B (ASSUMPTION B-02): the WPF (Eq. 4.7) about vertex `v`
/// over `Q = {v} ∪` the points of `DT(U)_v` (triangles at `v` with `M_t >= 1`), or
/// `{v} ∪ ring` when that has fewer than 3 points; `q` is scratch. Zero when degenerate.
pub fn dtu_plane_fit(cx: &Complex, m: &[u8], v: usize, ring: &[u32], q: &mut Vec<u32>) -> DVec3 {
    let facets = cx.facets();
    q.clear();
    q.push(v as u32);
    for &f in cx.row(v) {
        if m[f as usize] >= 1 {
            q.extend_from_slice(&facets[f as usize].v);
        }
    }
    q.sort_unstable();
    q.dedup();
    if q.len() < 3 {
        q.clear();
        q.push(v as u32);
        q.extend_from_slice(ring);
    }
    wpf(cx.dt.vertices(), q, v as u32)
}
