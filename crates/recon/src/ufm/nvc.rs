//! Algorithm C of Ma's thesis, chapter 5 (spec 000 §1.3): Normal Vector Cone (NVC)
//! filtering. Before an update, every point whose umbrella is not fully matched gets a
//! *nominal* normal (Algorithm B on the current state) and a cone around it; the
//! unmatched Delaunay triangles at the point whose normal lies inside the cone and whose
//! other two vertices lie within the limitation range (umbrella rings) form `NVC_v`.
//! The update then keeps `NVC_v` triangles in preference to the other unmatched ones
//! (the new top level of the four-level key, ASSUMPTION C-05 in `engine.rs`), which
//! makes umbrellas next to a sharp edge lie flat on one side of it.
//!
//! Output: one flag per CSR slot (like the umbrella membership), written per vertex
//! into its own slot range, so the parallel pass is deterministic.

use glam::DVec3;
use rayon::prelude::*;

use super::complex::{Complex, blocks};
use super::facet_fit::{dtu_plane_fit, facet_average};
use super::geometry::fold_angles;
use super::params::{Nvc, UfmParams};
use super::umbrella::LinkGraph;

/// The NVC settings of one run, from [`UfmParams`] (angles in radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NvcCfg {
    /// Which cones are used (never `Off` here).
    pub mode: Nvc,
    /// Generic cone angle `α_gen` (spec: π/4).
    pub generic: f64,
    /// `α_flat = flat_factor · θ̄` (spec: 2).
    pub flat_factor: f64,
    /// Limitation range `R` in umbrella rings (1 or 2; spec: 2).
    pub range: u32,
}

impl NvcCfg {
    /// The settings of `p`, `None` when NVC filtering is off.
    pub fn from_params(p: &UfmParams) -> Option<Self> {
        (p.nvc != Nvc::Off).then(|| Self {
            mode: p.nvc,
            generic: p.nvc_angle.to_radians(),
            flat_factor: p.nvc_flat_factor,
            range: p.nvc_range,
        })
    }

    /// The flatness-sensitive cone angle for a mean dihedral angle `theta_bar` of the
    /// matched mesh (`None` = no matched edge pair yet).
    pub fn alpha_flat(&self, theta_bar: Option<f64>) -> Option<f64> {
        // ASSUMPTION C-02: α_flat = min(2θ̄, α_gen), the "smaller" cone; when E_m is
        // empty no point is flat in this iteration.
        theta_bar.map(|t| (self.flat_factor * t).min(self.generic))
    }
}

/// Counters of the NVC passes (summed over iterations).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NvcStats {
    /// Points that got a cone (`G_v = 0` with a valid umbrella and nominal normal; with
    /// `flat-only` only the flat ones).
    pub filtered: u64,
    /// Of those, points with a potentially flat umbrella (flatness-sensitive cone).
    pub flat: u64,
    /// Triangles put in some `NVC_v` (slot count).
    pub members: u64,
    /// `α_flat` of the last pass, radians (NaN when undefined or not computed).
    pub last_alpha_flat: f64,
}

impl std::ops::Add for NvcStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            filtered: self.filtered + o.filtered,
            flat: self.flat + o.flat,
            members: self.members + o.members,
            last_alpha_flat: o.last_alpha_flat,
        }
    }
}

/// Dihedral (normal-deviation) angle of Eq. 5.1 between the triangles `(a, b, c)` and
/// `(a, b, d)` sharing the edge `ab`. ASSUMPTION C-01: the normals are oriented
/// consistently (the shared edge traversed in opposite directions), so coplanar
/// neighbours on opposite sides of the edge give 0 and a right-angle edge π/2.
/// Degenerate triangles give 0 (no evidence of a bend).
pub fn dihedral(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    // ASSUMPTION C-01: ab traversed as a→b in the first triangle, b→a in the second.
    let n1 = (b - a).cross(c - a).normalize_or_zero();
    let n2 = (d - a).cross(b - a).normalize_or_zero();
    if n1 == DVec3::ZERO || n2 == DVec3::ZERO {
        return 0.0;
    }
    n1.dot(n2).clamp(-1.0, 1.0).acos()
}

/// Cone test of §1.3.3: the acute angle between the normal of triangle `abc` and the
/// unit nominal normal `nbar` is below the cone angle whose cosine is `cos_alpha`
/// (`acos(|n·N̄|) < α ⇔ |n·N̄| > cos α` for α in [0, π/2]). The sign of `nbar` is
/// irrelevant; a degenerate triangle is never inside.
pub fn in_cone(a: DVec3, b: DVec3, c: DVec3, nbar: DVec3, cos_alpha: f64) -> bool {
    let n = (b - a).cross(c - a).normalize_or_zero();
    n != DVec3::ZERO && n.dot(nbar).abs() > cos_alpha
}

