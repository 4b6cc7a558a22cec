//! Poles and the cocone test (Amenta, Choi, Dey & Leekha 2002, §2).
//!
//! The pole `p⁺` of a sample `p` is the farthest vertex of its Voronoi cell; `p⁺ − p`
//! approximates the surface normal at `p` up to sign. The cocone of `p` is the part of
//! its Voronoi cell whose directions from `p` make an angle of at least `π/2 − θ` with the
//! pole vector, a thickened tangent plane. A Delaunay triangle is a cocone triangle when
//! its dual Voronoi edge meets the cocones of all three of its vertices.

use glam::DVec3;
use rayon::prelude::*;
use reconbench_delaunay::{Delaunay, INFINITE, NO_TET};

/// Vertex indices of face `i` of a tetrahedron, oriented outward for a positively
/// oriented tetrahedron.
pub const OUT_FACE: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// The Voronoi vertices (tetrahedron circumcentres) and the pole vector of every sample.
#[derive(Debug, Clone)]
pub struct Poles {
    /// Circumcentre of every finite tetrahedron (non-finite for a flat one).
    pub centres: Vec<DVec3>,
    /// Circumradius of every finite tetrahedron.
    pub radii: Vec<f64>,
    /// Unit pole vector of every vertex (zero when it has no finite tetrahedron).
    pub pole: Vec<DVec3>,
    /// Whether the vertex lies on the convex hull (its Voronoi cell is unbounded).
    pub on_hull: Vec<bool>,
}

/// The vertex of tetrahedron `t` that is not in the sorted triple `f`.
pub fn apex(tv: [u32; 4], f: [u32; 3]) -> u32 {
    tv[0] ^ tv[1] ^ tv[2] ^ tv[3] ^ f[0] ^ f[1] ^ f[2]
}

/// Unit normal of the hull facet `f` (sorted triple) pointing away from `inner`.
pub fn outward_normal(pts: &[DVec3], f: [u32; 3], inner: u32) -> DVec3 {
    let [a, b, c] = f.map(|v| pts[v as usize]);
    let n = (b - a).cross(c - a);
    let n = if n.dot(pts[inner as usize] - a) > 0.0 {
        -n
    } else {
        n
    };
    n.normalize_or_zero()
}

impl Poles {
    /// Poles of every vertex of `dt`.
    ///
    /// For a hull vertex the pole lies at infinity; its direction is the average of the
    /// outward normals of the incident hull facets (ACDL §2).
    pub fn new(dt: &Delaunay) -> Self {
        let nt = dt.n_tets() as u32;
        let pts = dt.vertices();
        let (centres, radii): (Vec<DVec3>, Vec<f64>) = (0..nt)
            .into_par_iter()
            .map(|t| {
                let c = dt.circumcenter(t);
                (c, c.distance(pts[dt.tet_vertices(t)[0] as usize]))
            })
            .unzip();
        let nv = dt.n_vertices();
        let mut far = vec![-1.0f64; nv];
        let mut pole = vec![DVec3::ZERO; nv];
        for t in 0..nt {
            let c = centres[t as usize];
            if !c.is_finite() {
                continue;
            }
            for v in dt.tet_vertices(t) {
                let d = c - pts[v as usize];
                let d2 = d.length_squared();
                if d2 > far[v as usize] {
                    far[v as usize] = d2;
                    pole[v as usize] = d;
                }
            }
        }
        let mut on_hull = vec![false; nv];
        let mut hull_sum = vec![DVec3::ZERO; nv];
        for t in nt..dt.n_all_tets() as u32 {
            let tv = dt.tet_vertices(t);
            let k = tv.iter().position(|&v| v == INFINITE).expect("ghost tet");
            let inner_tet = dt.tet_neighbors(t)[k];
            let mut f = [0u32; 3];
            let mut m = 0;
            for &v in &tv {
                if v != INFINITE {
                    f[m] = v;
                    m += 1;
                }
            }
            f.sort_unstable();
            let n = outward_normal(pts, f, apex(dt.tet_vertices(inner_tet), f));
            for v in f {
                on_hull[v as usize] = true;
                hull_sum[v as usize] += n;
            }
        }
        for v in 0..nv {
            pole[v] = if on_hull[v] {
                hull_sum[v].normalize_or_zero()
            } else {
                pole[v].normalize_or_zero()
            };
        }
        Poles {
            centres,
            radii,
            pole,
            on_hull,
        }
    }
}

