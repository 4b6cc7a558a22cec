//! One cell run in this process: the pipeline's earlier steps, the method call, and the
//! metrics of its output (the glue to the metric crate).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use reconbench_geom::method::{
    Diagnostic, Diagnostics, FeatureClass, INTERPOLATING_DIAGNOSTIC, RunCtx,
};
use reconbench_metrics::{Reference, Report, eval_features, eval_mesh, eval_normals};
use reconbench_synth::Shape;
use serde_json::Value;

use crate::experiment::Cell;
use crate::inputs::generate;
use crate::key::{derive_seed, fnv1a64};
use crate::metric_spec::metric_options;
use crate::registry::{self, Built, MethodEnv};
use crate::render::RenderData;
use crate::store::Dist;

/// What a cell produced.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Metrics by stable key.
    pub metrics: BTreeMap<String, f64>,
    /// Method diagnostics.
    pub diagnostics: BTreeMap<String, Value>,
    /// Per-point error distribution.
    pub dist: Option<Dist>,
    /// Method phases.
    pub phases: Vec<(String, f64)>,
    /// Data generation time.
    pub generate_s: f64,
    /// Method time (the last step of a pipeline).
    pub method_s: f64,
    /// Wall time of every step of a pipeline, in order (empty for a single method).
    pub steps: Vec<(String, f64)>,
    /// Metric time.
    pub metrics_s: f64,
    /// What a render of the reconstruction needs (only when asked for, see
    /// [`execute_with_render`]).
    pub render: Option<RenderData>,
}

pub(crate) fn diagnostics_json(d: &Diagnostics) -> BTreeMap<String, Value> {
    d.iter()
        .map(|(k, v)| {
            let j = match v {
                Diagnostic::Number(x) => {
                    serde_json::Number::from_f64(*x).map_or(Value::Null, Value::Number)
                }
                Diagnostic::Series(s) => Value::Array(
                    s.iter()
                        .map(|x| {
                            serde_json::Number::from_f64(*x).map_or(Value::Null, Value::Number)
                        })
                        .collect(),
                ),
                Diagnostic::Text(t) => Value::String(t.clone()),
            };
            (k.clone(), j)
        })
        .collect()
}

/// Numeric method diagnostics that are copied into the metrics of a reconstruction
/// row (deterministic counts, so `[[expect]]` entries and tables can use them): UFM's
/// matching percentage, iteration count, unmatched and pinched points.
pub const DIAGNOSTIC_METRICS: &[&str] = &[
    "matching",
    "iterations",
    "unmatched_points",
    "pinched_vertices",
    // ball-pivoting: input points no triangle reached.
    "unused_points",
    // ebt (seed 004): Table 1's columns and the measured error bound.
    "m1",
    "m2",
    "m3",
    "m_sum",
    "omega",
    "bin_size",
    "q_points",
    "bad_facets",
    "bad_r1_long_edge",
    "bad_r2_small_angle",
    "bad_r3_non_manifold",
    "bad_overlap",
    "unmeshed",
    "dev_max",
    "dev_p99",
    "dev_rms",
    "dev_above_eps",
    // hc-it (seed 003): clusters, the triangulation's counters, the closure pass
    // (`unmeshed` is shared with ebt above).
    "nc_components",
    "splits",
    "flips",
    "extra_cases",
    "sweep_unmeshed",
    "zip_triangles",
    // ebt: crack closing, enhancements and the mesh-quality histograms (spec §6 item 4).
    "crack_facets",
    "crack_flips",
    "sliver_facets",
    "swaps_e20",
    "swaps_e21",
    "feature_edges",
    "min_angle_hist_0_12",
    "min_angle_hist_12_20",
    "min_angle_hist_20_30",
    "min_angle_hist_30_45",
    "min_angle_hist_45_60",
    "edge_hist_0_050",
    "edge_hist_050_075",
    "edge_hist_075_100",
    "edge_hist_above_100",
];

/// Metrics that count input points as mesh vertices (the seed's V is the number of
/// input points): meaningless for a mesh with new vertices (Poisson's), so left out of
/// its rows.
pub const VERTEX_CLAIMS: &[&str] = &[
    "vertices",
    "referenced_vertices",
    "unreferenced_vertices",
    "delta_f",
];

