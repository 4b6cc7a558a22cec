//! Ground truth for reconbench: analytic shapes with exact closest points, normals,
//! sharp features and genus; samplers; perturbations; a virtual range scanner.
//!
//! Entry points: [`shapes::from_spec`] / [`shapes::catalog`] for shapes,
//! [`dataset::generate`] for a whole synthetic point cloud from a [`DatasetSpec`].
//! Randomness comes only from ChaCha8 streams derived from the one `u64` seed, so the
//! same spec and seed give identical output bit for bit.

pub mod cloud;
pub mod dataset;
pub mod error;
pub mod features;
pub mod geom2d;
pub mod perturb;
pub mod polygonize;
pub mod raycast;
pub mod real;
pub mod sampler;
pub mod scanner;
pub mod shape;
pub mod shapes;
pub mod spec;
pub mod util;

pub use cloud::{GroundTruthCloud, NO_FEATURE, NO_SOURCE};
pub use dataset::{DatasetSpec, generate, generate_for_shape, sample_or_scan};
pub use error::{Result, SynthError};
pub use perturb::{PerturbSpec, Reference};
pub use sampler::{Density, SamplerSpec};
pub use scanner::ScanSpec;
pub use shape::{FeatureCurve, Sample, Shape, ShapeInfo, SurfacePoint};
pub use shapes::{
    DEFAULT_MESH_FEATURE_ANGLE_DEG, MeshShape, MeshShapeOptions, ShapeSpec, catalog, from_spec,
};
