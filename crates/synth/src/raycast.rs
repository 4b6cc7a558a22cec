//! Ray casting against an exact signed distance: sphere tracing plus bracketed
//! refinement, used by [`crate::Shape::ray_intersect`]'s default.

use glam::DVec3;

/// A signed distance with the normal of the closest point.
pub type SdfFn<'a> = dyn Fn(DVec3) -> (f64, DVec3) + 'a;

/// First `t` in `[0, max_t]` with `sdf(origin + t dir) == 0` (to `1e-12 * diag`).
///
/// Sphere tracing never steps past the first crossing (the step is the exact distance to
/// the surface); near the surface, Newton steps on the signed distance (capped) speed up
/// convergence, and a sign change is refined by safeguarded regula falsi. Sign changes
/// without a zero (beside the boundary of an open sheet) are skipped.
pub fn sphere_trace(
    sdf: &SdfFn<'_>,
    origin: DVec3,
    dir: DVec3,
    max_t: f64,
    diag: f64,
) -> Option<f64> {
    let len = dir.length();
    if len == 0.0 || !len.is_finite() || max_t.is_nan() || max_t < 0.0 {
        return None;
    }
    let d = dir / len;
    let max_s = if max_t.is_finite() {
        max_t * len
    } else {
        f64::INFINITY
    };
    let tol = 1e-12 * diag.max(f64::MIN_POSITIVE);
    let (f0, _) = sdf(origin);
    if f0.abs() <= tol {
        return Some(0.0);
    }
    let mut sign = f0.signum();
    let mut s = 0.0;
    let mut g = f0.abs();
    let mut n = sdf(origin).1;
    for _ in 0..20_000 {
        let slope = sign * n.dot(d);
        let mut step = g;
        if g < 0.01 * diag && slope < -0.05 {
            step = (-g / slope).min(50.0 * g).min(0.01 * diag).max(g);
        }
        let s_new = s + step;
        if s_new > max_s + tol {
            // One last check at max_s.
            let (f, _) = sdf(origin + d * max_s);
            if sign * f <= tol && max_s > s {
                return refine(sdf, origin, d, s, g, max_s, sign * f, sign, tol).map(|x| x / len);
            }
            return None;
        }
        let (f, n_new) = sdf(origin + d * s_new);
        let g_new = sign * f;
        if g_new.abs() <= tol {
            return Some(s_new / len);
        }
        if g_new < 0.0 {
            if let Some(hit) = refine(sdf, origin, d, s, g, s_new, g_new, sign, tol) {
                return Some(hit / len);
            }
            // A sign flip without a zero crossing (beside the boundary of an open sheet):
            // continue from the other side.
            sign = -sign;
        }
        s = s_new;
        g = g_new.abs();
        n = n_new;
    }
    None
}

/// Refines a bracket `g(a) > 0 > g(b)`; `None` if it does not converge to a zero.
fn refine(
    sdf: &SdfFn<'_>,
    origin: DVec3,
    d: DVec3,
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
    sign: f64,
    tol: f64,
) -> Option<f64> {
    let mut side = 0i8;
    for _ in 0..300 {
        let mut m = (a * gb - b * ga) / (gb - ga);
        if !(m > a && m < b) {
            m = 0.5 * (a + b);
        }
        let gm = sign * sdf(origin + d * m).0;
        if gm.abs() <= tol || b - a <= tol {
            return if gm.abs() <= 4.0 * tol { Some(m) } else { None };
        }
        if gm > 0.0 {
            a = m;
            ga = gm;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        } else {
            b = m;
            gb = gm;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        }
    }
    None
}
