//! Statistical outlier removal (Rusu et al. 2008, as in PCL's `StatisticalOutlierRemoval`
//! and Open3D's `remove_statistical_outlier`): a point is removed when its mean distance
//! to its `k` nearest other points exceeds the cloud's mean of that quantity by more than
//! `std_ratio` standard deviations.
//!
//! The usual peer baseline before normal estimation or reconstruction of noisy scans
//! (SCUTSurface's outlier protocols); it keeps a subset of the input points, so the
//! harness carries every point's ground truth along exactly.

use rayon::prelude::*;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Describe, Diagnostic, Diagnostics, Filter, Filtered, MethodError, ParamDoc, RunCtx, Unit,
};
use reconbench_geom::spatial::knn_self_table;
use serde::{Deserialize, Serialize};

/// Relative slack on the removal limit that absorbs rounding in the mean distances.
const TIE_REL: f64 = 1e-12;

/// Parameters of `statistical-outliers`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StatisticalOutliersParams {
    /// Neighbours, the point itself excluded (Open3D's example: 20).
    pub k: usize,
    /// Standard deviations above the mean neighbour distance beyond which a point is
    /// removed (Open3D's example: 2).
    pub std_ratio: f64,
}

impl Default for StatisticalOutliersParams {
    fn default() -> Self {
        Self {
            k: 20,
            std_ratio: 2.0,
        }
    }
}

/// The `statistical-outliers` filter.
#[derive(Debug, Clone, Default)]
pub struct StatisticalOutliers {
    /// Parameters.
    pub params: StatisticalOutliersParams,
}

impl Describe for StatisticalOutliers {
    const NAME: &'static str = "statistical-outliers";
    const SOURCE: &'static str = "baseline (PCL, Open3D)";
    const SUMMARY: &'static str =
        "statistical outlier removal: drop points whose mean k-NN distance is far above the mean";
    type Params = StatisticalOutliersParams;
    const PARAMS: &'static [ParamDoc] = &[
        ParamDoc::new(
            "k",
            Unit::Count,
            "neighbours, the point excluded (Open3D: 20)",
        ),
        ParamDoc::new(
            "std_ratio",
            Unit::None,
            "remove points beyond mean + std_ratio x standard deviation (Open3D: 2)",
        ),
    ];

    fn from_params(params: StatisticalOutliersParams) -> Result<Self, MethodError> {
        if params.k == 0 {
            return Err(MethodError::InvalidParameter {
                name: "k".into(),
                message: "must be at least 1".into(),
            });
        }
        if !(params.std_ratio.is_finite() && params.std_ratio >= 0.0) {
            return Err(MethodError::InvalidParameter {
                name: "std_ratio".into(),
                message: format!("must be a finite number >= 0, got {}", params.std_ratio),
            });
        }
        Ok(Self { params })
    }
}

/// Mean distance of every point to its `k` nearest other points.
pub fn mean_knn_distances(points: &[glam::DVec3], k: usize) -> Result<Vec<f64>, MethodError> {
    let table = knn_self_table(points, k, true)?;
    Ok((0..table.rows())
        .into_par_iter()
        .map(|i| {
            let d = table.dist2(i);
            d.iter().map(|x| x.sqrt()).sum::<f64>() / d.len().max(1) as f64
        })
        .collect())
}

impl Filter for StatisticalOutliers {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError> {
        let n = cloud.len();
        let mut diagnostics = Diagnostics::new();
        if n < 2 {
            // Nothing to compare with: every point is kept (documented result).
            diagnostics.insert("removed".into(), Diagnostic::Number(0.0));
            return Ok(Filtered {
                cloud: cloud.clone(),
                source: Some((0..n as u32).collect()),
                diagnostics,
            });
        }
        // Distances on the cloud moved exactly by a power of two into the working range
        // (squared distances at 1e200 overflow, at 1e-160 vanish): the same points are
        // kept at every scale; `distance_limit` is reported in the cloud's units.
        let s = reconbench_geom::cloud::working_scale_exponent(cloud.positions());
        let moved = s.map(|s| reconbench_geom::cloud::scale_pow2(cloud.positions(), s));
        let d = ctx.phase("knn", || {
            mean_knn_distances(moved.as_deref().unwrap_or(cloud.positions()), self.params.k)
        })?;
        ctx.checkpoint()?;
        let mean = d.iter().sum::<f64>() / n as f64;
        let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
        // Distances within rounding of the limit count as on it, so a cloud whose mean
        // distances are all equal (a regular sampling) loses no point to rounding.
        let limit = (mean + self.params.std_ratio * var.sqrt()) * (1.0 + TIE_REL);
        let keep: Vec<usize> = (0..n).filter(|&i| d[i] <= limit).collect();
        let out = cloud.select(&keep)?;
        diagnostics.insert(
            "removed".into(),
            Diagnostic::Number((n - keep.len()) as f64),
        );
        let limit_here = match s {
            Some(s) => reconbench_geom::cloud::scale_pow2(&[glam::DVec3::splat(limit)], -s)[0].x,
            None => limit,
        };
        diagnostics.insert("distance_limit".into(), Diagnostic::Number(limit_here));
        Ok(Filtered {
            cloud: out,
            source: Some(keep.iter().map(|&i| i as u32).collect()),
            diagnostics,
        })
    }
}
