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
    for (name, _) in METRIC_SECTIONS {
        if let Some(v) = m.get(*name) {
            let defaults = match *name {
                "mesh" => defaults_of::<MeshEvalOptions>(),
                "normals" => defaults_of::<NormalOptions>(),
                _ => defaults_of::<FeatureOptions>(),
            };
            unknown_option(v, &defaults, &format!("metrics.{name}"))?;
        }
    }
    metric_options(m).map(drop)
}

fn defaults_of<T: serde::Serialize + Default>() -> Value {
    serde_json::to_value(T::default()).unwrap_or(Value::Null)
}

/// Refuses a key of the user's `[metrics.*]` table that the options type does not have
/// (serde's defaults would silently ignore a typo), naming the valid keys.
fn unknown_option(given: &Value, defaults: &Value, path: &str) -> Result<()> {
    let (Value::Object(g), Value::Object(d)) = (given, defaults) else {
        return Ok(());
    };
    for (k, v) in g {
        match d.get(k) {
            None => {
                return Err(HarnessError::input(format!(
                    "unknown key '{k}' in [{path}]; valid: {}",
                    list(d.keys().map(String::as_str))
                )));
            }
            Some(dv) => unknown_option(v, dv, &format!("{path}.{k}"))?,
        }
    }
    Ok(())
}

/// The metric keys the harness can put into a row, for checking `report.metrics`,
/// `report.plot_metrics` and `[[expect]] metric` when the file loads. Families with a
/// parameter in the name are matched by [`is_metric_name`]; a test runs every kind of
/// method and checks that every key it produced is known here.
pub const METRIC_NAMES: &[&str] = &[
    "aspect_ratio_max",
    "aspect_ratio_mean",
    "aspect_ratio_p95",
    "blend_collar_dist_max_sp",
    "blend_collar_dist_mean_sp",
    "blend_collar_normal_var_deg",
    "blend_collar_nn_cv",
    "blend_collar_points",
    "blend_gap_sp",
    "blend_nurbs_dist_max_sp",
    "blend_nurbs_dist_mean_sp",
    "blend_nurbs_points",
    "blend_region_normal_max_deg",
    "blend_region_normal_mean_deg",
    "blend_region_points",
    "blend_removed_points",
    "blend_scan_dist_max_sp",
    "blend_scan_dist_mean_sp",
    "blend_scan_points",
    "boundary_edges",
    "boundary_length_abs",
    "boundary_loops",
    "chamfer_l1",
    "chamfer_l1_abs",
    "clean_refused_share",
    "cloud_max_dist",
    "cloud_mean_dist",
    "cloud_rms_dist",
    "collapsed_faces",
    "components",
    "consistently_oriented",
    "degenerate_faces",
    "degenerate_triangles",
    "delta_f",
    "duplicate_faces",
    "edge_length_max_abs",
    "edge_length_mean_abs",
    "edge_length_min_abs",
    "edge_length_std_abs",
    "edge_length_target_abs",
    "edges",
    "euler",
    "faces",
    "feature_angle_deg",
    "feature_coverage",
    "feature_curve_length",
    "feature_curves",
    "feature_detected",
    "feature_dist_max",
    "feature_dist_max_abs",
    "feature_dist_mean",
    "feature_dist_mean_abs",
    "feature_f1",
    "feature_f1_2r",
    "feature_face_normal_max_deg",
    "feature_face_normal_mean_deg",
    "feature_faces_near",
    "feature_false_positives",
    "feature_false_positives_2r",
    "feature_gt_positives",
    "feature_gt_positives_2r",
    "feature_gt_share",
    "feature_points",
    "feature_precision",
    "feature_precision_2r",
    "feature_radius",
    "feature_radius_abs",
    "feature_recall",
    "feature_recall_2r",
    "feature_recovery",
    "feature_recovery_radius",
    "feature_recovery_radius_abs",
    "feature_sharp_edges",
    "feature_spacing_abs",
    "filter_spacing_abs",
    "genus",
    "gt_components",
    "gt_diagonal",
    "gt_genus",
    "hausdorff",
    "hausdorff_abs",
    "hausdorff_p95",
    "hausdorff_p95_abs",
    "input_dist_max",
    "input_dist_max_sp",
    "input_dist_mean",
    "input_dist_mean_sp",
    "invalid_normals",
    "max_angle_deg",
    "max_angle_mean_deg",
    "min_angle_deg",
    "min_angle_mean_deg",
    "non_manifold_edges",
    "non_manifold_vertices",
    "normal_away_max_deg",
    "normal_away_mean_deg",
    "normal_away_points",
    "normal_flip_rate",
    "normal_gt_missing",
    "normal_near_max_deg",
    "normal_near_mean_deg",
    "normal_near_points",
    "normal_pgp10",
    "normal_pgp5",
    "normal_points",
    "normal_skipped_points",
    "orientable",
    "outliers",
    "outliers_removed",
    "pinched_vertices",
    "input_points",
    "points_in",
    "points_out",
    "referenced_vertices",
    "refused",
    "refused_outlier_recall",
    "refused_outliers",
    "refused_precision",
    "sample_seed",
    "samples_recon",
    "samples_recon_vertices",
    "samples_reference",
    "self_intersections",
    "share_min_angle_below_12",
    "surface_dist_max",
    "surface_dist_max_sp",
    "surface_dist_mean",
    "surface_dist_mean_sp",
    "topology_ok",
    "topology_type_ok",
    "unreferenced_vertices",
    "valid_faces",
    "vertices",
    "watertight",
];

