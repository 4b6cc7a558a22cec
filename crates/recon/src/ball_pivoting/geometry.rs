//! Ball geometry: the centre of a ball of radius ρ touching three points on the positive
//! side of their triangle, and the angle a centre has on the pivot circle of an edge.

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
/// triangle's normal `(b - a) x (c - a)`.
#[inline]
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
            e1,
            e2: u.cross(e1),
        })
    }

    /// A monotone stand-in for the rotation angle from the current centre to centre
    /// `x`, in `[0, 4)` (the "diamond angle": `0` at the current centre, `1` a quarter
    /// turn, `2` half a turn); cheaper than `atan2` and enough to order contacts.
    #[inline]
    pub fn angle(&self, x: DVec3) -> f64 {
        let d = x - self.m;
        let (c, s) = (d.dot(self.e1), d.dot(self.e2));
        let (ac, as_) = (c.abs(), s.abs());
        let sum = ac + as_;
        if sum == 0.0 {
            return 0.0;
        }
        let t = as_ / sum;
        match (c >= 0.0, s >= 0.0) {
            (true, true) => t,
            (false, true) => 2.0 - t,
            (false, false) => 2.0 + t,
            (true, false) => 4.0 - t,
        }
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
