//! Closest points on a triangle and on a segment.

use glam::DVec3;

/// Closest point on triangle `abc` to `p`, with its barycentric coordinates
/// `(wa, wb, wc)` (`point == wa a + wb b + wc c`, all `>= 0`, summing to 1).
///
/// Ericson's Voronoi-region method (Real-Time Collision Detection, 5.1.5). Degenerate
/// triangles (collinear or coincident corners) have no interior and are handled as the
/// closest of their three edges, so the result is always finite for finite input.
pub fn closest_point_on_triangle_bary(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
    let n2 = ab.cross(ac).length_squared();
    let scale2 = ab
        .length_squared()
        .max(ac.length_squared())
        .max((c - b).length_squared());
    if n2 <= 1e-30 * scale2 * scale2 || scale2 == 0.0 {
        return closest_on_degenerate(p, a, b, c);
    }
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    let v = vb / denom;
    let w = vc / denom;
    (a + v * ab + w * ac, [1.0 - v - w, v, w])
}

/// Closest point on triangle `abc` to `p` (see [`closest_point_on_triangle_bary`]).
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    closest_point_on_triangle_bary(p, a, b, c).0
}

/// Closest point on segment `ab` to `p` and its parameter `t` (`point = a + t (b - a)`).
pub fn closest_point_on_segment(p: DVec3, a: DVec3, b: DVec3) -> (DVec3, f64) {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return (a, 0.0);
    }
    let t = ((p - a).dot(ab) / l2).clamp(0.0, 1.0);
    (a + t * ab, t)
}

fn closest_on_degenerate(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, [f64; 3]) {
    let (qab, t_ab) = closest_point_on_segment(p, a, b);
    let (qbc, t_bc) = closest_point_on_segment(p, b, c);
    let (qca, t_ca) = closest_point_on_segment(p, c, a);
    let cands = [
        (qab, [1.0 - t_ab, t_ab, 0.0]),
        (qbc, [0.0, 1.0 - t_bc, t_bc]),
        (qca, [t_ca, 0.0, 1.0 - t_ca]),
    ];
    let mut best = cands[0];
    for c in &cands[1..] {
        if (c.0 - p).length_squared() < (best.0 - p).length_squared() {
            best = *c;
        }
    }
    best
}
