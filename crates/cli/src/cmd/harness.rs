//! Harness subcommands (owned by the harness work; flattened into the top-level CLI).
//!
//! Every verb is a thin wrapper over `reconbench-harness`.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use reconbench_harness::compare::{Baseline, Tolerances, compare};
use reconbench_harness::experiment::{Experiment, parse_shard};
use reconbench_harness::registry::{self, MethodKind, parse_overrides};
use reconbench_harness::report::{load_results, write_report};
use reconbench_harness::runner::{self, RunOptions};
use reconbench_harness::{HarnessError, aggregate, oneshot, worker};

use super::{CliError, CliResult, print_json};

/// Harness verbs.
#[derive(Debug, Subcommand)]
pub enum HarnessCommand {
    /// Run an experiment file: expand the grid, run every cell in an isolated worker, write
    /// results/<name>/results.jsonl, manifest.json and report.md.
    #[command(
        after_help = "Examples:\n  reconbench run experiments/quickstart.toml\n  \
        reconbench run experiments/quickstart.toml --resume -j 4\n  \
        reconbench run experiments/quickstart.toml --dry-run   # print the grid\n  \
        reconbench run experiments/quickstart.toml --shard 0/8 --out results/quickstart"
    )]
    Run(RunArgs),
    /// Run one cell (internal: the runner starts it; request JSON on stdin, reply on stdout).
    #[command(
        hide = true,
        after_help = "Example:\n  reconbench worker < request.json"
    )]
    Worker,
    /// List the registered methods with their parameters, defaults and seed sections.
    #[command(
        after_help = "Examples:\n  reconbench list\n  reconbench list --json\n  reconbench list --all   # include test-only debug-* methods"
    )]
    List(ListArgs),
    /// Reconstruct a mesh from one point cloud file with a registered method.
    #[command(
        after_help = "Examples:\n  reconbench gen torus --points 20000 --seed 1 -o torus.ply\n  reconbench reconstruct --method ufm torus.ply -o torus-ufm.ply\n  reconbench reconstruct --method priority-front datasets/real/bunny.ply -o bunny-pf.ply --set threads=2\n  reconbench reconstruct --method reference-mesh torus.ply -o ref.ply --set shape=torus --set resolution=48   # an oracle: the true surface"
    )]
    Reconstruct(OneShotArgs),
    /// Estimate normals of one point cloud file with a registered method.
    #[command(
        after_help = "Example:\n  reconbench normals --method gt-normals cloud.ply -o with_normals.ply --json"
    )]
    Normals(OneShotArgs),
    /// Label sharp-feature points of one point cloud file (written as the PLY label
    /// channel `feature`: 0 none, 1 edge, 2 corner).
    #[command(
        after_help = "Example:\n  reconbench features --method gt-features cloud.ply -o labelled.ply --set radius=0.02"
    )]
    Features(OneShotArgs),
    /// Filter one point cloud file with a registered filter (cloud in, cloud out).
    #[command(
        after_help = "Example:\n  reconbench filter --method statistical-outliers scan.ply -o clean.ply --set std_ratio=2"
    )]
    Filter(OneShotArgs),
    /// (Re)write tables, plots and report.md of a results directory.
    #[command(after_help = "Example:\n  reconbench report results/quickstart")]
    Report(ReportArgs),
    /// Save or show regression baselines.
    #[command(
        subcommand,
        after_help = "Example:\n  reconbench baseline save results/quickstart -o results/baselines/quickstart.json"
    )]
    Baseline(BaselineCommand),
    /// Compare results against a baseline; exit code 1 on a regression.
    #[command(
        after_help = "Example:\n  reconbench compare --baseline results/baselines/quickstart.json --current results/quickstart --tol chamfer_l1=rel:0.05 --tol 'normal_*=abs:0.1'"
    )]
    Compare(CompareArgs),
    /// Merge shard results (files or directories) into one results directory.
    #[command(
        after_help = "Example:\n  reconbench merge results/big --out results/big-all   # every results.shard-*.jsonl in results/big\n  reconbench merge a/results.jsonl b/results.jsonl --out merged"
    )]
    Merge(MergeArgs),
}

