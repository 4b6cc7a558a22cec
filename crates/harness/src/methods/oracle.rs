//! Honest oracles for calibrating the harness before the seed algorithms land.
//!
//! They are the only methods that receive [`GroundTruth`]: `gt-normals` returns the
//! ground-truth normals (the metric floor of normal estimation, 0 degrees up to the
//! metric's own conventions), `gt-features` labels points by their true distance to a
//! sharp feature curve, and `reference-mesh` returns the shape's reference mesh (the
//! geometry floor: what a perfect reconstructor at that resolution would achieve).
//!
//! Outside an experiment (one-shot verbs on a file) there is no ground truth; then
//! `gt-normals` takes the normals stored in the input file, `gt-features` the file's
//! `feature_distance` channel, and `reference-mesh` needs its `shape` parameter.

use std::sync::Arc;

use reconbench_geom::PointCloud;
use reconbench_geom::method::{
    Diagnostic, Diagnostics, FeatureClass, FeatureDetector, FeatureLabels, MethodError,
    NormalEstimator, Normals, Reconstruction, Reconstructor, RunCtx,
};
use reconbench_synth::Shape;
use serde::{Deserialize, Serialize};

use crate::entry::{
    Built, GroundTruth, MethodEntry, MethodEnv, MethodKind, ParamDoc, Unit, custom,
};

/// Parameters of `gt-normals` (none).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GtNormalsParams {}

/// `gt-normals`: returns the ground-truth normals, oriented.
#[derive(Debug)]
pub struct GtNormals {
    gt: Option<Arc<GroundTruth>>,
}

impl NormalEstimator for GtNormals {
    fn name(&self) -> &str {
        "gt-normals"
    }

    fn estimate(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<Normals, MethodError> {
        let normals = ctx.phase("copy", || {
            match self.gt.as_ref().and_then(|g| g.normals.as_ref()) {
                Some(n) => Ok(n.clone()),
                None => cloud.normals().map(<[_]>::to_vec).ok_or_else(|| {
                    MethodError::InvalidInput(
                        "gt-normals needs ground truth: run it in an experiment, or give a \
                         cloud file that stores normals"
                            .into(),
                    )
                }),
            }
        })?;
        if normals.len() != cloud.len() {
            return Err(MethodError::InvalidInput(format!(
                "ground truth has {} normals for {} points",
                normals.len(),
                cloud.len()
            )));
        }
        Ok(Normals {
            normals,
            oriented: true,
            diagnostics: Diagnostics::new(),
        })
    }
}

/// Registry entry of `gt-normals`.
pub fn gt_normals() -> MethodEntry {
    custom::<GtNormalsParams>(
        MethodKind::Normals,
        "gt-normals",
        "oracle",
        "ground-truth normals (the metric floor); outside experiments: the file's normals",
        &[],
        |_p, env: &MethodEnv| {
            Ok(Built::Normals(Box::new(GtNormals {
                gt: env.ground_truth.clone(),
            })))
        },
    )
    .oracle()
}

/// Parameters of `gt-features`. The defaults match the feature metric's ground-truth
/// positive set (docs/METRICS.md: within `r = 1 x mean spacing` of a counted curve), so
/// the oracle scores the floor (F1 = 1) under default metric options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GtFeaturesParams {
    /// `r` as a multiple of the input cloud's mean spacing.
    pub radius_factor: f64,
    /// Explicit `r` (fraction of the diagonal; overrides `radius_factor` when > 0).
    pub radius: f64,
}

impl Default for GtFeaturesParams {
    fn default() -> Self {
        Self {
            radius_factor: 1.0,
            radius: 0.0,
        }
    }
}

const GT_FEATURES_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "radius_factor",
        Unit::Spacing,
        "label points whose clean position is within this many mean spacings of a feature curve",
    ),
    ParamDoc::new(
        "radius",
        Unit::Diag,
        "explicit radius; overrides radius_factor when > 0",
    ),
];

/// `gt-features`: labels points by their true distance to a feature curve.
#[derive(Debug)]
pub struct GtFeatures {
    gt: Option<Arc<GroundTruth>>,
    radius_factor: f64,
    radius: f64,
}

impl FeatureDetector for GtFeatures {
    fn name(&self) -> &str {
        "gt-features"
    }

