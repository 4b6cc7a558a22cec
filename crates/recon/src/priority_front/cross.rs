//! The 2-D crossing validation of spec §4.4 Step 4 (O'Rourke's proper-intersection test
//! in a local projection plane).

use glam::DVec3;

/// An orthonormal basis `(u, v)` of the plane with unit normal `n`.
#[inline]
pub(crate) fn plane_basis(n: DVec3) -> (DVec3, DVec3) {
    let u = n.any_orthonormal_vector();
    (u, n.cross(u))
}

#[inline]
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Proper crossing of segments `p0p1` and `q0q1` (touching or collinear overlap is not
/// proper).
#[inline]
fn proper(p0: [f64; 2], p1: [f64; 2], q0: [f64; 2], q1: [f64; 2]) -> bool {
    let d1 = orient(p0, p1, q0);
    let d2 = orient(p0, p1, q1);
    if !((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) {
        return false;
    }
    let d3 = orient(q0, q1, p0);
    let d4 = orient(q0, q1, p1);
    (d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)
}

/// True when a tentative edge of `new_edges` properly crosses a front edge of `xs` in
/// the plane through `o` with unit normal `n`. Front edges sharing an endpoint with the
/// tentative edge are skipped, and so are those with both endpoints farther than `r`
/// from the plane (another sheet).
pub(crate) fn crosses(
    pts: &[DVec3],
    xs: &[XNear],
    n: DVec3,
    o: DVec3,
    r: f64,
    new_edges: &[(u32, u32)],
) -> bool {
    if xs.is_empty() {
        return false;
    }
    let (u, v) = plane_basis(n);
    let proj = |i: u32| {
        let q = pts[i as usize] - o;
        [q.dot(u), q.dot(v)]
    };
    for &(s0, s1) in new_edges {
        let (p0, p1) = (proj(s0), proj(s1));
        for &XNear { x, y, .. } in xs {
            if x == s0 || x == s1 || y == s0 || y == s1 {
                continue;
            }
            let (px, py) = (pts[x as usize], pts[y as usize]);
            if (px - o).dot(n).abs() > r && (py - o).dot(n).abs() > r {
                continue;
            }
            if proper(p0, p1, proj(x), proj(y)) {
                return true;
            }
        }
    }
    false
}

/// A front edge `x -> y` projected into a validation plane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct XProj {
    pub x: u32,
    pub y: u32,
    pub p: [f64; 2],
    pub q: [f64; 2],
    /// `x` lies within `r` of the plane.
    pub near_x: bool,
    /// At least one endpoint lies within `r` of the plane.
    pub near: bool,
}

/// A front edge `x -> y` of the gather, seen from the popped edge's midpoint `o`: the
/// offset `w = pts[x] - o` of its first endpoint, `|w|^2`, and the edge's length (all
/// plane-independent).
#[derive(Debug, Clone, Copy)]
pub(crate) struct XNear {
    pub w: DVec3,
    pub ww: f64,
    pub len: f64,
    pub x: u32,
    pub y: u32,
}

/// [`project_near`] of only those front edges of `xs` whose projection
/// can reach the disk of radius `rt` around the projection of `o`; returns how many were
/// written into `out` (in the order of `xs`). A projected edge lies within its length of
/// the projection of its endpoint `o + w`, whose distance from `o`'s projection is
/// `sqrt(|w|^2 - (w.n)^2)`, so an edge with `|w|^2 - (w.n)^2 > (rt + len)^2` misses the
/// disk. With `rt` at least the distance from `o` of the triangle's vertices, such an
/// edge can neither cross the triangle's edges nor have its first endpoint inside it,
/// and the crossing and I6 tests on the returned edges decide as on all of them. The
/// bound carries a relative slack of 1e-6 and an absolute one of 1e-9 r against
/// rounding, far above the error of the projections. The kept edges are projected as by
/// [`project_near`] (same expressions, same values).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(crate) fn project_near(
    pts: &[DVec3],
    xs: &[XNear],
    rt: f64,
    u: DVec3,
    v: DVec3,
    n: DVec3,
    o: DVec3,
    r: f64,
    out: &mut Vec<XProj>,
) -> usize {
    if out.len() < xs.len() {
        out.resize(
            xs.len(),
            XProj {
                x: 0,
                y: 0,
                p: [0.0; 2],
                q: [0.0; 2],
                near_x: false,
                near: false,
            },
        );
    }
    let mut k = 0;
    let (rt, pad) = (rt * (1.0 + 1e-6), 1e-9 * r);
    for m in xs {
        let (x, y) = (m.x, m.y);
        debug_assert_eq!(m.w, pts[x as usize] - o);
        let h = m.w.dot(n);
        let s = rt + m.len + pad;
        if m.ww - h * h > s * s {
            continue;
        }
        // `w` is `pts[x] - o` (the gather computed it so), and `h` its height.
        let (px, py) = (m.w, pts[y as usize] - o);
        let near_x = h.abs() <= r;
        out[k] = XProj {
            x,
            y,
            p: [px.dot(u), px.dot(v)],
            q: [py.dot(u), py.dot(v)],
            near_x,
            near: near_x || py.dot(n).abs() <= r,
        };
        k += 1;
    }
    k
}

