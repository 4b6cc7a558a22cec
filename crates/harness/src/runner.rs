//! The runner: runs the cells of an experiment in parallel, each in its own worker
//! process, with a per-cell timeout and memory limit, appending one JSON line per cell.
//!
//! Isolation: the worker is a separate process (the same binary with the `worker` verb),
//! so a panic, an abort, a segfault, a hang or a memory blow-up ends only that process;
//! the runner records the cell as failed with the reason and goes on.
//!
//! * timeout: the runner polls `try_wait` and kills the worker after the cell timeout;
//! * memory: the runner reads the worker's resident set (`/proc/<pid>/status`) while it
//!   polls and kills it above the limit (status `oom`); a failed allocation inside the
//!   worker aborts it with Rust's "memory allocation failed" message, also `oom`;
//!   a SIGKILL from outside (e.g. the kernel's OOM killer) is reported as a crash by
//!   SIGKILL. No `unsafe`/`setrlimit` is needed (the workspace forbids unsafe code).

use std::collections::{BTreeMap, HashSet};
use std::ffi::OsString;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::error::{HarnessError, Result};
use crate::experiment::{Cell, Experiment, shard_cells};
use crate::progress::PROGRESS_PREFIX;
use crate::provenance::{Provenance, rss_mib};
use crate::registry::MethodKind;
use crate::store::{Row, Status, Store, dedupe_sorted, read_rows, write_rows};
use crate::worker::{PANIC_PREFIX, REPLY_PREFIX, RenderRequest, Reply, Request};

/// How to run an experiment.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Results directory (e.g. `results/<name>`).
    pub out_dir: PathBuf,
    /// Parallel workers.
    pub jobs: usize,
    /// Skip cells that already have a row.
    pub resume: bool,
    /// With `resume`: run again the cells whose row is not `ok`.
    pub retry_failed: bool,
    /// Move earlier results aside (to `previous/<time>/` in the results directory)
    /// instead of refusing to overwrite them.
    pub fresh: bool,
    /// Run only shard `i` of `n`.
    pub shard: Option<(usize, usize)>,
    /// Worker command: program and leading arguments (e.g. `[current_exe, "worker"]`).
    pub worker: Vec<OsString>,
    /// Overrides the experiment's per-cell timeout (seconds).
    pub timeout_s: Option<f64>,
    /// Overrides the experiment's memory limit (MiB).
    pub memory_limit_mib: Option<u64>,
    /// `RAYON_NUM_THREADS` of each worker.
    pub threads_per_worker: usize,
    /// Show progress: a bar on a terminal, else a line on stderr every `log_every_s`.
    pub progress: bool,
    /// Seconds between progress lines when stderr is not a terminal (0: none).
    pub log_every_s: f64,
    /// Set to a signal number (SIGINT 2, SIGTERM 15) to stop the run cleanly: no new
    /// cell starts, running workers are killed and their cells left for `--resume`.
    pub stop: Arc<AtomicUsize>,
}

/// A stop flag for [`RunOptions::stop`] set by SIGINT and SIGTERM (to the signal's
/// number); a second such signal ends the process at once with code 128 + signal.
pub fn stop_on_signals() -> Result<Arc<AtomicUsize>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let stop = Arc::new(AtomicUsize::new(0));
    let armed = Arc::new(std::sync::atomic::AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        let reg = signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, armed.clone())
            .and_then(|_| signal_hook::flag::register(sig, armed.clone()))
            .and_then(|_| signal_hook::flag::register_usize(sig, stop.clone(), sig as usize));
        reg.map_err(|e| HarnessError::failure(format!("cannot handle signal {sig}: {e}")))?;
    }
    Ok(stop)
}

/// A signal's name for messages.
pub fn signal_name(sig: usize) -> String {
    match sig {
        2 => "SIGINT".into(),
        15 => "SIGTERM".into(),
        s => format!("signal {s}"),
    }
}

/// File names of a run (shards write their own files).
pub fn result_file_names(shard: Option<(usize, usize)>) -> (String, String) {
    match shard {
        None => ("results.jsonl".into(), "manifest.json".into()),
        Some((i, n)) => (
            format!("results.shard-{i}-of-{n}.jsonl"),
            format!("manifest.shard-{i}-of-{n}.json"),
        ),
    }
}

