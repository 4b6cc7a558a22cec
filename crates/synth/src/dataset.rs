//! The glue: one [`DatasetSpec`] and a seed give one [`GroundTruthCloud`], bit for bit.

use serde::{Deserialize, Serialize};

use crate::cloud::GroundTruthCloud;
use crate::error::Result;
use crate::perturb::{self, PerturbContext, PerturbSpec};
use crate::sampler::{self, Density, SamplerSpec};
use crate::scanner::{self, ScanSpec};
use crate::shape::Shape;
use crate::shapes::ShapeSpec;

/// Everything that defines a synthetic point cloud (besides the seed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetSpec {
    /// The shape.
    pub shape: ShapeSpec,
    /// The surface sampler (ignored when `scan` is set).
    #[serde(default)]
    pub sampler: SamplerSpec,
    /// Point count or spacing (ignored when `scan` is set).
    pub density: Density,
    /// Perturbations, applied in order after sampling or scanning.
    #[serde(default)]
    pub perturbations: Vec<PerturbSpec>,
    /// Virtual range scan instead of surface sampling.
    #[serde(default)]
    pub scan: Option<ScanSpec>,
}

impl DatasetSpec {
    /// A spec sampling `count` points uniformly from `shape`, without perturbations.
    pub fn uniform(shape: ShapeSpec, count: usize) -> Self {
        Self {
            shape,
            sampler: SamplerSpec::Uniform,
            density: Density::Count(count),
            perturbations: Vec::new(),
            scan: None,
        }
    }
}

/// Builds the shape and generates the cloud. Same spec and seed give identical output,
/// whatever the number of threads.
pub fn generate(spec: &DatasetSpec, seed: u64) -> Result<GroundTruthCloud> {
    let shape = spec.shape.build()?;
    generate_for_shape(shape.as_ref(), spec, seed)
}

/// [`generate`] for an already built shape (e.g. a user's mesh as a
/// [`crate::shapes::MeshShape`]); `spec.shape` is not used.
pub fn generate_for_shape(
    shape: &dyn Shape,
    spec: &DatasetSpec,
    seed: u64,
) -> Result<GroundTruthCloud> {
    let mut cloud = sample_or_scan(shape, &spec.sampler, spec.density, spec.scan.as_ref(), seed)?;
    // Noise is relative to what is scanned (a blend shape's part).
    let scanned = shape.scanned_part().unwrap_or(shape);
    perturb::apply_all(
        &mut cloud,
        &spec.perturbations,
        &PerturbContext {
            aabb: scanned.aabb(),
        },
        seed,
    )?;
    Ok(cloud)
}

/// The clean cloud of a dataset, before perturbations: a virtual scan when `scan` is
/// given, else the sampler at the density; of [`Shape::scanned_part`] when the shape has
/// one (a blend shape's part, without its designed tube).
pub fn sample_or_scan(
    shape: &dyn Shape,
    sampler: &SamplerSpec,
    density: Density,
    scan: Option<&ScanSpec>,
    seed: u64,
) -> Result<GroundTruthCloud> {
    let shape = shape.scanned_part().unwrap_or(shape);
    match scan {
        Some(scan) => scanner::scan(shape, scan, seed),
        None => sampler::sample(shape, sampler, density, seed),
    }
}
