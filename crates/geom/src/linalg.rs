//! Small dense linear algebra: symmetric 3x3 eigen-decomposition, (weighted) covariance of
//! a point set and small weighted least squares.
//!
//! These are the building blocks of normal estimation (PCA of a neighbourhood), MLS and jet
//! fitting. They are thin, validated wrappers around nalgebra 0.35: inputs are checked
//! (non-finite values, lengths, weights) and reported as [`GeomError`] instead of panicking
//! or silently producing NaN, and outputs follow fixed conventions (ascending eigenvalues,
//! deterministic eigenvector signs) so that results are reproducible.

use glam::{DMat3, DVec3};
use nalgebra::{DMatrix, DVector, Matrix3};

use crate::error::{GeomError, Result, check_finite};

/// Maximum number of implicit QR sweeps for the 3x3 eigen-solver. A symmetric 3x3
/// tridiagonal matrix converges in a handful of sweeps; the bound only turns a
/// pathological non-convergence into an error instead of an endless loop.
const EIGEN_MAX_ITER: usize = 1000;

/// Maximum number of SVD sweeps in [`weighted_least_squares`] (same reasoning).
const SVD_MAX_ITER: usize = 10_000;

/// Eigen-decomposition of a symmetric 3x3 matrix.
///
/// `values` are ascending; `vectors[i]` is the unit eigenvector of `values[i]`. The vectors
/// form a right-handed orthonormal basis (`vectors[2] == vectors[0].cross(vectors[1])`).
/// Signs are made deterministic: the largest-magnitude component of `vectors[0]` and
/// `vectors[1]` is positive (ties to the lower axis); `vectors[2]` follows from the
/// cross product. For repeated eigenvalues any orthonormal basis of the eigenspace is
/// correct; this one is whatever the solver produced, made orthonormal.
///
/// For PCA of a neighbourhood, `vectors[0]` (smallest variance) is the normal direction
/// and `values[0] / (values[0] + values[1] + values[2])` the surface variation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymEigen3 {
    /// Eigenvalues in ascending order.
    pub values: [f64; 3],
    /// Unit eigenvectors, `vectors[i]` belonging to `values[i]`.
    pub vectors: [DVec3; 3],
}

impl SymEigen3 {
    /// Rebuilds `V diag(values) V^T` (useful to check the decomposition).
    pub fn reconstruct(&self) -> DMat3 {
        let mut m = DMat3::ZERO;
        for i in 0..3 {
            let v = self.vectors[i];
            m += self.values[i] * outer(v, v);
        }
        m
    }
}

/// Outer product `a b^T`.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Flips `v` so that its largest-magnitude component is positive.
fn canonical_sign(v: DVec3) -> DVec3 {
    let a = v.abs();
    let c = if a.x >= a.y && a.x >= a.z {
        v.x
    } else if a.y >= a.z {
        v.y
    } else {
        v.z
    };
    if c < 0.0 { -v } else { v }
}

/// The symmetric part of `m` and its largest absolute entry (the eigen solvers work on
/// the matrix scaled by it); an error naming the column for a non-finite entry.
#[inline]
fn symmetrized(m: DMat3) -> Result<(DMat3, f64)> {
    check_finite("matrix column", &[m.x_axis, m.y_axis, m.z_axis])?;
    let sym = 0.5 * (m + m.transpose());
    let scale = sym
        .to_cols_array()
        .iter()
        .fold(0.0f64, |s, x| s.max(x.abs()));
    Ok((sym, scale))
}