/// A failed cell in the summary.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FailedCell {
    /// Cell key.
    pub key: String,
    /// `dataset / perturbation / method seed i`.
    pub label: String,
    /// Status.
    pub status: Status,
    /// Reason.
    pub reason: String,
}

/// What a run did.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunSummary {
    /// Experiment name.
    pub experiment: String,
    /// Cells in this run (after sharding).
    pub cells: usize,
    /// Cells skipped by `--resume`.
    pub skipped: usize,
    /// Cells run.
    pub ran: usize,
    /// Cells run that finished ok.
    pub ok: usize,
    /// Failed cells run now.
    pub failed: Vec<FailedCell>,
    /// Wall time, seconds.
    pub wall_s: f64,
    /// Results file.
    pub results: PathBuf,
    /// Manifest file.
    pub manifest: PathBuf,
    /// The signal that stopped the run early (see [`RunOptions::stop`]); the cells that
    /// were running are not recorded, so `--resume` runs them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<usize>,
}

/// The manifest written next to the results.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    /// Experiment name.
    pub experiment: String,
    /// Experiment file.
    pub file: Option<PathBuf>,
    /// The experiment file's text (what was run).
    pub file_text: Option<String>,
    /// Shard `[i, n]`, if any.
    pub shard: Option<(usize, usize)>,
    /// Parallel workers.
    pub jobs: usize,
    /// Threads per worker (`RAYON_NUM_THREADS`).
    pub threads_per_worker: usize,
    /// Per-cell timeout, seconds.
    pub timeout_s: f64,
    /// Memory limit, MiB.
    pub memory_limit_mib: Option<u64>,
    /// Provenance of each run into this directory (several with `--resume`).
    pub runs: Vec<Provenance>,
    /// The resolved grid (every cell with its key, labels and resolved parameters).
    pub cells: Vec<Cell>,
}

/// Runs an experiment. Writes `results.jsonl` (rewritten sorted by grid index at the
/// end) and `manifest.json` in `opts.out_dir`.
pub fn run(exp: &Experiment, opts: &RunOptions) -> Result<RunSummary> {
    if opts.worker.is_empty() {
        return Err(HarnessError::failure("no worker command"));
    }
    let t0 = Instant::now();
    crate::error::create_dir_all(&opts.out_dir)?;
    let (results_name, manifest_name) = result_file_names(opts.shard);
    let results = opts.out_dir.join(&results_name);
    let manifest_path = opts.out_dir.join(manifest_name);
    // One run per results file at a time (shards write their own files). Taken before
    // anything looks at earlier rows: a second run must refuse naming the holder, not
    // report the first one's rows as "an earlier run" or, with --fresh, move them aside
    // while they are being written.
    let _lock = crate::lock::RunLock::acquire(&opts.out_dir.join(format!("{results_name}.lock")))?;
    set_aside_earlier(opts, &results, &manifest_path)?;
    let cells = shard_cells(&exp.cells, opts.shard);
    let limits = Limits {
        timeout_s: opts.timeout_s.unwrap_or(exp.timeout_s),
        memory_limit_mib: opts.memory_limit_mib.or(exp.file.memory_limit_mib),
    };
    let (done, runs) = resume_state(opts, &results, &manifest_path)?;
    write_manifest(exp, opts, &limits, runs, &cells, &manifest_path)?;

    let todo: Vec<&Cell> = cells.iter().filter(|c| !done.contains(&c.key)).collect();
    let (ok, mut failed) = run_cells(exp, opts, &limits, &cells, &todo, &results)?;
    compact(&cells, &results)?;
    failed.sort_by(|a, b| a.label.cmp(&b.label));
    let interrupted = Some(opts.stop.load(Ordering::SeqCst)).filter(|&s| s != 0);
    Ok(RunSummary {
        experiment: exp.name.clone(),
        cells: cells.len(),
        skipped: cells.len() - todo.len(),
        ran: ok + failed.len(),
        ok,
        failed,
        wall_s: t0.elapsed().as_secs_f64(),
        results,
        manifest: manifest_path,
        interrupted,
    })
}

