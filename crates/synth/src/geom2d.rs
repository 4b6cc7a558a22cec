//! Planar curves and regions made of segments and circular arcs, with exact closest
//! points: the building block of the revolved, extruded and offset shapes.

use glam::DVec2;
use rand::Rng;

use crate::util::{perp, uniform, wrap_tau};

/// Unit vector at `angle`, with components within 1e-15 of 0 snapped to exactly 0 so that
/// arc end points at multiples of 90 degrees are bit-identical however the angle was
/// reached (`sin(pi) != 0` in floating point).
pub fn dir(angle: f64) -> DVec2 {
    let (s, c) = angle.sin_cos();
    let snap = |x: f64| if x.abs() < 1e-15 { 0.0 } else { x };
    DVec2::new(snap(c), snap(s))
}

/// A segment or a circular arc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Elem2 {
    /// Straight segment from `a` to `b`.
    Seg {
        /// Start.
        a: DVec2,
        /// End.
        b: DVec2,
    },
    /// Arc of the circle (`c`, `r`) from angle `a0` over the signed angle `sweep`
    /// (positive = counter-clockwise).
    Arc {
        /// Centre.
        c: DVec2,
        /// Radius.
        r: f64,
        /// Start angle (radians).
        a0: f64,
        /// Signed sweep (radians), `|sweep| <= 2 pi`.
        sweep: f64,
    },
}

/// The closest point on an element.
#[derive(Debug, Clone, Copy)]
pub struct Closest2 {
    /// The point.
    pub point: DVec2,
    /// Squared distance to the query.
    pub dist2: f64,
    /// Unit normal to the right of the direction of travel at `point` (the outward normal
    /// of a counter-clockwise loop).
    pub normal: DVec2,
    /// Arc-length parameter of `point` from the element start.
    pub s: f64,
}

impl Elem2 {
    /// Start point.
    pub fn start(&self) -> DVec2 {
        match *self {
            Elem2::Seg { a, .. } => a,
            Elem2::Arc { c, r, a0, .. } => c + r * dir(a0),
        }
    }

    /// End point.
    pub fn end(&self) -> DVec2 {
        match *self {
            Elem2::Seg { b, .. } => b,
            Elem2::Arc { c, r, a0, sweep } => c + r * dir(a0 + sweep),
        }
    }

    /// Length.
    pub fn length(&self) -> f64 {
        match *self {
            Elem2::Seg { a, b } => (b - a).length(),
            Elem2::Arc { r, sweep, .. } => r * sweep.abs(),
        }
    }

    /// Point at arc length `s` in `[0, length]`.
    pub fn point_at(&self, s: f64) -> DVec2 {
        match *self {
            Elem2::Seg { a, b } => {
                let l = (b - a).length();
                if l == 0.0 { a } else { a + (b - a) * (s / l) }
            }
            Elem2::Arc { c, r, a0, sweep } => c + r * dir(a0 + sweep.signum() * s / r),
        }
    }

    /// Unit tangent (direction of travel) at arc length `s`.
    pub fn tangent_at(&self, s: f64) -> DVec2 {
        match *self {
            Elem2::Seg { a, b } => (b - a).normalize_or_zero(),
            Elem2::Arc { r, a0, sweep, .. } => {
                perp(dir(a0 + sweep.signum() * s / r)) * sweep.signum()
            }
        }
    }

    /// Unit normal to the right of the travel direction at arc length `s`.
    pub fn normal_at(&self, s: f64) -> DVec2 {
        -perp(self.tangent_at(s))
    }

