//! Small geometric helpers of the mesh growth: angles, local projection, 2-D
//! orientation and crossing tests (floating point; they steer heuristics, no topology
//! decision depends on an exact sign).

use glam::{DVec2, DVec3};

/// Smallest interior angle (radians) of the triangle `a b c`; 0 when degenerate.
pub fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let ang = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, v) = (q - p, r - p);
        u.cross(v).length().atan2(u.dot(v))
    };
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

/// Radius of the smallest disc containing the triangle `a b c`: half the longest edge
/// when the triangle is right or obtuse, else its circumradius.
pub fn enclosing_radius(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (x, y, z) = ((b - c).length(), (c - a).length(), (a - b).length());
    let l = x.max(y).max(z);
    if 2.0 * l * l >= x * x + y * y + z * z {
        return 0.5 * l;
    }
    let area2 = (b - a).cross(c - a).length();
    if area2 > 0.0 {
        x * y * z / (2.0 * area2)
    } else {
        0.5 * l
    }
}

/// Unnormalised normal of `a b c` (counter-clockwise seen from its side).
pub fn face_cross(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a)
}

/// An orthonormal basis of the plane orthogonal to the unit vector `n`.
pub fn plane_basis(n: DVec3) -> (DVec3, DVec3) {
    let e1 = n.any_orthonormal_vector();
    (e1, n.cross(e1))
}

/// A projection onto the plane through `origin` with unit normal `n`.
#[derive(Debug, Clone, Copy)]
pub struct Proj {
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl Proj {
    /// The projection onto the plane through `origin` orthogonal to `n` (unit); the
    /// 2-D frame is right-handed seen from `+n`.
    pub fn new(origin: DVec3, n: DVec3) -> Self {
        let (e1, e2) = plane_basis(n);
        Self { origin, e1, e2 }
    }

    /// 2-D coordinates of `p`.
    pub fn at(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.e1), d.dot(self.e2))
    }
}

/// Twice the signed area of `a b c` (> 0 counter-clockwise).
pub fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether the open segments `a b` and `c d` cross at a single interior point.
pub fn proper_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 < 0.0 && o3 * o4 < 0.0
}

/// Whether `p` lies strictly inside the triangle `a b c` (either orientation).
pub fn strictly_inside(p: DVec2, a: DVec2, b: DVec2, c: DVec2) -> bool {
    let (o1, o2, o3) = (orient(a, b, p), orient(b, c, p), orient(c, a, p));
    (o1 > 0.0 && o2 > 0.0 && o3 > 0.0) || (o1 < 0.0 && o2 < 0.0 && o3 < 0.0)
}

/// Distance from `p` to the interior of segment `a b`: `None` when the closest point is
/// an endpoint (parameter outside `(0, 1)`), else the distance.
pub fn interior_distance(p: DVec3, a: DVec3, b: DVec3) -> Option<f64> {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2.is_nan() || l2 <= 0.0 {
        return None;
    }
    let t = (p - a).dot(ab) / l2;
    (t > 0.0 && t < 1.0).then(|| (p - (a + ab * t)).length())
}

/// Distance from `p` to the closed segment `a b`.
pub fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

/// Undirected edge key.
pub fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}
