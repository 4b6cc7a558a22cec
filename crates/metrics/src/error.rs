//! The error type of `reconbench-metrics`.

use reconbench_geom::GeomError;

/// Errors of the metrics crate. Every variant says what is wrong with which input.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// An error from the geometry crate (BVH or k-d tree construction, invalid queries).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// The input cannot be evaluated (empty mesh, zero area, mismatched lengths, ...).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// An option is out of its valid range.
    #[error("option '{name}': {message}")]
    InvalidParameter {
        /// Option name as the user spells it.
        name: &'static str,
        /// What is wrong and what is expected.
        message: String,
    },
    /// A required per-point attribute is missing from a cloud.
    #[error("the point cloud has no {0}")]
    MissingAttribute(String),
}

/// Result alias of this crate.
pub type Result<T, E = MetricsError> = std::result::Result<T, E>;

/// Error for an option that must be finite and > 0.
pub(crate) fn check_positive(name: &'static str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(MetricsError::InvalidParameter {
            name,
            message: format!("{v} must be finite and > 0"),
        })
    }
}