/// Whether `name` is a metric key a row can hold: one of [`METRIC_NAMES`], a method
/// diagnostic copied into the metrics, or a member of a parametrised family
/// (`accuracy_{stat}[_abs]`, `completeness_{stat}[_abs]`, `fscore_{t}`,
/// `precision_{t}`, `recall_{t}`, `normal[_oriented]_{stat}_{deg|rad}`, `line_*`,
/// `line_curved_*`).
pub fn is_metric_name(name: &str) -> bool {
    if METRIC_NAMES.contains(&name) || crate::cell::DIAGNOSTIC_METRICS.contains(&name) {
        return true;
    }
    const STATS: &[&str] = &["mean", "rms", "p95", "max", "median", "std"];
    let stat = |s: &str| STATS.contains(&s);
    let number = |s: &str| s.parse::<f64>().is_ok_and(f64::is_finite);
    for fam in ["accuracy_", "completeness_"] {
        if let Some(rest) = name.strip_prefix(fam)
            && stat(rest.strip_suffix("_abs").unwrap_or(rest))
        {
            return true;
        }
    }
    for fam in ["fscore_", "precision_", "recall_"] {
        if name.strip_prefix(fam).is_some_and(number) {
            return true;
        }
    }
    for fam in ["normal_oriented_", "normal_"] {
        if let Some(rest) = name.strip_prefix(fam)
            && let Some(s) = rest
                .strip_suffix("_deg")
                .or_else(|| rest.strip_suffix("_rad"))
            && stat(s)
        {
            return true;
        }
    }
    ["line_", "line_curved_"].iter().any(|f| {
        name.strip_prefix(f)
            .is_some_and(|r| r == "count" || (r.starts_with("err_") && r.ends_with("_sp")))
    })
}

/// Refuses an unknown metric name in `what` (a report or expectation field), with the
/// closest known names as suggestions.
pub fn check_metric_name(name: &str, what: &str) -> Result<()> {
    if is_metric_name(name) {
        return Ok(());
    }
    let mut pool: Vec<String> = METRIC_NAMES
        .iter()
        .chain(crate::cell::DIAGNOSTIC_METRICS)
        .map(|k| k.to_string())
        .collect();
    for stat in ["mean", "rms", "p95", "max", "median", "std"] {
        for fam in ["normal", "normal_oriented"] {
            pool.push(format!("{fam}_{stat}_deg"));
            pool.push(format!("{fam}_{stat}_rad"));
        }
        for fam in ["accuracy", "completeness"] {
            pool.push(format!("{fam}_{stat}"));
        }
    }
    for t in reconbench_metrics::distance::FSCORE_THRESHOLDS {
        for fam in ["fscore", "precision", "recall"] {
            pool.push(format!("{fam}_{t}"));
        }
    }
    let mut near: Vec<(usize, &str)> = pool
        .iter()
        .map(|k| (edit_distance(name, k), k.as_str()))
        .collect();
    near.sort();
    let hint: Vec<&str> = near.iter().take(3).map(|(_, k)| *k).collect();
    Err(HarnessError::input(format!(
        "{what}: unknown metric '{name}'; did you mean {}? (docs/METRICS.md lists them all)",
        hint.join(", ")
    )))
}

/// Levenshtein distance, for suggestions.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for j in 0..b.len() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != b[j]))
                .min(row[j] + 1)
                .min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
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
