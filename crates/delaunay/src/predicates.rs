//! Geometric predicates: semi-static filters with exact fallback, symbolic perturbation.
//!
//! Sign conventions (right-handed, the opposite of Shewchuk's `orient3d`):
//! * `orient3d(a, b, c, d) > 0` iff `(b − a) · ((c − a) × (d − a)) > 0`, i.e. `d` lies
//!   above the plane of the counter-clockwise triangle `a, b, c`. Every finite
//!   tetrahedron `(v0, v1, v2, v3)` of the triangulation has `orient3d > 0`.
//! * `insphere(a, b, c, d, e) > 0` iff `e` lies strictly inside the sphere through
//!   `a, b, c, d`, for a positively oriented `(a, b, c, d)`.
//!
//! Both are `robust`'s (Shewchuk's) predicates with the sign flipped.
//!
//! The filters evaluate the same expression as Shewchuk's first stage in `f64` and
//! compare it with a *semi-static* bound `C · X · Y · Z (· L)` built from the largest
//! coordinate differences; see the comments at each constant for the derivation.
//! Outside the safe exponent range, and whenever the filter is inconclusive, an exact
//! evaluation decides: in fixed-size integer arithmetic when the coordinates are small
//! integers after a common power-of-two scaling (grids, integer spheres), otherwise with
//! the adaptive exact predicates of `robust`.

use robust::Coord3D;

use crate::exact::Expansion;
use crate::point::P3;

#[inline]
fn c3(p: &P3) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Exact `orient3d` sign (-1, 0, 1).
#[inline]
pub(crate) fn orient3d_exact(a: &P3, b: &P3, c: &P3, d: &P3) -> i32 {
    -sign(robust::orient3d(c3(a), c3(b), c3(c), c3(d)))
}

/// Exact `insphere` sign (-1, 0, 1).
#[inline]
pub(crate) fn insphere_exact(a: &P3, b: &P3, c: &P3, d: &P3, e: &P3) -> i32 {
    -sign(robust::insphere(c3(a), c3(b), c3(c), c3(d), c3(e)))
}

