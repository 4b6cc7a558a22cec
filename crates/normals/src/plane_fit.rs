//! Plane-fitting normals: `pf` (Hoppe et al. 1992) and `wpf` (Gaussian-weighted,
//! Pauly et al. 2003), the baselines of seed 000 Table 4.1 (§1.2.4, §1.2.5).
//!
//! The normal is the eigenvector of the smallest eigenvalue of the (weighted) covariance
//! of the k nearest neighbours about their (weighted) centroid.

use glam::{DMat3, DVec3};
use reconbench_geom::PointCloud;
use reconbench_geom::linalg::sym_eigen3_smallest_planar;
use reconbench_geom::method::{
    Describe, MethodError, NormalEstimator, Normals, ParamDoc, RunCtx, Unit,
};
use reconbench_geom::spatial::KnnHit;
use serde::{Deserialize, Serialize};

use crate::neighbors::{ORIENT_K_DOC, check_k, estimate_per_point_hits, row_points};

/// Relative eigenvalue gap under which a neighbourhood counts as degenerate (coincident
/// or collinear points): the normal is then undetermined and reported as zero.
const DEGENERATE_REL: f64 = 1e-12;

/// Parameters of `pf`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlaneFitParams {
    /// Neighbourhood size, the point itself included (seed 000: 30, ASSUMPTION B-06).
    pub k: usize,
    /// Neighbours of the MST orientation graph; 0 leaves normals unoriented.
    pub orient_k: usize,
}

impl Default for PlaneFitParams {
    fn default() -> Self {
        // ASSUMPTION B-06: "30 and 40 ... respectively" read in order: PF k = 30.
        Self {
            k: 30,
            orient_k: 18,
        }
    }
}

/// How `wpf` chooses the Gaussian width from the farthest of the k neighbours, `p_k`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SigmaRule {
    /// sigma^2 = |p - p_k|^2 / 3: the farthest neighbour gets weight e^-3.
    ThirdSquare,
    /// sigma = |p - p_k| / 3: the farthest neighbour gets weight e^-9 (the ablation).
    ThirdDistance,
}

/// Parameters of `wpf`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WeightedPlaneFitParams {
    /// Neighbourhood size, the point itself included (seed 000: 40, ASSUMPTION B-06).
    pub k: usize,
    /// Gaussian width rule (ASSUMPTION B-08).
    pub sigma_rule: SigmaRule,
    /// Neighbours of the MST orientation graph; 0 leaves normals unoriented.
    pub orient_k: usize,
}

impl Default for WeightedPlaneFitParams {
    fn default() -> Self {
        Self {
            k: 40,
            // ASSUMPTION B-08: "one third the square distance" read as sigma^2 = d_k^2 / 3.
            sigma_rule: SigmaRule::ThirdSquare,
            orient_k: 18,
        }
    }
}

/// `pf`: unweighted k-NN plane fit.
#[derive(Debug, Clone, Default)]
pub struct PlaneFit {
    /// Parameters.
    pub params: PlaneFitParams,
}

/// `wpf`: Gaussian-weighted k-NN plane fit.
#[derive(Debug, Clone, Default)]
pub struct WeightedPlaneFit {
    /// Parameters.
    pub params: WeightedPlaneFitParams,
}

/// Smallest-eigenvalue eigenvector of the weighted covariance of `row` (zero when the
/// neighbourhood is degenerate). `weight(q)` gives the weight of neighbour position q.
pub fn fit_plane_normal(points: &[DVec3], row: &[u32], weight: impl Fn(DVec3) -> f64) -> DVec3 {
    plane_normal_of(row.iter().map(|&j| points[j as usize]), weight)
}

/// [`fit_plane_normal`] over neighbour positions (iterated twice: centroid, then
/// covariance).
pub fn plane_normal_of(
    row: impl Iterator<Item = DVec3> + Clone,
    weight: impl Fn(DVec3) -> f64,
) -> DVec3 {
    let mut wsum = 0.0;
    let mut c = DVec3::ZERO;
    for q in row.clone() {
        let w = weight(q);
        wsum += w;
        c += w * q;
    }
    if wsum <= 0.0 {
        return DVec3::ZERO;
    }
    c /= wsum;
    let mut m = DMat3::ZERO;
    for q in row {
        let d = q - c;
        let w = weight(q);
        m += DMat3::from_cols(d * (w * d.x), d * (w * d.y), d * (w * d.z));
    }
    normal_of_covariance(m)
}

