//! Exact intersection test of two triangles (orientation predicates of the `robust`
//! crate): used to count self-intersections and to keep filled holes from crossing the
//! surface.

use glam::DVec3;
use robust::{Coord, Coord3D, orient2d, orient3d};

fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn o3(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> i8 {
    sign(orient3d(c3(a), c3(b), c3(c), c3(d)))
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Drops coordinate `axis`.
fn proj(p: DVec3, axis: usize) -> Coord<f64> {
    match axis {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

fn o2(a: DVec3, b: DVec3, c: DVec3, axis: usize) -> i8 {
    sign(orient2d(proj(a, axis), proj(b, axis), proj(c, axis)))
}

/// Exactly collinear (or coincident) corners.
/// Whether the three corners of `t` are exactly collinear (a degenerate triangle).
pub fn exactly_collinear(t: &[DVec3; 3]) -> bool {
    (0..3).all(|ax| o2(t[0], t[1], t[2], ax) == 0)
}

/// An axis whose projection keeps triangle `t` non-degenerate (exact test).
fn projection_axis(t: &[DVec3; 3]) -> usize {
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| n[b].total_cmp(&n[a]));
    axes.into_iter()
        .find(|&ax| o2(t[0], t[1], t[2], ax) != 0)
        .unwrap_or(axes[0])
}

/// Mixed strict signs among `s`.
fn mixed(s: &[i8]) -> bool {
    s.iter().any(|&x| x > 0) && s.iter().any(|&x| x < 0)
}

/// Closed segments `p1 p2` and `q1 q2` in the projection `axis` intersect.
fn seg_seg_2d(p1: DVec3, p2: DVec3, q1: DVec3, q2: DVec3, axis: usize) -> bool {
    let d1 = o2(q1, q2, p1, axis);
    let d2 = o2(q1, q2, p2, axis);
    let d3 = o2(p1, p2, q1, axis);
    let d4 = o2(p1, p2, q2, axis);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |a: DVec3, b: DVec3, c: DVec3| {
        let (a, b, c) = (proj(a, axis), proj(b, axis), proj(c, axis));
        c.x >= a.x.min(b.x) && c.x <= a.x.max(b.x) && c.y >= a.y.min(b.y) && c.y <= a.y.max(b.y)
    };
    (d1 == 0 && on(q1, q2, p1))
        || (d2 == 0 && on(q1, q2, p2))
        || (d3 == 0 && on(p1, p2, q1))
        || (d4 == 0 && on(p1, p2, q2))
}

/// `p` in the closed triangle `t` in the projection `axis`.
fn point_in_tri_2d(p: DVec3, t: &[DVec3; 3], axis: usize) -> bool {
    !mixed(&[
        o2(t[0], t[1], p, axis),
        o2(t[1], t[2], p, axis),
        o2(t[2], t[0], p, axis),
    ])
}

/// Closed segment `pq` and closed triangle `t`, all in one plane.
fn seg_tri_coplanar(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> bool {
    let ax = projection_axis(t);
    point_in_tri_2d(p, t, ax) || (0..3).any(|k| seg_seg_2d(p, q, t[k], t[(k + 1) % 3], ax))
}

/// Closed triangles in one plane.
fn tri_tri_coplanar(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let ax = projection_axis(a);
    (0..3).any(|i| (0..3).any(|j| seg_seg_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], ax)))
        || point_in_tri_2d(a[0], b, ax)
        || point_in_tri_2d(b[0], a, ax)
}

/// Closed segment `pq` (with the signs `sp`, `sq` of its ends against the plane of `t`)
/// and closed triangle `t`.
fn seg_tri(p: DVec3, q: DVec3, sp: i8, sq: i8, t: &[DVec3; 3]) -> bool {
    if sp == sq && sp != 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        return seg_tri_coplanar(p, q, t);
    }
    // The segment meets the plane; the line pq passes through the closed triangle iff
    // the three orientations have no strictly opposite signs.
    !mixed(&[
        o3(p, q, t[0], t[1]),
        o3(p, q, t[1], t[2]),
        o3(p, q, t[2], t[0]),
    ])
}

/// Exact intersection test of two non-degenerate closed triangles.
pub fn tri_tri_intersect(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let sb = [0, 1, 2].map(|k| o3(a[0], a[1], a[2], b[k]));
    if sb.iter().all(|&s| s > 0) || sb.iter().all(|&s| s < 0) {
        return false;
    }
    if sb.iter().all(|&s| s == 0) {
        return tri_tri_coplanar(a, b);
    }
    let sa = [0, 1, 2].map(|k| o3(b[0], b[1], b[2], a[k]));
    if sa.iter().all(|&s| s > 0) || sa.iter().all(|&s| s < 0) {
        return false;
    }
    (0..3).any(|k| seg_tri(a[k], a[(k + 1) % 3], sa[k], sa[(k + 1) % 3], b))
        || (0..3).any(|k| seg_tri(b[k], b[(k + 1) % 3], sb[k], sb[(k + 1) % 3], a))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [DVec3; 3] {
        [a, b, c].map(DVec3::from_array)
    }

    #[test]
    fn tri_tri_cases() {
        let base = t([0., 0., 0.], [1., 0., 0.], [0., 1., 0.]);
        // Piercing.
        assert!(tri_tri_intersect(
            &base,
            &t([0.2, 0.2, -1.], [0.3, 0.2, 1.], [0.2, 0.3, 1.])
        ));
        // Above.
        assert!(!tri_tri_intersect(
            &base,
            &t([0., 0., 1.], [1., 0., 1.], [0., 1., 1.])
        ));
        // Touching at a point on the plane (vertex on the interior).
        assert!(tri_tri_intersect(
            &base,
            &t([0.2, 0.2, 0.], [0.3, 0.2, 1.], [0.2, 0.3, 1.])
        ));
        // Near miss beside the hypotenuse.
        assert!(!tri_tri_intersect(
            &base,
            &t([0.6, 0.6, -1.], [0.6, 0.6, 1.], [2., 2., 0.])
        ));
        // Coplanar overlap and coplanar disjoint.
        assert!(tri_tri_intersect(
            &base,
            &t([0.2, 0.2, 0.], [2., 0.2, 0.], [0.2, 2., 0.])
        ));
        assert!(!tri_tri_intersect(
            &base,
            &t([2., 2., 0.], [3., 2., 0.], [2., 3., 0.])
        ));
        // Coplanar, one inside the other.
        assert!(tri_tri_intersect(
            &base,
            &t([0.1, 0.1, 0.], [0.2, 0.1, 0.], [0.1, 0.2, 0.])
        ));
        // An edge lying in the plane, crossing the triangle.
        assert!(tri_tri_intersect(
            &base,
            &t([-1., 0.25, 0.], [2., 0.25, 0.], [0.5, 0.25, 1.])
        ));
    }
}
