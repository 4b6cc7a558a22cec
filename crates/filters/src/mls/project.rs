//! The projection MLS operator of Levin and Alexa et al. (seed 002 §2.5): a weighted
//! reference plane through the neighbourhood, then a weighted polynomial height field
//! over it, evaluated at the foot of the query.
//!
//! Both `mls` and `mls-sharp` call [`mls_project`]; `mls-sharp` only edits the
//! neighbourhood it is given. Everything here is allocation-free: the plane fit is a
//! running weighted covariance and the polynomial fit a Givens QR of at most six columns
//! accumulated row by row, so the caller's scratch buffers are the only memory.

use glam::{DMat3, DVec3};
use reconbench_geom::linalg::sym_eigen3_smallest;
use serde::{Deserialize, Serialize};

/// Degree of the local height polynomial `g` of step 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PolyDegree {
    /// `g = c0`: the projection onto the reference plane.
    Constant,
    /// `g = c0 + c1 x + c2 y`.
    Linear,
    /// `g = c0 + c1 x + c2 y + c3 x^2 + c4 xy + c5 y^2` (default).
    #[default]
    Quadratic,
}

impl PolyDegree {
    /// Number of polynomial coefficients.
    pub fn columns(self) -> usize {
        match self {
            PolyDegree::Constant => 1,
            PolyDegree::Linear => 3,
            PolyDegree::Quadratic => 6,
        }
    }
}

/// Settings of one projection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MlsConfig {
    /// Gaussian width `h` of `theta(d) = exp(-d^2 / h^2)`, absolute units.
    pub h: f64,
    /// Maximal fixed-point iterations of the reference plane (1 = the non-iterative
    /// plane through the weighted centroid about the query).
    pub plane_iters: usize,
    /// The plane iteration stops when the foot moves less than this (absolute).
    pub tolerance: f64,
    /// Degree of the height polynomial.
    pub degree: PolyDegree,
}

/// What [`mls_project`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// The projected point `r' = q + g(0, 0) a`.
    pub point: DVec3,
    /// Unit normal `a` of the reference plane (sign: see [`mls_project`]).
    pub normal: DVec3,
    /// Plane iterations done.
    pub iterations: u32,
    /// The polynomial fell back to a lower degree (too few effective points or a
    /// rank-deficient design).
    pub lowered_degree: bool,
    /// Some plane step had fewer than 3 effective weights and used unit weights.
    pub unweighted: bool,
}

/// Relative weight below which a point does not count as effective (seed 002 §2.5).
const EFFECTIVE_W: f64 = 1e-12;
/// A diagonal entry of the QR factor below this fraction of the largest one makes the
/// polynomial design rank-deficient (a condition number above about 1e12 in the Gram
/// matrix, seed 002 §2.5).
const RANK_TOL: f64 = 1e-6;

/// Weights `exp(-(d_i^2 - min d^2) / h^2)` about `q` into `w`: the Gaussian up to one
/// common factor, which every weighted mean and least-squares fit here cancels, so no
/// weight underflows however small `h` is relative to the distances.
fn relative_weights(nbrs: &[DVec3], q: DVec3, inv_h2: f64, w: &mut [f64]) -> usize {
    let mut dmin = f64::INFINITY;
    for (wi, p) in w.iter_mut().zip(nbrs) {
        *wi = (*p - q).length_squared();
        dmin = dmin.min(*wi);
    }
    let mut effective = 0;
    for wi in w.iter_mut() {
        *wi = (-(*wi - dmin) * inv_h2).exp();
        effective += usize::from(*wi > EFFECTIVE_W);
    }
    effective
}

/// Weighted centroid and covariance; `None` without positive weight.
fn weighted_plane(nbrs: &[DVec3], w: &[f64]) -> Option<(DVec3, DMat3)> {
    let mut ws = 0.0;
    let mut c = DVec3::ZERO;
    for (p, &wi) in nbrs.iter().zip(w) {
        ws += wi;
        c += wi * *p;
    }
    if ws.is_nan() || ws <= 0.0 {
        return None;
    }
    c /= ws;
    let mut m = [0.0f64; 6];
    for (p, &wi) in nbrs.iter().zip(w) {
        let d = *p - c;
        m[0] += wi * d.x * d.x;
        m[1] += wi * d.x * d.y;
        m[2] += wi * d.x * d.z;
        m[3] += wi * d.y * d.y;
        m[4] += wi * d.y * d.z;
        m[5] += wi * d.z * d.z;
    }
    let cov = DMat3::from_cols(
        DVec3::new(m[0], m[1], m[2]),
        DVec3::new(m[1], m[3], m[4]),
        DVec3::new(m[2], m[4], m[5]),
    ) * (1.0 / ws);
    Some((c, cov))
}

/// Upper-triangular factor of an incremental Givens QR with at most 6 columns.
#[derive(Debug, Clone, Copy)]
struct Qr6 {
    n: usize,
    r: [[f64; 6]; 6],
    qtb: [f64; 6],
}

impl Qr6 {
    fn new(n: usize) -> Self {
        Self {
            n,
            r: [[0.0; 6]; 6],
            qtb: [0.0; 6],
        }
    }

    /// Adds the row `(v, b)` (already scaled by the square root of its weight).
    fn add_row(&mut self, mut v: [f64; 6], mut b: f64) {
        for j in 0..self.n {
            if v[j] == 0.0 {
                continue;
            }
            let rjj = self.r[j][j];
            let rho = rjj.hypot(v[j]);
            let (c, s) = (rjj / rho, v[j] / rho);
            for l in j..self.n {
                let (a, x) = (self.r[j][l], v[l]);
                self.r[j][l] = c * a + s * x;
                v[l] = -s * a + c * x;
            }
            let a = self.qtb[j];
            self.qtb[j] = c * a + s * b;
            b = -s * a + c * b;
        }
    }