/// Whether a reconstruction interpolates its input: true unless the method set the
/// [`INTERPOLATING_DIAGNOSTIC`] to 0.
fn interpolating(d: &Diagnostics) -> bool {
    !matches!(d.get(INTERPOLATING_DIAGNOSTIC), Some(Diagnostic::Number(x)) if *x == 0.0)
}

/// Removes the [`VERTEX_CLAIMS`] from a row.
fn drop_vertex_claims(metrics: &mut BTreeMap<String, f64>) {
    for k in VERTEX_CLAIMS {
        metrics.remove(*k);
    }
}

/// Keeps deterministic numeric entries (timings of the evaluation itself are cost, not
/// metrics, and are left out so that rows compare byte for byte).
fn keep_metrics(row: BTreeMap<String, f64>) -> BTreeMap<String, f64> {
    row.into_iter()
        .filter(|(k, v)| {
            v.is_finite() && !k.starts_with("eval_") && !k.ends_with("_s") && !k.contains("time")
        })
        .collect()
}

/// Runs one cell in this process: generate, run the method, evaluate. Errors are the
/// reasons recorded in the row (status `error`).
pub fn execute(cell: &Cell, budget: Duration) -> std::result::Result<Outcome, String> {
    execute_with_render(cell, budget, false)
}