    /// Exact closest point to `q`.
    pub fn closest(&self, q: DVec2) -> Closest2 {
        match *self {
            Elem2::Seg { a, b } => {
                let d = b - a;
                let l2 = d.length_squared();
                let t = if l2 == 0.0 {
                    0.0
                } else {
                    ((q - a).dot(d) / l2).clamp(0.0, 1.0)
                };
                let point = a + d * t;
                let dir = if l2 == 0.0 { DVec2::X } else { d / l2.sqrt() };
                Closest2 {
                    point,
                    dist2: (q - point).length_squared(),
                    normal: -perp(dir),
                    s: t * l2.sqrt(),
                }
            }
            Elem2::Arc { c, r, a0, sweep } => {
                let v = q - c;
                let len = sweep.abs();
                let s_ang = if v == DVec2::ZERO {
                    0.0
                } else {
                    let phi = v.y.atan2(v.x);
                    let t = wrap_tau((phi - a0) * sweep.signum());
                    if t <= len {
                        t
                    } else {
                        // Outside the arc: the nearer end (distance grows with angular gap).
                        let gap_end = t - len;
                        let gap_start = std::f64::consts::TAU - t;
                        if gap_start <= gap_end { 0.0 } else { len }
                    }
                };
                let ang = a0 + sweep.signum() * s_ang;
                let dir = dir(ang);
                let point = c + r * dir;
                Closest2 {
                    point,
                    dist2: (q - point).length_squared(),
                    normal: if sweep > 0.0 { dir } else { -dir },
                    s: s_ang * r,
                }
            }
        }
    }

    /// Whether the element is an arc that bulges away from the region on its left, i.e.
    /// convex as seen from the region (counter-clockwise arcs).
    pub fn is_convex_arc(&self) -> bool {
        matches!(*self, Elem2::Arc { sweep, .. } if sweep > 0.0)
    }

    /// Parity of the crossings of the ray `q + t (1, 0)`, `t > 0`, with the element, with
    /// the half-open rule on y (an end point counts for the piece that lies above it), so
    /// that crossings through shared end points are counted exactly once.
    fn parity(&self, q: DVec2) -> bool {
        match *self {
            Elem2::Seg { a, b } => {
                crosses(a, b, q, |y| a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y))
            }
            Elem2::Arc { c, r, a0, sweep } => {
                // Split into y-monotone pieces at the top and bottom of the circle.
                let (lo, hi) = if sweep >= 0.0 {
                    (a0, a0 + sweep)
                } else {
                    (a0 + sweep, a0)
                };
                let half = std::f64::consts::PI;
                let mut cuts = vec![lo];
                let mut k = ((lo - 0.5 * half) / half).floor() + 1.0;
                while 0.5 * half + k * half < hi {
                    cuts.push(0.5 * half + k * half);
                    k += 1.0;
                }
                cuts.push(hi);
                let mut odd = false;
                for w in cuts.windows(2) {
                    let (p0, p1) = (c + r * dir(w[0]), c + r * dir(w[1]));
                    let right = (0.5 * (w[0] + w[1])).cos() > 0.0;
                    let x_at = |y: f64| {
                        let dx = (r * r - (y - c.y) * (y - c.y)).max(0.0).sqrt();
                        if right { c.x + dx } else { c.x - dx }
                    };
                    if crosses(p0, p1, q, x_at) {
                        odd = !odd;
                    }
                }
                odd
            }
        }
    }

    /// Signed area contribution (shoelace of the chord plus the circular segment).
    fn signed_area(&self) -> f64 {
        let a = self.start();
        let b = self.end();
        let mut s = 0.5 * a.perp_dot(b);
        if let Elem2::Arc { r, sweep, .. } = *self {
            let t = sweep.abs();
            s += sweep.signum() * 0.5 * r * r * (t - t.sin());
        }
        s
    }

    /// Axis-aligned bounds `(min, max)`.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        match *self {
            Elem2::Seg { a, b } => (a.min(b), a.max(b)),
            Elem2::Arc { c, r, a0, sweep } => {
                let mut lo = self.start().min(self.end());
                let mut hi = self.start().max(self.end());
                for k in 0..4 {
                    let ang = k as f64 * std::f64::consts::FRAC_PI_2;
                    let t = wrap_tau((ang - a0) * sweep.signum());
                    if t <= sweep.abs() {
                        let p = c + r * dir(ang);
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
                (lo, hi)
            }
        }
    }

    /// Uniform random point by arc length: `(point, outward normal, s)`.
    pub fn sample(&self, rng: &mut dyn Rng) -> (DVec2, DVec2) {
        let s = uniform(rng, 0.0, self.length());
        (self.point_at(s), self.normal_at(s))
    }

    /// `n + 1` points along the element (including both ends).
    pub fn polyline(&self, n: usize) -> Vec<DVec2> {
        let l = self.length();
        (0..=n)
            .map(|i| self.point_at(l * i as f64 / n as f64))
            .collect()
    }
}