/// Without `--resume`, earlier rows are never overwritten silently: with `fresh` the
/// results file and its manifest move to `previous/<UTC time>/`, otherwise the run
/// refuses (before any work) and says how to go on.
fn set_aside_earlier(opts: &RunOptions, results: &Path, manifest: &Path) -> Result<()> {
    if opts.resume || !results.exists() {
        return Ok(());
    }
    let (rows, _) = read_rows(results)?;
    if rows.is_empty() {
        return Ok(());
    }
    if !opts.fresh {
        return Err(HarnessError::input(format!(
            "{} holds {} rows of an earlier run; --resume continues it, --fresh moves it aside \
             to {}/previous/, --out writes elsewhere",
            results.display(),
            rows.len(),
            opts.out_dir.display()
        )));
    }
    let stamp = crate::provenance::now_rfc3339().replace(':', "");
    let base = opts.out_dir.join("previous");
    let dest = (0..)
        .map(|k| {
            if k == 0 {
                base.join(&stamp)
            } else {
                base.join(format!("{stamp}-{k}"))
            }
        })
        .find(|d| !d.exists())
        .unwrap_or_else(|| base.join(&stamp));
    crate::error::create_dir_all(&dest)?;
    for f in [results, manifest] {
        if let Some(name) = f.file_name()
            && f.exists()
        {
            let to = dest.join(name);
            std::fs::rename(f, &to).map_err(|e| HarnessError::io(f, e))?;
        }
    }
    Ok(())
}

/// The per-cell limits of a run.
struct Limits {
    timeout_s: f64,
    memory_limit_mib: Option<u64>,
}

/// The keys already done (with `--resume`; `--retry-failed` leaves failed ones out) and
/// the provenance of earlier runs, or a fresh start (the old results file removed).
fn resume_state(
    opts: &RunOptions,
    results: &Path,
    manifest_path: &Path,
) -> Result<(HashSet<String>, Vec<Provenance>)> {
    if !opts.resume {
        if results.exists() {
            std::fs::remove_file(results).map_err(|e| HarnessError::io(results, e))?;
        }
        return Ok((HashSet::new(), Vec::new()));
    }
    let (rows, _) = read_rows(results)?;
    let mut runs = Vec::new();
    if let Ok(text) = std::fs::read_to_string(manifest_path)
        && let Ok(m) = serde_json::from_str::<Manifest>(&text)
    {
        runs = m.runs;
    }
    let done = rows
        .into_iter()
        .filter(|r| !(opts.retry_failed && r.status != Status::Ok))
        .map(|r| r.key)
        .collect();
    Ok((done, runs))
}

/// Writes the manifest (this run's provenance appended to the earlier runs').
fn write_manifest(
    exp: &Experiment,
    opts: &RunOptions,
    limits: &Limits,
    mut runs: Vec<Provenance>,
    cells: &[Cell],
    path: &Path,
) -> Result<()> {
    runs.push(Provenance::collect());
    let manifest = Manifest {
        experiment: exp.name.clone(),
        file: exp.path.clone(),
        file_text: exp
            .path
            .as_ref()
            .and_then(|p| std::fs::read_to_string(p).ok()),
        shard: opts.shard,
        jobs: opts.jobs.max(1),
        threads_per_worker: opts.threads_per_worker,
        timeout_s: limits.timeout_s,
        memory_limit_mib: limits.memory_limit_mib,
        runs,
        cells: cells.to_vec(),
    };
    let text = serde_json::to_string_pretty(&manifest)
        .map_err(|e| HarnessError::failure(format!("manifest: {e}")))?;
    crate::error::write_atomic(path, text.as_bytes())
}

