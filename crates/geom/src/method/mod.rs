//! The plug points: object-safe traits every method implements (normal estimator,
//! feature detector, filter, reconstructor), the descriptor each implements beside them
//! ([`Describe`]), and the run context (seed, phase timer, time budget, cancellation,
//! progress) they receive.
//!
//! They live in the geometry crate, below every algorithm crate, so that algorithms
//! never depend on the harness (see docs/ARCHITECTURE.md).

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

mod ctx;
mod describe;

pub use ctx::{PhaseGuard, PhaseTimer, ProgressSink, RunCtx, StopReason};
pub use describe::{Describe, Needs, ParamDoc, Unit};

use crate::cloud::PointCloud;
use crate::error::GeomError;
use crate::mesh::TriMesh;

/// Why a method did not produce a result.
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    /// The input cannot be processed by this method (too few points, missing normals...).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A parameter is out of range.
    #[error("parameter '{name}': {message}")]
    InvalidParameter {
        /// Parameter name as written in experiment files.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A geometry error from a shared routine.
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// The run was cancelled or ran out of its time budget.
    #[error("stopped: {0}")]
    Stopped(StopReason),
    /// The method failed for a reason of its own.
    #[error("{0}")]
    Failed(String),
}

impl MethodError {
    /// True when the input or a parameter is at fault, not the method: the CLI exits
    /// with code 2 for these (bad input) and 1 for the rest. `InvalidInput` covers
    /// everything a method refuses about its cloud (too few or degenerate points, an
    /// unusable scale, a result that would collapse to nothing on distinct points);
    /// a shared geometry routine's error counts when [`GeomError::is_input`] says so.
    pub fn is_input(&self) -> bool {
        match self {
            Self::InvalidInput(_) | Self::InvalidParameter { .. } => true,
            Self::Geom(g) => g.is_input(),
            Self::Stopped(_) | Self::Failed(_) => false,
        }
    }
}

/// A diagnostic value a method reports next to its result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Diagnostic {
    /// A single number (iterations, matching %, ...).
    Number(f64),
    /// A series (e.g. matching % after each iteration).
    Series(Vec<f64>),
    /// A free-form note.
    Text(String),
}

/// Named diagnostics, sorted by name for stable output.
pub type Diagnostics = BTreeMap<String, Diagnostic>;

/// Output of a normal estimator: one normal per input point.
#[derive(Debug, Clone, PartialEq)]
pub struct Normals {
    /// Unit normals (zero where the method could not decide; metrics count those).
    pub normals: Vec<DVec3>,
    /// Whether the method claims a consistent outward orientation.
    pub oriented: bool,
    /// Method diagnostics.
    pub diagnostics: Diagnostics,
}

/// Per-point class a feature detector assigns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(u8)]
pub enum FeatureClass {
    /// Not on a sharp feature.
    None = 0,
    /// On a sharp edge.
    Edge = 1,
    /// On a corner (three or more patches meet).
    Corner = 2,
}

/// Output of a feature detector.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureLabels {
    /// One class per input point.
    pub labels: Vec<FeatureClass>,
    /// Optional per-point score (e.g. surface variation or cluster count) for sweeps.
    pub scores: Option<Vec<f64>>,
    /// Method diagnostics.
    pub diagnostics: Diagnostics,
}

/// Output of a reconstructor.
#[derive(Debug, Clone, PartialEq)]
pub struct Reconstruction {
    /// The reconstructed mesh.
    pub mesh: TriMesh,
    /// Indices of input points the method refused (outliers, isolated points).
    pub refused: Vec<u32>,
    /// Method diagnostics (matching %, iterations, ...).
    pub diagnostics: Diagnostics,
}

/// Estimates a normal per point.
pub trait NormalEstimator: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Estimates normals for every point of `cloud`.
    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError>;
}

/// Labels points on sharp features.
pub trait FeatureDetector: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Labels every point of `cloud`.
    fn detect(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<FeatureLabels, MethodError>;
}

/// Builds a triangle mesh from a point cloud.
pub trait Reconstructor: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Reconstructs a surface from `cloud`.
    fn reconstruct(
        &self,
        cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError>;
}

/// Output of a filter: a new cloud that replaces the input in a pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Filtered {
    /// The output cloud (attached normals and channels as the filter leaves them).
    pub cloud: PointCloud,
    /// Per output point: the input point it came from (moved, kept or copied), or `None`
    /// when output points are new samples with no single source point.
    pub source: Option<Vec<u32>>,
    /// Method diagnostics.
    pub diagnostics: Diagnostics,
}

/// Turns a cloud into another cloud: smoothing, MLS projection, thinning, outlier
/// removal. In a pipeline its output replaces the input of the following steps.
pub trait Filter: Send + Sync + std::fmt::Debug {
    /// Stable kebab-case registry name.
    fn name(&self) -> &str;
    /// Filters `cloud`.
    fn filter(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Filtered, MethodError>;
}

/// Name of the point channel in which a pipeline attaches feature labels
/// ([`FeatureClass`] as integers) for later steps.
pub const FEATURE_CHANNEL: &str = "feature";

/// Name of the point channel (integer labels) in which a merging filter tags where each
/// output point came from: [`ORIGIN_SCAN`], [`ORIGIN_NURBS`] or [`ORIGIN_COLLAR`] (the
/// `blend` filter, seed 002 §7: the scanned points, the NURBS samples and the collar
/// between them). Metrics of the blend region read it.
pub const ORIGIN_CHANNEL: &str = "origin";
/// [`ORIGIN_CHANNEL`] value of a point of the input scan.
pub const ORIGIN_SCAN: i64 = 0;
/// [`ORIGIN_CHANNEL`] value of a sample of a designed (NURBS) surface.
pub const ORIGIN_NURBS: i64 = 1;
/// [`ORIGIN_CHANNEL`] value of a point the filter created to join the two.
pub const ORIGIN_COLLAR: i64 = 2;

/// Scalar channels a blending filter attaches so the collar metrics can chart the blend
/// region around a tube: per point the angle around the tube axis (rad), the distance
/// from the axis, that distance minus the tube radius, the distance to the nearest input
/// point (the height above the scan) and the signed position along the axis from where
/// it meets the part (all lengths in mean input spacings).
pub const BLEND_CHART_CHANNELS: [&str; 5] = [
    "blend_theta",
    "blend_radial_sp",
    "blend_offset_sp",
    "blend_height_sp",
    "blend_axial_sp",
];

/// Name of the [`Diagnostic::Number`] a reconstructor sets to 0 when its mesh does not
/// interpolate the input (new vertices, as Poisson's): the evaluator then reports no
/// vertex counts, Delta F or refused-point metrics for it, which count input points as
/// vertices.
pub const INTERPOLATING_DIAGNOSTIC: &str = "interpolating";
