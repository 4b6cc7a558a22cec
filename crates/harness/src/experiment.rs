//! Experiment files (TOML) and their expansion into a grid of cells.
//!
//! The reference for the format is `experiments/README.md`. In short:
//!
//! ```toml
//! name = "quickstart"        # default: the file stem; results go to results/<name>/
//! seed = 1                   # experiment seed
//! seeds = 3                  # seed indices 0..3 (or a list: [0, 4, 7])
//! timeout = 60               # per-cell seconds
//!
//! [[datasets]]
//! shape = "torus:R=0.5,r=0.2"
//! sampler = "uniform"
//! points = [2000, 4000]      # lists expand
//!
//! [[perturbations]]
//! noise = [0.0, 0.0025, 0.005]   # lists expand (Cartesian product within a block)
//!
//! [[methods]]
//! name = "reference-mesh"
//! params = { resolution = [32, 64] }   # lists expand
//!
//! [metrics]                  # options for the metric functions
//! [report]                   # tables, plots, renders
//! [[expect]]                 # published figures to compare with
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::error::{HarnessError, Result};
pub use crate::inputs::DataSpec;
use crate::inputs::{FileInput, FileKind};
use crate::key::{derive_seed, hash_value, hex_key};
use crate::pipeline::{self, StepSpec};
use crate::registry::{self, MethodEntry, MethodKind};
use crate::{inputs, metric_spec};

/// Seed indices: a count (`3` = 0, 1, 2) or an explicit list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Seeds {
    /// `0..n`.
    Count(u32),
    /// Explicit indices.
    List(Vec<u32>),
}

impl Default for Seeds {
    fn default() -> Self {
        Seeds::Count(1)
    }
}

impl Seeds {
    /// The indices.
    pub fn indices(&self) -> Vec<u32> {
        match self {
            Seeds::Count(n) => (0..*n).collect(),
            Seeds::List(v) => v.clone(),
        }
    }
}

/// One `[[datasets]]` entry: exactly one of `shape` (an analytic shape), `real` (a
/// vendored real set), `mesh` (a mesh file) or `cloud` (a point-cloud file, no ground
/// truth). File paths are relative to the experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetEntry {
    /// Label in tables and plots (default: the shape spec, real set name or file name).
    #[serde(default)]
    pub name: Option<String>,
    /// Shape spec, e.g. `torus:R=0.5,r=0.2` (see `reconbench shapes`).
    #[serde(default)]
    pub shape: Option<String>,
    /// A vendored real set (`reconbench datasets`), e.g. `fandisk`.
    #[serde(default)]
    pub real: Option<String>,
    /// A mesh file (any format `reconbench info` reads); the mesh is the ground truth.
    #[serde(default)]
    pub mesh: Option<String>,
    /// A point-cloud file, used as the input as is; there is no ground truth.
    #[serde(default)]
    pub cloud: Option<String>,
    /// For `real` and `mesh`: `vertices` (the mesh's own vertices, de-duplicated; the
    /// default), `sample` (the sampler, `points` points) or `scan` (the virtual scanner).
    /// For `shape`: `sample` (default) or `scan`.
    #[serde(default)]
    pub input: Option<String>,
    /// Scan spec for `input = "scan"` (`views=6,res=64`, see `reconbench gen --help`).
    #[serde(default)]
    pub scan: Option<String>,
    /// Sharp-edge threshold of a mesh ground truth, degrees (30).
    #[serde(default)]
    pub feature_angle_deg: Option<f64>,
    /// Declared closedness of a mesh ground truth (a real set: the seed's
    /// `thesis_closed`; a mesh: as measured).
    #[serde(default)]
    pub closed: Option<bool>,
    /// Sampler spec (default `uniform`).
    #[serde(default = "default_sampler")]
    pub sampler: String,
    /// Number of points for sampled inputs; a list expands.
    #[serde(default)]
    pub points: Option<toml::Value>,
}

fn default_sampler() -> String {
    "uniform".into()
}

/// One step of a `steps = [...]` pipeline: a registry name, or a table with the name
/// and the step's parameters (`{ name = "jet", params = { k = 18 } }`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum StepEntry {
    /// Just the name (default parameters).
    Name(String),
    /// Name and parameters.
    Table {
        /// Registry name.
        name: String,
        /// Parameters; list values expand like the entry's own.
        #[serde(default)]
        params: toml::Table,
    },
}

impl StepEntry {
    fn name(&self) -> &str {
        match self {
            StepEntry::Name(n) | StepEntry::Table { name: n, .. } => n,
        }
    }

    fn params(&self) -> toml::Table {
        match self {
            StepEntry::Name(_) => toml::Table::new(),
            StepEntry::Table { params, .. } => params.clone(),
        }
    }
}

/// One `[[methods]]` entry: a single method (`name`) or a pipeline (`steps`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodSpec {
    /// Registry name (a single method; leave out with `steps`).
    #[serde(default)]
    pub name: Option<String>,
    /// A pipeline: steps run in order, each seeing the cloud the previous ones left
    /// (normals and labels attached, filters applied). `params` belong to the last step.
    #[serde(default)]
    pub steps: Vec<StepEntry>,
    /// Label in tables (default: the name, plus the swept parameters).
    #[serde(default)]
    pub label: Option<String>,
    /// Parameters; list values expand (wrap a list-valued parameter in a list: `[[1, 2]]`).
    #[serde(default)]
    pub params: toml::Table,
}