/// Arguments of `run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Experiment file (TOML; see experiments/README.md).
    experiment: PathBuf,
    /// Results directory (default: results/<experiment name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Parallel worker processes (default: available cores).
    #[arg(short = 'j', long)]
    jobs: Option<usize>,
    /// Keep existing results and skip cells that already have a row (by stable key).
    #[arg(long)]
    resume: bool,
    /// With --resume: run again the cells whose row is not ok.
    #[arg(long, requires = "resume")]
    retry_failed: bool,
    /// Move the earlier results of this experiment aside (to <out>/previous/<time>/) and
    /// start again; without it (or --resume) a run refuses to overwrite them.
    #[arg(long, conflicts_with = "resume")]
    fresh: bool,
    /// Run only shard i of N (0 <= i < N): every N-th cell starting at i.
    #[arg(long, value_name = "i/N")]
    shard: Option<String>,
    /// Per-cell timeout in seconds (overrides the file).
    #[arg(long, value_name = "SECONDS")]
    timeout: Option<f64>,
    /// Per-cell resident-memory limit in MiB (overrides the file).
    #[arg(long, value_name = "MIB")]
    memory_limit: Option<u64>,
    /// Threads per worker (RAYON_NUM_THREADS).
    #[arg(long, default_value_t = 1)]
    threads_per_worker: usize,
    /// Do not write the report after the run.
    #[arg(long)]
    no_report: bool,
    /// Exit with code 1 when a cell failed or a published figure was missed.
    #[arg(long)]
    strict: bool,
    /// Print the run summary as JSON.
    #[arg(long)]
    json: bool,
    /// When stderr is not a terminal (a log file, Slurm, nohup, CI): print a progress
    /// line every SECONDS (0: none).
    #[arg(long, value_name = "SECONDS", default_value_t = 10.0)]
    log_every: f64,
    /// Check the file and print the grid (cells, keys, labels) without running anything.
    #[arg(long)]
    dry_run: bool,
}

/// Arguments of `list`.
#[derive(Debug, Args)]
pub struct ListArgs {
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Include the test-only `debug-*` methods.
    #[arg(long)]
    all: bool,
}

/// Arguments of the one-shot verbs.
#[derive(Debug, Args)]
pub struct OneShotArgs {
    /// Registered method name (see `reconbench list`).
    #[arg(long)]
    method: String,
    /// Input point cloud (ply, obj, off, stl, xyz, pts).
    input: PathBuf,
    /// Output file; its extension picks the format.
    #[arg(short, long)]
    output: PathBuf,
    /// Parameter override `key=value` (repeatable; values are TOML: 8, 0.5, true, "x").
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Seed of the method's randomness.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Arguments of `report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Results directory.
    dir: PathBuf,
    /// Print the report summary as JSON.
    #[arg(long)]
    json: bool,
}

/// Baseline verbs.
#[derive(Debug, Subcommand)]
pub enum BaselineCommand {
    /// Save per-configuration metric means of a results directory as a baseline.
    #[command(
        after_help = "Example:\n  reconbench baseline save results/quickstart -o results/baselines/quickstart.json"
    )]
    Save {
        /// Results directory.
        dir: PathBuf,
        /// Baseline file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Print a baseline.
    #[command(
        after_help = "Example:\n  reconbench baseline show results/baselines/quickstart.json"
    )]
    Show {
        /// Baseline file.
        file: PathBuf,
    },
}

