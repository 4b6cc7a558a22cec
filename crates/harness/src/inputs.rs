//! The input of a cell: the data spec of an experiment's dataset x perturbation, the
//! perturbation keys of experiment files, and data generation through
//! `reconbench_synth::generate_for_shape` (the one place to adapt when synth changes).
//!
//! The perturbation keys map to synth's perturbation kinds ([`PERTURB_KEYS`]); the
//! [`DatasetSpec`] comes from [`dataset_spec`].

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_synth::{
    DatasetSpec, Density, NO_FEATURE, PerturbSpec, SamplerSpec, Shape, ShapeSpec,
};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{HarnessError, Result};
use crate::registry::GroundTruth;

/// The data a cell's input cloud is generated from (shared by every method of a cell).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataSpec {
    /// Shape spec.
    pub shape: String,
    /// Sampler spec.
    pub sampler: String,
    /// Number of points.
    pub points: u64,
    /// Perturbation settings (resolved scalars, sorted by key).
    pub perturb: BTreeMap<String, Value>,
}

/// Perturbation keys of experiment files, in the order they are applied: the key, the
/// synth perturbation kind, its main parameter (the value given), and its meaning.
/// A value of 0 means "not applied" (except for `decimate`). `spec` takes full synth
/// perturbation specs (`"misalign:groups=4,angle=1,shift=0.01"`), applied after the
/// others but before outliers.
pub const PERTURB_KEYS: &[(&str, &str, &str, &str)] = &[
    (
        "decimate",
        "decimate",
        "keep",
        "keep this fraction of the points",
    ),
    (
        "duplicate",
        "duplicate",
        "fraction",
        "duplicate this fraction of the points",
    ),
    ("holes", "holes", "count", "cut this many holes"),
    (
        "ma-uniform",
        "ma-uniform",
        "level",
        "seed 000's noise: U[-level s_p, level s_p] per coordinate",
    ),
    (
        "noise",
        "ball",
        "radius",
        "uniform in a ball of this radius (fraction of the diagonal; seed 002's model)",
    ),
    ("ball", "ball", "radius", "same as noise"),
    (
        "gaussian",
        "gaussian",
        "sigma",
        "Gaussian noise, this per-axis standard deviation (fraction of the diagonal)",
    ),
    (
        "normal-gaussian",
        "normal-gaussian",
        "sigma",
        "Gaussian displacement along the normal (fraction of the diagonal)",
    ),
    (
        "spec",
        "",
        "",
        "full synth perturbation spec(s), e.g. \"misalign:groups=4,angle=1,shift=0.01\"",
    ),
    (
        "copies",
        "copies",
        "fraction",
        "SCUTSurface outliers: displaced copies of this fraction of the points",
    ),
    (
        "outliers",
        "outliers",
        "fraction",
        "this fraction of extra points, uniform in the inflated bounding box",
    ),
];

pub(crate) fn list<'a>(items: impl Iterator<Item = &'a str>) -> String {
    items.collect::<Vec<_>>().join(", ")
}

/// Checks a perturbation key.
pub fn validate_perturb_key(k: &str) -> Result<()> {
    if PERTURB_KEYS.iter().any(|(n, ..)| *n == k) {
        Ok(())
    } else {
        Err(HarnessError::input(format!(
            "unknown perturbation '{k}'; valid: name, {}",
            list(PERTURB_KEYS.iter().map(|(n, ..)| *n))
        )))
    }
}

/// The synth perturbation steps of resolved perturbation values, in application order.
pub fn perturb_specs(p: &BTreeMap<String, Value>) -> Result<Vec<PerturbSpec>> {
    let mut out = Vec::new();
    for (key, kind, param, _) in PERTURB_KEYS {
        let Some(v) = p.get(*key) else { continue };
        let texts: Vec<String> = if *key == "spec" {
            match v {
                Value::String(s) if s.trim().is_empty() => Vec::new(),
                Value::String(s) => vec![s.clone()],
                other => {
                    return Err(HarnessError::input(format!(
                        "perturbation 'spec': expected a synth perturbation spec string, got {other}"
                    )));
                }
            }
        } else {
            let x = v.as_f64().ok_or_else(|| {
                HarnessError::input(format!("perturbation '{key}': expected a number, got {v}"))
            })?;
            if !x.is_finite() || x < 0.0 {
                return Err(HarnessError::input(format!(
                    "perturbation '{key}' = {x}: must be a finite number >= 0"
                )));
            }
            if x == 0.0 && *key != "decimate" {
                Vec::new()
            } else {
                vec![format!("{kind}:{param}={x}")]
            }
        };
        for t in texts {
            let spec: PerturbSpec = t
                .parse()
                .map_err(|e| HarnessError::input(format!("perturbation '{key}' ({t}): {e}")))?;
            out.push(spec);
        }
    }
    Ok(out)
}

/// Checks resolved perturbation values.
pub fn validate_perturb_values(p: &BTreeMap<String, Value>) -> Result<()> {
    perturb_specs(p).map(drop)
}

/// Checks a dataset's shape and sampler specs.
pub fn validate_data(shape: &str, sampler: &str) -> Result<()> {
    reconbench_synth::from_spec(shape)
        .map_err(|e| HarnessError::input(format!("shape '{shape}': {e}")))?;
    sampler
        .parse::<SamplerSpec>()
        .map_err(|e| HarnessError::input(format!("sampler '{sampler}': {e}")))?;
    Ok(())
}

/// The synth dataset spec of a cell's data.
pub fn dataset_spec(data: &DataSpec) -> Result<DatasetSpec> {
    let shape: ShapeSpec = data
        .shape
        .parse()
        .map_err(|e| HarnessError::input(format!("shape '{}': {e}", data.shape)))?;
    let sampler: SamplerSpec = data
        .sampler
        .parse()
        .map_err(|e| HarnessError::input(format!("sampler '{}': {e}", data.sampler)))?;
    let n = usize::try_from(data.points).map_err(|_| HarnessError::input("too many points"))?;
    Ok(DatasetSpec {
        shape,
        sampler,
        density: Density::Count(n),
        perturbations: perturb_specs(&data.perturb)?,
        scan: None,
    })
}

/// The generated input of a cell and its ground truth.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The cloud methods see: positions only.
    pub input: PointCloud,
    /// Ground truth (handed to oracles and to the metrics).
    pub gt: GroundTruth,
    /// Per input point: the clean position it came from (outliers: their own).
    pub clean: Vec<DVec3>,
    /// Per input point: whether it is an added outlier.
    pub is_outlier: Vec<bool>,
}

/// Generates the input of a cell with synth (see the module docs).
pub fn generate(data: &DataSpec, shape: Arc<dyn Shape>, seed: u64) -> Result<Generated> {
    let spec = dataset_spec(data)?;
    let g = reconbench_synth::generate_for_shape(shape.as_ref(), &spec, seed)
        .map_err(|e| HarnessError::failure(format!("data generation: {e}")))?;
    let input = PointCloud::new(g.positions).map_err(|e| HarnessError::failure(e.to_string()))?;
    let feature_distance = g
        .feature_distance
        .iter()
        .map(|&d| if d == NO_FEATURE { f64::INFINITY } else { d })
        .collect();
    Ok(Generated {
        input,
        gt: GroundTruth {
            shape: Some(shape),
            normals: Some(g.normals),
            feature_distance: Some(feature_distance),
        },
        clean: g.clean_positions,
        is_outlier: g.is_outlier,
    })
}