/// [`execute`], and with `render` the [`RenderData`] of a reconstruction in
/// [`Outcome::render`]: its mesh, the distance at its vertices and face centroids, its
/// boundary edges and defective faces (the self-intersection search runs a second time
/// for it, so only the cells that render pay for it).
pub fn execute_with_render(
    cell: &Cell,
    budget: Duration,
    render: bool,
) -> std::result::Result<Outcome, String> {
    let spec = &cell.spec;
    let entry = registry::find(&spec.method).map_err(|e| e.to_string())?;
    let shape: Option<Arc<dyn Shape>> =
        crate::inputs::build_shape(&spec.data).map_err(|e| format!("data: {e}"))?;
    let t = Instant::now();
    let mut data =
        generate(&spec.data, shape.clone(), cell.data_seed).map_err(|e| format!("data: {e}"))?;
    let generate_s = t.elapsed().as_secs_f64();
    let n_input = data.input.len();
    let method_seed = derive_seed(&[cell.data_seed, fnv1a64(spec.method.as_bytes())]);
    let mut ctx = RunCtx::new(method_seed)
        .with_budget(budget)
        .with_progress(crate::progress::progress_sink());
    let (steps, oriented) = crate::pipeline::run_pre_steps(
        &spec.pre,
        &mut data,
        shape.as_deref(),
        cell.data_seed,
        &ctx,
    )?;
    crate::pipeline::check_input_needs(entry, data.input.normals().is_some(), oriented)
        .map_err(|m| format!("method: {m}"))?;
    let gt = Arc::new(data.gt.clone());
    let env = MethodEnv {
        ground_truth: Some(gt.clone()),
    };
    let built = entry
        .build(&spec.params, &env)
        .map_err(|e| format!("method: {e}"))?;
    let opts = metric_options(&spec.metrics).map_err(|e| e.to_string())?;
    // Without ground truth (a cloud file) only what needs none is measured.
    let reference = shape.as_deref().map(Reference::analytic);
    let diag = shape
        .as_deref()
        .map_or_else(|| data.input.aabb().diagonal(), |s| s.aabb().diagonal());
    let mut out = Outcome {
        metrics: BTreeMap::new(),
        diagnostics: BTreeMap::new(),
        dist: None,
        phases: Vec::new(),
        generate_s,
        method_s: 0.0,
        steps: Vec::new(),
        metrics_s: 0.0,
        render: None,
    };
    match built {
        Built::Filter(m) => {
            let t = Instant::now();
            let n_in = data.input.len();
            let r = m
                .filter(&data.input, &mut ctx)
                .map_err(|e| format!("method: {e}"))?;
            out.method_s = t.elapsed().as_secs_f64();
            let t = Instant::now();
            out.diagnostics = diagnostics_json(&r.diagnostics);
            let outliers_in = data.is_outlier.iter().filter(|&&o| o).count();
            let input_before = data.input.positions().to_vec();
            crate::pipeline::replace_cloud(&mut data, r, n_in, shape.as_deref())
                .map_err(|e| format!("method: {e}"))?;
            let outliers_out = data.is_outlier.iter().filter(|&&o| o).count();
            let d: Vec<f64> = match shape.as_deref() {
                Some(shape) => data
                    .input
                    .positions()
                    .iter()
                    .zip(&data.is_outlier)
                    .filter(|(_, o)| !**o)
                    .map(|(&p, _)| shape.distance(p) / diag)
                    .collect(),
                None => Vec::new(),
            };
            out.metrics = filter_metrics(n_in, data.input.len(), outliers_in, outliers_out, &d);
            out.metrics.extend(projection_metrics(
                &data.input,
                &input_before,
                shape.as_deref(),
                reference.as_ref(),
                diag,
                opts.features.feature_angle_deg,
            ));
            out.dist = Dist::of("point distance (diag)", &d);
            out.metrics_s = t.elapsed().as_secs_f64();
        }
        Built::Normals(m) => {
            let t = Instant::now();
            let r = m
                .estimate(&data.input, &mut ctx)
                .map_err(|e| format!("method: {e}"))?;
            out.method_s = t.elapsed().as_secs_f64();
            let t = Instant::now();
            if let Some(gt_n) = gt.normals.as_deref() {
                let mut o = opts.normals.clone();
                o.oriented = o.oriented || r.oriented;
                let ev = eval_normals(&r.normals, gt_n, &o).map_err(|e| format!("metrics: {e}"))?;
                out.metrics = keep_metrics(ev.to_row());
                out.dist = Dist::of("normal angle (deg)", &ev.per_point_deg);
            }
            out.metrics_s = t.elapsed().as_secs_f64();
            out.diagnostics = diagnostics_json(&r.diagnostics);
        }
        Built::Features(m) => {
            let t = Instant::now();
            let r = m
                .detect(&data.input, &mut ctx)
                .map_err(|e| format!("method: {e}"))?;
            out.method_s = t.elapsed().as_secs_f64();
            if r.labels.len() != data.input.len() {
                return Err(format!(
                    "method: {} labels for {} points",
                    r.labels.len(),
                    data.input.len()
                ));
            }
            let t = Instant::now();
            let detected: Vec<bool> = r.labels.iter().map(|&c| c != FeatureClass::None).collect();
            let Some(reference) = &reference else {
                out.metrics = BTreeMap::from([(
                    "detected".to_string(),
                    detected.iter().filter(|&&d| d).count() as f64,
                )]);
                out.metrics_s = t.elapsed().as_secs_f64();
                out.diagnostics = diagnostics_json(&r.diagnostics);
                out.phases = ctx.phases();
                return Ok(finish(out, spec, steps, n_input));
            };
            let curves = reference.feature_curves(opts.features.feature_angle_deg);
            let ev = eval_features(
                data.input.positions(),
                &data.clean,
                &detected,
                &curves,
                diag,
                &opts.features,
            )
            .map_err(|e| format!("metrics: {e}"))?;
            out.metrics = keep_metrics(ev.to_row());
            let fd = gt.feature_distance.as_deref().unwrap_or(&[]);
            let d: Vec<f64> = fd
                .iter()
                .zip(&detected)
                .filter(|(_, d)| **d)
                .map(|(x, _)| *x / diag)
                .collect();
            out.dist = Dist::of("feature distance (diag)", &d);
            out.metrics_s = t.elapsed().as_secs_f64();
            out.diagnostics = diagnostics_json(&r.diagnostics);
        }
        Built::Reconstruct(m) => {
            let t = Instant::now();
            let r = m
                .reconstruct(&data.input, &mut ctx)
                .map_err(|e| format!("method: {e}"))?;
            out.method_s = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let mut o = opts.mesh.clone();
            o.distance.vertex_error = true;
            let Some(reference) = &reference else {
                out.metrics = keep_metrics(without_ground_truth(&r.mesh, &o));
                if render {
                    // No truth: the surface is grey, the defects are still marked.
                    out.render = Some(
                        RenderData::from_mesh(&r.mesh, &[], &[])
                            .map_err(|e| format!("render: {e}"))?,
                    );
                }
                if !interpolating(&r.diagnostics) {
                    drop_vertex_claims(&mut out.metrics);
                }
                out.metrics_s = t.elapsed().as_secs_f64();
                out.diagnostics = diagnostics_json(&r.diagnostics);
                out.phases = ctx.phases();
                return Ok(finish(out, spec, steps, n_input));
            };
            let ev = eval_mesh(&r.mesh, reference, &o).map_err(|e| format!("metrics: {e}"))?;
            out.metrics = keep_metrics(ev.to_row());
            if interpolating(&r.diagnostics) {
                // Refused points against the generator's outliers (seed 001 §4.4).
                let re = reconbench_metrics::eval_refused(&r.refused, &data.is_outlier)
                    .map_err(|e| format!("metrics: {e}"))?;
                out.metrics.extend(keep_metrics(re.to_row()));
            } else {
                drop_vertex_claims(&mut out.metrics);
            }
            for k in DIAGNOSTIC_METRICS {
                if let Some(reconbench_geom::method::Diagnostic::Number(x)) = r.diagnostics.get(*k)
                    && x.is_finite()
                {
                    out.metrics.insert((*k).to_string(), *x);
                }
            }
            let verr: Vec<f64> = match &ev.distance.vertex_error {
                Some(v) if v.len() == r.mesh.n_vertices() => v.iter().map(|x| x / diag).collect(),
                _ => reference
                    .distances(r.mesh.vertices())
                    .map_err(|e| format!("metrics: {e}"))?
                    .into_iter()
                    .map(|x| x / diag)
                    .collect(),
            };
            // The error over the mesh surface, not at its vertices (which an
            // interpolating method takes from the noisy input).
            let serr: Vec<f64> = ev
                .distance
                .sample_error
                .as_deref()
                .unwrap_or(&[])
                .iter()
                .map(|x| x / diag)
                .collect();
            out.dist = Dist::of("surface distance (diag)", &serr)
                .or_else(|| Dist::of("vertex distance (diag)", &verr));
            out.metrics_s = t.elapsed().as_secs_f64();
            out.diagnostics = diagnostics_json(&r.diagnostics);
            if render {
                let centres: Vec<reconbench_geom::DVec3> = (0..r.mesh.n_faces())
                    .map(|f| {
                        let [a, b, c] = r.mesh.triangle(f);
                        (a + b + c) / 3.0
                    })
                    .collect();
                let ferr: Vec<f64> = reference
                    .distances(&centres)
                    .map_err(|e| format!("metrics: {e}"))?
                    .into_iter()
                    .map(|x| x / diag)
                    .collect();
                out.render = Some(
                    RenderData::from_mesh(&r.mesh, &verr, &ferr)
                        .map_err(|e| format!("render: {e}"))?,
                );
            }
        }
    }
    out.phases = ctx.phases();
    Ok(finish(out, spec, steps, n_input))
}