/// Arguments of `compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Baseline file.
    #[arg(long)]
    baseline: PathBuf,
    /// Current results directory (or another baseline file).
    #[arg(long)]
    current: PathBuf,
    /// Tolerance `metric=rel:X` or `metric=abs:X` (repeatable; `prefix*` and `*`
    /// patterns allowed; default rel:0.01,abs:1e-9).
    #[arg(long = "tol", value_name = "METRIC=TOL")]
    tol: Vec<String>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Arguments of `merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Result files or directories holding results*.jsonl.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// Do not write the report.
    #[arg(long)]
    no_report: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

fn harness_err(e: HarnessError) -> CliError {
    if e.is_input() {
        CliError::input(e)
    } else {
        CliError::failure(e)
    }
}

/// Runs a harness verb.
pub fn run(cmd: HarnessCommand) -> CliResult {
    match cmd {
        HarnessCommand::Run(a) => run_experiment(a),
        HarnessCommand::Worker => {
            worker::serve(std::io::stdin().lock(), std::io::stdout().lock()).map_err(harness_err)
        }
        HarnessCommand::List(a) => list(a),
        HarnessCommand::Reconstruct(a) => one_shot(MethodKind::Reconstruct, a),
        HarnessCommand::Normals(a) => one_shot(MethodKind::Normals, a),
        HarnessCommand::Features(a) => one_shot(MethodKind::Features, a),
        HarnessCommand::Filter(a) => one_shot(MethodKind::Filter, a),
        HarnessCommand::Report(a) => report(a),
        HarnessCommand::Baseline(c) => baseline(c),
        HarnessCommand::Compare(a) => compare_cmd(a),
        HarnessCommand::Merge(a) => merge(a),
    }
}

/// `run --dry-run`: the expanded grid (this shard's cells), nothing run or written.
fn print_grid(exp: &Experiment, shard: Option<(usize, usize)>, json: bool) -> CliResult {
    let cells = reconbench_harness::experiment::shard_cells(&exp.cells, shard);
    if json {
        let rows: Vec<_> = cells
            .iter()
            .map(|c| {
                serde_json::json!({
                    "index": c.index, "key": c.key, "dataset": c.labels.dataset,
                    "perturbation": c.labels.perturb, "method": c.labels.method,
                })
            })
            .collect();
        return super::print_json(&rows);
    }
    for c in &cells {
        println!(
            "{:>5} {} {:<20} {:<24} {}",
            c.index, c.key, c.labels.dataset, c.labels.perturb, c.labels.method
        );
    }
    println!(
        "{}: {} cells (of {}); nothing was run",
        exp.name,
        cells.len(),
        exp.cells.len()
    );
    Ok(())
}

fn run_experiment(a: RunArgs) -> CliResult {
    let exp = Experiment::load(&a.experiment).map_err(harness_err)?;
    let shard = a
        .shard
        .as_deref()
        .map(parse_shard)
        .transpose()
        .map_err(harness_err)?;
    if let Some(t) = a.timeout
        && !(t.is_finite() && t > 0.0)
    {
        return Err(CliError::input(format!("--timeout must be > 0, got {t}")));
    }
    if !(a.log_every.is_finite() && a.log_every >= 0.0) {
        return Err(CliError::input(format!(
            "--log-every must be >= 0 seconds, got {}",
            a.log_every
        )));
    }
    if a.dry_run {
        return print_grid(&exp, shard, a.json);
    }
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("results").join(&exp.name));
    let exe = std::env::current_exe().map_err(CliError::failure)?;
    let jobs = a
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let opts = RunOptions {
        out_dir: out_dir.clone(),
        jobs,
        resume: a.resume,
        retry_failed: a.retry_failed,
        fresh: a.fresh,
        shard,
        worker: vec![exe.into_os_string(), OsString::from("worker")],
        timeout_s: a.timeout,
        memory_limit_mib: a.memory_limit,
        threads_per_worker: a.threads_per_worker.max(1),
        progress: !a.json,
        log_every_s: a.log_every,
        stop: runner::stop_on_signals().map_err(harness_err)?,
    };
    let summary = runner::run(&exp, &opts).map_err(harness_err)?;
    if let Some(sig) = summary.interrupted {
        return Err(interrupted(&a, &summary, sig));
    }
    let mut misses = 0;
    let mut report_path = None;
    if !a.no_report && shard.is_none() {
        let (rows, _, manifest) = load_results(&out_dir).map_err(harness_err)?;
        let out =
            write_report(&out_dir, &rows, Some(&exp), manifest.as_ref()).map_err(harness_err)?;
        misses = out.misses();
        report_path = Some(out.report);
    }
    if a.json {
        print_json(&serde_json::json!({
            "summary": summary,
            "report": report_path,
            "expect_misses": misses,
        }))?;
    } else {
        println!(
            "{}: {} cells, {} skipped (resume), {} run: {} ok, {} failed in {:.1} s",
            summary.experiment,
            summary.cells,
            summary.skipped,
            summary.ran,
            summary.ok,
            summary.failed.len(),
            summary.wall_s
        );
        for f in &summary.failed {
            println!(
                "  failed ({}): {}: {}",
                f.status.as_str(),
                f.label,
                f.reason
            );
        }
        println!("results: {}", summary.results.display());
        if let Some(r) = &report_path {
            println!("report:  {}", r.display());
        }
        if misses > 0 {
            println!("published figures: {misses} outside tolerance (see the report)");
        }
    }
    if a.strict && (!summary.failed.is_empty() || misses > 0) {
        return Err(CliError::failure(format!(
            "{} failed cells, {misses} missed published figures",
            summary.failed.len()
        )));
    }
    Ok(())
}

/// The error of a run stopped by a signal: what was kept and how to go on; the exit
/// code is 128 + the signal (130 for SIGINT, 143 for SIGTERM), as a shell reports it.
fn interrupted(a: &RunArgs, summary: &runner::RunSummary, sig: usize) -> CliError {
    let mut again = format!("reconbench run {}", a.experiment.display());
    if let Some(o) = &a.out {
        again.push_str(&format!(" --out {}", o.display()));
    }
    if let Some(s) = &a.shard {
        again.push_str(&format!(" --shard {s}"));
    }
    CliError {
        message: format!(
            "interrupted by {}: {} of {} cells are saved in {} ({} run now); the cells that were running are not; resume with: {again} --resume",
            runner::signal_name(sig),
            summary.skipped + summary.ran,
            summary.cells,
            summary.results.display(),
            summary.ran,
        ),
        code: u8::try_from(128 + sig).unwrap_or(1),
    }
}

fn list(a: ListArgs) -> CliResult {
    let methods = registry::list(a.all);
    if a.json {
        return print_json(&methods);
    }
    for m in &methods {
        println!(
            "{:<18} {:<11} {:<10} {}{}",
            m.name,
            m.kind.as_str(),
            m.seed,
            m.summary,
            if m.oracle {
                " [oracle: receives ground truth]"
            } else {
                ""
            }
        );
        if m.needs != registry::Needs::Positions {
            println!(
                "    needs {} (put a normal estimator before it in `steps`)",
                m.needs.as_str()
            );
        }
        for p in &m.params {
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(" [{}]", p.unit)
            };
            println!("    {} = {}{}  {}", p.name, p.default, unit, p.doc);
        }
    }
    Ok(())
}

fn one_shot(kind: MethodKind, a: OneShotArgs) -> CliResult {
    let overrides = parse_overrides(&a.set).map_err(harness_err)?;
    let r = oneshot::run(kind, &a.method, &overrides, &a.input, &a.output, a.seed)
        .map_err(harness_err)?;
    if a.json {
        return print_json(&r);
    }
    let summary: Vec<String> = r
        .summary
        .iter()
        .map(|(k, v)| format!("{} {}", k.replace('_', " "), super::num_text(*v)))
        .collect();
    println!(
        "{} on {} ({} points): {} in {:.3} s",
        r.method,
        r.input,
        r.points,
        summary.join(", "),
        r.seconds
    );
    if !r.phases.is_empty() {
        let phases: Vec<String> = r
            .phases
            .iter()
            .map(|(n, s)| format!("{n} {s:.3} s"))
            .collect();
        println!("phases: {}", phases.join(", "));
    }
    if !r.diagnostics.is_empty() {
        println!("diagnostics (--json prints them whole):");
    }
    for (k, v) in &r.diagnostics {
        let unit = if reconbench_harness::store::is_timing(k) && !k.ends_with("_per_second") {
            " s"
        } else {
            ""
        };
        println!("  {k} = {}{unit}", diagnostic_text(v));
    }
    println!("wrote {}", r.output);
    Ok(())
}

/// A diagnostic for the terminal: numbers legible, a long series as its length, ends
/// and range, a long text cut.
fn diagnostic_text(v: &serde_json::Value) -> String {
    use serde_json::Value;
    let num = |v: &Value| v.as_f64().map_or_else(|| v.to_string(), super::num_text);
    match v {
        Value::Number(_) => num(v),
        Value::Array(a) if a.len() <= 6 => {
            let items: Vec<String> = a.iter().map(num).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Array(a) => {
            let xs: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
            let (lo, hi) = xs
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                    (l.min(x), h.max(x))
                });
            format!(
                "{} values: first {}, last {}, range {} .. {}",
                a.len(),
                num(&a[0]),
                num(&a[a.len() - 1]),
                super::num_text(lo),
                super::num_text(hi)
            )
        }
        Value::String(t) if t.chars().count() > 160 => {
            format!("{}...", t.chars().take(160).collect::<String>())
        }
        Value::String(t) => t.clone(),
        other => other.to_string(),
    }
}

fn report(a: ReportArgs) -> CliResult {
    let (rows, exp, manifest) = load_results(&a.dir).map_err(harness_err)?;
    let out = write_report(&a.dir, &rows, exp.as_ref(), manifest.as_ref()).map_err(harness_err)?;
    if a.json {
        return print_json(&out);
    }
    println!(
        "{} rows ({} failed), {} tables, {} plot files, {} published figures ({} missed)",
        out.rows,
        out.failed,
        out.tables.len(),
        out.plots.len(),
        out.expect.len(),
        out.misses()
    );
    println!("report: {}", out.report.display());
    Ok(())
}

fn load_current(path: &Path) -> Result<Baseline, CliError> {
    if path.is_file() && path.extension().is_some_and(|e| e == "json") {
        return Baseline::load(path).map_err(harness_err);
    }
    let (rows, exp, manifest) = load_results(path).map_err(harness_err)?;
    let rows = match &exp {
        Some(e) => {
            let keys: std::collections::HashSet<&str> =
                e.cells.iter().map(|c| c.key.as_str()).collect();
            rows.into_iter()
                .filter(|r| keys.contains(r.key.as_str()))
                .collect()
        }
        None => rows,
    };
    let groups = aggregate::aggregate(&rows);
    let name = manifest
        .as_ref()
        .map_or_else(|| "experiment".to_string(), |m| m.experiment.clone());
    let commit = manifest
        .as_ref()
        .and_then(|m| m.runs.last().map(|r| r.git_commit.clone()))
        .unwrap_or_else(|| "unknown".into());
    Ok(Baseline::from_groups(&name, &commit, &groups))
}

fn baseline(c: BaselineCommand) -> CliResult {
    match c {
        BaselineCommand::Save { dir, output } => {
            let b = load_current(&dir)?;
            b.save(&output).map_err(harness_err)?;
            println!(
                "saved {} configurations of '{}' to {}",
                b.configs.len(),
                b.experiment,
                output.display()
            );
            Ok(())
        }
        BaselineCommand::Show { file } => {
            let b = Baseline::load(&file).map_err(harness_err)?;
            print_json(&b)
        }
    }
}

fn compare_cmd(a: CompareArgs) -> CliResult {
    let tols = Tolerances::parse(&a.tol).map_err(harness_err)?;
    let base = Baseline::load(&a.baseline).map_err(harness_err)?;
    let cur = load_current(&a.current)?;
    let c = compare(&base, &cur, &tols);
    if a.json {
        print_json(&c)?;
    } else {
        println!(
            "compared {} metric values of {} configurations: {} improved, {} regressed, {} lost, {} new",
            c.compared,
            base.configs.len(),
            c.improved.len(),
            c.regressed.len(),
            c.lost.len(),
            c.new.len()
        );
        for ch in &c.improved {
            println!(
                "  improved  {}: {} {} -> {} (tol {})",
                ch.label, ch.metric, ch.baseline, ch.current, ch.tol
            );
        }
        for ch in &c.regressed {
            println!(
                "  REGRESSED {}: {} {} -> {} (tol {})",
                ch.label, ch.metric, ch.baseline, ch.current, ch.tol
            );
        }
        for l in &c.lost {
            println!("  LOST      {l}");
        }
        for n in &c.new {
            println!("  new       {n}");
        }
        for r in &c.rekeyed {
            println!("  re-keyed  {r} (key changed, matched by its label)");
        }
    }
    if c.has_regressions() {
        return Err(CliError::failure(format!(
            "{} regressed metrics, {} lost configurations against {}",
            c.regressed.len(),
            c.lost.len(),
            a.baseline.display()
        )));
    }
    Ok(())
}

fn merge(a: MergeArgs) -> CliResult {
    let s = runner::merge(&a.inputs, &a.out).map_err(harness_err)?;
    let mut report_path = None;
    if !a.no_report {
        let (rows, exp, manifest) = load_results(&a.out).map_err(harness_err)?;
        let out =
            write_report(&a.out, &rows, exp.as_ref(), manifest.as_ref()).map_err(harness_err)?;
        report_path = Some(out.report);
    }
    if a.json {
        return print_json(&serde_json::json!({ "merge": s, "report": report_path }));
    }
    println!(
        "merged {} files: {} rows read, {} written to {}",
        s.inputs.len(),
        s.rows_read,
        s.rows_written,
        s.output.display()
    );
    for w in &s.warnings {
        println!("  {w}");
    }
    if let Some(r) = report_path {
        println!("report: {}", r.display());
    }
    Ok(())
}
