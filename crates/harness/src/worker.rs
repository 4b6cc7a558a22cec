//! The worker side of cell isolation: `reconbench worker` reads one request (JSON) on
//! stdin, runs the cell, and prints one reply line prefixed with [`REPLY_PREFIX`] on
//! stdout. Anything else a method prints is ignored by the runner. A panic prints a
//! [`PANIC_PREFIX`] line on stderr (so the runner can name it) and the process exits
//! non-zero; aborts, signals, hangs and memory blow-ups kill only this process.

use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::time::Duration;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::cell;
use crate::error::{HarnessError, Result};
use crate::experiment::Cell;
use crate::provenance::{cpu_seconds, rss_mib};
use crate::store::{Cost, Dist, Status};

/// Ends this worker when its runner is gone (killed with SIGKILL, say), so that no
/// worker outlives the run as an orphan: the runner puts each worker in its own process
/// group, so nothing else would stop it.
fn exit_with_parent() {
    let parent = std::os::unix::process::parent_id();
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_millis(200));
            if std::os::unix::process::parent_id() != parent {
                std::process::exit(137);
            }
        }
    });
}

/// Prefix of the reply line on stdout.
pub const REPLY_PREFIX: &str = "RECONBENCH-REPLY ";
/// Prefix of the panic line on stderr.
pub const PANIC_PREFIX: &str = "RECONBENCH-PANIC ";

/// The render data the runner asks for: the worker writes the cell's
/// [`RenderData`](crate::render::RenderData) to `path`; the report draws it later, on
/// the scale of all the report's meshes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RenderRequest {
    /// Where to write the render data file.
    pub path: PathBuf,
    /// Path recorded in the row (relative to the results directory).
    pub rel: String,
}

/// What the runner sends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Request {
    /// The cell.
    pub cell: Cell,
    /// Time budget handed to the method's `RunCtx` (the runner also kills at its timeout).
    pub timeout_s: f64,
    /// Optional render.
    pub render: Option<RenderRequest>,
}

/// What the worker answers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reply {
    /// `ok` or `error` (other statuses are decided by the runner).
    pub status: Status,
    /// Reason for `error`.
    pub error: Option<String>,
    /// Metrics.
    pub metrics: BTreeMap<String, f64>,
    /// Method diagnostics.
    pub diagnostics: BTreeMap<String, Value>,
    /// Per-point error distribution.
    pub dist: Option<Dist>,
    /// Render data written (relative path).
    pub render: Option<String>,
    /// Cost (the runner fills in `wall_s`).
    pub cost: Cost,
}

/// Runs one request to completion and returns the reply (in-process; the `worker` verb
/// wraps it with stdin/stdout).
pub fn handle(req: &Request) -> Reply {
    let budget = Duration::from_secs_f64(req.timeout_s.max(0.001));
    let out = cell::execute_with_render(&req.cell, budget, req.render.is_some());
    let (rss, peak) = rss_mib(None).unwrap_or((0.0, 0.0));
    let _ = rss;
    let mut reply = match out {
        Ok(o) => {
            let mut render = None;
            let mut error = None;
            if let (Some(r), Some(data)) = (&req.render, &o.render) {
                match data.save(&r.path) {
                    Ok(()) => render = Some(r.rel.clone()),
                    Err(e) => error = Some(format!("render failed: {e}")),
                }
            }
            let mut diagnostics = o.diagnostics;
            let timings = take_timings(&mut diagnostics);
            if let Some(e) = error {
                diagnostics.insert("render_error".into(), Value::String(e));
            }
            Reply {
                status: Status::Ok,
                error: None,
                metrics: o.metrics,
                diagnostics,
                dist: o.dist,
                render,
                cost: Cost {
                    method_s: o.method_s,
                    generate_s: o.generate_s,
                    metrics_s: o.metrics_s,
                    phases: o.phases,
                    steps: o.steps,
                    timings,
                    ..Cost::default()
                },
            }
        }
        Err(e) => Reply {
            status: Status::Error,
            error: Some(e),
            metrics: BTreeMap::new(),
            diagnostics: BTreeMap::new(),
            dist: None,
            render: None,
            cost: Cost::default(),
        },
    };
    reply.cost.cpu_s = cpu_seconds().unwrap_or(0.0);
    reply.cost.peak_rss_mib = rss_mib(None).map_or(peak, |(_, p)| p);
    reply
}

/// Moves the numeric timing diagnostics ([`crate::store::is_timing`]) out of a row's
/// diagnostics, for its `cost`.
fn take_timings(d: &mut BTreeMap<String, Value>) -> BTreeMap<String, f64> {
    let names: Vec<String> = d
        .keys()
        .filter(|k| crate::store::is_timing(k))
        .cloned()
        .collect();
    names
        .into_iter()
        .filter_map(|k| {
            let v = d.remove(&k)?;
            v.as_f64().map(|x| (k, x))
        })
        .collect()
}

/// The `worker` verb: request on `input`, reply line on `output`.
pub fn serve(mut input: impl Read, mut output: impl Write) -> Result<()> {
    exit_with_parent();
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".into());
        let loc = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let line = serde_json::to_string(&format!("{msg}{loc}")).unwrap_or_default();
        eprintln!("{PANIC_PREFIX}{line}");
    }));
    let mut text = String::new();
    input
        .read_to_string(&mut text)
        .map_err(|e| HarnessError::failure(format!("worker: cannot read the request: {e}")))?;
    let req: Request = serde_json::from_str(&text)
        .map_err(|e| HarnessError::input(format!("worker: bad request: {e}")))?;
    let reply = handle(&req);
    let line = serde_json::to_string(&reply)
        .map_err(|e| HarnessError::failure(format!("worker: cannot encode the reply: {e}")))?;
    writeln!(output, "{REPLY_PREFIX}{line}")
        .and_then(|()| output.flush())
        .map_err(|e| HarnessError::failure(format!("worker: cannot write the reply: {e}")))
}
