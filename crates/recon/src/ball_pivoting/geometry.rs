//! Ball geometry: the centre of a ball of radius ρ touching three points on the positive
//! side of their triangle, and the angle a centre has on the pivot circle of an edge.

use crate::angle::pseudo_angle;
use glam::DVec3;

/// Circumcentre of triangle `(a, b, c)` and its squared circumradius, or `None` when the
/// triangle is degenerate (relative area below 1e-12 of its squared edge lengths).
#[inline]
pub(crate) fn circumcentre(a: DVec3, b: DVec3, c: DVec3) -> Option<(DVec3, f64)> {
    let ab = b - a;
    let ac = c - a;
    let n = ab.cross(ac);
    let n2 = n.length_squared();
    let scale = ab.length_squared() * ac.length_squared();
    if n2.is_nan() || n2 <= 1e-24 * scale {
        return None;
    }
    // Standard formula: o = a + (|ac|^2 (n x ab) + |ab|^2 (ac x n)) / (2 |n|^2).
    let off = (n.cross(ab) * ac.length_squared() + ac.cross(n) * ab.length_squared()) / (2.0 * n2);
    Some((a + off, off.length_squared()))
}

/// Centre of the ball of radius `rho` through `a`, `b`, `c` on the side of the normal
/// `(b - a) x (c - a)`, or `None` when the triangle is degenerate or its circumradius
/// exceeds `rho`.
#[inline]
pub(crate) fn ball_centre(a: DVec3, b: DVec3, c: DVec3, rho: f64) -> Option<DVec3> {
    let (cc, r2) = circumcentre(a, b, c)?;
    let h2 = rho * rho - r2;
    if h2 < 0.0 {
        return None;
    }
    let n = (b - a).cross(c - a).normalize();
    Some(cc + n * h2.sqrt())
}

/// Both ball centres of radius `rho` through `a`, `b`, `c`: `(above, below)` the
/// triangle's normal `(b - a) x (c - a)` (the reference of [`PivotFrame::contact`]'s
/// test).
#[cfg(test)]
pub(crate) fn ball_centres(a: DVec3, b: DVec3, c: DVec3, rho: f64) -> Option<(DVec3, DVec3)> {
    let (cc, r2) = circumcentre(a, b, c)?;
    let h2 = rho * rho - r2;
    if h2 < 0.0 {
        return None;
    }
    let n = (b - a).cross(c - a).normalize() * h2.sqrt();
    Some((cc + n, cc - n))
}

/// The pivot circle of a front edge: centre `m`, frame `(e1, e2)` with `e1` toward the
/// current ball centre and `e2` the direction the centre moves in (away from the edge's
/// triangle).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PivotFrame {
    pub m: DVec3,
    /// The unit edge direction `a -> b`.
    pub u: DVec3,
    pub e1: DVec3,
    pub e2: DVec3,
}

impl PivotFrame {
    /// The frame of edge `a -> b` of a counter-clockwise triangle `(a, b, o)` whose ball
    /// centre is `c`. With `u` along `a -> b`, `(u, w, n)` is right-handed for `w` the
    /// in-plane direction toward `o` and `n` the triangle normal, so rotating `e1` about
    /// `u` (`e2 = u x e1`) carries the ball over the edge away from `o`.
    #[inline]
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Option<Self> {
        let m = 0.5 * (a + b);
        let u = (b - a).normalize();
        let e1 = (c - m).try_normalize()?;
        Some(Self {
            m,
            u,
            e1,
            e2: u.cross(e1),
        })
    }

    /// Where the pivoting sphere first touches `k`: the ball centre moves on the circle
    /// of radius `rad = (rho² − half2)^½` about `m` (`half2 = |ab|²/4`) in the plane of
    /// `(e1, e2)`. With `d = k − m`, `d1 = d·e1`, `d2 = d·e2`, `D² = d1² + d2²`, the ball
    /// passes through `k` where `d1 cos θ + d2 sin θ = q = (|d|² − half2) / (2 rad)`, at
    /// `(cos θ, sin θ) = (q d1 ∓ h d2, q d2 ± h d1) / D²`, `h = (D² − q²)^½`. Returns the
    /// pseudo-angle of the first of the two positions reached and its unnormalised
    /// `(cos, sin)` (length `D²`; see [`Self::centre`]), or `None` when the ball cannot
    /// touch `k` (too far, or on the edge's line). Replaces a circumcentre and two
    /// normalisations per candidate.
    #[inline]
    pub fn contact(&self, k: DVec3, rad: f64, half2: f64) -> Option<(f64, f64, f64)> {
        let d = k - self.m;
        let (d1, d2) = (d.dot(self.e1), d.dot(self.e2));
        let dd = d1 * d1 + d2 * d2;
        let q = (d.length_squared() - half2) / (2.0 * rad);
        let disc = dd - q * q;
        if !(dd > 0.0 && disc >= 0.0) {
            return None;
        }
        let h = disc.sqrt();
        let (c1, s1) = (q * d1 - h * d2, q * d2 + h * d1);
        let (c2, s2) = (q * d1 + h * d2, q * d2 - h * d1);
        let (t1, t2) = (pseudo_angle(c1, s1), pseudo_angle(c2, s2));
        Some(if t1 <= t2 { (t1, c1, s1) } else { (t2, c2, s2) })
    }

