//! Parameters of `poisson`.

use reconbench_geom::method::{MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// Parameters of `poisson`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PoissonParams {
    /// Grid depth: `2^depth` cells per side of the padded cubic box (the usual default 8
    /// of Open3D, PCL and PoissonRecon, whose octree depth it matches at the finest
    /// level).
    pub depth: usize,
    /// Screening weight alpha of Kazhdan & Hoppe 2013 (PoissonRecon's `--pointWeight`,
    /// default 4); 0 solves the unscreened Poisson equation of Kazhdan et al. 2006.
    pub screening: f64,
    /// Side of the cubic grid over the side of the points' bounding cube (Open3D's and
    /// PoissonRecon's `scale`, 1.1); raised where needed to keep two cells of padding.
    pub scale: f64,
    /// Largest number of multigrid V-cycles.
    pub max_cycles: usize,
    /// Relative residual `|b - A x| / |b|` at which the V-cycles stop.
    pub tolerance: f64,
    /// Gauss-Seidel sweeps before and after the coarse-grid correction of a V-cycle.
    pub sweeps: usize,
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
            screening: 4.0,
            scale: 1.1,
            max_cycles: 40,
            tolerance: 1e-4,
            sweeps: 2,
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
        "grid depth: 2^depth cells per side of the padded cubic box (3..=9)",
    ),
    ParamDoc::new(
        "screening",
        Unit::None,
        "screening weight alpha (Kazhdan & Hoppe 2013; PoissonRecon's pointWeight); 0: unscreened 2006 equation",
    ),
    ParamDoc::new(
        "scale",
        Unit::None,
        "grid side over the points' bounding-cube side (Open3D's and PoissonRecon's scale)",
    ),
    ParamDoc::new(
        "max_cycles",
        Unit::Count,
        "largest number of multigrid V-cycles",
    ),
    ParamDoc::new(
        "tolerance",
        Unit::None,
        "relative residual at which the V-cycles stop",
    ),
    ParamDoc::new(
        "sweeps",
        Unit::Count,
        "Gauss-Seidel sweeps before and after each coarse-grid correction",
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
        if !(3..=9).contains(&self.depth) {
            return bad("depth", format!("must be in 3..=9, got {}", self.depth));
        }
        if !(self.screening.is_finite() && self.screening >= 0.0) {
            return bad(
                "screening",
                format!("must be finite and >= 0, got {}", self.screening),
            );
        }
        if !(self.scale.is_finite() && (1.0..=4.0).contains(&self.scale)) {
            return bad("scale", format!("must be in [1, 4], got {}", self.scale));
        }
        if !(1..=1000).contains(&self.max_cycles) {
            return bad(
                "max_cycles",
                format!("must be in 1..=1000, got {}", self.max_cycles),
            );
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0 && self.tolerance < 1.0) {
            return bad(
                "tolerance",
                format!("must be in (0, 1), got {}", self.tolerance),
            );
        }
        if !(1..=50).contains(&self.sweeps) {
            return bad("sweeps", format!("must be in 1..=50, got {}", self.sweeps));
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
