//! Stage 1 of EBT (paper §4.1, Eqs. 2-6): local quadrics `S = a u^2 + b uv + c v^2` fitted
//! by least squares on small neighbourhoods of randomly drawn centres, and the maximum
//! second derivatives M1, M2, M3 over them.

use glam::{DMat3, DVec3};
use rand::SeedableRng;
use rand::seq::index;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use reconbench_geom::linalg::{covariance, sym_eigen3};
use reconbench_geom::method::MethodError;
use reconbench_geom::spatial::PointIndex;

use super::params::{Aggregation, Derivatives, Neighborhood};

/// Condition number of `A^T A` above which a patch is skipped (spec §3.2 step 6).
const MAX_COND: f64 = 1e12;

/// Result of the curvature estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Curvature {
    /// M1, M2, M3: the maxima of `|d2S/du2|`, `|d2S/dudv|`, `|d2S/dv2|` in the chosen
    /// convention (literal coefficients or exact derivatives) and aggregation.
    pub m: [f64; 3],
    /// Per fitted patch, the three values before aggregation (literal or exact).
    pub per_patch: Vec<[f64; 3]>,
    /// Patches drawn (K).
    pub drawn: usize,
    /// Patches skipped as ill-conditioned.
    pub skipped: usize,
}

impl Curvature {
    /// `M1 + 2 M2 + M3`, the curvature term of Eqs. 11-16.
    pub fn sum(&self) -> f64 {
        self.m[0] + 2.0 * self.m[1] + self.m[2]
    }
}

/// Options of [`estimate`].
#[derive(Debug, Clone, Copy)]
pub struct CurvatureOpts {
    /// Points per patch N.
    pub n: usize,
    /// Neighbourhood rule.
    pub neighborhood: Neighborhood,
    /// Number of patches; 0 = ASSUMPTION E1.
    pub patches: usize,
    /// Derivative convention.
    pub derivatives: Derivatives,
    /// Aggregation over patches.
    pub aggregation: Aggregation,
}

/// The number of patches K for `n` points.
pub fn default_patches(n: usize) -> usize {
    // ASSUMPTION E1: K = min(200, max(20, n/500)) centres, uniform at random, seeded.
    (n / 500).clamp(20, 200)
}

/// The quadric coefficients `(a, b, c)` of the patch of `nbrs` around `centre`, or `None`
/// when the fit is ill-conditioned. `scratch` must hold the neighbour positions.
pub fn fit_quadric(centre: DVec3, nbrs: &[DVec3]) -> Option<[f64; 3]> {
    if nbrs.len() < 3 {
        return None;
    }
    // Step 2: plane fit (PCA of the same points); the normal is the smallest-variance axis.
    let cov = covariance(nbrs, None).ok()?;
    let eig = sym_eigen3(cov.matrix).ok()?;
    let normal = eig.vectors[0];
    // ASSUMPTION E3: u is the largest-variance direction, v = N x u.
    let u_axis = eig.vectors[2];
    let v_axis = normal.cross(u_axis);
    // Steps 4-6: local coordinates about the centre, rows [u^2, uv, v^2], normal equations.
    let mut ata = DMat3::ZERO;
    let mut atb = DVec3::ZERO;
    for &p in nbrs {
        let d = p - centre;
        let (u, v, s) = (d.dot(u_axis), d.dot(v_axis), d.dot(normal));
        let row = DVec3::new(u * u, u * v, v * v);
        ata += DMat3::from_cols(row * row.x, row * row.y, row * row.z);
        atb += row * s;
    }
    let e = sym_eigen3(ata).ok()?;
    let (lo, hi) = (e.values[0].abs(), e.values[2].abs());
    if hi.is_nan() || hi <= 0.0 || lo * MAX_COND < hi {
        return None;
    }
    let x = ata.inverse() * atb;
    x.is_finite().then_some([x.x, x.y, x.z])
}

/// Per-patch derivative values in the chosen convention.
pub fn derivative_values(abc: [f64; 3], conv: Derivatives) -> [f64; 3] {
    match conv {
        // ASSUMPTION E5 (default literal): the coefficients as printed in Eq. 4.
        Derivatives::Literal => [abc[0].abs(), abc[1].abs(), abc[2].abs()],
        Derivatives::Exact => [2.0 * abc[0].abs(), abc[1].abs(), 2.0 * abc[2].abs()],
    }
}

/// Nearest-rank 95th percentile of `v` (sorted in place).
fn p95(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let rank = ((0.95 * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// Combines per-patch values into M1, M2, M3.
pub fn aggregate(per_patch: &[[f64; 3]], agg: Aggregation) -> [f64; 3] {
    if per_patch.is_empty() {
        return [0.0; 3];
    }
    match agg {
        // ASSUMPTION E6: per-component maxima over all patches.
        Aggregation::Max => per_patch.iter().fold([0.0f64; 3], |m, p| {
            [m[0].max(p[0]), m[1].max(p[1]), m[2].max(p[2])]
        }),
        Aggregation::SumMax => *per_patch
            .iter()
            .max_by(|x, y| {
                let sx = x[0] + 2.0 * x[1] + x[2];
                let sy = y[0] + 2.0 * y[1] + y[2];
                sx.total_cmp(&sy)
            })
            .expect("non-empty"),
        Aggregation::P95 => {
            let mut out = [0.0; 3];
            let mut col = Vec::with_capacity(per_patch.len());
            for (k, o) in out.iter_mut().enumerate() {
                col.clear();
                col.extend(per_patch.iter().map(|p| p[k]));
                *o = p95(&mut col);
            }
            out
        }
    }
}

/// Estimates M1, M2, M3 of `points` (indexed by `index`) from K random patches drawn
/// with `seed`. Deterministic for a given seed, whatever the thread count.
pub fn estimate(
    points: &[DVec3],
    index: &PointIndex,
    opts: &CurvatureOpts,
    seed: u64,
) -> Result<Curvature, MethodError> {
    let n = points.len();
    let k = if opts.patches == 0 {
        default_patches(n)
    } else {
        opts.patches
    }
    .min(n);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut centres: Vec<usize> = index::sample(&mut rng, n, k).into_vec();
    centres.sort_unstable();
    let take = match opts.neighborhood {
        Neighborhood::Nearest => opts.n,
        Neighborhood::Random => 2 * opts.n,
    }
    .min(n);
    let fits: Vec<Option<[f64; 3]>> = centres
        .par_iter()
        .enumerate()
        .map(|(j, &c)| {
            // ASSUMPTION E2: the N nearest neighbours (the centre included), or N of 2N.
            let nb = index.knn(points[c], take).ok()?;
            let mut pts: Vec<DVec3> = nb.iter().map(|h| points[h.index as usize]).collect();
            if opts.neighborhood == Neighborhood::Random && pts.len() > opts.n {
                let mut r = ChaCha8Rng::seed_from_u64(seed ^ (0x9E37_79B9_7F4A_7C15 ^ j as u64));
                let mut pick = index::sample(&mut r, pts.len(), opts.n).into_vec();
                pick.sort_unstable();
                pts = pick.into_iter().map(|i| pts[i]).collect();
            }
            fit_quadric(points[c], &pts)
        })
        .collect();
    let per_patch: Vec<[f64; 3]> = fits
        .iter()
        .flatten()
        .map(|&abc| derivative_values(abc, opts.derivatives))
        .collect();
    let skipped = fits.len() - per_patch.len();
    Ok(Curvature {
        m: aggregate(&per_patch, opts.aggregation),
        per_patch,
        drawn: k,
        skipped,
    })
}