/// [`crosses`] on edges projected by [`project_near`]: true when one of the two tentative edges
/// `(s0, p0, s1, p1)` (ids and projected endpoints) properly crosses a projected front
/// edge. Front edges sharing an endpoint with the tentative edge, and those with both
/// endpoints farther than `r` from the plane, are skipped; a bounding-box test comes
/// before the orientation tests.
#[inline(never)]
pub(crate) fn crosses_projected(
    xp: &[XProj],
    new_edges: [(u32, [f64; 2], u32, [f64; 2]); 2],
) -> bool {
    // Per new edge: its ids and bounding box. The box test is written with plain
    // comparisons (`max(p, q) < lo` as `p < lo && q < lo`): `f64::max` / `min` carry
    // NaN handling that costs several instructions each, and this is the innermost loop
    // of the validation. One pass over the front edges tests both new edges.
    let nb = new_edges.map(|(s0, p0, s1, p1)| {
        (
            s0,
            p0,
            s1,
            p1,
            [p0[0].min(p1[0]), p0[1].min(p1[1])],
            [p0[0].max(p1[0]), p0[1].max(p1[1])],
        )
    });
    for e in xp {
        if !e.near {
            continue;
        }
        for &(s0, p0, s1, p1, lo, hi) in &nb {
            if (e.p[0] < lo[0] && e.q[0] < lo[0])
                || (e.p[0] > hi[0] && e.q[0] > hi[0])
                || (e.p[1] < lo[1] && e.q[1] < lo[1])
                || (e.p[1] > hi[1] && e.q[1] > hi[1])
            {
                continue;
            }
            if e.x == s0 || e.x == s1 || e.y == s0 || e.y == s1 {
                continue;
            }
            if proper(p0, p1, e.p, e.q) {
                return true;
            }
        }
    }
    false
}

/// True when a front vertex (the first endpoint of each projected edge, other than the
/// triangle's own vertices) within `r` of the plane projects strictly inside the
/// projected triangle `t2` with ids `tri`. The triangle would then cover part of the
/// front: a fold the edge-crossing test cannot see when the whole front piece lies
/// inside the triangle.
#[inline(never)]
pub(crate) fn front_inside_projected(xp: &[XProj], tri: [u32; 3], t2: [[f64; 2]; 3]) -> bool {
    // A point strictly inside the triangle lies inside its bounding box: the box test
    // rejects most front vertices before the three orientation tests.
    let lo = [
        t2[0][0].min(t2[1][0]).min(t2[2][0]),
        t2[0][1].min(t2[1][1]).min(t2[2][1]),
    ];
    let hi = [
        t2[0][0].max(t2[1][0]).max(t2[2][0]),
        t2[0][1].max(t2[1][1]).max(t2[2][1]),
    ];
    xp.iter().any(|e| {
        e.p[0] >= lo[0]
            && e.p[0] <= hi[0]
            && e.p[1] >= lo[1]
            && e.p[1] <= hi[1]
            && e.near_x
            && !tri.contains(&e.x)
            && inside_2d(t2, e.p)
    })
}