    fn detect(&self, cloud: &PointCloud, ctx: &mut RunCtx) -> Result<FeatureLabels, MethodError> {
        let from_file;
        let dist: &[f64] = match self.gt.as_ref().and_then(|g| g.feature_distance.as_ref()) {
            Some(d) => d,
            None => {
                let ch = cloud.channel("feature_distance").ok_or_else(|| {
                    MethodError::InvalidInput(
                        "gt-features needs ground truth: run it in an experiment, or give a \
                         cloud file with a 'feature_distance' channel"
                            .into(),
                    )
                })?;
                from_file = (0..ch.len()).map(|i| ch.get_f64(i)).collect::<Vec<_>>();
                &from_file
            }
        };
        if dist.len() != cloud.len() {
            return Err(MethodError::InvalidInput(format!(
                "ground truth has {} feature distances for {} points",
                dist.len(),
                cloud.len()
            )));
        }
        let r = if self.radius > 0.0 {
            self.radius
        } else {
            self.radius_factor * reconbench_geom::mean_spacing(cloud.positions(), 1)?
        };
        let labels = ctx.phase("label", || {
            dist.iter()
                .map(|&d| {
                    if d <= r {
                        FeatureClass::Edge
                    } else {
                        FeatureClass::None
                    }
                })
                .collect::<Vec<_>>()
        });
        let mut diagnostics = Diagnostics::new();
        let n = labels.iter().filter(|&&c| c != FeatureClass::None).count();
        diagnostics.insert("labelled".into(), Diagnostic::Number(n as f64));
        Ok(FeatureLabels {
            labels,
            scores: None,
            diagnostics,
        })
    }
}

/// Registry entry of `gt-features`.
pub fn gt_features() -> MethodEntry {
    custom::<GtFeaturesParams>(
        MethodKind::Features,
        "gt-features",
        "oracle",
        "labels points within r of a true feature curve, r as the feature metric (the feature floor)",
        GT_FEATURES_DOCS,
        |p, env| {
            for (name, v) in [("radius", p.radius), ("radius_factor", p.radius_factor)] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(MethodError::InvalidParameter {
                        name: name.into(),
                        message: format!("must be a finite number >= 0, got {v}"),
                    });
                }
            }
            Ok(Built::Features(Box::new(GtFeatures {
                gt: env.ground_truth.clone(),
                radius_factor: p.radius_factor,
                radius: p.radius,
            })))
        },
    )
    .oracle()
}

/// Parameters of `reference-mesh`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReferenceMeshParams {
    /// Segments along the longest parametric direction of the shape.
    pub resolution: usize,
    /// Shape spec to mesh when there is no ground truth (one-shot use), e.g.
    /// `torus:R=0.5,r=0.2`. Ignored inside experiments, where the cell's shape is used.
    pub shape: String,
}

impl Default for ReferenceMeshParams {
    fn default() -> Self {
        Self {
            resolution: 64,
            shape: String::new(),
        }
    }
}

const REFERENCE_MESH_DOCS: &[ParamDoc] = &[
    ParamDoc::new(
        "resolution",
        Unit::Count,
        "segments along the longest parametric direction of the shape",
    ),
    ParamDoc::new(
        "shape",
        Unit::None,
        "shape spec used outside experiments (e.g. torus:R=0.5,r=0.2)",
    ),
];

/// `reference-mesh`: the shape's reference mesh.
#[derive(Debug)]
pub struct ReferenceMesh {
    shape: Option<Arc<dyn Shape>>,
    spec: String,
    resolution: usize,
}

impl Reconstructor for ReferenceMesh {
    fn name(&self) -> &str {
        "reference-mesh"
    }

    fn reconstruct(
        &self,
        _cloud: &PointCloud,
        ctx: &mut RunCtx,
    ) -> Result<Reconstruction, MethodError> {
        let shape: Arc<dyn Shape> = match &self.shape {
            Some(s) => s.clone(),
            None if !self.spec.is_empty() => {
                Arc::from(reconbench_synth::from_spec(&self.spec).map_err(|e| {
                    MethodError::InvalidParameter {
                        name: "shape".into(),
                        message: e.to_string(),
                    }
                })?)
            }
            None => {
                return Err(MethodError::InvalidInput(
                    "reference-mesh needs ground truth: run it in an experiment, or set its \
                     'shape' parameter (--set shape=torus)"
                        .into(),
                ));
            }
        };
        let res = self.resolution;
        let mesh = ctx.phase("mesh", || shape.reference_mesh(res));
        let mut diagnostics = Diagnostics::new();
        diagnostics.insert("resolution".into(), Diagnostic::Number(res as f64));
        Ok(Reconstruction {
            mesh,
            refused: Vec::new(),
            diagnostics,
        })
    }
}

/// Registry entry of `reference-mesh`.
pub fn reference_mesh() -> MethodEntry {
    custom::<ReferenceMeshParams>(
        MethodKind::Reconstruct,
        "reference-mesh",
        "oracle",
        "the ground-truth shape's reference mesh (the geometry floor)",
        REFERENCE_MESH_DOCS,
        |p, env| {
            if p.resolution < 3 || p.resolution > 4096 {
                return Err(MethodError::InvalidParameter {
                    name: "resolution".into(),
                    message: format!("must be in 3..=4096, got {}", p.resolution),
                });
            }
            Ok(Built::Reconstruct(Box::new(ReferenceMesh {
                shape: env.ground_truth.as_ref().and_then(|g| g.shape.clone()),
                spec: p.shape,
                resolution: p.resolution,
            })))
        },
    )
    .oracle()
}