    /// The ball centre on the pivot circle of radius `rad` in direction `(c, s)`.
    #[inline]
    pub fn centre(&self, c: f64, s: f64, rad: f64) -> DVec3 {
        self.m + (self.e1 * c + self.e2 * s) * (rad / (c * c + s * s).sqrt())
    }

    /// A monotone stand-in for the rotation angle from the current centre to centre
    /// `x`, in `[0, 4)` (the "diamond angle": `0` at the current centre, `1` a quarter
    /// turn, `2` half a turn); cheaper than `atan2` and enough to order contacts.
    #[cfg(test)]
    pub fn angle(&self, x: DVec3) -> f64 {
        let d = x - self.m;
        pseudo_angle(d.dot(self.e1), d.dot(self.e2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circumcentre_of_a_right_triangle_is_the_hypotenuse_midpoint() {
        let (c, r2) = circumcentre(DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 2.0).unwrap();
        assert!((c - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-15);
        assert!((r2 - 2.0).abs() < 1e-14);
        assert!(circumcentre(DVec3::ZERO, DVec3::X, DVec3::X * 2.0).is_none());
    }

    #[test]
    fn ball_centre_is_at_rho_from_the_three_points_on_the_normal_side() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::new(0.3, 0.8, 0.1));
        let x = ball_centre(a, b, c, 1.0).unwrap();
        for p in [a, b, c] {
            assert!((x.distance(p) - 1.0).abs() < 1e-12);
        }
        assert!((x - a).dot((b - a).cross(c - a)) > 0.0);
        assert!(ball_centre(a, b, c, 0.1).is_none());
    }

    #[test]
    fn contact_is_the_first_of_the_two_ball_centres() {
        // Against the circumcentre construction: both centres through (b, a, k), the
        // one reached first on the pivot circle.
        let mut x = 0x1234_5678_9abc_def1u64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (a, b, o) = (DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.8, 0.0));
        let rho = 1.2;
        let f = PivotFrame::new(a, b, ball_centre(a, b, o, rho).unwrap()).unwrap();
        let half2 = 0.25;
        let rad = (rho * rho - half2).sqrt();
        let mut seen = 0;
        for _ in 0..5000 {
            let k = DVec3::new(r() * 2.0, r() * 2.0, r() * 2.0);
            let reference = ball_centres(b, a, k, rho).map(|(up, down)| {
                let (tu, td) = (f.angle(up), f.angle(down));
                if tu <= td { (tu, up) } else { (td, down) }
            });
            match (f.contact(k, rad, half2), reference) {
                (Some((t, c, s)), Some((tr, cr))) => {
                    seen += 1;
                    assert!((t - tr).abs() < 1e-9, "{k}: {t} {tr}");
                    assert!(f.centre(c, s, rad).distance(cr) < 1e-9, "{k}");
                }
                (None, None) => {}
                (got, want) => panic!("{k}: {got:?} vs {want:?}"),
            }
        }
        assert!(seen > 1000);
    }

    #[test]
    fn pivot_angle_grows_away_from_the_triangle() {
        // Triangle (a, b, o) in z = 0 with o on +y; the ball sits above (+z).
        let (a, b, o) = (DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.8, 0.0));
        let c = ball_centre(a, b, o, 1.0).unwrap();
        let f = PivotFrame::new(a, b, c).unwrap();
        assert!(f.angle(c) < 1e-12 || f.angle(c) > 4.0 - 1e-12);
        // A point just across the edge (-y) is hit after a small rotation, one on o's
        // side only after almost a full turn.
        let across = ball_centre(b, a, DVec3::new(0.5, -0.8, 0.0), 1.0).unwrap();
        let behind = ball_centre(b, a, DVec3::new(0.5, 0.9, 0.0), 1.0).unwrap();
        assert!(f.angle(across) < f.angle(behind));
        assert!(f.angle(across) < 2.0);
    }
}
