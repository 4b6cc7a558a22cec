//! Argument checks shared by the spatial queries.

use glam::DVec3;

use crate::error::{GeomError, Result, check_finite};

/// Checks a single query point.
pub(super) fn check_query(p: DVec3) -> Result<()> {
    check_finite("query point", &[p])
}

pub(super) fn check_k(k: usize) -> Result<()> {
    if k == 0 {
        return Err(GeomError::InvalidParameter {
            name: "k",
            message: "the number of neighbours must be at least 1".to_string(),
        });
    }
    Ok(())
}

pub(super) fn check_radius(r: f64) -> Result<()> {
    if !(r.is_finite() && r >= 0.0) {
        return Err(GeomError::InvalidParameter {
            name: "radius",
            message: format!("{r} must be finite and >= 0"),
        });
    }
    Ok(())
}