/// Whether the y-monotone piece from `a` to `b` crosses the ray from `q` to `+x`;
/// `x_at(y)` is the piece's x at height y.
fn crosses(a: DVec2, b: DVec2, q: DVec2, x_at: impl Fn(f64) -> f64) -> bool {
    (a.y > q.y) != (b.y > q.y) && x_at(q.y) > q.x
}

/// A closed planar region bounded by loops of elements: outer loops counter-clockwise,
/// holes clockwise (the region is on the left of every loop). Loops must be closed
/// (each element ends where the next starts) and must not intersect each other.
#[derive(Debug, Clone, PartialEq)]
pub struct Region2 {
    /// The boundary loops.
    pub loops: Vec<Vec<Elem2>>,
}

/// A vertex where two consecutive elements of a loop meet.
#[derive(Debug, Clone, Copy)]
pub struct Junction {
    /// Position.
    pub point: DVec2,
    /// Outward normal at the end of the incoming element.
    pub n_in: DVec2,
    /// Outward normal at the start of the outgoing element.
    pub n_out: DVec2,
    /// Signed turning angle from the incoming to the outgoing tangent (positive = left
    /// turn = convex corner of the region).
    pub turn: f64,
}

impl Junction {
    /// Whether the tangent is discontinuous here.
    pub fn is_corner(&self) -> bool {
        self.turn.abs() > 1e-9
    }
}

impl Region2 {
    /// A region from its loops.
    pub fn new(loops: Vec<Vec<Elem2>>) -> Self {
        Self { loops }
    }

    /// All boundary elements.
    pub fn elems(&self) -> impl Iterator<Item = &Elem2> {
        self.loops.iter().flatten()
    }

    /// Whether `q` is inside (parity rule; points exactly on the boundary are arbitrary).
    pub fn contains(&self, q: DVec2) -> bool {
        self.elems().fold(false, |acc, e| acc ^ e.parity(q))
    }

    /// Area.
    pub fn area(&self) -> f64 {
        self.elems().map(Elem2::signed_area).sum()
    }

    /// Perimeter (all loops).
    pub fn perimeter(&self) -> f64 {
        self.elems().map(Elem2::length).sum()
    }

    /// Exact closest boundary point to `q`.
    pub fn closest_boundary(&self, q: DVec2) -> Closest2 {
        let mut best: Option<Closest2> = None;
        for e in self.elems() {
            let c = e.closest(q);
            if best.is_none_or(|b| c.dist2 < b.dist2) {
                best = Some(c);
            }
        }
        best.expect("region without boundary")
    }

    /// Closest point of the closed region: `q` itself when inside.
    pub fn clamp(&self, q: DVec2) -> DVec2 {
        if self.contains(q) {
            q
        } else {
            self.closest_boundary(q).point
        }
    }