/// Runs `todo` on `opts.jobs` worker threads, each cell in its own worker process,
/// appending every row as it arrives. Returns the ok count and the failed cells.
fn run_cells(
    exp: &Experiment,
    opts: &RunOptions,
    limits: &Limits,
    cells: &[Cell],
    todo: &[&Cell],
    results: &Path,
) -> Result<(usize, Vec<FailedCell>)> {
    // Renders: reconstructions at the lowest seed index of each configuration.
    let min_seed = cells.iter().map(|c| c.spec.seed_index).min().unwrap_or(0);
    let store = Mutex::new(Store::open(results)?);
    let next = AtomicUsize::new(0);
    let failed = Mutex::new(Vec::new());
    let ok = AtomicUsize::new(0);
    let bar = progress_bar(todo.len(), opts.progress);
    let write_error: Mutex<Option<HarnessError>> = Mutex::new(None);
    let running: Arc<Mutex<BTreeMap<usize, (String, f64)>>> = Arc::default();
    let log = LogCounters::default();
    let log_lines = opts.progress && bar.is_hidden() && opts.log_every_s > 0.0;

    std::thread::scope(|s| {
        if log_lines {
            s.spawn(|| log_progress(&log, todo.len(), opts.log_every_s, &opts.stop));
        }
        let workers: Vec<_> = (0..opts.jobs.max(1).min(todo.len().max(1)))
            .map(|_| {
                s.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        let Some(cell) = todo.get(i) else { break };
                        if opts.stop.load(Ordering::SeqCst) != 0
                            || write_error.lock().map(|e| e.is_some()).unwrap_or(true)
                        {
                            break;
                        }
                        let render = render_request(exp, opts, cell, min_seed);
                        let progress =
                            (!bar.is_hidden()).then(|| cell_progress(&bar, &running, i, cell));
                        log.running.fetch_add(1, Ordering::SeqCst);
                        let row = run_cell_inner(
                            cell,
                            &opts.worker,
                            limits,
                            opts.threads_per_worker,
                            render,
                            progress,
                            Some(&opts.stop),
                        );
                        log.running.fetch_sub(1, Ordering::SeqCst);
                        if let Ok(mut r) = running.lock()
                            && r.remove(&i).is_some()
                        {
                            bar.set_message(running_message(&r));
                        }
                        // Interrupted: the cell is left for `--resume`, not recorded.
                        let Some(row) = row else { break };
                        if row.status == Status::Ok {
                            ok.fetch_add(1, Ordering::SeqCst);
                        } else {
                            let f = failed_cell(&row);
                            let msg = format!(
                                "cell {} failed ({}): {}",
                                f.label,
                                f.status.as_str(),
                                f.reason
                            );
                            if bar.is_hidden() {
                                if opts.progress {
                                    eprintln!("{msg}");
                                }
                            } else {
                                bar.println(msg);
                            }
                            if let Ok(mut v) = failed.lock() {
                                v.push(f);
                            }
                            log.failed.fetch_add(1, Ordering::SeqCst);
                        }
                        let res = store
                            .lock()
                            .map_err(|_| HarnessError::failure("store lock poisoned"))
                            .and_then(|mut st| st.append(&row));
                        if let Err(e) = res {
                            if let Ok(mut w) = write_error.lock() {
                                *w = Some(e);
                            }
                            break;
                        }
                        bar.inc(1);
                        log.done.fetch_add(1, Ordering::SeqCst);
                    }
                })
            })
            .collect();
        for w in workers {
            let _ = w.join();
        }
        log.finished.store(true, Ordering::SeqCst);
    });
    bar.finish_and_clear();
    if let Some(e) = write_error.into_inner().ok().flatten() {
        return Err(e);
    }
    Ok((
        ok.load(Ordering::SeqCst),
        failed.into_inner().unwrap_or_default(),
    ))
}

/// What the progress lines report, updated by the worker threads.
#[derive(Debug, Default)]
struct LogCounters {
    done: AtomicUsize,
    failed: AtomicUsize,
    running: AtomicUsize,
    finished: std::sync::atomic::AtomicBool,
}

/// Prints a progress line on stderr every `every_s` seconds until the run finishes:
/// for logs (Slurm, nohup, CI) where no progress bar can be drawn.
fn log_progress(c: &LogCounters, total: usize, every_s: f64, stop: &AtomicUsize) {
    let t0 = Instant::now();
    let mut next = every_s;
    while !c.finished.load(Ordering::SeqCst) && stop.load(Ordering::SeqCst) == 0 {
        std::thread::sleep(Duration::from_millis(50));
        let t = t0.elapsed().as_secs_f64();
        if t >= next {
            next = t + every_s;
            eprintln!(
                "{}",
                progress_line(
                    c.done.load(Ordering::SeqCst),
                    c.failed.load(Ordering::SeqCst),
                    c.running.load(Ordering::SeqCst),
                    total,
                    t
                )
            );
        }
    }
}

/// `progress: 45/513 cells done (2 failed), 2 running, 1m20s elapsed, ETA 13m52s`.
fn progress_line(done: usize, failed: usize, running: usize, total: usize, t: f64) -> String {
    let eta = if done == 0 {
        "unknown".to_string()
    } else {
        duration_text(t / done as f64 * total.saturating_sub(done) as f64)
    };
    format!(
        "progress: {done}/{total} cells done ({failed} failed), {running} running, {} elapsed, ETA {eta}",
        duration_text(t)
    )
}

