//! Provenance of the clouds `gen` writes: one `comment reconbench-provenance <JSON>` line
//! in the PLY header (other formats have no header comments, so none is written), and the
//! check that the evaluation verbs make with it: a cloud generated from one shape or mesh
//! must not be evaluated against another.

use std::path::Path;

use reconbench_geom::io::{self, Format};
use reconbench_synth::spec::resolve_params;
use reconbench_synth::{ShapeSpec, SynthError, shapes};
use serde::{Deserialize, Serialize};

use super::CliError;

/// First word of the provenance comment.
pub const TAG: &str = "reconbench-provenance";

/// What a cloud was generated from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Source {
    /// A built-in shape.
    Shape {
        /// Canonical spec: every parameter, defaults included (see [`canonical_shape`]).
        spec: String,
    },
    /// A mesh file.
    Mesh {
        /// File name (without the directory).
        file: String,
        /// [`io::content_hash`] of the file's bytes.
        hash: String,
        /// Sharp-edge threshold of the ground truth, degrees.
        feature_angle_deg: f64,
        /// Declared closedness (absent: as measured).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        closed: Option<bool>,
    },
}

impl Source {
    fn describe(&self) -> String {
        match self {
            Source::Shape { spec } => format!("shape '{spec}'"),
            Source::Mesh { file, hash, .. } => format!("mesh '{file}' (content hash {hash})"),
        }
    }
}

/// Everything that defines a generated cloud.
#[derive(Debug, Clone, Serialize)]
pub struct Provenance {
    /// Shape or mesh.
    pub source: Source,
    /// Sampler spec (absent for a scan).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampler: Option<String>,
    /// Requested point count (absent when the sampler or scan fixes the count).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<usize>,
    /// Requested spacing instead of a count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f64>,
    /// Perturbation specs, in the order applied.
    pub perturbations: Vec<String>,
    /// Scan spec.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan: Option<String>,
    /// Random seed.
    pub seed: u64,
    /// reconbench version that wrote the cloud.
    pub version: String,
}

impl Provenance {
    /// The header comment line (without the `comment ` keyword).
    pub fn comment(&self) -> Result<String, CliError> {
        let json = serde_json::to_string(self).map_err(CliError::failure)?;
        Ok(format!("{TAG} {json}"))
    }
}

/// A shape spec with every parameter spelled out (`torus` -> `torus:R=2,r=1`), so that
/// specs naming the same shape compare equal. Errors on an unknown shape or parameter
/// (values are checked when the shape is built).
pub fn canonical_shape(spec: &str) -> Result<String, SynthError> {
    let s: ShapeSpec = spec.parse()?;
    let defs = shapes::definitions();
    let Some(def) = defs.iter().find(|d| d.name == s.name) else {
        return Err(SynthError::UnknownName {
            what: "shape",
            name: s.name,
            valid: defs.iter().map(|d| d.name).collect::<Vec<_>>().join(", "),
        });
    };
    let params = resolve_params(&format!("shape '{}'", s.name), def.params, &s.params)?;
    Ok(ShapeSpec {
        name: s.name,
        params,
    }
    .to_string())
}

#[derive(Debug, Deserialize)]
struct SourceOnly {
    source: Source,
}

/// The source recorded in a PLY cloud's header; `None` when the file is not PLY or has no
/// provenance comment.
fn read_source(cloud: &Path) -> Result<Option<Source>, CliError> {
    if Format::from_path(cloud).ok() != Some(Format::Ply) {
        return Ok(None);
    }
    let comments = io::read_ply_comments(cloud).map_err(CliError::input)?;
    let Some(json) = comments.iter().find_map(|c| {
        c.strip_prefix(TAG)
            .filter(|r| r.starts_with(' '))
            .map(str::trim)
    }) else {
        return Ok(None);
    };
    let p: SourceOnly = serde_json::from_str(json).map_err(|e| {
        CliError::input(format!(
            "{}: malformed {TAG} header comment: {e}",
            cloud.display()
        ))
    })?;
    Ok(Some(p.source))
}

/// Fails (exit code 2) when `cloud` records a source that is not `reference` (a shape spec
/// or a mesh file, as `--reference` takes it). Shapes compare by canonical spec, meshes by
/// content hash; a cloud without provenance, a reference of the other kind (a shape's
/// cloud against a mesh file, which may be that shape's reference mesh) or a reference
/// that is neither a file nor a valid spec (reported by the evaluation itself) passes.
pub fn check(cloud: &Path, reference: &str) -> Result<(), CliError> {
    let Some(source) = read_source(cloud)? else {
        return Ok(());
    };
    let ref_path = Path::new(reference);
    let (matches, what) = match &source {
        Source::Mesh { hash, .. } if ref_path.is_file() => {
            let bytes = std::fs::read(ref_path)
                .map_err(|e| CliError::input(format!("cannot read {}: {e}", ref_path.display())))?;
            let h = io::content_hash(&bytes);
            (
                h == *hash,
                format!("mesh file {reference} (content hash {h})"),
            )
        }
        Source::Shape { spec } if !ref_path.is_file() => {
            let Ok(r) = canonical_shape(reference) else {
                return Ok(());
            };
            // A hand-edited spec is compared canonicalised too.
            let c = canonical_shape(spec).unwrap_or_else(|_| spec.clone());
            (c == r, format!("shape '{r}'"))
        }
        _ => return Ok(()),
    };
    if matches {
        Ok(())
    } else {
        Err(CliError::input(format!(
            "provenance mismatch: {} was generated from {}, but the reference is {what}",
            cloud.display(),
            source.describe()
        )))
    }
}