/// Range `[min, max]` of `cos∠(y − p, v)` for `y` on the segment `a + s·d`, `s ∈ [0, s_max]`
/// (`s_max = ∞` for a ray), with `a` relative to `p` and `v` a unit vector.
///
/// Along a line `cos∠` has at most one interior critical point (its derivative's
/// numerator is affine in `s`), so the range is spanned by the end points and that point.
pub fn cos_range(a: DVec3, d: DVec3, v: DVec3, s_max: f64) -> (f64, f64) {
    let f = |s: f64| {
        let y = a + s * d;
        let l = y.length();
        if l > 0.0 { y.dot(v) / l } else { 0.0 }
    };
    let mut lo = f(0.0);
    let mut hi = lo;
    let end = if s_max.is_finite() {
        f(s_max)
    } else {
        let l = d.length();
        if l > 0.0 { d.dot(v) / l } else { lo }
    };
    lo = lo.min(end);
    hi = hi.max(end);
    let (av, ad, dv, aa, dd) = (a.dot(v), a.dot(d), d.dot(v), a.dot(a), d.dot(d));
    let den = dv * ad - av * dd;
    if den != 0.0 {
        let s = (av * ad - dv * aa) / den;
        if s > 0.0 && s < s_max {
            let x = f(s);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo, hi)
}

/// Whether facet `f`'s dual Voronoi edge meets the cocones of its three vertices with
/// half-angle `theta` (radians) about the tangent plane.
pub fn is_cocone_facet(dt: &Delaunay, poles: &Poles, f: u32, sin_theta: f64) -> bool {
    let facet = dt.facets()[f as usize];
    let pts = dt.vertices();
    let c0 = poles.centres[facet.tets[0] as usize];
    if !c0.is_finite() {
        return false;
    }
    let (d, s_max) = if facet.tets[1] == NO_TET {
        let inner = apex(dt.tet_vertices(facet.tets[0]), facet.v);
        (outward_normal(pts, facet.v, inner), f64::INFINITY)
    } else {
        let c1 = poles.centres[facet.tets[1] as usize];
        if !c1.is_finite() {
            return false;
        }
        (c1 - c0, 1.0)
    };
    facet.v.iter().all(|&p| {
        let v = poles.pole[p as usize];
        if v == DVec3::ZERO {
            return false;
        }
        meets_cocone(c0 - pts[p as usize], d, v, s_max, sin_theta)
    })
}

/// Whether `cos_range(a, d, v, s_max)` meets `[-sin_theta, sin_theta]` (`sin_theta > 0`),
/// from the two end points alone: it does when one of them lies inside the band or the
/// two lie on opposite sides of it. When both lie on one side, e.g. `cos > sin_theta`,
/// the segment (or ray) lies in the cone `{y : cos∠(y, v) > sin_theta}`, which is convex
/// (its half-angle is below π/2), so no interior point reaches the band: the interior
/// critical point of [`cos_range`] is then a maximum of `|cos|` and cannot change the
/// answer. The end values are computed as in [`cos_range`].
#[inline]
fn meets_cocone(a: DVec3, d: DVec3, v: DVec3, s_max: f64, sin_theta: f64) -> bool {
    let f = |s: f64| {
        let y = a + s * d;
        let l = y.length();
        if l > 0.0 { y.dot(v) / l } else { 0.0 }
    };
    let start = f(0.0);
    if start.abs() <= sin_theta {
        return true;
    }
    let end = if s_max.is_finite() {
        f(s_max)
    } else {
        let l = d.length();
        if l > 0.0 { d.dot(v) / l } else { start }
    };
    if end.abs() <= sin_theta {
        return true;
    }
    if start.is_finite() && end.is_finite() {
        return (start > sin_theta) != (end > sin_theta);
    }
    let (lo, hi) = cos_range(a, d, v, s_max);
    lo <= sin_theta && hi >= -sin_theta
}

/// The cocone flag of every Delaunay facet, in parallel.
pub fn cocone_flags(dt: &Delaunay, poles: &Poles, theta: f64) -> Vec<bool> {
    let s = theta.sin();
    (0..dt.facets().len() as u32)
        .into_par_iter()
        .map(|f| is_cocone_facet(dt, poles, f, s))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cos_range_matches_dense_sampling() {
        let v = DVec3::new(0.3, -0.2, 0.9).normalize();
        let cases = [
            (DVec3::new(1.0, 0.5, -0.3), DVec3::new(-2.0, 0.1, 1.5)),
            (DVec3::new(-0.4, 1.0, 0.2), DVec3::new(0.8, -1.9, 0.4)),
            (DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.5, 0.5, -3.0)),
        ];
        for (a, d) in cases {
            for s_max in [1.0, 3.0] {
                let (lo, hi) = cos_range(a, d, v, s_max);
                let (mut blo, mut bhi) = (f64::MAX, f64::MIN);
                for i in 0..=20000 {
                    let y = a + (s_max * i as f64 / 20000.0) * d;
                    let c = y.dot(v) / y.length();
                    blo = blo.min(c);
                    bhi = bhi.max(c);
                }
                assert!(
                    (lo - blo).abs() < 1e-6 && (hi - bhi).abs() < 1e-6,
                    "{a} {d}"
                );
            }
        }
    }

    #[test]
    fn early_decision_matches_the_full_range() {
        // Pseudo-random segments and rays: the short-cut answer equals the range test.
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for k in 0..20000 {
            let a = DVec3::new(r(), r(), r());
            let d = DVec3::new(r(), r(), r()) * 3.0;
            let v = DVec3::new(r(), r(), r()).normalize();
            let s_max = if k % 5 == 0 { f64::INFINITY } else { 1.0 };
            let s = (22.5f64).to_radians().sin();
            let (lo, hi) = cos_range(a, d, v, s_max);
            assert_eq!(
                meets_cocone(a, d, v, s_max, s),
                lo <= s && hi >= -s,
                "{a} {d} {v}"
            );
        }
    }

    #[test]
    fn ray_limit_is_the_direction() {
        let (lo, hi) = cos_range(DVec3::X, DVec3::Z, DVec3::Z, f64::INFINITY);
        assert!(lo.abs() < 1e-12 && (hi - 1.0).abs() < 1e-12);
    }
}
