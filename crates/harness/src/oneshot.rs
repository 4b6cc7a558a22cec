//! One-shot method runs on a single input file (`reconbench reconstruct|normals|features`),
//! the way users first try a method. Runs in-process (no worker); there is no ground
//! truth, so oracles fall back to what the file stores (see [`crate::methods::oracle`]).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use reconbench_geom::io::Format;
use reconbench_geom::method::{FeatureClass, MethodError, RunCtx};
use reconbench_geom::{Channel, PointCloud};
use serde::Serialize;
use serde_json::Value;

use crate::error::{HarnessError, Result};
use crate::registry::{self, Built, MethodEnv, MethodKind};

/// Name of the label channel `features` writes (the metrics crate reads it).
pub use reconbench_geom::method::FEATURE_CHANNEL;
/// Name of the score channel `features` writes when the method gives scores.
pub const SCORE_CHANNEL: &str = "feature_score";

/// What a one-shot run did (printed by the CLI; `--json` prints it as is).
#[derive(Debug, Clone, Serialize)]
pub struct OneShot {
    /// Method name.
    pub method: String,
    /// Resolved parameters.
    pub params: Value,
    /// Input file.
    pub input: String,
    /// Output file.
    pub output: String,
    /// Input points.
    pub points: usize,
    /// Output summary (vertices, faces, labelled points, refused points, ...).
    pub summary: BTreeMap<String, f64>,
    /// Method wall time, seconds.
    pub seconds: f64,
    /// Per-phase times, seconds.
    pub phases: Vec<(String, f64)>,
    /// Method diagnostics.
    pub diagnostics: BTreeMap<String, Value>,
}

/// Runs method `name` of kind `kind` on the cloud in `input` and writes `output`.
pub fn run(
    kind: MethodKind,
    name: &str,
    overrides: &Value,
    input: &Path,
    output: &Path,
    seed: u64,
) -> Result<OneShot> {
    let entry = registry::find(name)?;
    if entry.kind != kind {
        let same: Vec<&str> = registry::registry()
            .iter()
            .filter(|e| e.kind == kind && !e.hidden)
            .map(|e| e.name)
            .collect();
        return Err(HarnessError::input(format!(
            "'{name}' is a {} method, not a {kind} method; {kind} methods: {}",
            entry.kind,
            same.join(", ")
        )));
    }
    let params = entry.resolve_params(overrides)?;
    check_output(output, kind)?;
    let cloud =
        reconbench_geom::io::read_cloud(input).map_err(|e| HarnessError::input(e.to_string()))?;
    crate::pipeline::check_input_needs(entry, cloud.normals().is_some(), None)
        .map_err(|e| HarnessError::input(format!("{}: {e}", input.display())))?;
    // The method sees the file's positions and normals (plus what oracles are documented
    // to read).
    let built = entry
        .build(&params, &MethodEnv::default())
        .map_err(|e| HarnessError::input(format!("{name}: {e}")))?;
    let mut ctx = RunCtx::new(seed);
    let mut summary = BTreeMap::new();
    let t0 = Instant::now();
    // What the input or a parameter cannot give is bad input (exit code 2 on the CLI);
    // the message names the file the method ran on.
    let shown = reconbench_geom::error::escape_control(&input.to_string_lossy()).into_owned();
    let method_err = |e: MethodError| {
        let text = e.to_string();
        let msg = if text.contains(name) {
            format!("{shown}: {text}")
        } else {
            format!("{shown}: {name}: {text}")
        };
        if e.is_input() {
            HarnessError::input(msg)
        } else {
            HarnessError::failure(msg)
        }
    };
    let diagnostics = match built {
        Built::Reconstruct(m) => {
            let r = m.reconstruct(&cloud, &mut ctx).map_err(method_err)?;
            summary.insert("vertices".into(), r.mesh.n_vertices() as f64);
            summary.insert("faces".into(), r.mesh.n_faces() as f64);
            summary.insert("refused".into(), r.refused.len() as f64);
            let mut used = vec![false; r.mesh.n_vertices()];
            for &v in r.mesh.faces().iter().flatten() {
                used[v as usize] = true;
            }
            let unused = used.iter().filter(|&&u| !u).count();
            summary.insert("unreferenced_vertices".into(), unused as f64);
            reconbench_geom::io::write_mesh(output, &r.mesh)
                .map_err(|e| HarnessError::failure(e.to_string()))?;
            r.diagnostics
        }
        Built::Normals(m) => {
            let r = m.estimate(&cloud, &mut ctx).map_err(method_err)?;
            let zero = r
                .normals
                .iter()
                .filter(|n| n.length_squared() == 0.0)
                .count();
            summary.insert("undecided".into(), zero as f64);
            summary.insert("oriented".into(), if r.oriented { 1.0 } else { 0.0 });
            let out = PointCloud::clone(&cloud)
                .with_normals(r.normals)
                .map_err(|e| HarnessError::failure(format!("{name}: {e}")))?;
            reconbench_geom::io::write_cloud(output, &out)
                .map_err(|e| HarnessError::failure(e.to_string()))?;
            r.diagnostics
        }
        Built::Filter(m) => {
            let r = m.filter(&cloud, &mut ctx).map_err(method_err)?;
            summary.insert("points_out".into(), r.cloud.len() as f64);
            reconbench_geom::io::write_cloud(output, &r.cloud)
                .map_err(|e| HarnessError::failure(e.to_string()))?;
            r.diagnostics
        }
        Built::Features(m) => {
            let r = m.detect(&cloud, &mut ctx).map_err(method_err)?;
            let mut out = cloud.clone();
            let labels: Vec<i64> = r.labels.iter().map(|&c| c as u8 as i64).collect();
            for (k, class) in [
                ("edges", FeatureClass::Edge),
                ("corners", FeatureClass::Corner),
            ] {
                summary.insert(
                    k.into(),
                    r.labels.iter().filter(|&&c| c == class).count() as f64,
                );
            }
            out.set_channel(FEATURE_CHANNEL, Channel::Label(labels))
                .map_err(|e| HarnessError::failure(format!("{name}: {e}")))?;
            if let Some(s) = r.scores {
                out.set_channel(SCORE_CHANNEL, Channel::Scalar(s))
                    .map_err(|e| HarnessError::failure(format!("{name}: {e}")))?;
            }
            reconbench_geom::io::write_cloud(output, &out)
                .map_err(|e| HarnessError::failure(e.to_string()))?;
            r.diagnostics
        }
    };
    let seconds = t0.elapsed().as_secs_f64();
    Ok(OneShot {
        method: name.to_string(),
        params,
        input: input.display().to_string(),
        output: output.display().to_string(),
        points: cloud.len(),
        summary,
        seconds,
        phases: ctx.phases(),
        diagnostics: crate::cell::diagnostics_json(&diagnostics),
    })
}

/// Checks, before any work, that `output` names a format that can hold the result (a
/// reconstruction needs a mesh format) in a directory that exists.
fn check_output(output: &Path, kind: MethodKind) -> Result<()> {
    let format = Format::from_path(output).map_err(|e| HarnessError::input(e.to_string()))?;
    if kind == MethodKind::Reconstruct && matches!(format, Format::Xyz | Format::Pts) {
        return Err(HarnessError::input(format!(
            "{}: a .{} file holds points only; write the mesh as .ply, .obj, .off, .stl or .m",
            output.display(),
            format.name()
        )));
    }
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(HarnessError::input(format!(
            "{}: the directory {} does not exist",
            output.display(),
            dir.display()
        )));
    }
    Ok(())
}
