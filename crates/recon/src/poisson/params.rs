//! Parameters of `poisson`.

use reconbench_geom::method::{MethodError, ParamDoc, Unit};
use serde::{Deserialize, Serialize};

/// How a vertex of the iso-surface is placed on its grid edge (marching tetrahedra puts
/// vertices on the axis edges and on the face and body diagonals of the cells).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum VertexFit {
    /// Root of the tricubic (Lagrange, 4x4x4 nodes) interpolant of the indicator along
    /// the edge: nodes one cell apart on every edge kind (the default).
    #[default]
    Tricubic,
    /// Root of the cubic through the four nodes on the edge's own line (the behaviour
    /// before the tricubic fit: on a diagonal those nodes are `sqrt 2` or `sqrt 3`
    /// cells apart, and the surface is noisier there).
    EdgeCubic,
    /// Linear interpolation of the two end values (classic marching cubes/tetrahedra,
    /// and Open3D's `linear_fit = True`).
    Linear,
}

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
    /// Side weight `w` of the `(w, 1 - 2w, w)` filter applied along each axis to the
    /// splatted normal field: 1/8 represents it in the quadratic B-spline basis as
    /// PoissonRecon does (IMPL-CHOICE P-04); 0 keeps the point-sampled splat alone.
    pub field_smoothing: f64,
    /// How each vertex is placed on its grid edge.
    pub vertex_fit: VertexFit,
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
            field_smoothing: 0.125,
            vertex_fit: VertexFit::Tricubic,
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
        "field_smoothing",
        Unit::None,
        "side weight w of the (w, 1-2w, w) per-axis filter of the normal field: 1/8 is PoissonRecon's B-spline representation, 0 the point-sampled splat (in [0, 0.25])",
    ),
    ParamDoc::new(
        "vertex_fit",
        Unit::Choice,
        "vertex placement on a grid edge: tricubic (root of the 4x4x4-node interpolant), edge-cubic (cubic through the edge's line, the old behaviour), linear",
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
        if !(0.0..=0.25).contains(&self.field_smoothing) {
            return bad(
                "field_smoothing",
                format!("must be in [0, 0.25], got {}", self.field_smoothing),
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
