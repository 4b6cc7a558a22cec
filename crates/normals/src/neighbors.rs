//! k-nearest-neighbour tables shared by the estimators, and the common finishing step
//! (optional orientation, diagnostics).

use glam::DVec3;
use rayon::prelude::*;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, MethodError, Normals, RunCtx};
use reconbench_geom::spatial::PointIndex;

use crate::orient::orient_mst;

/// Row-major k-NN table: row `i` holds the `k` nearest points of point `i`, the point
/// itself first (distance 0), then by increasing distance.
#[derive(Debug, Clone)]
pub struct Neighbors {
    /// Neighbours per row (the requested k, clamped to the number of points).
    pub k: usize,
    /// `n * k` point indices.
    pub indices: Vec<u32>,
}

impl Neighbors {
    /// The neighbour row of point `i`.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.indices[i * self.k..(i + 1) * self.k]
    }
}

/// Builds the k-NN table of `points`, counting each point as its own first neighbour
/// (ASSUMPTION B-07: k includes the point itself, as in Hoppe's formulation).
/// `k` is clamped to the number of points; fewer than `min_points` points is an error.
pub fn knn_including_self(
    points: &[DVec3],
    k: usize,
    min_points: usize,
) -> Result<Neighbors, MethodError> {
    if points.len() < min_points {
        return Err(MethodError::InvalidInput(format!(
            "normal estimation needs at least {min_points} points, got {}",
            points.len()
        )));
    }
    let k = k.min(points.len());
    let index = PointIndex::new(points)?;
    let table = index.knn_all(k, false)?;
    // With exact duplicates the query point need not come first: put it first so that
    // row[0] is always the point itself.
    let mut indices = table.indices;
    for (i, row) in indices.chunks_mut(k).enumerate() {
        if row[0] as usize != i {
            match row.iter().position(|&j| j as usize == i) {
                Some(p) => row.swap(0, p),
                None => row[0] = i as u32,
            }
        }
    }
    Ok(Neighbors { k, indices })
}

/// Checks a neighbourhood size parameter.
pub fn check_k(name: &str, k: usize, min: usize) -> Result<(), MethodError> {
    if k < min {
        return Err(MethodError::InvalidParameter {
            name: name.to_string(),
            message: format!("must be at least {min}, got {k}"),
        });
    }
    Ok(())
}

/// Orients (when `orient_k > 0`) and packages the normals with diagnostics.
pub fn finish(
    points: &[DVec3],
    mut normals: Vec<DVec3>,
    orient_k: usize,
    ctx: &mut RunCtx,
) -> Result<Normals, MethodError> {
    let mut diagnostics = reconbench_geom::method::Diagnostics::new();
    let degenerate = normals.iter().filter(|n| **n == DVec3::ZERO).count();
    diagnostics.insert(
        "degenerate_neighbourhoods".into(),
        Diagnostic::Number(degenerate as f64),
    );
    let oriented = orient_k > 0;
    if oriented {
        ctx.checkpoint()?;
        let report = ctx.phase("orient", || orient_mst(points, &mut normals, orient_k))?;
        diagnostics.insert(
            "orient_components".into(),
            Diagnostic::Number(report.components as f64),
        );
        diagnostics.insert(
            "orient_flipped".into(),
            Diagnostic::Number(report.flipped as f64),
        );
    }
    Ok(Normals {
        normals,
        oriented,
        diagnostics,
    })
}

/// The common shape of every k-NN estimator: validate `k`, build the neighbour table
/// (phase `knn`), fit each point's normal in parallel from its row (phase `fit`), then
/// orient and package. `fit(points, row)` gets the row with the point itself first.
pub fn estimate_per_point(
    cloud: &PointCloud,
    ctx: &mut RunCtx,
    k: usize,
    min_k: usize,
    orient_k: usize,
    fit: impl Fn(&[DVec3], &[u32]) -> DVec3 + Sync,
) -> Result<Normals, MethodError> {
    check_k("k", k, min_k)?;
    let pts = cloud.positions();
    let nb = ctx.phase("knn", || knn_including_self(pts, k, 3))?;
    ctx.checkpoint()?;
    let normals: Vec<DVec3> = ctx.phase("fit", || {
        (0..pts.len())
            .into_par_iter()
            .map(|i| fit(pts, nb.row(i)))
            .collect()
    });
    finish(pts, normals, orient_k, ctx)
}