/// True when `q` lies strictly inside the 2-D triangle `tri` (either orientation).
pub(crate) fn inside_2d(tri: [[f64; 2]; 3], q: [f64; 2]) -> bool {
    let d0 = orient(tri[0], tri[1], q);
    let d1 = orient(tri[1], tri[2], q);
    let d2 = orient(tri[2], tri[0], q);
    (d0 > 0.0 && d1 > 0.0 && d2 > 0.0) || (d0 < 0.0 && d1 < 0.0 && d2 < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proper_crossing_and_touching() {
        assert!(proper([0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]));
        assert!(!proper([0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [2.0, 1.0]));
        assert!(!proper([0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]));
        assert!(inside_2d([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], [0.2, 0.2]));
        assert!(!inside_2d([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], [0.5, 0.5]));
    }

    /// The 3-D cull of `project_near` never changes the crossing and I6 tests: random
    /// triangles within `rt` of `o` against random front edges (near the plane, some
    /// long, some steep), with and without the cull (`rt` infinite keeps every edge).
    #[test]
    fn culled_projection_decides_as_the_full_one() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let r = 1.0;
        let (mut full, mut cut) = (Vec::new(), Vec::new());
        let (mut hits, mut kept, mut total) = (0, 0, 0);
        for _ in 0..3000 {
            let mut rv = |s: f64| {
                DVec3::new(
                    rng.random_range(-s..s),
                    rng.random_range(-s..s),
                    rng.random_range(-s..s),
                )
            };
            let o = rv(5.0);
            let n = (DVec3::Z + rv(0.5)).normalize();
            let (u, v) = plane_basis(n);
            let flat = |p: DVec3| p - p.dot(n) * n * 0.9;
            // Triangle a, t, b around o (a, b symmetric about o as for a front edge).
            let ea = flat(rv(0.3));
            let t = o + flat(rv(1.0));
            let mut pts = vec![o + ea, t, o - ea];
            let mut xs = Vec::new();
            for k in 0..40u32 {
                let x = o + flat(rv(2.0));
                let y = x + rv(if k % 5 == 0 { 1.5 } else { 0.4 });
                pts.push(x);
                pts.push(y);
                let (ix, iy) = (3 + 2 * k, 4 + 2 * k);
                let w = x - o;
                xs.push(XNear {
                    w,
                    ww: w.length_squared(),
                    len: (y - x).length(),
                    x: ix,
                    y: iy,
                });
            }
            let rt = (t - o).length().max(ea.length());
            let nf = project_near(&pts, &xs, f64::INFINITY, u, v, n, o, r, &mut full);
            let nc = project_near(&pts, &xs, rt, u, v, n, o, r, &mut cut);
            assert_eq!(nf, xs.len());
            let pr = |p: DVec3| [(p - o).dot(u), (p - o).dot(v)];
            let (qa, qt, qb) = (pr(pts[0]), pr(pts[1]), pr(pts[2]));
            let edges = [(0, qa, 1, qt), (1, qt, 2, qb)];
            let c_full = crosses_projected(&full[..nf], edges);
            let i_full = front_inside_projected(&full[..nf], [0, 1, 2], [qa, qt, qb]);
            assert_eq!(c_full, crosses_projected(&cut[..nc], edges));
            assert_eq!(
                i_full,
                front_inside_projected(&cut[..nc], [0, 1, 2], [qa, qt, qb])
            );
            hits += usize::from(c_full || i_full);
            kept += nc;
            total += nf;
        }
        // The cases are not trivial: some tests fire, and the cull drops most edges.
        assert!(hits > 300, "{hits}");
        assert!(kept * 2 < total, "{kept} of {total}");
    }
}