    /// Bounds `(min, max)`.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        self.elems().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), e| {
                let (a, b) = e.bounds();
                (lo.min(a), hi.max(b))
            },
        )
    }

    /// The junctions of all loops (element `i` to element `i + 1`).
    pub fn junctions(&self) -> Vec<Junction> {
        let mut out = Vec::new();
        for lp in &self.loops {
            for i in 0..lp.len() {
                let a = &lp[i];
                let b = &lp[(i + 1) % lp.len()];
                let ta = a.tangent_at(a.length());
                let tb = b.tangent_at(0.0);
                out.push(Junction {
                    point: b.start(),
                    n_in: a.normal_at(a.length()),
                    n_out: b.normal_at(0.0),
                    turn: ta.perp_dot(tb).atan2(ta.dot(tb)),
                });
            }
        }
        out
    }

    /// Uniform random point of the region (rejection in the bounding box).
    pub fn sample_interior(&self, rng: &mut dyn Rng) -> DVec2 {
        let (lo, hi) = self.bounds();
        loop {
            let q = DVec2::new(uniform(rng, lo.x, hi.x), uniform(rng, lo.y, hi.y));
            if self.contains(q) {
                return q;
            }
        }
    }

    /// Checks that every loop is closed; returns a message naming the first gap.
    pub fn check_closed(&self) -> Result<(), String> {
        for (li, lp) in self.loops.iter().enumerate() {
            for i in 0..lp.len() {
                let e = lp[i].end();
                let s = lp[(i + 1) % lp.len()].start();
                if (e - s).length() > 1e-9 {
                    return Err(format!(
                        "loop {li} element {i} ends at {e} but the next starts at {s}"
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Builders for common loops.
pub mod loops {
    use super::*;
    use std::f64::consts::TAU;

    /// A closed polygon loop through `pts` (counter-clockwise for an outer boundary).
    pub fn polygon(pts: &[DVec2]) -> Vec<Elem2> {
        (0..pts.len())
            .map(|i| Elem2::Seg {
                a: pts[i],
                b: pts[(i + 1) % pts.len()],
            })
            .collect()
    }

    /// A full circle as two half arcs; `ccw` for an outer boundary, clockwise for a hole.
    pub fn circle(c: DVec2, r: f64, ccw: bool) -> Vec<Elem2> {
        let s = if ccw { 0.5 * TAU } else { -0.5 * TAU };
        vec![
            Elem2::Arc {
                c,
                r,
                a0: 0.0,
                sweep: s,
            },
            Elem2::Arc {
                c,
                r,
                a0: 0.5 * TAU,
                sweep: s,
            },
        ]
    }

    /// A counter-clockwise rectangle.
    pub fn rect(lo: DVec2, hi: DVec2) -> Vec<Elem2> {
        polygon(&[lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)])
    }

    /// A counter-clockwise stadium: the convex hull of two circles of radius `r` centred
    /// at `(-d, 0)` and `(d, 0)`.
    pub fn stadium(d: f64, r: f64) -> Vec<Elem2> {
        use std::f64::consts::{FRAC_PI_2, PI};
        vec![
            Elem2::Seg {
                a: DVec2::new(-d, -r),
                b: DVec2::new(d, -r),
            },
            Elem2::Arc {
                c: DVec2::new(d, 0.0),
                r,
                a0: -FRAC_PI_2,
                sweep: PI,
            },
            Elem2::Seg {
                a: DVec2::new(d, r),
                b: DVec2::new(-d, r),
            },
            Elem2::Arc {
                c: DVec2::new(-d, 0.0),
                r,
                a0: FRAC_PI_2,
                sweep: PI,
            },
        ]
    }

    /// Replaces the corners of a closed polygon loop (`pts`, counter-clockwise) by arcs of
    /// radius `radii[i]` tangent to both sides (0 keeps the sharp corner). Reflex corners
    /// get concave (clockwise) arcs.
    pub fn filleted_polygon(pts: &[DVec2], radii: &[f64]) -> Vec<Elem2> {
        let n = pts.len();
        // Tangent points and arcs per corner.
        let mut corner: Vec<(DVec2, DVec2, Option<Elem2>)> = Vec::with_capacity(n);
        for i in 0..n {
            let p = pts[i];
            let prev = pts[(i + n - 1) % n];
            let next = pts[(i + 1) % n];
            let r = radii[i];
            if r <= 0.0 {
                corner.push((p, p, None));
                continue;
            }
            let d1 = (p - prev).normalize();
            let d2 = (next - p).normalize();
            let turn = d1.perp_dot(d2).atan2(d1.dot(d2));
            let half = 0.5 * (std::f64::consts::PI - turn.abs());
            let t = r / half.tan();
            let t1 = p - d1 * t;
            let t2 = p + d2 * t;
            // Centre: on the left of d1 for a left turn, on the right for a right turn.
            let side = turn.signum();
            let c = t1 + perp(d1) * (r * side);
            let a0 = (t1 - c).y.atan2((t1 - c).x);
            let arc = Elem2::Arc {
                c,
                r,
                a0,
                sweep: turn,
            };
            // The segments end exactly where the arc does (consistent crossing tests).
            let _ = t2;
            corner.push((arc.start(), arc.end(), Some(arc)));
        }
        let mut out = Vec::new();
        for i in 0..n {
            let (_, t2, _) = corner[i];
            let (t1n, _, _) = corner[(i + 1) % n];
            if let Some(arc) = corner[i].2 {
                out.push(arc);
            }
            out.push(Elem2::Seg { a: t2, b: t1n });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn square_with_hole_area_contains_and_closest() {
        let r = Region2::new(vec![
            loops::rect(DVec2::splat(-1.0), DVec2::splat(1.0)),
            loops::circle(DVec2::ZERO, 0.5, false),
        ]);
        r.check_closed().unwrap();
        assert!((r.area() - (4.0 - PI * 0.25)).abs() < 1e-14);
        assert!(r.contains(DVec2::new(0.8, 0.1)));
        assert!(!r.contains(DVec2::new(0.1, 0.1)));
        assert!(!r.contains(DVec2::new(1.5, 0.1)));
        let c = r.closest_boundary(DVec2::new(0.1, 0.0));
        assert!((c.point - DVec2::new(0.5, 0.0)).length() < 1e-15);
        // Outward normal of a hole points into the hole.
        assert!((c.normal - DVec2::new(-1.0, 0.0)).length() < 1e-15);
    }

    #[test]
    fn stadium_and_fillets_are_closed_with_right_area() {
        let s = Region2::new(vec![loops::stadium(1.0, 0.5)]);
        s.check_closed().unwrap();
        assert!((s.area() - (2.0 + PI * 0.25)).abs() < 1e-14);
        let sq = [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
        ];
        let f = Region2::new(vec![loops::filleted_polygon(&sq, &[0.5; 4])]);
        f.check_closed().unwrap();
        assert!(
            (f.area() - (4.0 - (4.0 - PI) * 0.25)).abs() < 1e-13,
            "{}",
            f.area()
        );
        // An L shape with a concave fillet.
        let l = [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(1.0, 2.0),
            DVec2::new(0.0, 2.0),
        ];
        let f = Region2::new(vec![loops::filleted_polygon(
            &l,
            &[0.0, 0.0, 0.0, 0.25, 0.0, 0.0],
        )]);
        f.check_closed().unwrap();
        assert!(
            (f.area() - (3.0 + (1.0 - PI / 4.0) * 0.0625)).abs() < 1e-13,
            "{}",
            f.area()
        );
    }

    #[test]
    fn arc_closest_point_clamps_to_the_nearer_end() {
        let a = Elem2::Arc {
            c: DVec2::ZERO,
            r: 1.0,
            a0: 0.0,
            sweep: PI / 2.0,
        };
        let c = a.closest(DVec2::new(1.0, -0.1));
        assert!((c.point - DVec2::X).length() < 1e-15);
        let c = a.closest(DVec2::new(-1.0, 0.1));
        assert!((c.point - DVec2::Y).length() < 1e-15);
        let c = a.closest(DVec2::new(2.0, 2.0));
        assert!((c.point - DVec2::splat(0.5f64.sqrt())).length() < 1e-15);
    }
}
