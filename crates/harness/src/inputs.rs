//! The input of a cell: the data spec of an experiment's dataset x perturbation, the
//! perturbation keys of experiment files, and data generation through synth's samplers,
//! scanner and perturbations (the one place to adapt when synth changes).
//!
//! The data comes from an analytic shape, a mesh file (a vendored real set or any mesh:
//! sampled, scanned, or its own vertices, with the mesh as exact ground truth) or a
//! point-cloud file (no ground truth). The perturbation keys map to synth's perturbation
//! kinds ([`PERTURB_KEYS`]).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use reconbench_geom::PointCloud;
use reconbench_synth::perturb::PerturbContext;
use reconbench_synth::{
    Density, GroundTruthCloud, MeshShape, MeshShapeOptions, NO_FEATURE, PerturbSpec, SamplerSpec,
    ScanSpec, Shape,
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
    /// Virtual range scan instead of surface sampling (a synth scan spec).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scan: Option<String>,
    /// The file the data comes from, for a `real`, `mesh` or `cloud` dataset (`shape`
    /// then holds `real:NAME`, `mesh:PATH` or `cloud:PATH`, as written).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<FileInput>,
}

/// What kind of file a dataset reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FileKind {
    /// A vendored real set (`datasets/real/`), a mesh.
    Real,
    /// A user's mesh.
    Mesh,
    /// A user's point cloud: the input as is, without ground truth.
    Cloud,
}

/// A dataset file: where it is, what it must contain, how it becomes ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileInput {
    /// Kind.
    pub kind: FileKind,
    /// Resolved path. Not part of cell keys (results do not depend on where the
    /// checkout is); `hash` is.
    pub path: String,
    /// FNV-1a 64 of the file's bytes (hex): a changed file changes the keys, and a worker
    /// refuses a file that changed after expansion.
    pub hash: String,
    /// Sharp-edge threshold of the mesh ground truth, degrees.
    pub feature_angle_deg: f64,
    /// Declared closedness of the mesh ground truth (`None`: as measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closed: Option<bool>,
}

/// Content hash of a file (hex FNV-1a 64), naming the file on error.
pub fn file_hash(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path)
        .map_err(|e| HarnessError::input(format!("cannot read {}: {e}", path.display())))?;
    Ok(reconbench_geom::io::content_hash(&bytes))
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

/// Checks a dataset's shape (unless it reads a file), sampler and scan specs.
pub fn validate_data(shape: Option<&str>, sampler: &str, scan: Option<&str>) -> Result<()> {
    if let Some(shape) = shape {
        reconbench_synth::from_spec(shape)
            .map_err(|e| HarnessError::input(format!("shape '{shape}': {e}")))?;
    }
    sampler
        .parse::<SamplerSpec>()
        .map_err(|e| HarnessError::input(format!("sampler '{sampler}': {e}")))?;
    if let Some(scan) = scan {
        scan.parse::<ScanSpec>()
            .map_err(|e| HarnessError::input(format!("scan '{scan}': {e}")))?;
    }
    Ok(())
}

/// The ground-truth shape of a cell's data: the analytic shape, the mesh of a `real` or
/// `mesh` file (checked against its hash), or `None` for a cloud file.
pub fn build_shape(data: &DataSpec) -> Result<Option<Arc<dyn Shape>>> {
    let Some(f) = &data.file else {
        let shape = reconbench_synth::from_spec(&data.shape)
            .map_err(|e| HarnessError::input(format!("shape '{}': {e}", data.shape)))?;
        return Ok(Some(Arc::from(shape)));
    };
    let path = Path::new(&f.path);
    if file_hash(path)? != f.hash {
        return Err(HarnessError::input(format!(
            "{} changed since the experiment was expanded (content hash differs); run again",
            path.display()
        )));
    }
    if f.kind == FileKind::Cloud {
        return Ok(None);
    }
    let mesh = reconbench_geom::io::read_mesh(path)
        .map_err(|e| HarnessError::input(format!("{}: {e}", path.display())))?;
    let opts = MeshShapeOptions {
        feature_angle_deg: f.feature_angle_deg,
        closed: f.closed,
    };
    let shape = MeshShape::with_options(&data.shape, mesh, opts)
        .map_err(|e| HarnessError::input(format!("{}: {e}", path.display())))?;
    Ok(Some(Arc::new(shape)))
}