/// Seconds as `45s`, `1m20s` or `2h03m`.
fn duration_text(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, s / 60 % 60),
    }
}

/// The render data a reconstruction cell at the lowest seed index writes, if renders
/// are on (the report draws the images from it).
fn render_request(
    exp: &Experiment,
    opts: &RunOptions,
    cell: &Cell,
    min_seed: u32,
) -> Option<RenderRequest> {
    let report = &exp.file.report;
    (report.renders
        && cell.spec.kind == MethodKind::Reconstruct
        && cell.spec.seed_index == min_seed)
        .then(|| {
            let rel = crate::render::data_path(&cell.key);
            RenderRequest {
                path: opts.out_dir.join(&rel),
                rel,
            }
        })
}

/// Shows the progress a running cell reports in the bar's message.
fn cell_progress(
    bar: &indicatif::ProgressBar,
    running: &Arc<Mutex<BTreeMap<usize, (String, f64)>>>,
    i: usize,
    cell: &Cell,
) -> ProgressFn {
    let label = format!("{} / {}", cell.labels.dataset, cell.labels.method);
    let (bar, running) = (bar.clone(), running.clone());
    Arc::new(move |f: f64| {
        if let Ok(mut r) = running.lock() {
            r.insert(i, (label.clone(), f));
            bar.set_message(running_message(&r));
        }
    })
}

/// The summary entry of a failed row.
fn failed_cell(row: &Row) -> FailedCell {
    FailedCell {
        key: row.key.clone(),
        label: format!(
            "{} / {} / {} seed {}",
            row.labels.dataset, row.labels.perturb, row.labels.method, row.spec.seed_index
        ),
        status: row.status,
        reason: row.error.clone().unwrap_or_default(),
    }
}

/// Keeps the latest row per key of this grid, sorted by grid index, so a finished run's
/// file does not depend on the completion order.
fn compact(cells: &[Cell], results: &Path) -> Result<()> {
    let keys: HashSet<&str> = cells.iter().map(|c| c.key.as_str()).collect();
    let (rows, _) = read_rows(results)?;
    let rows: Vec<Row> = dedupe_sorted(
        rows.into_iter()
            .filter(|r| keys.contains(r.key.as_str()))
            .collect(),
    );
    write_rows(results, &rows)
}

/// The progress bar's message: the running cells that reported progress.
fn running_message(r: &BTreeMap<usize, (String, f64)>) -> String {
    r.values()
        .map(|(l, f)| format!("{l} {:.0}%", 100.0 * f))
        .collect::<Vec<_>>()
        .join(", ")
}

