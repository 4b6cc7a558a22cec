//! The results store: one JSON line per finished cell, appended atomically.
//!
//! A line is built in memory and written with a single `write_all` on a file opened
//! for appending, then flushed to disk (`sync_data`). A process killed mid-write (even
//! with `kill -9`) can leave at most a trailing fragment without its `'\n'`; readers
//! ignore such a fragment, and the next append first terminates it, so it never merges
//! with a good line.
//!
//! Everything machine-dependent (wall and CPU time, phases, memory) lives in the `cost`
//! sub-object, so two runs with the same seed give identical rows apart from `cost`.

use std::collections::BTreeMap;
use std::fs::OpenOptions;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{HarnessError, Result};
use crate::experiment::{Cell, CellSpec, Labels};

/// Outcome of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Finished, metrics computed.
    Ok,
    /// The method (or data generation, or a metric) returned an error.
    Error,
    /// The worker panicked.
    Panic,
    /// The worker died from a signal (abort, segfault, external kill) or exited oddly.
    Crash,
    /// The worker exceeded the per-cell timeout and was killed.
    Timeout,
    /// The worker exceeded the memory limit (killed) or failed to allocate.
    Oom,
}

impl Status {
    /// Stable name.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Error => "error",
            Status::Panic => "panic",
            Status::Crash => "crash",
            Status::Timeout => "timeout",
            Status::Oom => "oom",
        }
    }
}

/// Quartile summary of a per-point error distribution (for box plots).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dist {
    /// What the values are, e.g. `normal angle (deg)`.
    pub what: String,
    /// Number of values.
    pub n: usize,
    /// Minimum.
    pub min: f64,
    /// First quartile.
    pub q1: f64,
    /// Median.
    pub median: f64,
    /// Third quartile.
    pub q3: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Maximum.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Dist {
    /// Summary of `values` (non-finite values dropped); `None` when empty.
    pub fn of(what: &str, values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| {
            let pos = p * (v.len() - 1) as f64;
            let lo = pos.floor() as usize;
            let hi = pos.ceil() as usize;
            v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
        };
        Some(Self {
            what: what.to_string(),
            n: v.len(),
            min: v[0],
            q1: q(0.25),
            median: q(0.5),
            q3: q(0.75),
            p95: q(0.95),
            max: v[v.len() - 1],
            mean: v.iter().sum::<f64>() / v.len() as f64,
        })
    }
}

/// Machine-dependent measurements of a cell (excluded from comparisons).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Wall time of the whole worker as seen by the runner, seconds.
    pub wall_s: f64,
    /// Wall time of the method call, seconds.
    pub method_s: f64,
    /// Wall time of data generation, seconds.
    pub generate_s: f64,
    /// Wall time of the metrics, seconds.
    pub metrics_s: f64,
    /// CPU time (user + system) of the worker, seconds.
    pub cpu_s: f64,
    /// Peak resident memory of the worker, MiB.
    pub peak_rss_mib: f64,
    /// Per-phase times reported by the method (a pipeline's earlier steps prefixed
    /// `step/`).
    pub phases: Vec<(String, f64)>,
    /// Wall time of each step of a pipeline, in order (left out for a single method).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub steps: Vec<(String, f64)>,
    /// The method's own timing diagnostics (see [`is_timing`]), kept here rather than
    /// in `diagnostics` so that rows compare byte for byte apart from `cost`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub timings: BTreeMap<String, f64>,
}

/// Whether a diagnostic is a timing (machine-dependent): its name, after any pipeline
/// step prefix `step/`, is `seconds` or ends in `_s` or `_per_second`.
pub fn is_timing(name: &str) -> bool {
    let last = name.rsplit('/').next().unwrap_or(name);
    last == "seconds" || last.ends_with("_s") || last.ends_with("_per_second")
}

/// One result line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Cell key.
    pub key: String,
    /// Configuration key (cell key without the seed index).
    pub config: String,
    /// Grid index.
    pub index: usize,
    /// Labels.
    pub labels: Labels,
    /// The resolved spec.
    pub spec: CellSpec,
    /// Outcome.
    pub status: Status,
    /// Reason when not ok.
    #[serde(default)]
    pub error: Option<String>,
    /// Metrics by stable key (finite values only).
    #[serde(default)]
    pub metrics: BTreeMap<String, f64>,
    /// Method diagnostics.
    #[serde(default)]
    pub diagnostics: BTreeMap<String, Value>,
    /// Per-point error distribution.
    #[serde(default)]
    pub dist: Option<Dist>,
    /// Relative path of the render data file (`renders/<key>.rbr`), if one was written;
    /// the report draws the images from it.
    #[serde(default)]
    pub render: Option<String>,
    /// Machine-dependent measurements.
    #[serde(default)]
    pub cost: Cost,
}

impl Row {
    /// A row for `cell` with the given outcome and nothing measured.
    pub fn failed(cell: &Cell, status: Status, reason: impl Into<String>) -> Self {
        Self {
            key: cell.key.clone(),
            config: cell.config.clone(),
            index: cell.index,
            labels: cell.labels.clone(),
            spec: cell.spec.clone(),
            status,
            error: Some(reason.into()),
            metrics: BTreeMap::new(),
            diagnostics: BTreeMap::new(),
            dist: None,
            render: None,
            cost: Cost::default(),
        }
    }

    /// The row as one JSON line (with its `'\n'`).
    pub fn to_line(&self) -> Result<String> {
        let mut s = serde_json::to_string(self)
            .map_err(|e| HarnessError::failure(format!("cannot serialise row: {e}")))?;
        s.push('\n');
        Ok(s)
    }
}

