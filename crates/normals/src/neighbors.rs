//! k-nearest-neighbour tables shared by the estimators, and the common finishing step
//! (optional orientation, diagnostics).

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_geom::method::{Diagnostic, MethodError, Normals, ParamDoc, RunCtx, Unit};
use reconbench_geom::spatial::{KnnHit, knn_self_map, knn_self_table};

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
    check_min_points(points, min_points)?;
    let k = k.min(points.len());
    let table = knn_self_table(points, k, false)?;
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

/// Errors when there are fewer than `min_points` points.
fn check_min_points(points: &[DVec3], min_points: usize) -> Result<(), MethodError> {
    if points.len() < min_points {
        return Err(MethodError::InvalidInput(format!(
            "normal estimation needs at least {min_points} points, got {}",
            points.len()
        )));
    }
    Ok(())
}

/// Position in the sorted kNN result `hits` of point `i` of the row convention of
/// [`Neighbors`] (the point itself first): row slot `j` holds `hits[row_slot(self_pos,
/// j)]`, where `self_pos` is where point `i` is in `hits` (see [`self_position`]).
/// Slot 0 is the point itself; the hit it displaced moves to the point's old slot.
#[inline]
pub fn row_slot(self_pos: Option<usize>, j: usize) -> Option<usize> {
    match (self_pos, j) {
        (_, 0) => None,
        (Some(p), j) if j == p => Some(0),
        (_, j) => Some(j),
    }
}

/// Where point `i` is in its own sorted kNN result (normally 0; with exact duplicates of
/// lower index it can be later, or missing when k of them precede it).
#[inline]
pub fn self_position(i: usize, hits: &[KnnHit]) -> Option<usize> {
    if hits.first().is_some_and(|h| h.index as usize == i) {
        Some(0)
    } else {
        hits.iter().position(|h| h.index as usize == i)
    }
}

/// The neighbour positions of point `i` in the row order of [`Neighbors`] (the point
/// itself first), from its sorted kNN result.
pub fn row_points(
    points: &[DVec3],
    i: usize,
    hits: &[KnnHit],
) -> impl Iterator<Item = DVec3> + Clone {
    let sp = self_position(i, hits);
    let me = points[i];
    (0..hits.len()).map(move |j| row_slot(sp, j).map_or(me, |h| hits[h].point))
}

/// Doc of the `orient_k` parameter every estimator of this crate shares.
pub const ORIENT_K_DOC: ParamDoc = ParamDoc::new(
    "orient_k",
    Unit::Count,
    "neighbours of the MST orientation graph (Hoppe); 0 leaves normals unoriented",
);

/// Checks a neighbourhood size parameter.
pub fn check_k(name: &str, k: usize, min: usize) -> Result<(), MethodError> {
    if k < min {
        return Err(MethodError::InvalidParameter {
            name: name.to_string(),
            message: format!("must be at least {min}, got {k}"),
        });
    }
    if k > MAX_K {
        return Err(MethodError::InvalidParameter {
            name: name.to_string(),
            message: format!(
                "{k} neighbours per point: at most {MAX_K} (a kNN table of 1,000,000 points \
                 with k = {k} needs about {:.0} GB)",
                1e6 * k as f64 * 12.0 / 1e9
            ),
        });
    }
    Ok(())
}

/// Largest neighbourhood size an estimator accepts: far above any useful `k` (a few
/// hundred), and small enough that the kNN table of a large cloud fits in memory.
pub const MAX_K: usize = 100_000;

/// Orients (when `orient_k > 0`) and packages the normals with diagnostics; fails when
/// every normal is zero-length on points that are not collinear.
pub fn finish(
    points: &[DVec3],
    mut normals: Vec<DVec3>,
    orient_k: usize,
    ctx: &mut RunCtx,
) -> Result<Normals, MethodError> {
    let mut diagnostics = reconbench_geom::method::Diagnostics::new();
    let degenerate = normals.iter().filter(|n| **n == DVec3::ZERO).count();
    if degenerate == normals.len() && !reconbench_geom::cloud::all_collinear(points) {
        // An input error (exit code 2): the estimator cannot handle this cloud.
        return Err(MethodError::InvalidInput(format!(
            "every one of the {} normals is zero-length although the points are not \
             collinear",
            normals.len()
        )));
    }
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

/// The common shape of every k-NN estimator: validate `k`, find each point's k nearest
/// neighbours and fit its normal from that row, in parallel and fused (phase `knn+fit`:
/// no neighbour table is materialised), then orient and package. `fit(points, row)` gets
/// the row with the point itself first, exactly the rows of [`knn_including_self`].
pub fn estimate_per_point(
    cloud: &PointCloud,
    ctx: &mut RunCtx,
    k: usize,
    min_k: usize,
    orient_k: usize,
    fit: impl Fn(&[DVec3], &[u32]) -> DVec3 + Sync + Send,
) -> Result<Normals, MethodError> {
    estimate_per_point_hits(cloud, ctx, k, min_k, orient_k, |pts, i, hits, row| {
        row.clear();
        row.extend(row_points_indices(i, hits));
        fit(pts, row)
    })
}

/// Indices of the row of point `i` (the point itself first) from its sorted kNN result.
fn row_points_indices(i: usize, hits: &[KnnHit]) -> impl Iterator<Item = u32> + '_ {
    let sp = self_position(i, hits);
    (0..hits.len()).map(move |j| row_slot(sp, j).map_or(i as u32, |h| hits[h].index))
}

/// [`estimate_per_point`] for fits that use the kNN result directly:
/// `fit(points, i, hits, scratch)` gets point `i`'s k nearest points sorted by
/// (distance, index) with their positions (see [`row_points`] for the row order) and a
/// reusable per-thread scratch vector.
pub fn estimate_per_point_hits(
    cloud: &PointCloud,
    ctx: &mut RunCtx,
    k: usize,
    min_k: usize,
    orient_k: usize,
    fit: impl Fn(&[DVec3], usize, &[KnnHit], &mut Vec<u32>) -> DVec3 + Sync + Send,
) -> Result<Normals, MethodError> {
    check_k("k", k, min_k)?;
    // Scale robustness: fit on the cloud moved exactly by a power of two into the
    // working range (normals are scale-free, so they need no mapping back).
    let scaled = cloud.at_working_scale();
    let cloud = scaled.as_ref().map_or(cloud, |(c, _)| c);
    let pts = cloud.positions();
    check_min_points(pts, 3)?;
    // ASSUMPTION B-07: k includes the point itself.
    let k = k.min(pts.len());
    let normals = ctx.phase("knn+fit", || {
        knn_self_map(pts, k, false, Vec::new, |row, i, hits| {
            fit(pts, i, hits, row)
        })
    })?;
    ctx.checkpoint()?;
    finish(pts, normals, orient_k, ctx)
}