/// Eigen-decomposition of the symmetric 3x3 matrix `m` (see [`SymEigen3`]).
///
/// Only the symmetric part `(m + m^T) / 2` is used, so a matrix that is symmetric up to
/// rounding is fine. The matrix is scaled by its largest entry before the solve, so
/// very large or very small magnitudes do not overflow; the values are scaled back.
/// Repeated (double, triple) eigenvalues are handled: the vectors are still orthonormal.
///
/// Errors: [`GeomError::NonFinite`] (naming the column) for NaN/infinite entries, and
/// [`GeomError::InvalidInput`] if the iteration does not converge (not expected for
/// finite input).
pub fn sym_eigen3(m: DMat3) -> Result<SymEigen3> {
    let (sym, scale) = symmetrized(m)?;
    if scale == 0.0 {
        return Ok(SymEigen3 {
            values: [0.0; 3],
            vectors: [DVec3::X, DVec3::Y, DVec3::Z],
        });
    }
    let s = sym * (1.0 / scale);
    // nalgebra is column-major like glam; the matrix is symmetric anyway.
    let nm = Matrix3::from_fn(|r, c| s.col(c)[r]);
    let eig = nm
        .try_symmetric_eigen(f64::EPSILON, EIGEN_MAX_ITER)
        .ok_or_else(|| {
            GeomError::InvalidInput(
                "symmetric 3x3 eigen-decomposition did not converge".to_string(),
            )
        })?;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let col = |i: usize| {
        let c = eig.eigenvectors.column(i);
        DVec3::new(c[0], c[1], c[2])
    };
    // Re-orthonormalise (Gram-Schmidt + cross product): removes the last ulps of
    // non-orthogonality and makes the basis right-handed.
    let v0 = canonical_sign(col(order[0]).normalize());
    let v1 = col(order[1]);
    let v1 = canonical_sign((v1 - v1.dot(v0) * v0).normalize());
    let v2 = v0.cross(v1);
    if !(v0.is_finite() && v1.is_finite() && v2.is_finite()) {
        return Err(GeomError::InvalidInput(
            "symmetric 3x3 eigen-decomposition produced degenerate eigenvectors".to_string(),
        ));
    }
    let values = order.map(|i| eig.eigenvalues[i] * scale);
    Ok(SymEigen3 {
        values,
        vectors: [v0, v1, v2],
    })
}

/// Smallest eigenpair of a symmetric 3x3 matrix, with all three eigenvalues: the fast
/// path of PCA normal estimation ([`sym_eigen3_smallest`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmallestEigen3 {
    /// Eigenvalues in ascending order.
    pub values: [f64; 3],
    /// Unit eigenvector of `values[0]`, with the sign convention of [`SymEigen3`] (its
    /// largest-magnitude component is positive, ties to the lower axis).
    pub vector: DVec3,
}

/// Relative gap `(l1 - l0) / max|l|` below which [`sym_eigen3_smallest`] hands the
/// matrix to the iterative solver. The closed-form vector's error grows like
/// `eps * max|l| / (l1 - l0)`, as any solver's does, but the two solvers' noise would no
/// longer agree closely; near-repeated smallest eigenvalues (isotropic or rod-like
/// neighbourhoods, all coincident or collinear points) are rare in surface data, so the
/// fallback costs nothing measurable.
const SMALLEST_GAP_REL: f64 = 1e-4;

/// Unit null vector of the (numerically rank-2) symmetric matrix with rows `r0, r1, r2`:
/// the largest cross product of two rows. `None` when all cross products vanish.
fn null_vector(r0: DVec3, r1: DVec3, r2: DVec3) -> Option<DVec3> {
    let c = [r0.cross(r1), r0.cross(r2), r1.cross(r2)];
    let l = c.map(DVec3::length_squared);
    let best = if l[0] >= l[1] && l[0] >= l[2] {
        0
    } else if l[1] >= l[2] {
        1
    } else {
        2
    };
    (l[best] > 0.0 && l[best].is_finite()).then(|| c[best] / l[best].sqrt())
}

/// Smallest eigenvalue's eigenvector of the symmetric 3x3 matrix `m`, plus all three
/// eigenvalues: the same result as [`sym_eigen3`] (`values`, `vectors[0]`) up to
/// rounding, several times faster.
///
/// Method: the smallest root of the characteristic cubic by Newton's method (no
/// trigonometric calls; the other two roots from the remaining quadratic, for the
/// separation test only), the eigenvector as the largest cross product of two rows of
/// `A - l0 I`, and the two larger eigenvalues recomputed from the 2x2 restriction of `A`
/// to the plane orthogonal to the vector. Where the gap `l1 - l0` is below 0.25 of the
/// largest magnitude, the vector is refined once: `l0` is replaced by the Rayleigh
/// quotient of the first vector (error quadratic in the vector's error) and the cross
/// product repeated. Matrices whose two smallest eigenvalues are within
/// 1e-4 of each other (relative to the largest magnitude, `SMALLEST_GAP_REL`), including
/// every degenerate or isotropic case, are solved by [`sym_eigen3`] instead.
///
/// Like [`sym_eigen3`], only the symmetric part is used and the matrix is scaled by its
/// largest entry. Errors: as [`sym_eigen3`].
pub fn sym_eigen3_smallest(m: DMat3) -> Result<SmallestEigen3> {
    match smallest_fast(m)? {
        Some(f) => Ok(f.with_values()),
        None => full_smallest(m),
    }
}