/// [`plane_normal_of`] with unit weights over the positions of a kNN result, in one
/// fused loop per pass (the `pf` hot path).
///
/// The result is bit for bit that of `plane_normal_of(row_points(..), |_| 1.0)`: the
/// hits hold the same positions as the row (the point itself is either one of them or
/// replaced by an exact duplicate at distance 0, which comes first), the sums run in the
/// same order, and the six distinct covariance entries are the same products.
pub fn unweighted_normal_of_hits(hits: &[KnnHit]) -> DVec3 {
    if hits.is_empty() {
        return DVec3::ZERO;
    }
    let mut wsum = 0.0;
    let mut c = DVec3::ZERO;
    for h in hits {
        wsum += 1.0;
        c += 1.0 * h.point;
    }
    c /= wsum;
    let (mut xx, mut xy, mut xz, mut yy, mut yz, mut zz) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for h in hits {
        let d = h.point - c;
        xx += d.x * (1.0 * d.x);
        xy += d.y * (1.0 * d.x);
        xz += d.z * (1.0 * d.x);
        yy += d.y * (1.0 * d.y);
        yz += d.z * (1.0 * d.y);
        zz += d.z * (1.0 * d.z);
    }
    let m = DMat3::from_cols(
        DVec3::new(xx, xy, xz),
        DVec3::new(xy, yy, yz),
        DVec3::new(xz, yz, zz),
    );
    normal_of_covariance(m)
}

/// The plane normal of a covariance matrix: the smallest eigenvalue's eigenvector, zero
/// when the two largest eigenvalues do not span a plane (coincident or collinear points).
pub fn normal_of_covariance(m: DMat3) -> DVec3 {
    match sym_eigen3_smallest_planar(m, DEGENERATE_REL) {
        Ok(Some(v)) => v,
        _ => DVec3::ZERO,
    }
}

impl Describe for PlaneFit {
    const NAME: &'static str = "pf";
    const SOURCE: &'static str = "seed 000 §1.2.4";
    const SUMMARY: &'static str = "k-NN plane fit (Hoppe et al. 1992)";
    type Params = PlaneFitParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "k",
            Unit::Count,
            "neighbourhood size incl. the point itself (seed 000: 30, ASSUMPTION B-06/B-07)",
        ),
        ORIENT_K_DOC,
    ];

    fn from_params(params: PlaneFitParams) -> Result<Self, MethodError> {
        check_k("k", params.k, 3)?;
        Ok(Self { params })
    }
}

impl NormalEstimator for PlaneFit {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        let p = &self.params;
        estimate_per_point_hits(cloud, ctx, p.k, 3, p.orient_k, |_, _, hits, _| {
            unweighted_normal_of_hits(hits)
        })
    }
}

impl Describe for WeightedPlaneFit {
    const NAME: &'static str = "wpf";
    const SOURCE: &'static str = "seed 000 §1.2.5";
    const SUMMARY: &'static str = "Gaussian-weighted plane fit (Pauly et al. 2003)";
    type Params = WeightedPlaneFitParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "k",
            Unit::Count,
            "neighbourhood size incl. the point itself (seed 000: 40, ASSUMPTION B-06)",
        ),
        ParamDoc::new(
            "sigma_rule",
            Unit::Choice,
            "third-square: sigma^2 = d_k^2/3 (ASSUMPTION B-08); third-distance: sigma = d_k/3",
        ),
        ORIENT_K_DOC,
    ];

    fn from_params(params: WeightedPlaneFitParams) -> Result<Self, MethodError> {
        check_k("k", params.k, 3)?;
        Ok(Self { params })
    }
}

impl NormalEstimator for WeightedPlaneFit {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        let p = &self.params;
        let rule = p.sigma_rule;
        estimate_per_point_hits(cloud, ctx, p.k, 3, p.orient_k, |pts, i, hits, _| {
            let c = pts[i];
            let row = row_points(pts, i, hits);
            let dk2 = row
                .clone()
                .map(|q| q.distance_squared(c))
                .fold(0.0, f64::max);
            let sigma2 = match rule {
                SigmaRule::ThirdSquare => dk2 / 3.0,
                SigmaRule::ThirdDistance => dk2 / 9.0,
            };
            if sigma2 <= 0.0 {
                return DVec3::ZERO;
            }
            plane_normal_of(row, |q| (-q.distance_squared(c) / sigma2).exp())
        })
    }
}
