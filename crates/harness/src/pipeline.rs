//! Pipelines: a method entry of an experiment can be a chain of steps whose outputs flow
//! into the next one. Normals and feature labels attach to the cloud, a filter replaces
//! it, and the last step (any kind) is the one the cell's metrics evaluate.
//!
//! The ground truth follows the cloud through filters: a filter that reports the source
//! point of each output point carries the per-point truth along exactly; one that makes
//! new points gets it recomputed from the analytic shape (closest point, its normal and
//! feature distance; no point counts as an outlier any more).

use std::sync::Arc;
use std::time::Instant;

use reconbench_geom::Channel;
use reconbench_geom::method::{FEATURE_CHANNEL, Filtered, RunCtx};
use reconbench_synth::{NO_FEATURE, Shape};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{HarnessError, Result};
use crate::inputs::Generated;
use crate::key::{derive_seed, fnv1a64};
use crate::registry::{self, Built, MethodEntry, MethodEnv, MethodKind, Needs};

/// One step before the last of a pipeline, as stored in a cell spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepSpec {
    /// Registry name.
    pub method: String,
    /// Method kind (never `reconstruct`: a mesh cannot feed a later step).
    pub kind: MethodKind,
    /// Resolved parameters (defaults filled in).
    pub params: Value,
}

/// What the cloud carries at some point of a pipeline, as far as it is known when the
/// experiment file loads (`oriented` is only known at run time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Carried {
    /// Normals are attached.
    pub normals: bool,
    /// Whether they are consistently oriented (`None`: not known yet).
    pub oriented: Option<bool>,
}

/// Checks that `entry`'s input needs are met; the message says how to meet them.
pub fn check_input_needs(
    entry: &MethodEntry,
    normals: bool,
    oriented: Option<bool>,
) -> std::result::Result<(), String> {
    let name = entry.name;
    match entry.needs {
        Needs::Positions => Ok(()),
        Needs::Normals | Needs::OrientedNormals if !normals => Err(format!(
            "'{name}' needs {} but its input has none: put a normal estimator before it \
             (steps = [\"jet\", \"{name}\"]) or give it a cloud with normals",
            entry.needs.as_str()
        )),
        Needs::OrientedNormals if oriented == Some(false) => Err(format!(
            "'{name}' needs oriented normals but the normals before it are unoriented \
             (an estimator with orient_k = 0?)"
        )),
        _ => Ok(()),
    }
}

/// Checks a chain when the experiment file loads: only the last step may be a
/// reconstructor, and every step's input needs are met by the steps before it (or, for
/// the first step, by the dataset: `input_normals`).
pub fn validate_chain(steps: &[&MethodEntry], input_normals: bool) -> Result<()> {
    let mut carried = Carried {
        normals: input_normals,
        oriented: None,
    };
    for (i, e) in steps.iter().enumerate() {
        let last = i + 1 == steps.len();
        if !last && e.kind == MethodKind::Reconstruct {
            return Err(HarnessError::input(format!(
                "step {} '{}' is a reconstructor: only the last step of a pipeline may be one",
                i + 1,
                e.name
            )));
        }
        check_input_needs(e, carried.normals, carried.oriented)
            .map_err(|m| HarnessError::input(format!("step {}: {m}", i + 1)))?;
        if e.kind == MethodKind::Normals {
            carried.normals = true;
        }
    }
    Ok(())
}

/// Per-step wall times of a pipeline run: `(method, seconds)`.
pub type StepTimes = Vec<(String, f64)>;

/// Seed of pre-step `i` (the last step keeps the seed a single-method cell has).
fn step_seed(data_seed: u64, method: &str, i: usize) -> u64 {
    derive_seed(&[data_seed, fnv1a64(method.as_bytes()), i as u64 + 1])
}