/// `[report]` options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReportOptions {
    /// Perturbation key on the x axis of metric plots (default: the first swept key).
    pub x: Option<String>,
    /// Metric columns of the tables (default: a standard set per method kind).
    pub metrics: Vec<String>,
    /// Metrics plotted against `x` (default: the first two columns per kind).
    pub plot_metrics: Vec<String>,
    /// Table formats among `md`, `tex`, `csv`.
    pub tables: Vec<String>,
    /// Write plots.
    pub plots: bool,
    /// Write error renders of reconstructions (seed index 0 of each configuration), one
    /// image per configuration with the methods side by side.
    pub renders: bool,
    /// Top of a fixed colour scale of renders (fraction of the diagonal), to compare
    /// renders across reports; by default each report picks its own scale from its
    /// meshes' distances (`render::Scale::robust`).
    pub render_max: Option<f64>,
    /// Side in pixels of each render view.
    pub render_size: u32,
    /// Plot size in pixels `[width, height]`.
    pub plot_size: [u32; 2],
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            x: None,
            metrics: Vec::new(),
            plot_metrics: Vec::new(),
            tables: vec!["md".into(), "tex".into(), "csv".into()],
            plots: true,
            renders: true,
            render_max: None,
            render_size: 240,
            plot_size: [800, 500],
        }
    }
}

/// An `[[expect]]` entry: a published figure to reproduce.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Expect {
    /// Cell selector: `dataset`, `method` (label or name), `shape`, `points`, any
    /// perturbation key, or `params.NAME`; every given key must match.
    #[serde(rename = "where", default)]
    pub select: toml::Table,
    /// Metric name (as in the tables, e.g. `normal_mean_deg`), or `time` (the method's
    /// wall time) or `cost.NAME` (any cost entry, e.g. `cost.peak_rss_mib`).
    pub metric: String,
    /// When given, the value is a ratio: the selected cells' metric over that of the
    /// cells this selector picks (same keys as `where`), e.g. a published speed-up.
    #[serde(default)]
    pub over: Option<toml::Table>,
    /// The published value.
    pub value: f64,
    /// Where it is published, e.g. `seed 000 Table 4.1`.
    #[serde(default)]
    pub source: String,
    /// Tolerance: `rel:0.05` (default) or `abs:0.001`.
    #[serde(default = "default_expect_tol")]
    pub tol: String,
    /// Why the reproduction differs when it misses (a substitution, a known deviation,
    /// a page of `docs/methods/`); shown next to the miss, and a miss without one is
    /// reported as unexplained.
    #[serde(default)]
    pub note: String,
}

fn default_expect_tol() -> String {
    "rel:0.05".into()
}

/// The TOML file as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentFile {
    /// Name (default: file stem).
    #[serde(default)]
    pub name: Option<String>,
    /// Free text for the report.
    #[serde(default)]
    pub description: String,
    /// Experiment seed.
    #[serde(default)]
    pub seed: u64,
    /// Seed indices.
    #[serde(default)]
    pub seeds: Seeds,
    /// Per-cell timeout in seconds (default 600).
    #[serde(default)]
    pub timeout: Option<f64>,
    /// Per-cell resident-memory limit in MiB (default: none).
    #[serde(default)]
    pub memory_limit_mib: Option<u64>,
    /// Datasets.
    #[serde(default)]
    pub datasets: Vec<DatasetEntry>,
    /// Perturbation blocks (default: one block without perturbation).
    #[serde(default)]
    pub perturbations: Vec<toml::Table>,
    /// Methods.
    #[serde(default)]
    pub methods: Vec<MethodSpec>,
    /// Metric options, passed to the metric functions.
    #[serde(default)]
    pub metrics: toml::Table,
    /// Report options.
    #[serde(default)]
    pub report: ReportOptions,
    /// Published figures.
    #[serde(default)]
    pub expect: Vec<Expect>,
}

/// Everything a worker needs to run one cell. Its canonical JSON (minus labels) is hashed
/// into the cell key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellSpec {
    /// The input data.
    pub data: DataSpec,
    /// Method registry name (the last step of a pipeline).
    pub method: String,
    /// Method kind (of the last step).
    pub kind: MethodKind,
    /// Resolved parameters (defaults filled in) of the last step.
    pub params: Value,
    /// The steps of a pipeline before the last, in order (empty for a single method,
    /// and then left out of the key so single-method keys are unchanged).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pre: Vec<StepSpec>,
    /// Experiment seed.
    pub experiment_seed: u64,
    /// Seed index (repetition).
    pub seed_index: u32,
    /// Metric options.
    pub metrics: Value,
}

/// Human-readable labels of a cell (not part of its key).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Labels {
    /// Dataset label.
    pub dataset: String,
    /// Perturbation label (`clean` when none).
    pub perturb: String,
    /// Method label.
    pub method: String,
}

/// One cell of the expanded grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// Position in the grid (stable for a given file).
    pub index: usize,
    /// Stable key: hash of the spec and the harness version.
    pub key: String,
    /// Key of the configuration (the spec without its seed index): groups repetitions.
    pub config: String,
    /// Seed of the input data, from (experiment seed, data spec, seed index).
    pub data_seed: u64,
    /// Labels.
    pub labels: Labels,
    /// The spec.
    pub spec: CellSpec,
}

/// A loaded and validated experiment.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// Name.
    pub name: String,
    /// Where it was read from.
    pub path: Option<PathBuf>,
    /// The file.
    pub file: ExperimentFile,
    /// Per-cell timeout, seconds.
    pub timeout_s: f64,
    /// The expanded grid.
    pub cells: Vec<Cell>,
    /// Perturbation keys that take more than one value (plot axes).
    pub swept: Vec<String>,
}

/// Longest per-cell timeout, seconds (a week).
pub const MAX_TIMEOUT_S: f64 = 604_800.0;
/// Smallest per-cell memory limit, MiB.
pub const MIN_MEMORY_LIMIT_MIB: u64 = 16;
/// Most points a sampled dataset may ask for (about 2.4 GB of positions alone).
pub const MAX_POINTS: u64 = 100_000_000;
/// Most cells an experiment may expand to.
pub const MAX_CELLS: u64 = 1_000_000;

