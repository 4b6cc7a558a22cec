//! Parameters of `poisson`.

use reconbench_geom::method::{MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// Parameters of `poisson`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PoissonParams {
    /// Grid depth: `2^depth` nodes per side of the padded cubic box (the usual
    /// default 8 of Open3D, PCL and PoissonRecon, whose octree depth it matches at the
    /// finest level).
    pub depth: usize,
    /// Width of the Gaussian that spreads each normal into the vector field, in mean
    /// point spacings: wider fills larger holes and smooths more.
    pub smoothing: f64,
    /// Conjugate-gradient iteration cap per grid level.
    pub cg_iterations: usize,
    /// Relative residual at which the conjugate gradients stop.
    pub cg_tolerance: f64,
    /// Share of the output vertices with the lowest sample density to remove (0: keep
    /// the watertight surface).
    pub trim_quantile: f64,
    /// Radius of the density count around each vertex, in grid cells.
    pub trim_radius_cells: f64,
    /// Largest share of points whose nearest neighbour's normal is opposite before the
    /// input is refused as unoriented.
    pub max_flipped_share: f64,
}

impl Default for PoissonParams {
    fn default() -> Self {
        Self {
            depth: 8,
            smoothing: 1.0,
            cg_iterations: 1000,
            cg_tolerance: 1e-4,
            trim_quantile: 0.0,
            trim_radius_cells: 2.0,
            max_flipped_share: 0.2,
        }
    }
}

/// One doc per field of [`PoissonParams`].
pub const PARAM_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "depth",
        Unit::Count,
        "grid depth: 2^depth nodes per side of the padded cubic box (3..=8)",
    ),
    ParamDoc::new(
        "smoothing",
        Unit::Spacing,
        "width of the Gaussian spreading each normal into the vector field",
    ),
    ParamDoc::new(
        "cg_iterations",
        Unit::Count,
        "conjugate-gradient iteration cap per grid level",
    ),
    ParamDoc::new(
        "cg_tolerance",
        Unit::None,
        "relative residual at which the conjugate gradients stop",
    ),
    ParamDoc::new(
        "trim_quantile",
        Unit::Fraction,
        "share of output vertices with the lowest sample density removed (0: off, watertight)",
    ),
    ParamDoc::new(
        "trim_radius_cells",
        Unit::None,
        "radius of the per-vertex sample count used by trimming, in grid cells",
    ),
    ParamDoc::new(
        "max_flipped_share",
        Unit::Fraction,
        "largest share of points whose nearest neighbour's normal is opposite before the normals count as unoriented",
    ),
];

impl PoissonParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), MethodError> {
        let bad = |name: &str, message: String| {
            Err(MethodError::InvalidParameter {
                name: name.into(),
                message,
            })
        };
        if !(3..=8).contains(&self.depth) {
            return bad("depth", format!("must be in 3..=8, got {}", self.depth));
        }
        if !(self.smoothing.is_finite() && self.smoothing > 0.0) {
            return bad("smoothing", format!("must be > 0, got {}", self.smoothing));
        }
        if !(1..=100_000).contains(&self.cg_iterations) {
            return bad(
                "cg_iterations",
                format!("must be in 1..=100000, got {}", self.cg_iterations),
            );
        }
        if !(self.cg_tolerance.is_finite() && self.cg_tolerance > 0.0 && self.cg_tolerance < 1.0) {
            return bad(
                "cg_tolerance",
                format!("must be in (0, 1), got {}", self.cg_tolerance),
            );
        }
        if !(0.0..1.0).contains(&self.trim_quantile) {
            return bad(
                "trim_quantile",
                format!("must be in [0, 1), got {}", self.trim_quantile),
            );
        }
        if !(self.trim_radius_cells.is_finite() && self.trim_radius_cells > 0.0) {
            return bad(
                "trim_radius_cells",
                format!("must be > 0, got {}", self.trim_radius_cells),
            );
        }
        if !(0.0..=1.0).contains(&self.max_flipped_share) {
            return bad(
                "max_flipped_share",
                format!("must be in [0, 1], got {}", self.max_flipped_share),
            );
        }
        Ok(())
    }
}