/// Runs the steps before the last on `data`, in place. Returns their wall times and
/// whether the attached normals are oriented.
pub fn run_pre_steps(
    pre: &[StepSpec],
    data: &mut Generated,
    shape: Option<&dyn Shape>,
    data_seed: u64,
    ctx: &RunCtx,
) -> std::result::Result<(StepTimes, Option<bool>), String> {
    let n = pre.len() + 1;
    let mut times = Vec::with_capacity(pre.len());
    let mut oriented = None;
    for (i, st) in pre.iter().enumerate() {
        let entry = registry::find(&st.method).map_err(|e| e.to_string())?;
        check_input_needs(entry, data.input.normals().is_some(), oriented)
            .map_err(|m| format!("step {} {m}", i + 1))?;
        let env = MethodEnv {
            ground_truth: Some(Arc::new(data.gt.clone())),
        };
        let fail = |e: &dyn std::fmt::Display| format!("step {} '{}': {e}", i + 1, st.method);
        let built = entry.build(&st.params, &env).map_err(|e| fail(&e))?;
        let mut sctx = ctx.sub_step(
            step_seed(data_seed, &st.method, i),
            &format!("{}/", st.method),
            i as f64 / n as f64,
            (i + 1) as f64 / n as f64,
        );
        let t = Instant::now();
        let n_in = data.input.len();
        match built {
            Built::Normals(m) => {
                let r = m.estimate(&data.input, &mut sctx).map_err(|e| fail(&e))?;
                data.input
                    .set_normals(Some(r.normals))
                    .map_err(|e| fail(&e))?;
                oriented = Some(r.oriented);
            }
            Built::Features(m) => {
                let r = m.detect(&data.input, &mut sctx).map_err(|e| fail(&e))?;
                let labels = r.labels.iter().map(|&c| c as u8 as i64).collect();
                data.input
                    .set_channel(FEATURE_CHANNEL, Channel::Label(labels))
                    .map_err(|e| fail(&e))?;
            }
            Built::Filter(m) => {
                let r = m.filter(&data.input, &mut sctx).map_err(|e| fail(&e))?;
                if r.cloud.normals().is_none() {
                    oriented = None;
                }
                replace_cloud(data, r, n_in, shape).map_err(|e| fail(&e))?;
            }
            Built::Reconstruct(_) => {
                return Err(fail(&"a reconstructor can only be the last step"));
            }
        }
        times.push((st.method.clone(), t.elapsed().as_secs_f64()));
    }
    Ok((times, oriented))
}

fn pick<T: Copy>(v: &[T], src: &[u32]) -> Vec<T> {
    src.iter().map(|&i| v[i as usize]).collect()
}

/// Replaces the cell's cloud by a filter's output and carries the ground truth along.
pub fn replace_cloud(
    data: &mut Generated,
    out: Filtered,
    n_in: usize,
    shape: Option<&dyn Shape>,
) -> std::result::Result<(), String> {
    let m = out.cloud.len();
    match (&out.source, shape) {
        (Some(src), _) => {
            if src.len() != m {
                return Err(format!(
                    "{} source indices for {m} output points",
                    src.len()
                ));
            }
            if let Some(&bad) = src.iter().find(|&&i| i as usize >= n_in) {
                return Err(format!(
                    "source index {bad} out of range for {n_in} input points"
                ));
            }
            data.gt.normals = data.gt.normals.as_deref().map(|v| pick(v, src));
            data.gt.feature_distance = data.gt.feature_distance.as_deref().map(|v| pick(v, src));
            data.clean = pick(&data.clean, src);
            data.is_outlier = pick(&data.is_outlier, src);
        }
        (None, None) => {
            // A cloud without ground truth: nothing to carry along.
            data.clean = out.cloud.positions().to_vec();
            data.gt.normals = None;
            data.gt.feature_distance = None;
            data.is_outlier = vec![false; m];
        }
        (None, Some(shape)) => {
            let hits: Vec<_> = out
                .cloud
                .positions()
                .iter()
                .map(|&p| shape.closest_point(p))
                .collect();
            data.clean = hits.iter().map(|h| h.point).collect();
            data.gt.normals = Some(hits.iter().map(|h| h.normal).collect());
            data.gt.feature_distance = Some(
                hits.iter()
                    .map(|h| {
                        let d = shape.feature_distance(h.point);
                        if d == NO_FEATURE { f64::INFINITY } else { d }
                    })
                    .collect(),
            );
            data.is_outlier = vec![false; m];
        }
    }
    data.input = out.cloud;
    Ok(())
}