/// Appends rows to a JSON-lines file.
#[derive(Debug)]
pub struct Store {
    path: PathBuf,
    file: std::fs::File,
}

impl Store {
    /// Opens (creating) `path` for appending. A trailing fragment left by a killed
    /// writer is terminated with `'\n'` so that later lines stay whole.
    pub fn open(path: &Path) -> Result<Self> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            crate::error::create_dir_all(dir)?;
        }
        let mut file = OpenOptions::new()
            .create(true)
            .append(true)
            .read(true)
            .open(path)
            .map_err(|e| HarnessError::io(path, e))?;
        let len = file
            .metadata()
            .map_err(|e| HarnessError::io(path, e))?
            .len();
        if len > 0 {
            let mut last = [0u8; 1];
            file.seek(SeekFrom::Start(len - 1))
                .map_err(|e| HarnessError::io(path, e))?;
            file.read_exact(&mut last)
                .map_err(|e| HarnessError::io(path, e))?;
            if last[0] != b'\n' {
                file.write_all(b"\n")
                    .map_err(|e| HarnessError::io(path, e))?;
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            file,
        })
    }

    /// Appends one row: one `write_all` of the whole line, then `sync_data`.
    pub fn append(&mut self, row: &Row) -> Result<()> {
        let line = row.to_line()?;
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.sync_data())
            .map_err(|e| HarnessError::io(&self.path, e))
    }
}

/// Reads rows; skips blank lines and a trailing line without `'\n'` (a write cut short)
/// or any line that does not parse (reported in the second value, with line numbers).
pub fn read_rows(path: &Path) -> Result<(Vec<Row>, Vec<String>)> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), Vec::new())),
        Err(e) => return Err(HarnessError::io(path, e)),
    };
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let complete = if text.ends_with('\n') {
        text.as_str()
    } else {
        &text[..text.rfind('\n').map_or(0, |i| i + 1)]
    };
    if complete.len() < text.len() {
        skipped.push(format!(
            "{}: ignored a trailing partial line",
            path.display()
        ));
    }
    for (i, line) in complete.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Row>(line) {
            Ok(r) => rows.push(r),
            Err(e) => skipped.push(format!(
                "{}:{}: ignored a bad line ({e})",
                path.display(),
                i + 1
            )),
        }
    }
    Ok((rows, skipped))
}

/// Keeps the last row of each key, sorted by grid index then key.
pub fn dedupe_sorted(rows: Vec<Row>) -> Vec<Row> {
    let mut by_key: BTreeMap<String, Row> = BTreeMap::new();
    for r in rows {
        by_key.insert(r.key.clone(), r);
    }
    let mut out: Vec<Row> = by_key.into_values().collect();
    out.sort_by(|a, b| a.index.cmp(&b.index).then_with(|| a.key.cmp(&b.key)));
    out
}

/// Rewrites `path` atomically with `rows` (one line each).
pub fn write_rows(path: &Path, rows: &[Row]) -> Result<()> {
    let mut text = String::new();
    for r in rows {
        text.push_str(&r.to_line()?);
    }
    crate::error::write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows are re-read through serde_json: every float must come back bit for bit, or
    /// `merge` and `--resume` would change values by an ulp (the `float_roundtrip`
    /// feature; the default parser is off by one ulp on some inputs).
    #[test]
    fn floats_round_trip_bit_for_bit() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if !v.is_finite() {
                continue;
            }
            let text = serde_json::to_string(&v).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v:e} written as {text}");
        }
    }
    use crate::experiment::Experiment;

    fn cells() -> Vec<Cell> {
        Experiment::parse(
            "seeds = 3\n[[datasets]]\nshape = \"sphere\"\npoints = 10\n[[methods]]\nname = \"gt-normals\"\n",
            "t",
        )
        .unwrap()
        .cells
    }

    #[test]
    fn partial_trailing_line_is_ignored_and_terminated() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("results.jsonl");
        let cells = cells();
        let mut s = Store::open(&path).unwrap();
        s.append(&Row::failed(&cells[0], Status::Error, "x"))
            .unwrap();
        drop(s);
        // Simulate a writer killed mid-line.
        let line = Row::failed(&cells[1], Status::Error, "y")
            .to_line()
            .unwrap();
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(&line.as_bytes()[..line.len() / 2]).unwrap();
        drop(f);
        let (rows, skipped) = read_rows(&path).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(skipped.len(), 1);
        let mut s = Store::open(&path).unwrap();
        s.append(&Row::failed(&cells[2], Status::Ok, "z")).unwrap();
        let (rows, skipped) = read_rows(&path).unwrap();
        assert_eq!(rows.iter().map(|r| r.index).collect::<Vec<_>>(), vec![0, 2]);
        assert_eq!(skipped.len(), 1, "{skipped:?}");
    }

    #[test]
    fn dist_quartiles() {
        let d = Dist::of("normal angle (deg)", &[4.0, 1.0, 3.0, 2.0, 5.0, f64::NAN]).unwrap();
        assert_eq!(
            (d.n, d.min, d.q1, d.median, d.q3, d.max),
            (5, 1.0, 2.0, 3.0, 4.0, 5.0)
        );
        assert_eq!(d.mean, 3.0);
        let json = serde_json::to_string(&d).unwrap();
        let back: Dist = serde_json::from_str(&json).unwrap();
        assert_eq!(back, d);
    }
}