/// The flatness test of §1.3.3 on an umbrella in cyclic order: `shadow[j]` marks the
/// shadow facets, `folds[j]` is the dihedral angle at the rib between facets `j` and
/// `j + 1` (mod k, [`fold_angles`]). Flat iff every pair of consecutive shadow facets
/// bends by at most `alpha`; ASSUMPTION C-03: at least one such pair is required (an
/// isolated shadow facet gives no evidence).
pub fn flat_umbrella(shadow: &[bool], folds: &[f64], alpha: f64) -> bool {
    let k = shadow.len();
    if k < 2 || folds.len() != k {
        return false;
    }
    let mut pairs = 0usize;
    for j in 0..k {
        if shadow[j] && shadow[(j + 1) % k] {
            pairs += 1;
            if folds[j] > alpha {
                return false;
            }
        }
    }
    pairs > 0
}

/// Mean dihedral angle `θ̄` over `E_m`, the edges shared by exactly two matched facets
/// (`M_f = 3`), or `None` when `E_m` is empty (ASSUMPTION C-02). Per vertex `a` in
/// parallel, the edges `ab` with `b > a` (each edge once); the per-vertex partial sums
/// are added sequentially in vertex order, so the result does not depend on the thread
/// count.
pub fn mean_dihedral(cx: &Complex, m: &[u8]) -> Option<f64> {
    let facets = cx.facets();
    let pts = cx.dt.vertices();
    let parts: Vec<(f64, u32)> = (0..cx.n_vertices())
        .into_par_iter()
        .with_min_len(256)
        .map_init(Vec::new, |mf: &mut Vec<u32>, a| {
            mf.clear();
            mf.extend(cx.row(a).iter().copied().filter(|&f| m[f as usize] == 3));
            let (mut sum, mut cnt) = (0.0, 0u32);
            for (x, &f) in mf.iter().enumerate() {
                for &b in &facets[f as usize].v {
                    if (b as usize) <= a {
                        continue;
                    }
                    // Matched facets at a containing b: f and the later ones.
                    let mut other = None;
                    let mut n = 1;
                    for (y, &g) in mf.iter().enumerate() {
                        if y != x && facets[g as usize].v.contains(&b) {
                            n += 1;
                            if y > x {
                                other = Some(g);
                            }
                        }
                    }
                    // Exactly two facets on the edge; count the pair at its first one.
                    if let (2, Some(g)) = (n, other) {
                        let third = |t: [u32; 3]| {
                            t.into_iter()
                                .find(|&w| w as usize != a && w != b)
                                .unwrap_or(b)
                        };
                        let c = third(facets[f as usize].v);
                        let d = third(facets[g as usize].v);
                        sum += dihedral(pts[a], pts[b as usize], pts[c as usize], pts[d as usize]);
                        cnt += 1;
                    }
                }
            }
            (sum, cnt)
        })
        .collect();
    let (sum, cnt) = parts
        .iter()
        .fold((0.0, 0u64), |(s, c), &(x, n)| (s + x, c + n as u64));
    (cnt > 0).then(|| sum / cnt as f64)
}

/// Per-thread scratch of the NVC pass (no allocation per vertex once warm).
#[derive(Debug, Default)]
struct NvcScratch {
    g: LinkGraph,
    fl: Vec<u32>,
    ring: Vec<u32>,
    folds: Vec<f64>,
    shadow: Vec<bool>,
    q: Vec<u32>,
    range: Vec<u32>,
}

/// `NVC_v` of every point with `G_v = 0` into `out` (one flag per CSR slot of `DT_v`;
/// all other slots false), from the state at the start of the iteration (membership
/// `inu`, matching indices `m`, grades `grade`). Returns the counters of this pass.
pub fn nvc_flags(
    cx: &Complex,
    inu: &[bool],
    m: &[u8],
    grade: &[bool],
    cfg: &NvcCfg,
    out: &mut [bool],
) -> NvcStats {
    let alpha_flat = match cfg.mode {
        Nvc::Flatness | Nvc::FlatOnly => cfg.alpha_flat(mean_dihedral(cx, m)),
        _ => None,
    };
    let cos_gen = cfg.generic.cos();
    let mut stats = blocks(cx, out, 256)
        .into_par_iter()
        .map_init(NvcScratch::default, |s, (v0, v1, chunk)| {
            let mut st = NvcStats::default();
            let start = cx.off[v0] as usize;
            for v in v0..v1 {
                let a = cx.off[v] as usize - start;
                let b = cx.off[v + 1] as usize - start;
                let o = &mut chunk[a..b];
                o.fill(false);
                // ASSUMPTION C-07: fully matched points get no filter.
                if grade[v] {
                    continue;
                }
                vertex_nvc(
                    cx, inu, m, grade, cfg, alpha_flat, cos_gen, v, s, o, &mut st,
                );
            }
            st
        })
        .reduce(NvcStats::default, |x, y| x + y);
    stats.last_alpha_flat = alpha_flat.unwrap_or(f64::NAN);
    stats
}