/// The smallest eigenvalue's unit eigenvector of the symmetric 3x3 matrix `m` when the
/// middle eigenvalue exceeds `min_ratio` times the largest (the points span a plane),
/// else `None`: exactly `sym_eigen3_smallest(m)` followed by the test
/// `values[1] > min_ratio * max(values[2], f64::MIN_POSITIVE)`, the same vector bit for
/// bit.
///
/// Why: PCA normals need the vector and that test only. Where the fast path applies,
/// the test cannot fail for `min_ratio <= 1e-6` (the gap test gives
/// `l1 >= 1e-4 max|l|` with `l0 >= 0`), so the two larger eigenvalues are not computed,
/// which is most of the cost after the vector.
///
/// Errors: as [`sym_eigen3_smallest`].
pub fn sym_eigen3_smallest_planar(m: DMat3, min_ratio: f64) -> Result<Option<DVec3>> {
    let planar = |e: SmallestEigen3| {
        (e.values[1] > min_ratio * e.values[2].max(f64::MIN_POSITIVE)).then_some(e.vector)
    };
    match smallest_fast(m)? {
        Some(f) if f.l0 >= 0.0 && min_ratio <= PLANAR_FAST_RATIO_MAX => {
            Ok(Some(canonical_sign(f.vector)))
        }
        Some(f) => Ok(planar(f.with_values())),
        None => full_smallest(m).map(planar),
    }
}

/// Largest `min_ratio` for which [`sym_eigen3_smallest_planar`] may skip the two larger
/// eigenvalues: with `l0 >= 0` and `l1 - l0 > SMALLEST_GAP_REL max|l|`, the ratio
/// `l1 / l2` is at least about `SMALLEST_GAP_REL / 3`.
const PLANAR_FAST_RATIO_MAX: f64 = 1e-6;

/// [`sym_eigen3`]'s smallest eigenpair and values, for matrices the fast path hands on.
fn full_smallest(m: DMat3) -> Result<SmallestEigen3> {
    sym_eigen3(m).map(|e| SmallestEigen3 {
        values: e.values,
        vector: e.vectors[0],
    })
}

/// The fast path's result: the (unsigned) unit vector of the smallest eigenvalue `l0` of
/// the scaled matrix `a = sym(m) / scale`.
struct FastSmallest {
    a: DMat3,
    scale: f64,
    l0: f64,
    vector: DVec3,
}

impl FastSmallest {
    /// All three eigenvalues: the other two from the 2x2 restriction of `a` to the plane
    /// orthogonal to the vector (stable even when they nearly coincide, where the cubic's
    /// roots are not).
    fn with_values(&self) -> SmallestEigen3 {
        let (a, v) = (self.a, self.vector);
        let (e1, e2) = v.any_orthonormal_pair();
        let (ae1, ae2) = (a * e1, a * e2);
        let (b11, b22, b12) = (e1.dot(ae1), e2.dot(ae2), e1.dot(ae2));
        let mean = 0.5 * (b11 + b22);
        let half = 0.5 * (b11 - b22);
        let rad = (half * half + b12 * b12).sqrt();
        let (l1, l2) = (mean - rad, mean + rad);
        let l0 = v.dot(a * v).min(l1);
        let scale = self.scale;
        SmallestEigen3 {
            values: [l0 * scale, l1 * scale, l2 * scale],
            vector: canonical_sign(v),
        }
    }
}

