//! The metric side of an experiment file: the `[metrics]` sections and their options,
//! the default table columns per method kind and the direction of every metric.

use reconbench_metrics::{FeatureOptions, MeshEvalOptions, NormalOptions};
use serde_json::Value;

use crate::error::{HarnessError, Result};
use crate::inputs::list;
use crate::registry::MethodKind;

/// Top-level keys of `[metrics]`.
pub const METRIC_SECTIONS: &[(&str, &str)] = &[
    (
        "mesh",
        "options of metrics::eval_mesh (distance sampling, topology, quality, features)",
    ),
    ("normals", "options of metrics::eval_normals"),
    (
        "features",
        "options of metrics::eval_features (feature angle, radius)",
    ),
];

/// Checks `[metrics]` (top-level sections and their option types).
pub fn validate_metric_options(m: &Value) -> Result<()> {
    if let Value::Object(map) = m {
        for k in map.keys() {
            if !METRIC_SECTIONS.iter().any(|(n, _)| n == k) {
                return Err(HarnessError::input(format!(
                    "unknown [metrics] section '{k}'; valid: {}",
                    list(METRIC_SECTIONS.iter().map(|(n, _)| *n))
                )));
            }
        }
    }
    metric_options(m).map(drop)
}

pub(crate) struct MetricOptions {
    pub(crate) mesh: MeshEvalOptions,
    pub(crate) normals: NormalOptions,
    pub(crate) features: FeatureOptions,
}

fn section<T: serde::de::DeserializeOwned + Default>(m: &Value, name: &str) -> Result<T> {
    match m.get(name) {
        None => Ok(T::default()),
        Some(v) => serde_json::from_value(v.clone())
            .map_err(|e| HarnessError::input(format!("[metrics.{name}]: {e}"))),
    }
}

pub(crate) fn metric_options(m: &Value) -> Result<MetricOptions> {
    Ok(MetricOptions {
        mesh: section(m, "mesh")?,
        normals: section(m, "normals")?,
        features: section(m, "features")?,
    })
}

/// Default table columns per method kind (the first two are plotted).
pub fn default_metrics(kind: MethodKind) -> &'static [&'static str] {
    match kind {
        MethodKind::Normals => &[
            "normal_mean_deg",
            "normal_rms_deg",
            "normal_pgp5",
            "normal_pgp10",
        ],
        MethodKind::Features => &[
            "feature_f1",
            "feature_precision",
            "feature_recall",
            "feature_false_positives",
        ],
        MethodKind::Filter => &[
            "cloud_rms_dist",
            "cloud_mean_dist",
            "points_out",
            "outliers_removed",
        ],
        MethodKind::Reconstruct => &[
            "chamfer_l1",
            "hausdorff",
            "fscore_0.005",
            "topology_ok",
            "self_intersections",
            "unreferenced_vertices",
        ],
    }
}

/// Whether larger values of `metric` are better (for bold table entries and
/// regression directions).
pub fn higher_is_better(metric: &str) -> bool {
    const UP: &[&str] = &[
        "pgp",
        "fscore",
        "precision",
        "recall",
        "f1",
        "coverage",
        "recovery",
        "_ok",
        "watertight",
        "orientable",
        "min_angle",
        "matching",
    ];
    UP.iter().any(|u| metric.contains(u))
}