/// Records the pipeline's step times (the last step's too) in the outcome, and for data
/// read from a file (whose size is not in its spec) the input's point count as the
/// metric `input_points`.
fn finish(
    mut out: Outcome,
    spec: &crate::experiment::CellSpec,
    mut steps: Vec<(String, f64)>,
    n_input: usize,
) -> Outcome {
    if spec.data.file.is_some() {
        out.metrics.insert("input_points".into(), n_input as f64);
    }
    if !spec.pre.is_empty() {
        steps.push((spec.method.clone(), out.method_s));
        out.steps = steps;
    }
    out
}

/// What a reconstruction is measured by without ground truth: its topology and the
/// quality of its triangles.
fn without_ground_truth(
    mesh: &reconbench_geom::TriMesh,
    o: &reconbench_metrics::MeshEvalOptions,
) -> BTreeMap<String, f64> {
    let mut row = reconbench_metrics::eval_topology(mesh, None, &o.topology).to_row();
    row.extend(reconbench_metrics::eval_quality(mesh, &o.quality).to_row());
    row
}

/// Metrics of a projecting filter (seed 002 ch. 4, `reconbench_metrics::filter_eval`):
/// distance of the output to the filter's input and to the surface, normal error near
/// and away from the true features, the error of the feature lines `mls-sharp`
/// attaches as channels, and the collar metrics of a `blend` output.
fn projection_metrics(
    output: &reconbench_geom::PointCloud,
    input: &[reconbench_geom::DVec3],
    shape: Option<&dyn Shape>,
    reference: Option<&Reference>,
    diag: f64,
    feature_angle_deg: f64,
) -> BTreeMap<String, f64> {
    use reconbench_filters::mls_sharp::{LINE_CHANNELS, LINE_FLAG_CHANNEL};
    use reconbench_geom::Channel;
    if output.is_empty() || input.is_empty() {
        return BTreeMap::new();
    }
    let mut lines = Vec::new();
    if let Some(Channel::Label(flag)) = output.channel(LINE_FLAG_CHANNEL) {
        let ch: Vec<&Channel> = LINE_CHANNELS
            .iter()
            .filter_map(|n| output.channel(n))
            .collect();
        if ch.len() == 12 {
            for (i, _) in flag.iter().enumerate().filter(|(_, f)| **f != 0) {
                let c = |j: usize| {
                    reconbench_geom::DVec3::new(
                        ch[3 * j].get_f64(i),
                        ch[3 * j + 1].get_f64(i),
                        ch[3 * j + 2].get_f64(i),
                    )
                };
                lines.push([c(0), c(1), c(2), c(3)]);
            }
        }
    }
    let opts = reconbench_metrics::FilterEvalOptions {
        feature_angle_deg,
        ..Default::default()
    };
    let curves = reference.map(|r| r.feature_curves(feature_angle_deg));
    let truth = shape.zip(curves.as_deref());
    // A cloud these metrics cannot measure (fewer than two distinct points) leaves them
    // out rather than failing the cell, as the filter itself succeeded.
    let mut row = match reconbench_metrics::eval_filter(
        output.positions(),
        output.normals(),
        input,
        truth,
        &lines,
        diag,
        &opts,
    ) {
        Ok(ev) => keep_metrics(ev.to_row()),
        Err(_) => BTreeMap::new(),
    };
    // A blended set (origin tags, seed 002 §7): its collar metrics.
    if let Ok(Some(ev)) =
        reconbench_metrics::eval_blend(output, Some(input.len()), &Default::default())
    {
        row.extend(keep_metrics(ev.to_row()));
        // Against the true blended surface (a blend shape: part and tube).
        if let Some(shape) = shape
            && let Ok(sp) = reconbench_geom::mean_spacing(input, 1)
            && let Ok(Some(t)) =
                reconbench_metrics::eval_blend_truth(output, shape, sp, &Default::default())
        {
            row.extend(keep_metrics(t.to_row()));
        }
    }
    row
}