/// Checks the `[[expect]]` entries before any cell runs: tolerance syntax and selector
/// keys.
fn validate_expectations(expect: &[Expect]) -> Result<()> {
    for (i, e) in expect.iter().enumerate() {
        crate::compare::Tol::parse(&e.tol)
            .map_err(|err| HarnessError::input(format!("expect[{i}].tol: {err}")))?;
        if e.metric != "time" && !e.metric.starts_with("cost.") {
            metric_spec::check_metric_name(&e.metric, &format!("expect[{i}].metric"))?;
        }
        for sel in std::iter::once(&e.select).chain(e.over.as_ref()) {
            for k in sel.keys() {
                let known = ["dataset", "method", "perturbation", "shape", "points"]
                    .contains(&k.as_str())
                    || k.strip_prefix("params.").is_some_and(|p| !p.is_empty())
                    || inputs::validate_perturb_key(k).is_ok();
                if !known {
                    return Err(HarnessError::input(format!(
                        "expect[{i}]: unknown selector key '{}'; valid: dataset, method, perturbation, shape, points, params.NAME or a perturbation key",
                        k.escape_debug()
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Salt of every key: changes when the harness version changes.
pub fn key_salt() -> String {
    format!("reconbench-harness/{}", env!("CARGO_PKG_VERSION"))
}

impl Experiment {
    /// Reads and expands an experiment file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::error::read_to_string(path)?;
        let stem = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("experiment")
            .to_string();
        let base = path.parent().filter(|p| !p.as_os_str().is_empty());
        let mut exp = Self::parse_at(&text, &stem, base)
            .map_err(|e| HarnessError::input(format!("{}: {e}", path.display())))?;
        exp.path = Some(path.to_path_buf());
        Ok(exp)
    }

    /// Parses and expands experiment text; `default_name` is used when it has no name.
    pub fn parse(text: &str, default_name: &str) -> Result<Self> {
        Self::parse_at(text, default_name, None)
    }

    /// [`parse`](Self::parse) with file paths resolved against `base` (default: the
    /// current directory).
    pub fn parse_at(text: &str, default_name: &str, base: Option<&Path>) -> Result<Self> {
        let file: ExperimentFile =
            toml::from_str(text).map_err(|e| HarnessError::input(e.to_string()))?;
        let name = file
            .name
            .clone()
            .unwrap_or_else(|| default_name.to_string());
        if name.is_empty()
            || name.starts_with('.')
            || name.len() > 128
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.')
        {
            return Err(HarnessError::input(format!(
                "experiment name '{}' must be 1 to 128 letters, digits, '-', '_', '.', not starting with '.' (it names the results directory)",
                name.escape_debug()
            )));
        }
        let timeout_s = file.timeout.unwrap_or(600.0);
        if !(timeout_s.is_finite() && timeout_s > 0.0 && timeout_s <= MAX_TIMEOUT_S) {
            return Err(HarnessError::input(format!(
                "timeout = {timeout_s}: must be in (0, {MAX_TIMEOUT_S}] seconds (a week)"
            )));
        }
        if let Some(m) = file.memory_limit_mib
            && m < MIN_MEMORY_LIMIT_MIB
        {
            return Err(HarnessError::input(format!(
                "memory_limit_mib = {m}: below {MIN_MEMORY_LIMIT_MIB} MiB no worker can start"
            )));
        }
        validate_expectations(&file.expect)?;
        let cwd = std::env::current_dir().unwrap_or_default();
        let (cells, swept) = expand(&file, base.unwrap_or(&cwd))?;
        validate_report(&file.report, &swept)?;
        Ok(Self {
            name,
            path: None,
            file,
            timeout_s,
            cells,
            swept,
        })
    }
}

fn validate_report(r: &ReportOptions, swept: &[String]) -> Result<()> {
    for m in &r.metrics {
        metric_spec::check_metric_name(m, "report.metrics")?;
    }
    for m in &r.plot_metrics {
        metric_spec::check_metric_name(m, "report.plot_metrics")?;
    }
    for t in &r.tables {
        if !["md", "tex", "csv"].contains(&t.as_str()) {
            return Err(HarnessError::input(format!(
                "report.tables: unknown format '{t}'; valid: md, tex, csv"
            )));
        }
    }
    if let Some(x) = &r.x
        && !swept.contains(x)
        && x != "points"
    {
        return Err(HarnessError::input(format!(
            "report.x = '{x}' is not a swept perturbation key; swept: {}",
            if swept.is_empty() {
                "(none)".to_string()
            } else {
                swept.join(", ")
            }
        )));
    }
    if r.render_max.is_some_and(|m| !(m.is_finite() && m > 0.0)) {
        return Err(HarnessError::input("report.render_max must be > 0"));
    }
    if r.render_size < 16
        || r.render_size > 4096
        || r.plot_size.iter().any(|&s| !(64..=8192).contains(&s))
    {
        return Err(HarnessError::input(
            "report: render_size must be in 16..=4096, plot_size in 64..=8192",
        ));
    }
    Ok(())
}

/// Expands list values of a table into the Cartesian product of scalar tables (keys
/// sorted; the last key varies fastest). Returns the combinations and the keys that had
/// lists of more than one value.
pub fn expand_table(table: &Map<String, Value>) -> (Vec<Map<String, Value>>, Vec<String>) {
    let mut combos = vec![Map::new()];
    let mut swept = Vec::new();
    let mut keys: Vec<&String> = table.keys().collect();
    keys.sort();
    for k in keys {
        let values: Vec<Value> = match &table[k] {
            Value::Array(items) => items.clone(),
            v => vec![v.clone()],
        };
        if values.len() > 1 {
            swept.push(k.clone());
        }
        let mut next = Vec::with_capacity(combos.len() * values.len());
        for c in &combos {
            for v in &values {
                let mut c = c.clone();
                c.insert(k.clone(), v.clone());
                next.push(c);
            }
        }
        combos = next;
    }
    (combos, swept)
}

fn to_json(t: &toml::Table) -> Map<String, Value> {
    match serde_json::to_value(t) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    }
}

fn fmt_value(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

fn expand(file: &ExperimentFile, base: &Path) -> Result<(Vec<Cell>, Vec<String>)> {
    if file.datasets.is_empty() {
        return Err(HarnessError::input("no [[datasets]]: add at least one"));
    }
    if file.methods.is_empty() {
        return Err(HarnessError::input("no [[methods]]: add at least one"));
    }
    if let Seeds::Count(n) = file.seeds
        && u64::from(n) > MAX_CELLS
    {
        return Err(HarnessError::input(format!(
            "seeds = {n}: at most {MAX_CELLS} (the grid's cell limit)"
        )));
    }
    let seeds = file.seeds.indices();
    if seeds.is_empty() {
        return Err(HarnessError::input("seeds: need at least one seed index"));
    }
    let metrics = Value::Object(to_json(&file.metrics));
    metric_spec::validate_metric_options(&metrics)?;
    metric_spec::metric_options(&metrics)?
        .mesh
        .validate()
        .map_err(|e| HarnessError::input(format!("[metrics.mesh]: {e}")))?;

    let datasets = expand_datasets(file, base)?;
    let (perturbs, swept_all) = expand_perturbations(file)?;
    // Methods x params.
    let mut methods = Vec::new();
    for (i, m) in file.methods.iter().enumerate() {
        methods.extend(
            expand_method(m).map_err(|e| HarnessError::input(format!("methods[{i}]: {e}")))?,
        );
    }

    let n_cells = [datasets.len(), perturbs.len(), methods.len(), seeds.len()]
        .iter()
        .fold(1u64, |a, &b| a.saturating_mul(b as u64));
    if n_cells > MAX_CELLS {
        return Err(HarnessError::input(format!(
            "the grid has {n_cells} cells ({} datasets x {} perturbations x {} methods x {} seeds); at most {MAX_CELLS}: split the experiment",
            datasets.len(),
            perturbs.len(),
            methods.len(),
            seeds.len()
        )));
    }
    let cells = grid_cells(file, &datasets, &perturbs, &methods, &seeds, &metrics);
    let mut seen = std::collections::HashSet::new();
    for c in &cells {
        if !seen.insert(&c.key) {
            return Err(HarnessError::input(format!(
                "two cells resolve to the same spec ({} / {} / {} seed {}): remove the duplicate",
                c.labels.dataset, c.labels.perturb, c.labels.method, c.spec.seed_index
            )));
        }
    }
    Ok((cells, swept_all))
}

/// One expanded dataset: its label and data spec (without perturbations).
type DatasetConfig = (String, DataSpec);

/// Expands the `[[datasets]]` over their point counts; file paths are resolved against
/// `base` (the experiment file's directory).
fn expand_datasets(file: &ExperimentFile, base: &Path) -> Result<Vec<DatasetConfig>> {
    let mut datasets = Vec::new();
    for (i, d) in file.datasets.iter().enumerate() {
        let at = |e: HarnessError| HarnessError::input(format!("datasets[{i}]: {e}"));
        let (label, base_spec, sampled) = dataset_base(d, base).map_err(at)?;
        let points: Vec<u64> = match (&d.points, sampled) {
            (None, true) => {
                return Err(at(HarnessError::input(
                    "points: required for a sampled input (or use input = \"scan\")",
                )));
            }
            (Some(_), false) => {
                return Err(at(HarnessError::input(
                    "points: not used by this input (its points are the file's or the scanner's); remove it",
                )));
            }
            (None, false) => vec![0],
            (Some(v), true) => parse_points(v).map_err(at)?,
        };
        for &p in &points {
            let label = if points.len() > 1 {
                format!("{label} n={p}")
            } else {
                label.clone()
            };
            let mut spec = base_spec.clone();
            spec.points = p;
            datasets.push((label, spec));
        }
    }
    Ok(datasets)
}

fn parse_points(v: &toml::Value) -> Result<Vec<u64>> {
    let points: Vec<u64> = match v {
        toml::Value::Integer(n) if *n > 0 && (*n as u64) <= MAX_POINTS => vec![*n as u64],
        toml::Value::Array(a) => a
            .iter()
            .map(|v| {
                v.as_integer()
                    .filter(|&n| n > 0 && (n as u64) <= MAX_POINTS)
                    .map(|n| n as u64)
            })
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| {
                HarnessError::input(format!("points: expected integers from 1 to {MAX_POINTS}"))
            })?,
        other => {
            return Err(HarnessError::input(format!(
                "points = {other}: expected an integer from 1 to {MAX_POINTS} (about {:.1} GB of positions at the limit) or a list",
                MAX_POINTS as f64 * 24.0 / 1e9
            )));
        }
    };
    if points.is_empty() {
        return Err(HarnessError::input("points: need at least one count"));
    }
    Ok(points)
}

/// A dataset entry's label and data spec (points unset), and whether it samples (so
/// needs `points`).
fn dataset_base(d: &DatasetEntry, base: &Path) -> Result<(String, DataSpec, bool)> {
    let given: Vec<&str> = [
        ("shape", &d.shape),
        ("real", &d.real),
        ("mesh", &d.mesh),
        ("cloud", &d.cloud),
    ]
    .iter()
    .filter(|(_, v)| v.is_some())
    .map(|(k, _)| *k)
    .collect();
    if given.len() != 1 {
        return Err(HarnessError::input(format!(
            "give exactly one of shape, real, mesh, cloud (got {})",
            if given.is_empty() {
                "none".to_string()
            } else {
                given.join(", ")
            }
        )));
    }
    let file_like = d.shape.is_none();
    let (default_input, allowed): (&str, &[&str]) = if d.shape.is_some() {
        ("sample", &["sample", "scan"])
    } else if d.cloud.is_some() {
        ("file", &["file"])
    } else {
        ("vertices", &["vertices", "sample", "scan"])
    };
    let input = d.input.clone().unwrap_or_else(|| default_input.to_string());
    if !allowed.contains(&input.as_str()) {
        return Err(HarnessError::input(format!(
            "input = '{input}': valid here: {}",
            allowed.join(", ")
        )));
    }
    if d.scan.is_some() && input != "scan" {
        return Err(HarnessError::input("scan: only used with input = \"scan\""));
    }
    if (!file_like || d.cloud.is_some()) && (d.feature_angle_deg.is_some() || d.closed.is_some()) {
        return Err(HarnessError::input(
            "feature_angle_deg and closed describe a mesh ground truth: only for real or mesh",
        ));
    }
    let feature_angle_deg = d
        .feature_angle_deg
        .unwrap_or(reconbench_synth::DEFAULT_MESH_FEATURE_ANGLE_DEG);
    if !(feature_angle_deg.is_finite() && feature_angle_deg > 0.0 && feature_angle_deg < 180.0) {
        return Err(HarnessError::input(format!(
            "feature_angle_deg = {feature_angle_deg}: must be in (0, 180)"
        )));
    }
    let sampler = if input == "vertices" {
        "vertices".to_string()
    } else {
        d.sampler.clone()
    };
    let scan = (input == "scan").then(|| d.scan.clone().unwrap_or_default());
    inputs::validate_data(d.shape.as_deref(), &sampler, scan.as_deref())?;
    let (shape, label, file) = if let Some(shape) = &d.shape {
        (shape.clone(), shape.clone(), None)
    } else if let Some(name) = &d.real {
        let manifest = reconbench_synth::real::Manifest::locate(Some(base))
            .map_err(|e| HarnessError::input(format!("real = '{name}': {e}")))?;
        let set = manifest
            .find(name)
            .map_err(|e| HarnessError::input(e.to_string()))?;
        if set.kind != reconbench_synth::real::RealKind::Mesh {
            return Err(HarnessError::input(format!(
                "real = '{name}' is a point cloud without ground truth: use cloud = \"{}\"",
                manifest.path_of(set).display()
            )));
        }
        let path = manifest.path_of(set);
        let file = FileInput {
            kind: FileKind::Real,
            hash: inputs::file_hash(&path)?,
            path: path.display().to_string(),
            feature_angle_deg,
            closed: Some(d.closed.unwrap_or(set.thesis_closed)),
        };
        (format!("real:{name}"), name.clone(), Some(file))
    } else {
        let (kind, given) = match (&d.mesh, &d.cloud) {
            (Some(m), _) => (FileKind::Mesh, m),
            (None, Some(c)) => (FileKind::Cloud, c),
            (None, None) => return Err(HarnessError::input("no data source")),
        };
        let path = base.join(given);
        if !path.is_file() {
            return Err(HarnessError::input(format!(
                "{} = '{given}': no such file ({})",
                if kind == FileKind::Mesh {
                    "mesh"
                } else {
                    "cloud"
                },
                path.display()
            )));
        }
        let label = Path::new(given)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(given)
            .to_string();
        let file = FileInput {
            kind,
            hash: inputs::file_hash(&path)?,
            path: path.display().to_string(),
            feature_angle_deg,
            closed: if kind == FileKind::Mesh {
                d.closed
            } else {
                None
            },
        };
        let prefix = if kind == FileKind::Mesh {
            "mesh"
        } else {
            "cloud"
        };
        (format!("{prefix}:{given}"), label, Some(file))
    };
    let spec = DataSpec {
        shape,
        sampler: if input == "file" {
            "file".into()
        } else {
            sampler
        },
        points: 0,
        perturb: BTreeMap::new(),
        scan,
        file,
    };
    Ok((d.name.clone().unwrap_or(label), spec, input == "sample"))
}

/// One expanded perturbation setting: label and resolved values.
type PerturbConfig = (String, BTreeMap<String, Value>);

/// Expands the `[[perturbations]]` blocks; also returns the swept keys (plot axes).
fn expand_perturbations(file: &ExperimentFile) -> Result<(Vec<PerturbConfig>, Vec<String>)> {
    let blocks: Vec<toml::Table> = if file.perturbations.is_empty() {
        vec![toml::Table::new()]
    } else {
        file.perturbations.clone()
    };
    let mut perturbs: Vec<(String, BTreeMap<String, Value>)> = Vec::new();
    let mut swept_all: Vec<String> = Vec::new();
    for (i, b) in blocks.iter().enumerate() {
        let mut m = to_json(b);
        let name = match m.remove("name") {
            Some(Value::String(s)) => Some(s),
            Some(other) => {
                return Err(HarnessError::input(format!(
                    "perturbations[{i}].name: expected a string, got {other}"
                )));
            }
            None => None,
        };
        for k in m.keys() {
            inputs::validate_perturb_key(k)
                .map_err(|e| HarnessError::input(format!("perturbations[{i}]: {e}")))?;
        }
        let (combos, swept) = expand_table(&m);
        for s in &swept {
            if !swept_all.contains(s) {
                swept_all.push(s.clone());
            }
        }
        for c in combos {
            let parts: Vec<String> = c
                .iter()
                .filter(|(k, _)| swept.contains(k) || name.is_none())
                .map(|(k, v)| format!("{k}={}", fmt_value(v)))
                .collect();
            let label = match (&name, parts.is_empty()) {
                (Some(n), true) => n.clone(),
                (Some(n), false) => format!("{n} {}", parts.join(" ")),
                (None, true) => "clean".to_string(),
                (None, false) => parts.join(" "),
            };
            let map: BTreeMap<String, Value> = c.into_iter().collect();
            inputs::validate_perturb_values(&map)
                .map_err(|e| HarnessError::input(format!("perturbations[{i}]: {e}")))?;
            perturbs.push((label, map));
        }
    }

    Ok((perturbs, swept_all))
}

/// What a key hashes of a serialized spec: everything but where a data file is (its
/// content hash stays), so a moved checkout keeps its keys.
fn key_view(mut v: Value) -> Value {
    let data = match v.get_mut("data") {
        Some(d) => d,
        None => &mut v,
    };
    if let Some(Value::Object(f)) = data.get_mut("file") {
        f.remove("path");
    }
    v
}

/// The grid: datasets x perturbations x methods x seeds, each cell keyed by its spec.
fn grid_cells(
    file: &ExperimentFile,
    datasets: &[DatasetConfig],
    perturbs: &[PerturbConfig],
    methods: &[MethodConfig],
    seeds: &[u32],
    metrics: &Value,
) -> Vec<Cell> {
    let salt = key_salt();
    let mut cells = Vec::new();
    for (dlabel, base_data) in datasets {
        for (plabel, perturb) in perturbs {
            let data = DataSpec {
                perturb: perturb.clone(),
                ..base_data.clone()
            };
            let data_hash = hash_value(
                &salt,
                &key_view(serde_json::to_value(&data).unwrap_or(Value::Null)),
            );
            for (mlabel, entry, params, pre) in methods {
                for &s in seeds {
                    let spec = CellSpec {
                        data: data.clone(),
                        method: entry.name.to_string(),
                        kind: entry.kind,
                        params: params.clone(),
                        pre: pre.clone(),
                        experiment_seed: file.seed,
                        seed_index: s,
                        metrics: metrics.clone(),
                    };
                    let v = key_view(serde_json::to_value(&spec).unwrap_or(Value::Null));
                    let key = hex_key(hash_value(&salt, &v));
                    let mut cv = v;
                    if let Value::Object(o) = &mut cv {
                        o.remove("seed_index");
                    }
                    let config = hex_key(hash_value(&salt, &cv));
                    cells.push(Cell {
                        index: cells.len(),
                        key,
                        config,
                        data_seed: derive_seed(&[file.seed, data_hash, u64::from(s)]),
                        labels: Labels {
                            dataset: dlabel.clone(),
                            perturb: plabel.clone(),
                            method: mlabel.clone(),
                        },
                        spec,
                    });
                }
            }
        }
    }
    cells
}

/// One expanded method configuration: label, last step, its parameters, earlier steps.
type MethodConfig = (String, &'static MethodEntry, Value, Vec<StepSpec>);

/// Expands one `[[methods]]` entry over its list-valued parameters. A pipeline's steps
/// expand too; their swept parameters are labelled `step.param`.
fn expand_method(m: &MethodSpec) -> Result<Vec<MethodConfig>> {
    let steps: Vec<StepEntry> = match (&m.name, m.steps.is_empty()) {
        (Some(n), true) => vec![StepEntry::Name(n.clone())],
        (None, false) => m.steps.clone(),
        (Some(_), false) => {
            return Err(HarnessError::input(
                "give either 'name' (one method) or 'steps' (a pipeline), not both",
            ));
        }
        (None, true) => {
            return Err(HarnessError::input(
                "missing 'name' (one method) or 'steps' (a pipeline)",
            ));
        }
    };
    let entries: Vec<&'static MethodEntry> = steps
        .iter()
        .enumerate()
        .map(|(j, st)| {
            registry::find(st.name()).map_err(|e| {
                if steps.len() > 1 {
                    HarnessError::input(format!("step {}: {e}", j + 1))
                } else {
                    e
                }
            })
        })
        .collect::<Result<_>>()?;
    pipeline::validate_chain(&entries, false)?;
    if m.label.is_none() && entries.iter().any(|e| e.name.starts_with("external")) {
        return Err(HarnessError::input(
            "an external method needs a 'label' (the name its rows are shown under)",
        ));
    }
    // One table over all steps' parameters: keys `j:name` (step j), the last step's
    // own `params` at the end.
    let last = steps.len() - 1;
    let mut table = Map::new();
    for (j, st) in steps.iter().enumerate() {
        let mut p = to_json(&st.params());
        if j == last {
            p.extend(to_json(&m.params));
        }
        for (k, v) in p {
            table.insert(format!("{j}:{k}"), v);
        }
    }
    let (combos, swept) = expand_table(&table);
    let default_label = steps
        .iter()
        .map(|s| s.name())
        .collect::<Vec<_>>()
        .join(" -> ");
    let mut out = Vec::new();
    for c in combos {
        let mut resolved = Vec::with_capacity(steps.len());
        for (j, e) in entries.iter().enumerate() {
            let prefix = format!("{j}:");
            let own: Map<String, Value> = c
                .iter()
                .filter_map(|(k, v)| k.strip_prefix(&prefix).map(|k| (k.to_string(), v.clone())))
                .collect();
            let r = e.resolve_params(&Value::Object(own)).map_err(|err| {
                if steps.len() > 1 {
                    HarnessError::input(format!("step {} {err}", j + 1))
                } else {
                    err
                }
            })?;
            resolved.push(r);
        }
        let base = m.label.clone().unwrap_or_else(|| default_label.clone());
        let suffix: Vec<String> = swept
            .iter()
            .map(|k| {
                let (j, name) = k.split_once(':').unwrap_or(("0", k));
                let shown = match j.parse::<usize>() {
                    Ok(j) if j != last => format!("{}.{name}", steps[j].name()),
                    _ => name.to_string(),
                };
                format!("{shown}={}", fmt_value(&c[k]))
            })
            .collect();
        let label = if suffix.is_empty() {
            base
        } else {
            format!("{base} {}", suffix.join(" "))
        };
        let params = resolved.pop().unwrap_or(Value::Null);
        let pre = entries[..last]
            .iter()
            .zip(resolved)
            .map(|(e, params)| StepSpec {
                method: e.name.to_string(),
                kind: e.kind,
                params,
            })
            .collect();
        out.push((label, entries[last], params, pre));
    }
    Ok(out)
}

/// Parses a `--shard i/N` (0-based `i < N`).
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || HarnessError::input(format!("--shard '{s}': expected i/N with 0 <= i < N"));
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// The cells of shard `i` of `n`: every `n`-th cell starting at `i` (round robin over the
/// grid order, so expensive methods spread evenly).
pub fn shard_cells(cells: &[Cell], shard: Option<(usize, usize)>) -> Vec<Cell> {
    match shard {
        None => cells.to_vec(),
        Some((i, n)) => cells.iter().filter(|c| c.index % n == i).cloned().collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = r#"
        seed = 7
        seeds = 2
        [[datasets]]
        shape = "sphere"
        points = [100, 200]
        [[perturbations]]
        noise = [0.0, 0.01]
        [[methods]]
        name = "gt-normals"
        [[methods]]
        name = "reference-mesh"
        params = { resolution = [8, 16] }
    "#;

    #[test]
    fn grid_expands_every_list() {
        let e = Experiment::parse(SMALL, "small").unwrap();
        // 2 sizes x 2 noise x (1 + 2) method configs x 2 seeds
        assert_eq!(e.cells.len(), 2 * 2 * 3 * 2);
        assert_eq!(e.swept, vec!["noise".to_string()]);
        let labels: std::collections::BTreeSet<_> =
            e.cells.iter().map(|c| c.labels.method.clone()).collect();
        assert!(labels.contains("reference-mesh resolution=8"), "{labels:?}");
        assert_eq!(e.cells[0].labels.perturb, "noise=0.0");
        // Indices are positions, seeds vary fastest.
        assert!(e.cells.iter().enumerate().all(|(i, c)| c.index == i));
        assert_eq!(e.cells[0].spec.seed_index, 0);
        assert_eq!(e.cells[1].spec.seed_index, 1);
        assert_eq!(e.cells[0].config, e.cells[1].config);
        assert_ne!(e.cells[0].key, e.cells[1].key);
        // All methods of one data configuration see the same data seed.
        assert_eq!(e.cells[0].data_seed, e.cells[2].data_seed);
        assert_ne!(e.cells[0].data_seed, e.cells[1].data_seed);
    }

    #[test]
    fn keys_are_stable_and_ignore_order_and_labels() {
        let a = Experiment::parse(SMALL, "small").unwrap();
        let reordered = r#"
            seeds = 2
            seed = 7
            [[methods]]
            params = { resolution = [8, 16] }
            name = "reference-mesh"
            label = "renamed"
            [[datasets]]
            points = [100, 200]
            shape = "sphere"
            name = "ball"
            [[perturbations]]
            noise = [0.0, 0.01]
        "#;
        let b = Experiment::parse(reordered, "other").unwrap();
        let ka: std::collections::BTreeSet<_> = a.cells.iter().map(|c| c.key.clone()).collect();
        for c in &b.cells {
            assert!(ka.contains(&c.key), "{:?}", c.labels);
        }
        // Frozen key: if this changes, every stored result is invalidated. Update it
        // only together with the harness version.
        let first = &a.cells[0];
        assert_eq!(first.key.len(), 16);
        assert_eq!(
            first.key,
            hex_key(hash_value(
                &key_salt(),
                &serde_json::to_value(&first.spec).unwrap()
            ))
        );
    }

    #[test]
    fn unknown_keys_and_methods_list_the_valid_ones() {
        let err = Experiment::parse("seedz = 1", "x").unwrap_err().to_string();
        assert!(err.contains("seedz") && err.contains("seeds"), "{err}");
        let bad_method = SMALL.replace("gt-normals", "gt-normalz");
        let err = Experiment::parse(&bad_method, "x").unwrap_err().to_string();
        assert!(
            err.contains("gt-normalz") && err.contains("gt-normals"),
            "{err}"
        );
        let bad_param = SMALL.replace("resolution = [8, 16]", "resolutoin = 8");
        let err = Experiment::parse(&bad_param, "x").unwrap_err().to_string();
        assert!(
            err.contains("resolutoin") && err.contains("resolution"),
            "{err}"
        );
        let bad_report = format!("{SMALL}\n[report]\ntabels = [\"md\"]\n");
        let err = Experiment::parse(&bad_report, "x").unwrap_err().to_string();
        assert!(err.contains("tabels") && err.contains("tables"), "{err}");
    }

    #[test]
    fn shards_partition_the_grid() {
        let e = Experiment::parse(SMALL, "small").unwrap();
        let mut all: Vec<usize> = (0..3)
            .flat_map(|i| shard_cells(&e.cells, Some((i, 3))))
            .map(|c| c.index)
            .collect();
        all.sort_unstable();
        assert_eq!(all, (0..e.cells.len()).collect::<Vec<_>>());
        assert!(parse_shard("3/3").is_err());
        assert_eq!(parse_shard("1/4").unwrap(), (1, 4));
    }

    fn real_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/real")
    }

    fn one_dataset(body: &str, base: &Path) -> Result<Experiment> {
        let text = format!("[[datasets]]\n{body}\n[[methods]]\nname = \"gt-normals\"\n");
        Experiment::parse_at(&text, "t", Some(base))
    }

    #[test]
    fn file_datasets_resolve_and_check_their_keys() {
        let base = real_dir();
        let e = one_dataset("real = \"3holes\"", &base).unwrap();
        let d = &e.cells[0].spec.data;
        assert_eq!(d.shape, "real:3holes");
        assert_eq!(d.sampler, "vertices");
        assert_eq!(d.points, 0);
        let f = d.file.as_ref().unwrap();
        assert_eq!(f.kind, FileKind::Real);
        assert_eq!(f.closed, Some(true), "the manifest's thesis_closed");
        assert_eq!(e.cells[0].labels.dataset, "3holes");
        let sampled = one_dataset(
            "real = \"fandisk\"\ninput = \"sample\"\npoints = [100, 200]",
            &base,
        )
        .unwrap();
        assert_eq!(sampled.cells.len(), 2);
        assert_eq!(sampled.cells[1].labels.dataset, "fandisk n=200");
        let cloud = one_dataset("cloud = \"cactus.ply\"", &base).unwrap();
        assert_eq!(cloud.cells[0].spec.data.sampler, "file");
        // Input errors name what is wrong.
        for (body, want) in [
            ("real = \"nope\"", "unknown real data set 'nope'"),
            ("real = \"cactus\"", "point cloud without ground truth"),
            ("shape = \"sphere\"\nreal = \"3holes\"", "exactly one of"),
            ("points = 10", "exactly one of"),
            ("real = \"3holes\"\npoints = 10", "not used by this input"),
            ("real = \"3holes\"\ninput = \"sample\"", "points: required"),
            (
                "real = \"3holes\"\ninput = \"grid\"",
                "valid here: vertices, sample, scan",
            ),
            ("mesh = \"missing.ply\"", "no such file"),
            (
                "shape = \"sphere\"\npoints = 10\nclosed = true",
                "only for real or mesh",
            ),
            (
                "real = \"3holes\"\nfeature_angle_deg = 0",
                "must be in (0, 180)",
            ),
            (
                "real = \"3holes\"\nscan = \"views=2\"",
                "only used with input",
            ),
            (
                "real = \"3holes\"\ninput = \"scan\"\nscan = \"bogus=1\"",
                "scan",
            ),
        ] {
            let e = one_dataset(body, &base).unwrap_err().to_string();
            assert!(e.contains(want), "{body}: {e}");
        }
    }

    #[test]
    fn a_mesh_file_keys_by_content_not_by_path() {
        let src = real_dir().join("3holes.ply");
        let d = tempfile::tempdir().unwrap();
        for sub in ["a", "b"] {
            std::fs::create_dir_all(d.path().join(sub)).unwrap();
            std::fs::copy(&src, d.path().join(sub).join("m.ply")).unwrap();
        }
        let key = |base: &Path| {
            one_dataset("mesh = \"m.ply\"", base).unwrap().cells[0]
                .key
                .clone()
        };
        let (ka, kb) = (key(&d.path().join("a")), key(&d.path().join("b")));
        assert_eq!(ka, kb, "same bytes at another path: same key");
        let mut bytes = std::fs::read(&src).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(d.path().join("b").join("m.ply"), bytes).unwrap();
        assert_ne!(ka, key(&d.path().join("b")), "changed bytes: new key");
    }

    #[test]
    fn out_of_range_requests_are_refused_when_the_file_loads() {
        let base = "[[methods]]\nname = \"gt-normals\"\n";
        let data = "[[datasets]]\nshape = \"sphere\"\npoints = 10\n";
        for (text, want) in [
            (
                format!("{base}[[datasets]]\nshape = \"sphere\"\npoints = -100\n"),
                "points",
            ),
            (
                format!("{base}[[datasets]]\nshape = \"sphere\"\npoints = 1e12\n"),
                "expected an integer",
            ),
            (
                format!("{base}[[datasets]]\nshape = \"sphere\"\npoints = 9223372036854775807\n"),
                "points",
            ),
            (
                format!("{base}[[datasets]]\nshape = \"sphere\"\npoints = [10, 0]\n"),
                "from 1 to",
            ),
            (format!("seeds = 10000000\n{base}{data}"), "at most 1000000"),
            (
                format!(
                    "{base}[[datasets]]\nshape = \"sphere\"\npoints = 10\nsampler = \"grid:nu=1000000,nv=1000000\"\n"
                ),
                "1000000 x 1000000 grid",
            ),
            (
                format!("{base}{data}[[perturbations]]\nduplicate = 1e9\n"),
                "points added per input point",
            ),
            (
                format!("{base}{data}[metrics.mesh.distance]\nmin_samples = 100000000000\n"),
                "distance.min_samples",
            ),
            (
                format!("{data}[[methods]]\nname = \"pf\"\nparams = {{ k = 1000000000000 }}\n"),
                "neighbours per point",
            ),
            (format!("timeout = 1e300\n{base}{data}"), "a week"),
            (
                format!("memory_limit_mib = 0\n{base}{data}"),
                "below 16 MiB",
            ),
            (
                format!("name = \"..\"\n{base}{data}"),
                "not starting with '.'",
            ),
            (
                format!("name = \".\"\n{base}{data}"),
                "not starting with '.'",
            ),
            (
                format!("{base}{data}[[expect]]\nmetric = \"x\"\nvalue = 1\ntol = \"rel:abc\"\n"),
                "expect[0].tol",
            ),
            (
                format!(
                    "{base}{data}[[expect]]\nwhere = {{ methd = \"x\" }}\nmetric = \"hausdorff\"\nvalue = 1\n"
                ),
                "unknown selector key 'methd'",
            ),
        ] {
            let e = Experiment::parse(&text, "t").unwrap_err().to_string();
            assert!(e.contains(want), "{text}\n{e}");
        }
        // A big but honest grid is accepted; one past the limit is not.
        let many =
            format!("seeds = 1000\n{base}[[datasets]]\nshape = \"sphere\"\npoints = [10, 20]\n");
        assert_eq!(Experiment::parse(&many, "t").unwrap().cells.len(), 2000);
    }
}