/// `NVC_v` of one point into `out` (its slots).
#[allow(clippy::too_many_arguments)]
fn vertex_nvc(
    cx: &Complex,
    inu: &[bool],
    m: &[u8],
    grade: &[bool],
    cfg: &NvcCfg,
    alpha_flat: Option<f64>,
    cos_gen: f64,
    v: usize,
    s: &mut NvcScratch,
    out: &mut [bool],
    st: &mut NvcStats,
) {
    let pts = cx.dt.vertices();
    let facets = cx.facets();
    let row = cx.row(v);
    let base = cx.off[v] as usize;
    cx.prepare(v, &mut s.g);
    s.g.cycle(|i| inu[base + i], &mut s.fl, &mut s.ring);
    let k = s.fl.len();
    if k < 3 {
        // No valid umbrella (build failure): nothing to filter around.
        return;
    }
    let mf = |j: usize| m[row[s.fl[j] as usize] as usize];
    // Shadow facets S_v (only for partially matched points, flatness mode): matched
    // facets of U_v with another corner w whose umbrella is fully matched.
    s.shadow.clear();
    let mut flat = false;
    if let Some(af) = alpha_flat {
        let partially = (0..k).any(|j| mf(j) == 3);
        if partially {
            s.shadow.extend((0..k).map(|j| {
                mf(j) == 3 && (grade[s.ring[j] as usize] || grade[s.ring[(j + 1) % k] as usize])
            }));
            // ASSUMPTION C-01: the fold angles use normals oriented by the umbrella's
            // cyclic order, so consecutive coplanar facets bend by 0.
            fold_angles(pts, v as u32, &s.ring, &mut s.folds);
            flat = flat_umbrella(&s.shadow, &s.folds, af);
        }
    }
    // Ablation `flat-only`: non-flat points get no filter.
    if cfg.mode == Nvc::FlatOnly && !flat {
        return;
    }
    // Nominal normal N̄_v (Algorithm B on the current state).
    let pv = pts[v];
    let mut nbar = None;
    if flat {
        // ASSUMPTION C-04: flat points always use the facet average, with the weights
        // of their shadow facets incremented by one: w_i = (M_{f_i} + 1) θ_i.
        let shadow = &s.shadow;
        nbar = facet_average(pts, pv, &s.ring, |j| mf(j) as f64 + shadow[j] as u8 as f64);
    }
    if nbar.is_none() {
        // Algorithm B's rule: |U(f̄)_v| >= 3 -> facet average (w = M_f θ); else, or
        // if it cancels (B-03), the WPF over DT(U)_v.
        let ubar = (0..k).filter(|&j| mf(j) == 3).count();
        if ubar >= 3 {
            nbar = facet_average(pts, pv, &s.ring, |j| mf(j) as f64);
        }
        if nbar.is_none() {
            let n = dtu_plane_fit(cx, m, v, &s.ring, &mut s.q);
            nbar = (n != DVec3::ZERO).then_some(n);
        }
    }
    // Without a nominal normal (degenerate neighbourhood) the point gets no filter.
    let Some(nbar) = nbar else {
        return;
    };
    st.filtered += 1;
    st.flat += flat as u64;
    let cos_alpha = match (flat, alpha_flat) {
        (true, Some(af)) => af.cos(),
        _ => cos_gen,
    };
    // Limitation range: R = 1 -> Ring1(v); R = 2 -> Ring2(v), the vertices of the
    // umbrellas of the ring points (current state, synchronous).
    s.range.clear();
    s.range.extend_from_slice(&s.ring);
    if cfg.range >= 2 {
        for &p in &s.ring {
            let pb = cx.off[p as usize] as usize;
            for (i, &f) in cx.row(p as usize).iter().enumerate() {
                if inu[pb + i] {
                    s.range.extend_from_slice(&facets[f as usize].v);
                }
            }
        }
    }
    s.range.sort_unstable();
    s.range.dedup();
    let inr = |x: u32| x as usize == v || s.range.binary_search(&x).is_ok();
    for (i, &f) in row.iter().enumerate() {
        if m[f as usize] >= 3 {
            continue;
        }
        let t = facets[f as usize].v;
        if !t.iter().all(|&x| inr(x)) {
            continue;
        }
        let [a, b, c] = t.map(|x| pts[x as usize]);
        if in_cone(a, b, c, nbar, cos_alpha) {
            out[i] = true;
            st.members += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    #[test]
    fn dihedral_is_zero_when_coplanar_and_right_across_a_box_edge() {
        let a = DVec3::ZERO;
        let b = DVec3::X;
        // Coplanar, apexes on opposite sides of ab.
        let t = dihedral(a, b, DVec3::Y, -DVec3::Y);
        assert!(t.abs() < 1e-12, "{t}");
        // Right-angle edge of a box: one face in z = 0, the other in y = 0.
        let t = dihedral(a, b, DVec3::Y, DVec3::Z);
        assert!((t - FRAC_PI_2).abs() < 1e-12, "{t}");
        // Folded onto itself (both apexes on the same side): π.
        let t = dihedral(a, b, DVec3::Y, DVec3::new(0.5, 1.0, 0.0));
        assert!((t - PI).abs() < 1e-9, "{t}");
        // Degenerate apex on the edge line.
        assert_eq!(dihedral(a, b, 2.0 * DVec3::X, DVec3::Y), 0.0);
    }

    #[test]
    fn cone_membership_uses_the_acute_angle() {
        let cos = FRAC_PI_4.cos();
        let (a, b) = (DVec3::ZERO, DVec3::X);
        // Triangle in z = 0: normal ±z, inside a cone around z and around -z.
        let c = DVec3::Y;
        assert!(in_cone(a, b, c, DVec3::Z, cos));
        assert!(in_cone(a, b, c, -DVec3::Z, cos));
        // Tilted by 30° about the x axis: inside the π/4 cone, outside a 20° cone.
        let t30 = 30f64.to_radians();
        let c30 = DVec3::new(0.0, t30.cos(), t30.sin());
        assert!(in_cone(a, b, c30, DVec3::Z, cos));
        assert!(!in_cone(a, b, c30, DVec3::Z, 20f64.to_radians().cos()));
        // Tilted by 60°: outside the π/4 cone (either sign of N̄).
        let t60 = 60f64.to_radians();
        let c60 = DVec3::new(0.0, t60.cos(), t60.sin());
        assert!(!in_cone(a, b, c60, DVec3::Z, cos));
        assert!(!in_cone(a, b, c60, -DVec3::Z, cos));
        // A vertical triangle is never inside a cone around z; degenerate never.
        assert!(!in_cone(a, b, DVec3::Z, DVec3::Z, cos));
        assert!(!in_cone(a, b, 3.0 * DVec3::X, DVec3::Z, -1.0));
    }

    #[test]
    fn flatness_needs_an_adjacent_shadow_pair_below_the_threshold() {
        let a = 0.2;
        // Facets 0, 1 shadow; the rib between them (folds[0]) bends 0.1.
        let mut folds = vec![0.1, 1.5, 1.5, 1.5];
        let shadow = [true, true, false, false];
        assert!(flat_umbrella(&shadow, &folds, a));
        // The same pair bending more than α: not flat (point B of the thesis).
        folds[0] = 0.3;
        assert!(!flat_umbrella(&shadow, &folds, a));
        // Non-shadow ribs do not matter; the wrap-around pair (3, 0) counts.
        let shadow = [true, false, false, true];
        let folds = [1.5, 1.5, 1.5, 0.05];
        assert!(flat_umbrella(&shadow, &folds, a));
        // ASSUMPTION C-03: isolated shadow facets are no evidence.
        assert!(!flat_umbrella(&[true, false, true, false], &[0.0; 4], a));
        assert!(!flat_umbrella(&[false; 4], &[0.0; 4], a));
        // Bad input (length mismatch) is not flat.
        assert!(!flat_umbrella(&[true, true], &[0.0], a));
    }

    #[test]
    fn alpha_flat_is_clamped_to_the_generic_cone() {
        let cfg = NvcCfg {
            mode: Nvc::Flatness,
            generic: FRAC_PI_4,
            flat_factor: 2.0,
            range: 2,
        };
        assert_eq!(cfg.alpha_flat(None), None);
        assert!((cfg.alpha_flat(Some(0.1)).unwrap() - 0.2).abs() < 1e-15);
        assert_eq!(cfg.alpha_flat(Some(1.0)), Some(FRAC_PI_4));
    }
}