/// Metrics of a filter's output cloud: distances of its non-outlier points to the
/// surface (fractions of the diagonal), point counts and the share of the generator's
/// outliers it removed.
fn filter_metrics(
    n_in: usize,
    n_out: usize,
    outliers_in: usize,
    outliers_out: usize,
    d: &[f64],
) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::new();
    m.insert("points_in".into(), n_in as f64);
    m.insert("points_out".into(), n_out as f64);
    if !d.is_empty() {
        let n = d.len() as f64;
        m.insert("cloud_mean_dist".into(), d.iter().sum::<f64>() / n);
        m.insert(
            "cloud_rms_dist".into(),
            (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
        );
        m.insert(
            "cloud_max_dist".into(),
            d.iter().fold(0.0, |a, &b| a.max(b)),
        );
    }
    if outliers_in > 0 {
        let removed = outliers_in.saturating_sub(outliers_out);
        m.insert(
            "outliers_removed".into(),
            removed as f64 / outliers_in as f64,
        );
    }
    keep_metrics(m)
}

#[cfg(test)]
mod interpolating_tests {
    use super::*;

    #[test]
    fn a_non_interpolating_mesh_claims_no_vertex_counts_or_delta_f() {
        let mut d = Diagnostics::new();
        assert!(interpolating(&d));
        d.insert(INTERPOLATING_DIAGNOSTIC.into(), Diagnostic::Number(1.0));
        assert!(interpolating(&d));
        d.insert(INTERPOLATING_DIAGNOSTIC.into(), Diagnostic::Number(0.0));
        assert!(!interpolating(&d));
        let mut row: BTreeMap<String, f64> = ["vertices", "delta_f", "faces", "genus"]
            .iter()
            .map(|k| (k.to_string(), 1.0))
            .collect();
        drop_vertex_claims(&mut row);
        assert_eq!(row.keys().collect::<Vec<_>>(), ["faces", "genus"]);
    }
}