/// The closed-form part of [`sym_eigen3_smallest`]; `None` where the matrix goes to the
/// iterative solver (zero, not separated, no converged root or null vector).
fn smallest_fast(m: DMat3) -> Result<Option<FastSmallest>> {
    let (sym, scale) = symmetrized(m)?;
    if scale == 0.0 {
        return Ok(None);
    }
    let a = sym * (1.0 / scale);
    let (a00, a11, a22) = (a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let (a01, a02, a12) = (a.y_axis.x, a.z_axis.x, a.z_axis.y);
    // Characteristic polynomial p(l) = -l^3 + c2 l^2 - c1 l + c0.
    let c2 = a00 + a11 + a22;
    let c1 = a00 * a11 - a01 * a01 + a00 * a22 - a02 * a02 + a11 * a22 - a12 * a12;
    let c0 = a00 * (a11 * a22 - a12 * a12) - a01 * (a01 * a22 - a12 * a02)
        + a02 * (a01 * a12 - a11 * a02);
    let Some(l0) = smallest_root(c2, c1, c0) else {
        return Ok(None);
    };
    // The two others from the remaining quadratic l^2 - s l + t (only for the
    // separation test; reported values come from `FastSmallest::with_values`).
    let s = c2 - l0;
    let t = c1 - l0 * s;
    let disc = 0.25 * s * s - t;
    let l1 = 0.5 * s - disc.max(0.0).sqrt();
    let mag = l0
        .abs()
        .max(0.5 * s + disc.max(0.0).sqrt())
        .max(c2.abs() / 3.0);
    // Written so that a NaN (not expected for finite input) also takes the fallback.
    let separated = l1 - l0 > SMALLEST_GAP_REL * mag;
    if !separated {
        return Ok(None);
    }
    let rows = |l: f64| {
        (
            DVec3::new(a00 - l, a01, a02),
            DVec3::new(a01, a11 - l, a12),
            DVec3::new(a02, a12, a22 - l),
        )
    };
    let (r0, r1, r2) = rows(l0);
    let Some(v) = null_vector(r0, r1, r2) else {
        return Ok(None);
    };
    // Newton's root is accurate to rounding, so the vector's error is about
    // eps / gap^2 (relative to |l|max); where the gap is small the vector is refined once
    // from the Rayleigh quotient, whose error is quadratic in the vector's.
    let vector = if l1 - l0 > REFINE_GAP_REL * mag {
        v
    } else {
        let (r0, r1, r2) = rows(v.dot(a * v));
        match null_vector(r0, r1, r2) {
            Some(v) => v,
            None => return Ok(None),
        }
    };
    Ok(Some(FastSmallest {
        a,
        scale,
        l0,
        vector,
    }))
}

/// Eigenvalue gap (relative to the largest magnitude) above which the eigenvector from
/// Newton's root is not refined.
const REFINE_GAP_REL: f64 = 0.25;

/// Smallest root of `-l^3 + c2 l^2 - c1 l + c0` (the characteristic polynomial of a
/// symmetric matrix scaled to entries of at most 1, so all roots are real and in
/// `[-3, 3]`), by Newton's method from the left of every root: from there the iterates
/// increase monotonically to the smallest root, quadratically once near it. `None` when
/// it has not settled after a few dozen steps (a double smallest root converges only
/// linearly; such matrices are not separated anyway and go to the full solver).
fn smallest_root(c2: f64, c1: f64, c0: f64) -> Option<f64> {
    // Start at 0 when the matrix is positive semi-definite up to rounding (the common
    // case, covariances: few steps), else at the bound -3.
    let p = |l: f64| ((c2 - l) * l - c1) * l + c0;
    let mut l = if c0 >= 0.0 && c1 >= 0.0 && c2 >= 0.0 {
        0.0
    } else {
        -3.0
    };
    for _ in 0..40 {
        let dp = (2.0 * c2 - 3.0 * l) * l - c1;
        let step = p(l) / dp;
        if step.is_nan() {
            return None;
        }
        let next = l - step;
        if next <= l || step.abs() <= 1e-15 * (1.0 + l.abs()) {
            return Some(next.max(l));
        }
        l = next;
    }
    None
}

/// Weighted mean and covariance of a point set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Covariance {
    /// Weighted centroid `sum w_i p_i / sum w_i`.
    pub centroid: DVec3,
    /// Weighted covariance `sum w_i (p_i - c)(p_i - c)^T / sum w_i` (population
    /// normalisation, no Bessel correction: PCA only needs the shape of the matrix).
    pub matrix: DMat3,
    /// `sum w_i` (the number of points when unweighted).
    pub weight_sum: f64,
}

/// Centroid and covariance matrix of `points`, optionally weighted.
///
/// Uses two passes (centroid first, then centred outer products), which keeps precision
/// for clouds far from the origin. `weights`, when given, must have one finite,
/// non-negative value per point with a positive sum.
///
/// Errors: empty input, non-finite points, weight length mismatch, negative or non-finite
/// weights, zero total weight.
pub fn covariance(points: &[DVec3], weights: Option<&[f64]>) -> Result<Covariance> {
    if points.is_empty() {
        return Err(GeomError::InvalidInput(
            "covariance of an empty point set".to_string(),
        ));
    }
    check_finite("point", points)?;
    if let Some(w) = weights {
        crate::error::check_len("weights", w.len(), points.len(), "point")?;
        if let Some(i) = w.iter().position(|x| !x.is_finite() || *x < 0.0) {
            return Err(GeomError::InvalidParameter {
                name: "weights",
                message: format!("weight {i} is {} (must be finite and >= 0)", w[i]),
            });
        }
    }
    let weight = |i: usize| weights.map_or(1.0, |w| w[i]);
    let mut wsum = 0.0;
    let mut acc = DVec3::ZERO;
    for (i, &p) in points.iter().enumerate() {
        let wi = weight(i);
        wsum += wi;
        acc += wi * p;
    }
    if wsum <= 0.0 {
        return Err(GeomError::InvalidParameter {
            name: "weights",
            message: "the weights sum to zero".to_string(),
        });
    }
    let centroid = acc / wsum;
    let mut m = DMat3::ZERO;
    for (i, &p) in points.iter().enumerate() {
        let d = p - centroid;
        m += outer(weight(i) * d, d);
    }
    Ok(Covariance {
        centroid,
        matrix: m * (1.0 / wsum),
        weight_sum: wsum,
    })
}