fn progress_bar(n: usize, show: bool) -> indicatif::ProgressBar {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    let bar = ProgressBar::with_draw_target(
        Some(n as u64),
        if show {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    if let Ok(style) = ProgressStyle::with_template(
        "{bar:40.cyan/blue} {pos}/{len} cells  {elapsed_precise}  ETA {eta_precise}  {msg}",
    ) {
        bar.set_style(style);
    }
    bar
}

/// Runs one cell in a worker process and turns whatever happens into a row.
pub fn run_cell(
    cell: &Cell,
    worker: &[OsString],
    timeout_s: f64,
    memory_limit_mib: Option<u64>,
    threads: usize,
    render: Option<RenderRequest>,
) -> Row {
    run_cell_with_progress(
        cell,
        worker,
        timeout_s,
        memory_limit_mib,
        threads,
        render,
        None,
    )
}

/// Receives the progress fractions a worker's method reports.
pub type ProgressFn = Arc<dyn Fn(f64) + Send + Sync>;

/// [`run_cell`], passing the method's progress reports to `progress` as they arrive.
pub fn run_cell_with_progress(
    cell: &Cell,
    worker: &[OsString],
    timeout_s: f64,
    memory_limit_mib: Option<u64>,
    threads: usize,
    render: Option<RenderRequest>,
    progress: Option<ProgressFn>,
) -> Row {
    let limits = Limits {
        timeout_s,
        memory_limit_mib,
    };
    run_cell_inner(cell, worker, &limits, threads, render, progress, None)
        .unwrap_or_else(|| Row::failed(cell, Status::Crash, "interrupted"))
}

/// Runs a cell in a worker; `None` when `stop` was set while it ran (the worker is
/// killed and nothing is recorded).
fn run_cell_inner(
    cell: &Cell,
    worker: &[OsString],
    limits: &Limits,
    threads: usize,
    render: Option<RenderRequest>,
    progress: Option<ProgressFn>,
    stop: Option<&AtomicUsize>,
) -> Option<Row> {
    let t0 = Instant::now();
    let req = Request {
        cell: cell.clone(),
        timeout_s: limits.timeout_s,
        render,
    };
    let mut row = match spawn_and_wait(&req, worker, limits, threads, progress, stop) {
        Ok(Outcome::Reply(reply)) => {
            let mut row = Row::failed(cell, reply.status, "");
            row.error = reply.error;
            row.metrics = reply.metrics;
            row.diagnostics = reply.diagnostics;
            row.dist = reply.dist;
            row.render = reply.render;
            row.cost = reply.cost;
            row
        }
        Ok(Outcome::Failed(status, reason)) => Row::failed(cell, status, reason),
        Ok(Outcome::Interrupted) => return None,
        Err(e) => Row::failed(
            cell,
            Status::Crash,
            format!("could not run the worker: {e}"),
        ),
    };
    row.cost.wall_s = t0.elapsed().as_secs_f64();
    Some(row)
}

enum Outcome {
    Reply(Box<Reply>),
    Failed(Status, String),
    Interrupted,
}

/// Starts a worker in its own process group (so a terminal's Ctrl-C reaches only the
/// runner, which then stops the workers itself) and waits for it under the limits.
fn spawn_and_wait(
    req: &Request,
    worker: &[OsString],
    limits: &Limits,
    threads: usize,
    progress: Option<ProgressFn>,
    stop: Option<&AtomicUsize>,
) -> std::io::Result<Outcome> {
    use std::os::unix::process::CommandExt;
    let (timeout_s, memory_limit_mib) = (limits.timeout_s, limits.memory_limit_mib);
    let payload = serde_json::to_vec(req).map_err(std::io::Error::other)?;
    let mut child = Command::new(&worker[0])
        .args(&worker[1..])
        .process_group(0)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .env("RAYON_NUM_THREADS", threads.max(1).to_string())
        .spawn()?;
    let pid = child.id();
    let mut stdin = child.stdin.take();
    let writer = std::thread::spawn(move || {
        if let Some(mut w) = stdin.take() {
            let _ = w.write_all(&payload);
        }
    });
    let mut out = child.stdout.take();
    let mut err = child.stderr.take();
    let out_reader = std::thread::spawn(move || read_tail(out.as_mut(), 1 << 24));
    let err_reader = std::thread::spawn(move || read_stderr(err.as_mut(), 1 << 16, progress));

    let t0 = Instant::now();
    let timeout = Duration::from_secs_f64(timeout_s);
    let mut killed: Option<(Status, String)> = None;
    let mut interrupted = false;
    let status: ExitStatus = loop {
        if let Some(st) = child.try_wait()? {
            break st;
        }
        if !interrupted && stop.is_some_and(|s| s.load(Ordering::SeqCst) != 0) {
            interrupted = true;
            let _ = child.kill();
        }
        if killed.is_none() {
            if t0.elapsed() > timeout {
                killed = Some((
                    Status::Timeout,
                    format!("exceeded the per-cell timeout of {timeout_s} s"),
                ));
            } else if let (Some(limit), Some((rss, _))) = (memory_limit_mib, rss_mib(Some(pid)))
                && rss > limit as f64
            {
                killed = Some((
                    Status::Oom,
                    format!("resident memory {rss:.0} MiB exceeded the limit of {limit} MiB"),
                ));
            }
            if killed.is_some() {
                let _ = child.kill();
            }
        }
        std::thread::sleep(Duration::from_millis(15));
    };
    let _ = writer.join();
    let stdout = out_reader.join().unwrap_or_default();
    let stderr = err_reader.join().unwrap_or_default();
    if interrupted || stopped_with_the_run(status, stop) {
        return Ok(Outcome::Interrupted);
    }
    if let Some((st, reason)) = killed {
        return Ok(Outcome::Failed(st, reason));
    }
    if status.success()
        && let Some(line) = stdout
            .lines()
            .rev()
            .find_map(|l| l.strip_prefix(REPLY_PREFIX))
    {
        return Ok(match serde_json::from_str::<Reply>(line) {
            Ok(r) => Outcome::Reply(Box::new(r)),
            Err(e) => Outcome::Failed(Status::Crash, format!("unreadable worker reply: {e}")),
        });
    }
    let (st, reason) = classify(status, &stderr);
    Ok(Outcome::Failed(st, reason))
}

/// Whether a worker that died of SIGINT or SIGTERM went down with the whole run: a
/// scheduler's cancel (`scancel`) or a kill of the process tree signals the workers
/// together with the runner, and the runner's own handler may run a moment later, so
/// it is given half a second to set `stop`. Such a cell did not finish and is left for
/// `--resume`; a worker signalled alone is a crash.
fn stopped_with_the_run(status: ExitStatus, stop: Option<&AtomicUsize>) -> bool {
    use std::os::unix::process::ExitStatusExt;
    let Some(stop) = stop else { return false };
    if !matches!(status.signal(), Some(2 | 15)) {
        return false;
    }
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(500) {
        if stop.load(Ordering::SeqCst) != 0 {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    false
}

fn read_tail(r: Option<&mut impl Read>, cap: usize) -> String {
    let Some(r) = r else { return String::new() };
    let mut buf = Vec::new();
    let mut chunk = [0u8; 8192];
    loop {
        match r.read(&mut chunk) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                buf.extend_from_slice(&chunk[..n]);
                if buf.len() > 2 * cap {
                    buf.drain(..buf.len() - cap);
                }
            }
        }
    }
    if buf.len() > cap {
        buf.drain(..buf.len() - cap);
    }
    String::from_utf8_lossy(&buf).into_owned()
}

/// Reads a worker's stderr to the end: progress lines go to `progress`, the rest is
/// kept (its last `cap` bytes) for failure reasons.
fn read_stderr(r: Option<&mut impl Read>, cap: usize, progress: Option<ProgressFn>) -> String {
    let Some(r) = r else { return String::new() };
    let mut kept = Vec::new();
    let mut line = Vec::new();
    let mut chunk = [0u8; 8192];
    let take_line = |line: &mut Vec<u8>, kept: &mut Vec<u8>| {
        let text = String::from_utf8_lossy(line);
        match text.trim_end().strip_prefix(PROGRESS_PREFIX) {
            Some(f) => {
                if let (Some(p), Ok(f)) = (&progress, f.trim().parse::<f64>()) {
                    p(f);
                }
            }
            None => {
                kept.extend_from_slice(line);
                if kept.len() > 2 * cap {
                    kept.drain(..kept.len() - cap);
                }
            }
        }
        line.clear();
    };
    loop {
        match r.read(&mut chunk) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                for &b in &chunk[..n] {
                    line.push(b);
                    if b == b'\n' || line.len() > cap {
                        take_line(&mut line, &mut kept);
                    }
                }
            }
        }
    }
    if !line.is_empty() {
        take_line(&mut line, &mut kept);
    }
    if kept.len() > cap {
        kept.drain(..kept.len() - cap);
    }
    String::from_utf8_lossy(&kept).into_owned()
}