    /// Back substitution; `None` when the factor is numerically rank-deficient.
    fn solve(&self) -> Option<[f64; 6]> {
        let n = self.n;
        let dmax = (0..n).map(|j| self.r[j][j].abs()).fold(0.0, f64::max);
        if dmax.is_nan() || dmax <= 0.0 || (0..n).any(|j| self.r[j][j].abs() <= RANK_TOL * dmax) {
            return None;
        }
        let mut x = [0.0; 6];
        for j in (0..n).rev() {
            let mut s = self.qtb[j];
            for l in j + 1..n {
                s -= self.r[j][l] * x[l];
            }
            x[j] = s / self.r[j][j];
        }
        x.iter().all(|v| v.is_finite()).then_some(x)
    }
}

/// Fits `g` of `degree` to the heights over the plane `(q, e1, e2, a)` and returns
/// `g(0, 0)`, lowering the degree when the fit is under-determined or rank-deficient.
/// Coordinates are divided by `h` so the monomials are of order one.
fn height_at_foot(
    nbrs: &[DVec3],
    w: &[f64],
    effective: usize,
    frame: (DVec3, DVec3, DVec3, DVec3),
    h: f64,
    degree: PolyDegree,
) -> (f64, bool) {
    let (q, e1, e2, a) = frame;
    let inv_h = 1.0 / h;
    let mut deg = degree;
    let mut lowered = false;
    loop {
        let cols = deg.columns();
        if effective >= cols {
            let mut qr = Qr6::new(cols);
            for (p, &wi) in nbrs.iter().zip(w) {
                if wi <= 0.0 {
                    continue;
                }
                let d = *p - q;
                let (x, y, f) = (d.dot(e1) * inv_h, d.dot(e2) * inv_h, d.dot(a) * inv_h);
                let s = wi.sqrt();
                let v = [s, s * x, s * y, s * x * x, s * x * y, s * y * y];
                qr.add_row(v, s * f);
            }
            if let Some(c) = qr.solve() {
                return (c[0] * h, lowered);
            }
        }
        lowered = true;
        deg = match deg {
            PolyDegree::Quadratic => PolyDegree::Linear,
            PolyDegree::Linear => PolyDegree::Constant,
            // The foot of the plane itself: the weighted mean height is zero there
            // (the plane passes through the weighted centroid).
            PolyDegree::Constant => return (0.0, true),
        };
    }
}

/// Projects `r` onto the MLS surface of `nbrs` (seed 002 §2.5). `w` is scratch of at
/// least `nbrs.len()` values. `hint` orients the normal (`a . hint >= 0`) when it is
/// nonzero; otherwise the eigenvector's sign convention holds (largest component
/// positive). `None` when the neighbourhood spans no plane (fewer than 3 points, all
/// coincident or collinear).
pub fn mls_project(
    r: DVec3,
    nbrs: &[DVec3],
    cfg: &MlsConfig,
    hint: DVec3,
    w: &mut Vec<f64>,
) -> Option<Projection> {
    let n = nbrs.len();
    if n < 3 {
        return None;
    }
    w.clear();
    w.resize(n, 0.0);
    let inv_h2 = 1.0 / (cfg.h * cfg.h);
    let mut q = r;
    let mut a_prev = hint;
    let mut a = DVec3::ZERO;
    let mut unweighted = false;
    let mut iterations = 0;
    for _ in 0..cfg.plane_iters.max(1) {
        iterations += 1;
        // ASSUMPTION W-30: the plane of step 1 by the fixed-point iteration "plane
        // through the weighted centroid, weights recentred at the foot q" (seed 002
        // §2.5); plane_iters = 1 is the non-iterative variant.
        let eff = relative_weights(nbrs, q, inv_h2, w);
        if eff < 3 {
            // ASSUMPTION W-31: fewer than 3 effective weights -> unit weights for this
            // step (seed 002 §2.5).
            w.iter_mut().for_each(|x| *x = 1.0);
            unweighted = true;
        }
        let (c, cov) = weighted_plane(nbrs, w)?;
        let eig = sym_eigen3_smallest(cov).ok()?;
        // Collinear or coincident points: no plane (the two smallest eigenvalues
        // vanish against the largest).
        if eig.values[1].is_nan() || eig.values[1] <= 1e-14 * eig.values[2].max(f64::MIN_POSITIVE) {
            return None;
        }
        a = eig.vector;
        if a.dot(a_prev) < 0.0 {
            a = -a;
        }
        a_prev = a;
        let q_new = r - (r - c).dot(a) * a;
        let moved = (q_new - q).length();
        q = q_new;
        if moved < cfg.tolerance {
            break;
        }
    }
    let eff = relative_weights(nbrs, q, inv_h2, w);
    if eff < 3 {
        w.iter_mut().for_each(|x| *x = 1.0);
        unweighted = true;
    }
    let e1 = a.any_orthonormal_vector();
    let e2 = a.cross(e1);
    // ASSUMPTION W-32: quadratic height polynomial by weighted least squares (QR),
    // falling back to linear, then constant, when under-determined (seed 002 §2.5).
    let (g0, lowered) = height_at_foot(
        nbrs,
        w,
        if unweighted { n } else { eff },
        (q, e1, e2, a),
        cfg.h,
        cfg.degree,
    );
    Some(Projection {
        point: q + g0 * a,
        normal: a,
        iterations,
        lowered_degree: lowered,
        unweighted,
    })
}