/// `max` without NaN handling (compiles to one `maxsd`); inputs here are never NaN.
#[inline(always)]
fn fmax(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

#[inline(always)]
fn fmin(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

#[inline]
fn sign(x: f64) -> i32 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Range in which the filters' absolute error bounds are valid: below it products may
/// underflow, above it they may overflow. Outside it we go exact directly.
const FILTER_MIN: f64 = 1e-50;
const FILTER_MAX: f64 = 1e50;

/// Orient3d error bound factor. The computed determinant equals the sum of its six
/// monomials (each `x·y·z` of exact differences), each with a relative perturbation of
/// at most `γ8 = 8u/(1-8u)` (1 rounding for each difference, 2 products, 1 subtraction in
/// the 2×2 minor, 1 product and 2 additions at the top level), so the error is at most
/// `6 γ8 X Y Z ≈ 48u X Y Z` (X, Y, Z the largest |differences| per axis, u = 2^-53).
/// We use about 90u, which also covers the rounding of the bound itself.
const O3D_EPS: f64 = 1e-14;

/// Insphere error bound factor: 24 monomials `x·y·z·lift`, each with relative error at
/// most `γ16` (differences 1, 2×2 minor 2, 3×3 minor 3, lift 3, lift product 1, top-level
/// sums 2, plus the rounding of the differences inside the lifts), i.e. `≈ 384u X Y Z L`
/// with L the largest lift. We use about 900u.
const INS_EPS: f64 = 1e-13;

/// Filtered exact `orient3d` sign.
#[inline]
pub(crate) fn orient3d(a: &P3, b: &P3, c: &P3, d: &P3) -> i32 {
    let adx = a[0] - d[0];
    let bdx = b[0] - d[0];
    let cdx = c[0] - d[0];
    let ady = a[1] - d[1];
    let bdy = b[1] - d[1];
    let cdy = c[1] - d[1];
    let adz = a[2] - d[2];
    let bdz = b[2] - d[2];
    let cdz = c[2] - d[2];
    let det = adx * (bdy * cdz - bdz * cdy)
        + bdx * (cdy * adz - cdz * ady)
        + cdx * (ady * bdz - adz * bdy);
    let mx = fmax(fmax(adx.abs(), bdx.abs()), cdx.abs());
    let my = fmax(fmax(ady.abs(), bdy.abs()), cdy.abs());
    let mz = fmax(fmax(adz.abs(), bdz.abs()), cdz.abs());
    let lo = fmin(fmin(mx, my), mz);
    let hi = fmax(fmax(mx, my), mz);
    if lo > FILTER_MIN && hi < FILTER_MAX {
        let eps = O3D_EPS * mx * my * mz;
        if det > eps {
            return -1;
        }
        if det < -eps {
            return 1;
        }
    }
    if let Some(s) = crate::exact_int::orient3d(a, b, c, d) {
        return s;
    }
    orient3d_exact(a, b, c, d)
}

/// Filtered exact `insphere` sign (without perturbation).
#[inline]
pub(crate) fn insphere(a: &P3, b: &P3, c: &P3, d: &P3, e: &P3) -> i32 {
    let aex = a[0] - e[0];
    let bex = b[0] - e[0];
    let cex = c[0] - e[0];
    let dex = d[0] - e[0];
    let aey = a[1] - e[1];
    let bey = b[1] - e[1];
    let cey = c[1] - e[1];
    let dey = d[1] - e[1];
    let aez = a[2] - e[2];
    let bez = b[2] - e[2];
    let cez = c[2] - e[2];
    let dez = d[2] - e[2];

    let ab = aex * bey - bex * aey;
    let bc = bex * cey - cex * bey;
    let cd = cex * dey - dex * cey;
    let da = dex * aey - aex * dey;
    let ac = aex * cey - cex * aey;
    let bd = bex * dey - dex * bey;

    let abc = aez * bc - bez * ac + cez * ab;
    let bcd = bez * cd - cez * bd + dez * bc;
    let cda = cez * da + dez * ac + aez * cd;
    let dab = dez * ab + aez * bd + bez * da;

    let alift = aex * aex + aey * aey + aez * aez;
    let blift = bex * bex + bey * bey + bez * bez;
    let clift = cex * cex + cey * cey + cez * cez;
    let dlift = dex * dex + dey * dey + dez * dez;

    let det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);

    let mx = fmax(fmax(aex.abs(), bex.abs()), fmax(cex.abs(), dex.abs()));
    let my = fmax(fmax(aey.abs(), bey.abs()), fmax(cey.abs(), dey.abs()));
    let mz = fmax(fmax(aez.abs(), bez.abs()), fmax(cez.abs(), dez.abs()));
    let ml = fmax(fmax(alift, blift), fmax(clift, dlift));
    let lo = fmin(fmin(mx, my), mz);
    let hi = fmax(fmax(mx, my), mz);
    if lo > FILTER_MIN && hi < FILTER_MAX {
        let eps = INS_EPS * mx * my * mz * ml;
        if det > eps {
            return -1;
        }
        if det < -eps {
            return 1;
        }
    }
    if let Some(s) = crate::exact_int::insphere(a, b, c, d, e) {
        return s;
    }
    insphere_exact(a, b, c, d, e)
}

/// Symbolically perturbed insphere: never 0 for a non-flat tetrahedron.
///
/// The perturbation lifts point `i` to `|p_i|² + ε^(N - rank_i)`: the point with the
/// highest rank is lifted the most. Expanding the 5×5 lifted determinant along the lift
/// column, the coefficient of the lift of `e` is `-orient3d(a, b, c, d)` and that of a
/// tetrahedron vertex is `orient3d` of the tetrahedron with that vertex replaced by `e`.
/// When the exact determinant is 0 the sign is that of the first non-zero coefficient in
/// decreasing rank order; the term of `e` is non-zero for a non-flat tetrahedron, so the
/// sequence always ends.
///
/// `pts` holds `a, b, c, d` (positively oriented) and `ranks` their ranks; `e`/`re` is
/// the query point and its rank. Returns `> 0` when `e` is in conflict (inside).
pub(crate) fn insphere_sos(pts: [&P3; 4], ranks: [u32; 4], e: &P3, re: u32) -> i32 {
    let s = insphere(pts[0], pts[1], pts[2], pts[3], e);
    if s != 0 {
        return s;
    }
    // Indices 0..4 are tet vertices, 4 is e.
    let mut order = [0usize, 1, 2, 3, 4];
    let rank = |i: usize| if i == 4 { re } else { ranks[i] };
    order.sort_unstable_by_key(|&j| std::cmp::Reverse(rank(j)));
    for &i in &order {
        if i == 4 {
            return -orient3d(pts[0], pts[1], pts[2], pts[3]);
        }
        let mut q = pts;
        q[i] = e;
        let o = orient3d(q[0], q[1], q[2], q[3]);
        if o != 0 {
            return o;
        }
    }
    0
}

/// Floating-point value with a running absolute error bound (`|value - exact| <= err`).
#[derive(Clone, Copy, Debug)]
struct Fe {
    v: f64,
    e: f64,
}

const U: f64 = f64::EPSILON * 0.5;

impl Fe {
    fn diff(a: f64, b: f64) -> Fe {
        let v = a - b;
        Fe { v, e: U * v.abs() }
    }
    fn add(self, o: Fe) -> Fe {
        let v = self.v + o.v;
        Fe {
            v,
            e: self.e + o.e + U * v.abs(),
        }
    }
    fn sub(self, o: Fe) -> Fe {
        let v = self.v - o.v;
        Fe {
            v,
            e: self.e + o.e + U * v.abs(),
        }
    }
    fn mul(self, o: Fe) -> Fe {
        let v = self.v * o.v;
        Fe {
            v,
            e: self.v.abs() * o.e + o.v.abs() * self.e + self.e * o.e + U * v.abs(),
        }
    }
}

/// Arithmetic used by the generic Gabriel polynomial.
trait Num: Clone {
    fn diff(a: f64, b: f64) -> Self;
    fn add(&self, o: &Self) -> Self;
    fn sub(&self, o: &Self) -> Self;
    fn mul(&self, o: &Self) -> Self;
}

impl Num for Fe {
    fn diff(a: f64, b: f64) -> Self {
        Fe::diff(a, b)
    }
    fn add(&self, o: &Self) -> Self {
        Fe::add(*self, *o)
    }
    fn sub(&self, o: &Self) -> Self {
        Fe::sub(*self, *o)
    }
    fn mul(&self, o: &Self) -> Self {
        Fe::mul(*self, *o)
    }
}

impl Num for Expansion {
    fn diff(a: f64, b: f64) -> Self {
        Expansion::diff(a, b)
    }
    fn add(&self, o: &Self) -> Self {
        Expansion::add(self, o)
    }
    fn sub(&self, o: &Self) -> Self {
        Expansion::sub(self, o)
    }
    fn mul(&self, o: &Self) -> Self {
        Expansion::mul(self, o)
    }
}

fn cross<T: Num>(a: &[T; 3], b: &[T; 3]) -> [T; 3] {
    [
        a[1].mul(&b[2]).sub(&a[2].mul(&b[1])),
        a[2].mul(&b[0]).sub(&a[0].mul(&b[2])),
        a[0].mul(&b[1]).sub(&a[1].mul(&b[0])),
    ]
}

fn dot<T: Num>(a: &[T; 3], b: &[T; 3]) -> T {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}

/// `G(p) = |u|² q·(w×n) + |w|² q·(n×u) − |q|²|n|²` with `u = b−a`, `w = c−a`, `q = p−a`,
/// `n = u×w`. Since the circumcentre of the triangle is `a + (|u|²(w×n) + |w|²(n×u)) /
/// (2|n|²)`, `p` lies strictly inside the triangle's smallest circumsphere iff `G > 0`
/// (for a non-degenerate triangle, `|n| > 0`).
fn gabriel_poly<T: Num>(a: &P3, b: &P3, c: &P3, p: &P3) -> T {
    let u = [
        T::diff(b[0], a[0]),
        T::diff(b[1], a[1]),
        T::diff(b[2], a[2]),
    ];
    let w = [
        T::diff(c[0], a[0]),
        T::diff(c[1], a[1]),
        T::diff(c[2], a[2]),
    ];
    let q = [
        T::diff(p[0], a[0]),
        T::diff(p[1], a[1]),
        T::diff(p[2], a[2]),
    ];
    let n = cross(&u, &w);
    let wn = cross(&w, &n);
    let nu = cross(&n, &u);
    let uu = dot(&u, &u);
    let ww = dot(&w, &w);
    let qq = dot(&q, &q);
    let nn = dot(&n, &n);
    uu.mul(&dot(&q, &wn))
        .add(&ww.mul(&dot(&q, &nu)))
        .sub(&qq.mul(&nn))
}

/// Semi-static error bound factor of [`gabriel_poly`] evaluated in `f64`: the expression
/// tree has at most 19 roundings on any path (differences included) and the sum of the
/// absolute values of its monomials is at most `108 M^6` (`M` the largest |difference|),
/// so the error is below `19 · 108 · u · M^6 ≈ 2.3e-13 M^6`.
const GABRIEL_EPS: f64 = 3e-13;

/// Is `p` strictly inside the smallest sphere through the triangle `a, b, c`? Exact.
pub(crate) fn in_diametral_sphere(a: &P3, b: &P3, c: &P3, p: &P3) -> bool {
    // Stage 1: plain f64 with a semi-static bound.
    let d = |x: &P3| [x[0] - a[0], x[1] - a[1], x[2] - a[2]];
    let (u, w, q) = (d(b), d(c), d(p));
    let m = u
        .iter()
        .chain(&w)
        .chain(&q)
        .fold(0.0f64, |m, &x| fmax(m, x.abs()));
    if m > 1e-40 && m < 1e40 {
        let cr = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dt = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let n = cr(u, w);
        let g = dt(u, u) * dt(q, cr(w, n)) + dt(w, w) * dt(q, cr(n, u)) - dt(q, q) * dt(n, n);
        let m2 = m * m;
        let eps = GABRIEL_EPS * m2 * m2 * m2;
        if g > eps {
            return true;
        }
        if g < -eps {
            return false;
        }
    }
    let scale = [b, c, p]
        .iter()
        .flat_map(|x| (0..3).map(move |k| (x[k] - a[k]).abs()))
        .fold(0.0f64, f64::max);
    // Stage 2: running error bound.
    if scale < 1e40 {
        let g: Fe = gabriel_poly(a, b, c, p);
        // Absolute slack for possible underflow in intermediate products: at most ~30
        // operations, each losing ≤ 2^-1074, amplified by at most max(1, scale)^5.
        let slack = 1e-120;
        let bound = g.e * (1.0 + 1e-10) + slack;
        if g.v > bound {
            return true;
        }
        if g.v < -bound {
            return false;
        }
    }
    // Stage 3: exact.
    let g: Expansion = gabriel_poly(a, b, c, p);
    g.sign() > 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conventions() {
        let a = [0.0, 0.0, 0.0];
        let b = [1.0, 0.0, 0.0];
        let c = [0.0, 1.0, 0.0];
        let d = [0.0, 0.0, 1.0]; // above the ccw triangle a, b, c
        assert_eq!(orient3d(&a, &b, &c, &d), 1);
        assert_eq!(orient3d_exact(&a, &b, &c, &d), 1);
        let inside = [0.2, 0.2, 0.2];
        let outside = [5.0, 5.0, 5.0];
        assert_eq!(insphere(&a, &b, &c, &d, &inside), 1);
        assert_eq!(insphere(&a, &b, &c, &d, &outside), -1);
        let on = [1.0, 1.0, 0.0];
        assert_eq!(insphere(&a, &b, &c, &d, &on), 0);
        assert_eq!(insphere_exact(&a, &b, &c, &d, &on), 0);
        assert_eq!(insphere_exact(&a, &b, &c, &d, &inside), 1);
        // Perturbation: the highest-ranked query point is pushed outside.
        assert_eq!(insphere_sos([&a, &b, &c, &d], [0, 1, 2, 3], &on, 4), -1);
    }

    /// Lifted 4×4 determinant with expansions (independent of `robust`).
    fn insphere_expansion(p: [&P3; 4], e: &P3) -> i32 {
        let rows: Vec<[Expansion; 4]> = p
            .iter()
            .map(|q| {
                let d = [0, 1, 2].map(|k| Expansion::diff(q[k], e[k]));
                let l = d[0].mul(&d[0]).add(&d[1].mul(&d[1])).add(&d[2].mul(&d[2]));
                [d[0].clone(), d[1].clone(), d[2].clone(), l]
            })
            .collect();
        let det3 = |r: [usize; 3]| -> Expansion {
            let m = |i: usize, j: usize| &rows[r[i]][j];
            let t0 = m(1, 1).mul(m(2, 2)).sub(&m(1, 2).mul(m(2, 1)));
            let t1 = m(1, 0).mul(m(2, 2)).sub(&m(1, 2).mul(m(2, 0)));
            let t2 = m(1, 0).mul(m(2, 1)).sub(&m(1, 1).mul(m(2, 0)));
            m(0, 0)
                .mul(&t0)
                .sub(&m(0, 1).mul(&t1))
                .add(&m(0, 2).mul(&t2))
        };
        // Expansion along the lift column: sum of (-1)^(i+3) l_i M_i.
        let mut det = Expansion::default();
        for i in 0..4 {
            let others: Vec<usize> = (0..4).filter(|&k| k != i).collect();
            let term = rows[i][3].mul(&det3([others[0], others[1], others[2]]));
            det = if (i + 3) % 2 == 0 {
                det.add(&term)
            } else {
                det.sub(&term)
            };
        }
        det.sign()
    }

    #[test]
    fn robust_insphere_agrees_with_expansions() {
        let mut rng = crate::sort::SplitMix(42);
        let sphere = reconbench_testkit::points::integer_sphere(1105);
        let pts: Vec<P3> = sphere.iter().map(|p| p.to_array()).collect();
        // Calibrate the sign on a clearly inside point.
        let t = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let cal = insphere_expansion([&t[0], &t[1], &t[2], &t[3]], &[0.2, 0.2, 0.2]);
        let mut n_zero = 0;
        for round in 0..3000 {
            let mut q: Vec<P3> = (0..5).map(|_| pts[rng.below(pts.len())]).collect();
            let off = [0.0, 1e8, 0.1, 1e-3][round % 4];
            for p in &mut q {
                for k in 0..3 {
                    p[k] += off;
                }
            }
            if round % 3 == 1 {
                q[4][rng.below(3)] = q[4][0].next_up();
            }
            if round % 5 == 2 {
                let k = rng.below(3);
                q[4][k] = q[4][k].next_down();
            }
            let o = orient3d_exact(&q[0], &q[1], &q[2], &q[3]);
            if o == 0 {
                continue;
            }
            if o < 0 {
                q.swap(0, 1);
            }
            let mine = insphere_expansion([&q[0], &q[1], &q[2], &q[3]], &q[4]) * cal;
            assert_eq!(insphere_exact(&q[0], &q[1], &q[2], &q[3], &q[4]), mine);
            assert_eq!(insphere(&q[0], &q[1], &q[2], &q[3], &q[4]), mine);
            n_zero += usize::from(mine == 0);
        }
        assert!(n_zero > 100);
    }

    #[test]
    fn gabriel_filters_agree_with_exact() {
        let mut rng = crate::sort::SplitMix(5);
        let mut ties = 0;
        for k in 0..20000 {
            let mut p = [[0.0f64; 3]; 4];
            for q in &mut p {
                for c in q.iter_mut() {
                    *c = rng.below(5) as f64 * [1.0, 0.1, 1e-20, 3e15][k % 4];
                }
            }
            if k % 3 == 0 {
                p[3][0] = p[3][0].next_up();
            }
            let n: Expansion = {
                // Skip degenerate (collinear) triangles.
                let u = [0, 1, 2].map(|i| Expansion::diff(p[1][i], p[0][i]));
                let w = [0, 1, 2].map(|i| Expansion::diff(p[2][i], p[0][i]));
                let c = cross(&u, &w);
                dot(&c, &c)
            };
            if n.sign() == 0 {
                continue;
            }
            let exact: Expansion = gabriel_poly(&p[0], &p[1], &p[2], &p[3]);
            ties += usize::from(exact.sign() == 0);
            assert_eq!(
                in_diametral_sphere(&p[0], &p[1], &p[2], &p[3]),
                exact.sign() > 0,
                "{p:?}"
            );
        }
        assert!(ties > 100);
    }

    #[test]
    fn gabriel_exact() {
        let a = [0.0, 0.0, 0.0];
        let b = [2.0, 0.0, 0.0];
        let c = [0.0, 2.0, 0.0];
        // Diametral sphere: centre (1,1,0), radius sqrt 2.
        assert!(in_diametral_sphere(&a, &b, &c, &[1.0, 1.0, 1.0]));
        assert!(!in_diametral_sphere(&a, &b, &c, &[2.0, 2.0, 0.0])); // on the sphere
        assert!(!in_diametral_sphere(
            &a,
            &b,
            &c,
            &[1.0, 1.0, 2f64.sqrt() + 1e-15]
        ));
        assert!(in_diametral_sphere(
            &a,
            &b,
            &c,
            &[1.0, 1.0, std::f64::consts::SQRT_2.next_down()]
        ));
        // Tiny offsets far from the origin go through the exact path.
        let o = 1e8;
        let sh = |p: [f64; 3]| [p[0] + o, p[1] + o, p[2] + o];
        assert!(!in_diametral_sphere(
            &sh(a),
            &sh(b),
            &sh(c),
            &sh([2.0, 2.0, 0.0])
        ));
    }

    #[test]
    fn integer_predicates_agree_with_robust() {
        let mut rng = crate::sort::SplitMix(7);
        let mut zeros = 0;
        for k in 0..20000 {
            let scale = [1.0, 0.125, 1024.0, 1.0 / 80.0][k % 4];
            let r = [3usize, 9, 1000][k % 3];
            let mut p = [[0.0f64; 3]; 5];
            for q in &mut p {
                for c in q.iter_mut() {
                    *c = (rng.below(r) as f64 - (r / 2) as f64) * scale;
                }
            }
            if let Some(s) = crate::exact_int::orient3d(&p[0], &p[1], &p[2], &p[3]) {
                assert_eq!(s, orient3d_exact(&p[0], &p[1], &p[2], &p[3]));
                if s < 0 {
                    p.swap(0, 1);
                }
                if s != 0 {
                    let t = crate::exact_int::insphere(&p[0], &p[1], &p[2], &p[3], &p[4]).unwrap();
                    let want = insphere_exact(&p[0], &p[1], &p[2], &p[3], &p[4]);
                    assert_eq!(t, want, "{p:?}");
                    zeros += usize::from(t == 0);
                }
            }
        }
        assert!(zeros > 100);
        // Coordinates spanning too many bits are declined.
        assert!(
            crate::exact_int::orient3d(
                &[1.0, 0.0, 0.0],
                &[1e-30, 0.0, 0.0],
                &[0.0; 3],
                &[0.0, 0.0, 1.0]
            )
            .is_none()
        );
    }
}