/// The generated input of a cell and its ground truth.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The cloud methods see: positions only.
    pub input: PointCloud,
    /// Ground truth (handed to oracles and to the metrics); empty for a cloud file.
    pub gt: GroundTruth,
    /// Per input point: the clean position it came from (outliers: their own; a cloud
    /// file's points: their unperturbed position).
    pub clean: Vec<DVec3>,
    /// Per input point: whether it is an added outlier.
    pub is_outlier: Vec<bool>,
}

/// Generates the input of a cell: samples or scans `shape` and perturbs the result, or,
/// without a shape, reads the cloud file and perturbs it (see the module docs).
pub fn generate(data: &DataSpec, shape: Option<Arc<dyn Shape>>, seed: u64) -> Result<Generated> {
    let perturbations = perturb_specs(&data.perturb)?;
    let fail =
        |e: reconbench_synth::SynthError| HarnessError::failure(format!("data generation: {e}"));
    let (mut g, aabb) = match &shape {
        Some(shape) => {
            let scan: Option<ScanSpec> =
                data.scan
                    .as_deref()
                    .map(str::parse)
                    .transpose()
                    .map_err(|e| {
                        HarnessError::input(format!(
                            "scan '{}': {e}",
                            data.scan.as_deref().unwrap_or_default()
                        ))
                    })?;
            let sampler: SamplerSpec = data
                .sampler
                .parse()
                .map_err(|e| HarnessError::input(format!("sampler '{}': {e}", data.sampler)))?;
            let n =
                usize::try_from(data.points).map_err(|_| HarnessError::input("too many points"))?;
            let g = reconbench_synth::sample_or_scan(
                shape.as_ref(),
                &sampler,
                Density::Count(n),
                scan.as_ref(),
                seed,
            )
            .map_err(fail)?;
            // Noise is relative to what is scanned (a blend shape's part).
            (g, shape.scanned_part().unwrap_or(shape.as_ref()).aabb())
        }
        None => {
            let f = data
                .file
                .as_ref()
                .ok_or_else(|| HarnessError::failure("a dataset without shape or file"))?;
            let cloud = reconbench_geom::io::read_cloud(&f.path)
                .map_err(|e| HarnessError::input(format!("{}: {e}", f.path)))?;
            let aabb = cloud.aabb();
            (file_cloud(&cloud), aabb)
        }
    };
    reconbench_synth::perturb::apply_all(&mut g, &perturbations, &PerturbContext { aabb }, seed)
        .map_err(fail)?;
    let input = PointCloud::new(g.positions).map_err(|e| HarnessError::failure(e.to_string()))?;
    let gt = match shape {
        Some(shape) => GroundTruth {
            shape: Some(shape),
            normals: Some(g.normals),
            feature_distance: Some(
                g.feature_distance
                    .iter()
                    .map(|&d| if d == NO_FEATURE { f64::INFINITY } else { d })
                    .collect(),
            ),
        },
        None => GroundTruth {
            shape: None,
            normals: None,
            feature_distance: None,
        },
    };
    Ok(Generated {
        input,
        gt,
        clean: g.clean_positions,
        is_outlier: g.is_outlier,
    })
}

/// A cloud file as synth's cloud type, so that the perturbations apply to it: its
/// points are their own clean positions; its normals (zero when it has none) are what
/// normal-direction noise moves along; no feature distances.
fn file_cloud(cloud: &PointCloud) -> GroundTruthCloud {
    let n = cloud.len();
    let positions = cloud.positions().to_vec();
    GroundTruthCloud {
        clean_positions: positions.clone(),
        normals: cloud
            .normals()
            .map(<[DVec3]>::to_vec)
            .unwrap_or_else(|| vec![DVec3::ZERO; n]),
        source_ids: (0..n as u32).collect(),
        feature_distance: vec![NO_FEATURE; n],
        is_outlier: vec![false; n],
        positions,
        scan_ids: None,
        view_dirs: None,
    }
}
