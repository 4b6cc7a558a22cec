//! Metrics of reconbench, exactly as `METRICS.md` defines them (the user-facing copy with
//! every formula and JSON key is `docs/METRICS.md`).
//!
//! * [`distance`]: accuracy, completeness, Chamfer-L1, Hausdorff, p95, RMS, F-score;
//!   exact point-to-surface distances against a [`Reference`] (analytic shape or mesh).
//! * [`normals`]: unoriented / oriented angle statistics, PGP5 / PGP10, flip rate.
//! * [`features`]: sharp-feature precision / recall / F1, distance to the curves, curve
//!   coverage, mesh feature recovery.
//! * [`filter_eval`]: projecting filters (MLS): distance to the input and to the surface,
//!   normal error near and away from features, feature-line error (seed 002 Tables 3-6).
//! * [`blend`]: blended point sets (seed 002 §7): collar uniformity, normal variation,
//!   largest gap of the blend region, point counts; against a true blended surface,
//!   distances per origin and the normal error of the blend region.
//! * [`topology`]: geom's topology analysis plus Delta F, `topology_ok` and
//!   self-intersections.
//! * [`quality`]: triangle angles, aspect ratios, edge lengths.
//! * [`refused`]: refused-point precision / recall against the generator's outliers.
//! * [`cost`]: per-phase timer, CPU time, peak RSS.
//! * [`eval`]: the entry points the CLI wraps (`eval_mesh`, `eval_cloud_normals`,
//!   `eval_cloud_features`).
//!
//! Every report implements [`Report`]: a flat list of stable keys, serialised as a flat
//! JSON object and convertible to a table row.

pub mod blend;
pub mod cost;
pub mod distance;
pub mod error;
pub mod eval;
pub mod features;
pub mod filter_eval;
pub mod normals;
pub mod quality;
pub mod reference;
pub mod refused;
pub mod report;
pub mod sampling;
pub mod stats;
pub mod topology;

mod boxtree;

pub use blend::{BlendEval, BlendOptions, BlendTruthEval, eval_blend, eval_blend_truth};
pub use cost::{CostReport, cpu_time_seconds, peak_rss_bytes};
pub use distance::{DistanceEval, DistanceOptions, FScore, Sides, eval_distance};
pub use error::{MetricsError, Result};
pub use eval::{MeshEval, MeshEvalOptions, eval_cloud_features, eval_mesh};
pub use features::{
    CleanPositions, FeatureEval, FeatureOptions, MeshFeatureEval, eval_features, eval_mesh_features,
};
pub use filter_eval::{FilterEval, FilterEvalOptions, eval_filter};
pub use normals::{NormalEval, NormalGroundTruth, NormalOptions, eval_cloud_normals, eval_normals};
pub use quality::{QualityEval, QualityOptions, eval_quality};
pub use reference::{Reference, SurfaceHit};
pub use refused::{RefusedEval, eval_refused};
pub use report::{Report, Value};
pub use stats::Summary;
pub use topology::{TopologyEval, TopologyOptions, count_self_intersections, eval_topology};