fn stderr_tail(stderr: &str) -> String {
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    let tail = lines[lines.len().saturating_sub(3)..].join(" | ");
    let mut t: String = tail.chars().take(400).collect();
    if t.len() < tail.len() {
        t.push_str("...");
    }
    t
}

/// Names the way a worker ended without a reply.
fn classify(status: ExitStatus, stderr: &str) -> (Status, String) {
    if let Some(msg) = stderr
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix(PANIC_PREFIX))
    {
        let msg: String = serde_json::from_str(msg).unwrap_or_else(|_| msg.to_string());
        return (Status::Panic, format!("panicked: {msg}"));
    }
    let alloc_failed = stderr.lines().find(|l| l.contains("memory allocation of"));
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            return match sig {
                6 if alloc_failed.is_some() => (
                    Status::Oom,
                    format!("out of memory: {}", alloc_failed.unwrap_or_default().trim()),
                ),
                6 => (Status::Crash, with_tail("aborted (SIGABRT)", stderr)),
                9 => (
                    Status::Crash,
                    with_tail(
                        "killed by SIGKILL (from outside, e.g. the kernel's out-of-memory killer)",
                        stderr,
                    ),
                ),
                11 => (
                    Status::Crash,
                    with_tail("segmentation fault (SIGSEGV)", stderr),
                ),
                7 => (Status::Crash, with_tail("bus error (SIGBUS)", stderr)),
                15 => (Status::Crash, "terminated (SIGTERM)".to_string()),
                s => (
                    Status::Crash,
                    with_tail(&format!("killed by signal {s}"), stderr),
                ),
            };
        }
    }
    if let Some(l) = alloc_failed {
        return (Status::Oom, format!("out of memory: {}", l.trim()));
    }
    match status.code() {
        Some(0) => (
            Status::Crash,
            with_tail("worker exited without a reply", stderr),
        ),
        Some(c) => (
            Status::Crash,
            with_tail(&format!("worker exited with code {c}"), stderr),
        ),
        None => (Status::Crash, with_tail("worker ended abnormally", stderr)),
    }
}