/// Solves the weighted least-squares problem `min_x sum_i w_i (a_i . x - b_i)^2`.
///
/// `a_rows` is the `m x n` design matrix in row-major order (`m = a_rows.len() / n`), `b`
/// has `m` values and `w` has `m` non-negative weights (or is empty for unit weights).
/// The rows are scaled by `sqrt(w_i)`, the columns are equilibrated to unit norm (so that
/// e.g. monomials of very different magnitudes do not spoil the rank test), and the
/// system is solved by SVD.
///
/// The numerical rank counts singular values above `sigma_max * max(m, n) * f64::EPSILON`
/// (the LAPACK/NumPy default); a rank below `n` (including `m < n` effective rows, or an
/// all-zero column) is reported as [`GeomError::RankDeficient`] rather than returning an
/// arbitrary minimum-norm solution, because callers (MLS, jet fits) must then fall back
/// to a lower degree.
///
/// Errors: `n == 0`, lengths that do not match, non-finite entries, negative weights,
/// rank deficiency.
pub fn weighted_least_squares(a_rows: &[f64], b: &[f64], w: &[f64], n: usize) -> Result<Vec<f64>> {
    if n == 0 {
        return Err(GeomError::InvalidParameter {
            name: "n",
            message: "the number of unknowns must be positive".to_string(),
        });
    }
    let m = a_rows.len() / n;
    if m * n != a_rows.len() {
        return Err(GeomError::InvalidInput(format!(
            "design matrix has {} values, not a multiple of n = {n} columns",
            a_rows.len()
        )));
    }
    crate::error::check_len("right-hand side", b.len(), m, "row")?;
    if !w.is_empty() {
        crate::error::check_len("weights", w.len(), m, "row")?;
    }
    if let Some(i) = a_rows.iter().position(|x| !x.is_finite()) {
        return Err(GeomError::InvalidInput(format!(
            "design matrix entry ({}, {}) is not finite ({})",
            i / n,
            i % n,
            a_rows[i]
        )));
    }
    if let Some(i) = b.iter().position(|x| !x.is_finite()) {
        return Err(GeomError::InvalidInput(format!(
            "right-hand side value {i} is not finite ({})",
            b[i]
        )));
    }
    if let Some(i) = w.iter().position(|x| !x.is_finite() || *x < 0.0) {
        return Err(GeomError::InvalidParameter {
            name: "weights",
            message: format!("weight {i} is {} (must be finite and >= 0)", w[i]),
        });
    }
    if m < n {
        return Err(GeomError::RankDeficient { rank: m, cols: n });
    }
    let sw = |i: usize| if w.is_empty() { 1.0 } else { w[i].sqrt() };
    let mut a = DMatrix::from_fn(m, n, |r, c| sw(r) * a_rows[r * n + c]);
    let rhs = DVector::from_fn(m, |r, _| sw(r) * b[r]);
    let mut col_scale = vec![0.0; n];
    for c in 0..n {
        let norm = a.column(c).norm();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(GeomError::RankDeficient {
                rank: n - 1,
                cols: n,
            });
        }
        col_scale[c] = 1.0 / norm;
        a.column_mut(c).scale_mut(col_scale[c]);
    }
    let svd = nalgebra::SVD::try_new(a, true, true, f64::EPSILON, SVD_MAX_ITER)
        .ok_or_else(|| GeomError::InvalidInput("least-squares SVD did not converge".to_string()))?;
    let smax = svd.singular_values.max();
    let tol = smax * (m.max(n) as f64) * f64::EPSILON;
    let rank = svd.rank(tol);
    if rank < n {
        return Err(GeomError::RankDeficient { rank, cols: n });
    }
    let x = svd
        .solve(&rhs, tol)
        .map_err(|e| GeomError::InvalidInput(format!("least-squares solve failed: {e}")))?;
    let out: Vec<f64> = (0..n).map(|c| x[c] * col_scale[c]).collect();
    if out.iter().any(|v| !v.is_finite()) {
        return Err(GeomError::InvalidInput(
            "least-squares solution is not finite".to_string(),
        ));
    }
    Ok(out)
}
