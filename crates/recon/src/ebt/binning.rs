//! Stage 3 of EBT (paper §4.3, after Weir et al. 1996): voxel binning. The padded
//! bounding box is cut into cubes of edge B; each occupied cube keeps the one input
//! point nearest its centre.

use std::collections::HashMap;

use glam::DVec3;
use reconbench_geom::Aabb;
use reconbench_geom::method::MethodError;

/// Cells per axis above which binning refuses (the bin size is then absurdly small; the
/// linear cell key of three such axes still fits in a `u64`).
const MAX_CELLS_PER_AXIS: f64 = 2.0e6;

/// Result of [`voxel_thin`].
#[derive(Debug, Clone, PartialEq)]
pub struct Binned {
    /// Kept input indices, ascending.
    pub kept: Vec<u32>,
    /// Cells per axis of the padded box (V1).
    pub dims: [u64; 3],
}

/// Keeps, in every occupied cube of edge `b` of the box of `points` padded by `tol`, the
/// point nearest the cube centre. Ties go to the lower index. O(n).
pub fn voxel_thin(points: &[DVec3], b: f64, tol: f64) -> Result<Binned, MethodError> {
    if !(b.is_finite() && b > 0.0) {
        return Err(MethodError::InvalidParameter {
            name: "bin_size".into(),
            message: format!("the bin size must be finite and > 0, got {b}"),
        });
    }
    // E-1 with ASSUMPTION E9: the box padded by TOL on every side.
    let bb = Aabb::from_points(points);
    let lo = bb.min - DVec3::splat(tol);
    let ext = bb.max + DVec3::splat(tol) - lo;
    let cells = (ext / b).ceil().max(DVec3::ONE);
    if cells.max_element() > MAX_CELLS_PER_AXIS {
        return Err(MethodError::InvalidInput(format!(
            "bin size {b:.3e} gives {:.0} cells along an axis of a box of extent {:.3e}",
            cells.max_element(),
            ext.max_element()
        )));
    }
    let dims = [cells.x as u64, cells.y as u64, cells.z as u64];
    let mut best: HashMap<u64, (u32, f64)> = HashMap::with_capacity(points.len() / 8 + 16);
    for (i, &p) in points.iter().enumerate() {
        // V2: the cell, clamped to the grid.
        let c = ((p - lo) / b).floor();
        let ix = (c.x.max(0.0) as u64).min(dims[0] - 1);
        let iy = (c.y.max(0.0) as u64).min(dims[1] - 1);
        let iz = (c.z.max(0.0) as u64).min(dims[2] - 1);
        let centre = lo + (DVec3::new(ix as f64, iy as f64, iz as f64) + 0.5) * b;
        let d2 = (p - centre).length_squared();
        let key = ix + dims[0] * (iy + dims[1] * iz);
        // V3 with ASSUMPTION E10: the nearest to the centre, ties to the lowest index
        // (points arrive in index order, so only a strictly nearer point replaces).
        best.entry(key)
            .and_modify(|e| {
                if d2 < e.1 {
                    *e = (i as u32, d2);
                }
            })
            .or_insert((i as u32, d2));
    }
    let mut kept: Vec<u32> = best.into_values().map(|(i, _)| i).collect();
    kept.sort_unstable();
    Ok(Binned { kept, dims })
}