fn with_tail(what: &str, stderr: &str) -> String {
    let t = stderr_tail(stderr);
    if t.is_empty() {
        what.to_string()
    } else {
        format!("{what}: {t}")
    }
}

/// Merges result files (shards, or directories holding them) into `out_dir`:
/// `results.jsonl` with one row per key (a later file wins on duplicates, after a
/// consistency check of the spec) and `manifest.json` combining the shard manifests.
pub fn merge(inputs: &[PathBuf], out_dir: &Path) -> Result<MergeSummary> {
    let mut files = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| HarnessError::io(p, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("results") && n.ends_with(".jsonl"))
                })
                .collect();
            found.sort();
            files.extend(found);
        } else if p.exists() {
            files.push(p.clone());
        } else {
            return Err(HarnessError::input(format!(
                "{}: no such file or directory",
                p.display()
            )));
        }
    }
    if files.is_empty() {
        return Err(HarnessError::input(
            "merge: no results*.jsonl files in the inputs",
        ));
    }
    let mut by_key: BTreeMap<String, Row> = BTreeMap::new();
    // The directory each kept row came from, for its render data file.
    let mut source: BTreeMap<String, PathBuf> = BTreeMap::new();
    let mut warnings = Vec::new();
    let mut total = 0;
    for f in &files {
        let (rows, skipped) = read_rows(f)?;
        warnings.extend(skipped);
        total += rows.len();
        let dir = f.parent().map(Path::to_path_buf).unwrap_or_default();
        for r in rows {
            source.insert(r.key.clone(), dir.clone());
            if let Some(old) = by_key.get(&r.key)
                && old.spec != r.spec
            {
                return Err(HarnessError::input(format!(
                    "merge: key {} has different specs in two inputs (different code versions?)",
                    r.key
                )));
            }
            by_key.insert(r.key.clone(), r);
        }
    }
    let rows = dedupe_sorted(by_key.into_values().collect());
    crate::error::create_dir_all(out_dir)?;
    let out = out_dir.join("results.jsonl");
    // Manifests: take the first, union the cells and runs of all.
    let mut manifest: Option<Manifest> = None;
    for f in &files {
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let mname = name
            .replacen("results", "manifest", 1)
            .replace(".jsonl", ".json");
        let mpath = f.with_file_name(mname);
        if let Ok(text) = std::fs::read_to_string(&mpath)
            && let Ok(m) = serde_json::from_str::<Manifest>(&text)
        {
            match &mut manifest {
                None => manifest = Some(m),
                Some(acc) => {
                    acc.runs.extend(m.runs);
                    acc.cells.extend(m.cells);
                }
            }
        }
    }
    if let Some(mut m) = manifest {
        m.cells.sort_by_key(|c| c.index);
        m.cells.dedup_by(|a, b| a.key == b.key);
        m.shard = None;
        let text =
            serde_json::to_string_pretty(&m).map_err(|e| HarnessError::failure(e.to_string()))?;
        crate::error::write_atomic(&out_dir.join("manifest.json"), text.as_bytes())?;
    }
    write_rows(&out, &rows)?;
    for r in &rows {
        if let (Some(rel), Some(from)) = (&r.render, source.get(&r.key)) {
            warnings.extend(crate::render::copy_data(from, out_dir, rel));
        }
    }
    Ok(MergeSummary {
        inputs: files,
        rows_read: total,
        rows_written: rows.len(),
        output: out,
        warnings,
    })
}

/// What `merge` did.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MergeSummary {
    /// Result files read.
    pub inputs: Vec<PathBuf>,
    /// Rows read.
    pub rows_read: usize,
    /// Rows written (one per key).
    pub rows_written: usize,
    /// Merged results file.
    pub output: PathBuf,
    /// Lines skipped.
    pub warnings: Vec<String>,
}
