//! `results/<experiment>/report.md` and everything it links: tables, plots, renders,
//! published figures.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::aggregate::{Group, aggregate};
use crate::compare::Tol;
use crate::error::{HarnessError, Result};
use crate::experiment::{Expect, Experiment, ReportOptions};
use crate::inputs::FileKind;
use crate::plots::{BoxEntry, BoxPlot, LinePlot, Plot, Series, loglog_slope};
use crate::registry::MethodKind;
use crate::render::{Panel, RenderData, Scale, render_comparison};
use crate::runner::Manifest;
use crate::store::{Row, Status, read_rows};
use crate::tables::{self, TIME_COLUMN, fmt_num};

/// A published figure next to its reproduction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExpectResult {
    /// Selector as text.
    pub selector: String,
    /// Metric.
    pub metric: String,
    /// Published value.
    pub published: f64,
    /// Reproduced value (mean over the matching configurations' means), if any matched.
    pub reproduced: Option<f64>,
    /// `reproduced / published`.
    pub ratio: Option<f64>,
    /// Configurations that matched.
    pub matched: usize,
    /// The matched configurations as `dataset / method` labels (numerator side).
    #[serde(default)]
    pub cells: Vec<String>,
    /// Source of the published value.
    pub source: String,
    /// Tolerance.
    pub tol: String,
    /// Within tolerance.
    pub pass: bool,
    /// Why it may miss (the expectation's `note`).
    #[serde(default)]
    pub note: String,
}

/// What `write_report` produced.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportOutput {
    /// `report.md`.
    pub report: PathBuf,
    /// Table files.
    pub tables: Vec<PathBuf>,
    /// Plot files.
    pub plots: Vec<PathBuf>,
    /// Render images (one per configuration).
    #[serde(default)]
    pub renders: Vec<PathBuf>,
    /// Published-figure checks.
    pub expect: Vec<ExpectResult>,
    /// Rows used.
    pub rows: usize,
    /// Rows not ok.
    pub failed: usize,
}

impl ReportOutput {
    /// Expectations outside their tolerance.
    pub fn misses(&self) -> usize {
        self.expect.iter().filter(|e| !e.pass).count()
    }
}

/// Loads the rows of a results directory (or a results file) and the experiment recorded
/// in its manifest, if it still parses.
pub fn load_results(path: &Path) -> Result<(Vec<Row>, Option<Experiment>, Option<Manifest>)> {
    let (file, dir) = if path.is_dir() {
        (path.join("results.jsonl"), path.to_path_buf())
    } else {
        (
            path.to_path_buf(),
            path.parent().map(Path::to_path_buf).unwrap_or_default(),
        )
    };
    if !file.exists() {
        return Err(HarnessError::input(format!(
            "{}: no results (run the experiment first, or merge shard results)",
            file.display()
        )));
    }
    let (rows, _) = read_rows(&file)?;
    let manifest: Option<Manifest> = std::fs::read_to_string(dir.join("manifest.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let exp = manifest
        .as_ref()
        .and_then(|m| m.file_text.as_ref().map(|t| (t, m.experiment.clone())))
        .and_then(|(t, name)| Experiment::parse(t, &name).ok());
    Ok((rows, exp, manifest))
}

/// Input size of a group: the spec's point count, or for data read from a file the
/// measured `input_points`.
fn group_points(g: &Group) -> u64 {
    g.metrics
        .get("input_points")
        .map_or(g.data.points, |s| s.mean.round() as u64)
}

fn slug(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() || c == '.' {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_matches('-').to_string()
}

fn value_matches(want: &toml::Value, have: &Value) -> bool {
    match (want, have) {
        (toml::Value::String(a), Value::String(b)) => a == b,
        (toml::Value::Integer(a), v) => v
            .as_f64()
            .is_some_and(|b| (*a as f64 - b).abs() <= 1e-12 * b.abs().max(1.0)),
        (toml::Value::Float(a), v) => v
            .as_f64()
            .is_some_and(|b| (a - b).abs() <= 1e-12 * b.abs().max(1.0)),
        (toml::Value::Boolean(a), Value::Bool(b)) => a == b,
        _ => false,
    }
}

fn group_matches(g: &Group, sel: &toml::Table) -> bool {
    sel.iter().all(|(k, want)| match k.as_str() {
        "dataset" => want.as_str() == Some(g.labels.dataset.as_str()),
        "perturbation" => want.as_str() == Some(g.labels.perturb.as_str()),
        "method" => want
            .as_str()
            .is_some_and(|w| w == g.labels.method || w == g.method),
        "shape" => want.as_str() == Some(g.data.shape.as_str()),
        "points" => value_matches(want, &Value::from(group_points(g))),
        k => {
            if let Some(p) = k.strip_prefix("params.") {
                g.params.get(p).is_some_and(|v| value_matches(want, v))
            } else {
                // A perturbation key; absent means 0 (no perturbation).
                let v = g.data.perturb.get(k).cloned().unwrap_or(Value::from(0.0));
                value_matches(want, &v)
            }
        }
    })
}

/// The per-configuration means of `metric` (or `time`, `cost.NAME`) of the groups a
/// selector picks.
fn selected_values(groups: &[Group], sel: &toml::Table, metric: &str) -> Vec<f64> {
    groups
        .iter()
        .filter(|g| group_matches(g, sel))
        .filter_map(|g| {
            let stat = match (metric, metric.strip_prefix("cost.")) {
                ("time", _) => g.cost.get("method_s"),
                (_, Some(c)) => g.cost.get(c),
                _ => g.metrics.get(metric),
            };
            stat.map(|s| s.mean)
        })
        .collect()
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn selector_text(sel: &toml::Table) -> String {
    sel.iter()
        .map(|(k, v)| {
            format!(
                "{k}={}",
                v.as_str().map_or_else(|| v.to_string(), str::to_string)
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Evaluates `[[expect]]` entries against aggregated groups.
pub fn check_expectations(expect: &[Expect], groups: &[Group]) -> Result<Vec<ExpectResult>> {
    let mut out = Vec::new();
    for e in expect {
        let tol = Tol::parse(&e.tol)?;
        let vals = selected_values(groups, &e.select, &e.metric);
        let cells: Vec<String> = groups
            .iter()
            .filter(|g| group_matches(g, &e.select))
            .map(|g| format!("{} / {}", g.labels.dataset, g.labels.method))
            .collect();
        let mut reproduced = mean(&vals);
        if let Some(over) = &e.over {
            let den = mean(&selected_values(groups, over, &e.metric));
            reproduced = match (reproduced, den) {
                (Some(n), Some(d)) if d != 0.0 => Some(n / d),
                _ => None,
            };
        }
        let ratio = reproduced.and_then(|r| (e.value != 0.0).then(|| r / e.value));
        let mut selector = selector_text(&e.select);
        if let Some(over) = &e.over {
            selector = format!("({selector}) over ({})", selector_text(over));
        }
        out.push(ExpectResult {
            selector,
            metric: e.metric.clone(),
            published: e.value,
            reproduced,
            ratio,
            matched: vals.len(),
            cells,
            source: e.source.clone(),
            tol: tol.to_string(),
            pass: reproduced.is_some_and(|r| tol.within(e.value, r)),
            note: e.note.clone(),
        });
    }
    Ok(out)
}

fn kind_title(k: MethodKind) -> &'static str {
    match k {
        MethodKind::Normals => "Normal estimation",
        MethodKind::Features => "Sharp features",
        MethodKind::Filter => "Filters (cloud in, cloud out)",
        MethodKind::Reconstruct => "Reconstruction",
    }
}

/// Writes tables, plots and `report.md` into `dir` from `rows`. `exp` supplies report
/// options and expectations (defaults without it).
pub fn write_report(
    dir: &Path,
    rows: &[Row],
    exp: Option<&Experiment>,
    manifest: Option<&Manifest>,
) -> Result<ReportOutput> {
    let default_opts = ReportOptions::default();
    let opts = exp.map_or(&default_opts, |e| &e.file.report);
    // Only rows of the current grid, when the experiment is known.
    let rows: Vec<Row> = match exp {
        Some(e) => {
            let keys: BTreeSet<&str> = e.cells.iter().map(|c| c.key.as_str()).collect();
            rows.iter()
                .filter(|r| keys.contains(r.key.as_str()))
                .cloned()
                .collect()
        }
        None => rows.to_vec(),
    };
    let groups = aggregate(&rows);
    let name = exp.map_or_else(
        || manifest.map_or_else(|| "experiment".to_string(), |m| m.experiment.clone()),
        |e| e.name.clone(),
    );
    let failed: Vec<&Row> = rows.iter().filter(|r| r.status != Status::Ok).collect();
    let mut md = String::new();
    write_header(&mut md, &name, exp, manifest, rows.len(), failed.len());

    let expect = match exp {
        Some(e) => check_expectations(&e.file.expect, &groups)?,
        None => Vec::new(),
    };
    write_data(&mut md, &groups);
    write_expectations(&mut md, &expect, &groups);

    let mut table_files = Vec::new();
    for t in &tables::build(&groups, &opts.metrics) {
        table_files.extend(write_kind_section(
            &mut md, dir, t, &groups, opts, &name, exp,
        )?);
    }
    let plot_files = list_files(&dir.join("plots"));
    let render_files = write_renders(&mut md, dir, &rows, opts)?;
    write_failed(&mut md, &failed);

    let report = dir.join("report.md");
    crate::error::write_atomic(&report, md.as_bytes())?;
    Ok(ReportOutput {
        report,
        tables: table_files,
        plots: plot_files,
        renders: render_files,
        expect,
        rows: rows.len(),
        failed: failed.len(),
    })
}

/// Title, description, cell counts and the provenance line of the last run.
fn write_header(
    md: &mut String,
    name: &str,
    exp: Option<&Experiment>,
    manifest: Option<&Manifest>,
    rows: usize,
    failed: usize,
) {
    let _ = writeln!(md, "# {name}\n");
    if let Some(e) = exp
        && !e.file.description.is_empty()
    {
        let _ = writeln!(md, "{}\n", e.file.description.trim());
    }
    let _ = writeln!(
        md,
        "{} cells, {} ok, {} failed. Raw rows: [results.jsonl](results.jsonl); provenance and the resolved grid: [manifest.json](manifest.json).\n",
        rows,
        rows - failed,
        failed
    );
    if let Some(run) = manifest.and_then(|m| m.runs.last()) {
        let _ = writeln!(
            md,
            "Run {} on `{}` ({} CPUs), commit `{}`{}, {}; {} workers x {} thread(s).\n",
            run.started,
            run.cpu_model,
            run.cpus,
            run.git_commit.chars().take(12).collect::<String>(),
            if run.git_dirty == Some(true) {
                " (dirty)"
            } else {
                ""
            },
            run.rustc,
            manifest.map_or(0, |m| m.jobs),
            manifest.map_or(1, |m| m.threads_per_worker),
        );
    }
}

/// The published figures next to the reproduced ones.
fn write_expectations(md: &mut String, expect: &[ExpectResult], groups: &[Group]) {
    if expect.is_empty() {
        return;
    }
    let misses = expect.iter().filter(|e| !e.pass).count();
    let _ = writeln!(
        md,
        "## Published figures\n\n{} of {} within tolerance.\n",
        expect.len() - misses,
        expect.len()
    );
    write_expectation_pivot(md, expect, groups);
    md.push_str("| cells | metric | published | reproduced | ratio | tolerance | source | |\n|---|---|---:|---:|---:|---|---|---|\n");
    for e in expect {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            e.selector,
            e.metric,
            fmt_num(e.published),
            e.reproduced.map_or("no match".into(), fmt_num),
            e.ratio.map_or("–".into(), fmt_num),
            e.tol,
            e.source,
            if e.pass { "ok" } else { "**MISS**" }
        );
    }
    md.push('\n');
    if misses == 0 {
        return;
    }
    // Grouped by explanation, so that one cause shared by many rows is said once.
    let mut by_note: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    for e in expect.iter().filter(|e| !e.pass) {
        by_note
            .entry(e.note.trim())
            .or_default()
            .push(format!("{} / {}", e.selector, e.metric));
    }
    md.push_str("Why the misses:\n\n");
    for (note, cells) in by_note {
        let why = if note.is_empty() {
            "**unexplained** (no `note` in the experiment file)"
        } else {
            note
        };
        let _ = writeln!(md, "- {why} ({}: {})", cells.len(), cells.join("; "));
    }
    md.push('\n');
}

/// The published figures that each concern one configuration, one row per configuration
/// and one column per metric: `reproduced (published)`, a miss in bold. Left out when no
/// configuration has two or more of them (the list below says it all then).
fn write_expectation_pivot(md: &mut String, expect: &[ExpectResult], groups: &[Group]) {
    let single: Vec<&ExpectResult> = expect
        .iter()
        .filter(|e| e.cells.len() == 1 && !e.selector.contains(" over "))
        .collect();
    let mut rows: Vec<&str> = Vec::new();
    let mut cols: Vec<&str> = Vec::new();
    for e in &single {
        if !rows.contains(&e.cells[0].as_str()) {
            rows.push(&e.cells[0]);
        }
        if !cols.contains(&e.metric.as_str()) {
            cols.push(&e.metric);
        }
    }
    if rows.len() == single.len() {
        return;
    }
    md.push_str("Reproduced (published); a miss in bold:\n\n| configuration |");
    for c in &cols {
        let _ = write!(md, " {c} |");
    }
    md.push_str(" time (s) |\n|---|");
    md.push_str(&"---:|".repeat(cols.len() + 1));
    md.push('\n');
    for r in &rows {
        let _ = write!(md, "| {r} |");
        for c in &cols {
            let cell = single
                .iter()
                .find(|e| e.cells[0] == *r && e.metric == *c)
                .map_or_else(String::new, |e| {
                    let text = format!(
                        "{} ({})",
                        e.reproduced.map_or("–".into(), fmt_num),
                        fmt_num(e.published)
                    );
                    if e.pass { text } else { format!("**{text}**") }
                });
            let _ = write!(md, " {cell} |");
        }
        let time = groups
            .iter()
            .find(|g| format!("{} / {}", g.labels.dataset, g.labels.method) == *r)
            .and_then(|g| g.cost.get("method_s"))
            .map_or("–".into(), |s| fmt_num(s.mean));
        let _ = writeln!(md, " {time} |");
    }
    md.push_str("\nEvery figure with its source and tolerance:\n\n");
}

/// The data of an experiment that reads files: per dataset its source, input, size and
/// ground truth (nothing for purely analytic experiments, whose specs say it all).
fn write_data(md: &mut String, groups: &[Group]) {
    if groups.iter().all(|g| g.data.file.is_none()) {
        return;
    }
    let mut seen = BTreeSet::new();
    let mut lines = Vec::new();
    let mut without_gt = Vec::new();
    for g in groups {
        if !seen.insert(g.labels.dataset.clone()) {
            continue;
        }
        let (source, truth) = match &g.data.file {
            None => (
                format!("shape `{}`", g.data.shape),
                "analytic shape".to_string(),
            ),
            Some(f) => {
                let file = Path::new(&f.path)
                    .file_name()
                    .map_or_else(|| f.path.clone(), |n| n.to_string_lossy().into_owned());
                let truth = match (f.kind, f.closed) {
                    (FileKind::Cloud, _) => {
                        without_gt.push(g.labels.dataset.clone());
                        "none".to_string()
                    }
                    (_, Some(c)) => format!(
                        "the mesh (sharp edges >= {} deg; closed declared {c})",
                        f.feature_angle_deg
                    ),
                    (_, None) => format!("the mesh (sharp edges >= {} deg)", f.feature_angle_deg),
                };
                (
                    format!("{} `{file}`", g.data.shape.split(':').next().unwrap_or("")),
                    truth,
                )
            }
        };
        let input = match (&g.data.scan, g.data.sampler.as_str()) {
            (Some(s), _) => format!("scan `{s}`"),
            (None, "vertices") => "mesh vertices".into(),
            (None, "file") => "the file's points".into(),
            (None, s) => format!("sampler `{s}`"),
        };
        lines.push(format!(
            "| {} | {source} | {input} | {} | {truth} |",
            g.labels.dataset,
            group_points(g)
        ));
    }
    md.push_str(
        "## Data\n\n| dataset | source | input | points | ground truth |\n|---|---|---|---:|---|\n",
    );
    for l in lines {
        md.push_str(&l);
        md.push('\n');
    }
    md.push('\n');
    if !without_gt.is_empty() {
        let _ = writeln!(
            md,
            "{} {} no ground truth: the metrics that need the true surface (distances, normal and feature errors, Delta F, topology_ok) are absent there (–), not zero; topology, triangle quality, time and memory are measured.\n",
            without_gt.join(", "),
            if without_gt.len() == 1 { "has" } else { "have" }
        );
    }
}

/// One method kind's section: its table (and table files) and plots. Returns the table
/// files written.
fn write_kind_section(
    md: &mut String,
    dir: &Path,
    t: &tables::Table,
    groups: &[Group],
    opts: &ReportOptions,
    name: &str,
    exp: Option<&Experiment>,
) -> Result<Vec<PathBuf>> {
    let tables_dir = dir.join("tables");
    let mut table_files = Vec::new();
    let stem = t.kind.as_str();
    let _ = writeln!(md, "## {}\n", kind_title(t.kind));
    md.push_str("Mean ± std over seeds; best of each dataset and perturbation in bold; ↑ higher is better, ↓ lower is better; oracles (handed the ground truth: the floor or ceiling a method can reach) last in each block, in italics and never bold; no bold in a column where a method of the block has no value (–).\n\n");
    md.push_str(&tables::markdown(t));
    let mut links = Vec::new();
    for fmt in &opts.tables {
        let (text, ext) = match fmt.as_str() {
            "md" => (tables::markdown(t), "md"),
            "tex" => (
                tables::latex(t, &format!("{name}: {}", kind_title(t.kind))),
                "tex",
            ),
            _ => (tables::csv(t), "csv"),
        };
        let p = tables_dir.join(format!("{stem}.{ext}"));
        crate::error::write_atomic(&p, text.as_bytes())?;
        links.push(format!("[{ext}](tables/{stem}.{ext})"));
        table_files.push(p);
    }
    if !links.is_empty() {
        let _ = writeln!(md, "\nTable files: {}.\n", links.join(", "));
    }
    if opts.plots {
        let plots = kind_plots(
            t.kind,
            groups,
            &t.columns,
            opts,
            exp.map_or(&[][..], |e| &e.swept[..]),
        );
        for (file, caption, plot) in plots {
            let stem_path = dir.join("plots").join(&file);
            crate::plots::write(&plot, &stem_path, (opts.plot_size[0], opts.plot_size[1]))?;
            let _ = writeln!(
                md,
                "![{caption}](plots/{file}.png)\n\n*{caption}* ([svg](plots/{file}.svg))\n"
            );
        }
    }
    Ok(table_files)
}

/// The renders: one image per configuration (dataset x perturbation) with the
/// reconstruction methods side by side, drawn from the render data the workers stored
/// (`renders/<key>.rbr`), all on one colour scale: the experiment's `render_max` when
/// given, else [`Scale::robust`] over every mesh of the report. Rows of an older
/// version (a per-cell PNG, no data file) or whose file is gone are left out with a
/// note; nothing here fails the report but a file that cannot be written.
fn write_renders(
    md: &mut String,
    dir: &Path,
    rows: &[Row],
    opts: &ReportOptions,
) -> Result<Vec<PathBuf>> {
    let recon: Vec<&Row> = rows
        .iter()
        .filter(|r| r.spec.kind == MethodKind::Reconstruct)
        .collect();
    if !opts.renders || recon.is_empty() {
        return Ok(Vec::new());
    }
    md.push_str("## Renders\n\n");
    let Some(seed) = recon
        .iter()
        .filter(|r| r.render.is_some())
        .map(|r| r.spec.seed_index)
        .min()
    else {
        md.push_str("No reconstruction of this run has render data (every one failed, or the run had `renders = false`).\n\n");
        return Ok(Vec::new());
    };
    let shown: Vec<&Row> = recon
        .iter()
        .copied()
        .filter(|r| r.spec.seed_index == seed)
        .collect();
    let mut notes = Vec::new();
    let mut data: BTreeMap<&str, RenderData> = BTreeMap::new();
    let mut old_format = 0;
    for r in &shown {
        let Some(rel) = r.render.as_deref() else {
            continue;
        };
        if !rel.ends_with(".rbr") {
            old_format += 1;
            continue;
        }
        match RenderData::load(&dir.join(rel)) {
            Ok(d) => {
                data.insert(r.key.as_str(), d);
            }
            Err(e) => notes.push(format!(
                "{} / {} / {}: {e}",
                r.labels.dataset, r.labels.perturb, r.labels.method
            )),
        }
    }
    if old_format > 0 {
        notes.push(format!(
            "{old_format} rows name a render of an older version (a PNG on a fixed scale, without the data to redraw it); rerun the experiment (`--fresh`) to draw them"
        ));
    }
    if data.is_empty() {
        let _ = writeln!(md, "No render data to draw:\n");
        for n in &notes {
            let _ = writeln!(md, "- {n}");
        }
        md.push('\n');
        return Ok(Vec::new());
    }
    let meshes: Vec<&RenderData> = data.values().collect();
    let scale = opts
        .render_max
        .map_or_else(|| Scale::robust(&meshes), Scale::fixed);
    let how = match (opts.render_max, scale.percentile_95) {
        (Some(_), _) => "fixed by the experiment (`report.render_max`)".to_string(),
        (None, Some(p)) => format!(
            "the 95th percentile ({}) of the distances of all {} meshes below, each mesh weighted equally, rounded up; larger distances get the top colour",
            fmt_num(p),
            meshes.len()
        ),
        (None, None) => "a default (no mesh has a measured distance)".to_string(),
    };
    let _ = writeln!(
        md,
        "Seed index {seed}, one image per configuration, one column per method, each seen from the front, the side and the top (z up). Colour: distance of the mesh to the true surface (fraction of the bounding-box diagonal), one scale for the whole report, 0 to {} ({how}). Red lines: boundary edges (holes, open rims); magenta: faces that intersect another face or sit on an edge of three or more faces. Each heading gives the method's Hausdorff distance and its numbers of boundary edges, self-intersecting face pairs and non-manifold edges.\n",
        scale.label(scale.max)
    );
    let mut groups: Vec<((&str, &str), Vec<&Row>)> = Vec::new();
    for r in &shown {
        let k = (r.labels.dataset.as_str(), r.labels.perturb.as_str());
        match groups.iter_mut().find(|(g, _)| *g == k) {
            Some((_, v)) => v.push(r),
            None => groups.push((k, vec![r])),
        }
    }
    let mut files = Vec::new();
    let mut used = BTreeSet::new();
    for ((dataset, perturb), rs) in groups {
        let lines: Vec<Vec<String>> = rs
            .iter()
            .map(|r| panel_lines(r, data.get(r.key.as_str())))
            .collect();
        let panels: Vec<Panel<'_>> = rs
            .iter()
            .zip(&lines)
            .map(|(r, l)| Panel {
                title: r.labels.method.as_str(),
                lines: l,
                data: data.get(r.key.as_str()),
            })
            .collect();
        let title = format!("{dataset} / {perturb} (seed index {seed})");
        let cmp = match render_comparison(&title, &panels, &scale, opts.render_size) {
            Ok(c) => c,
            Err(e) => {
                notes.push(format!("{dataset} / {perturb}: {e}"));
                continue;
            }
        };
        let mut stem = format!("{}_{}", slug(dataset), slug(perturb));
        let base = stem.clone();
        let mut n = 2;
        while !used.insert(stem.clone()) {
            stem = format!("{base}-{n}");
            n += 1;
        }
        let rel = format!("renders/{stem}.png");
        let path = dir.join(&rel);
        cmp.image.save_png(&path)?;
        let _ = writeln!(
            md,
            "**{dataset} / {perturb}**\n\n![{dataset} / {perturb}]({rel})\n"
        );
        files.push(path);
    }
    if !notes.is_empty() {
        md.push_str("Left out:\n\n");
        for n in &notes {
            let _ = writeln!(md, "- {n}");
        }
        md.push('\n');
    }
    Ok(files)
}

/// The heading lines of a render panel: the row's Hausdorff distance and defect counts
/// (the metrics of the row, the same code as the tables), or why there is no mesh.
fn panel_lines(r: &Row, data: Option<&RenderData>) -> Vec<String> {
    if r.status != Status::Ok {
        return vec![
            format!("failed ({})", r.status.as_str()),
            r.error.clone().unwrap_or_default(),
        ];
    }
    if data.is_none() {
        return vec!["no render data".into()];
    }
    let m = |k: &str| r.metrics.get(k).copied();
    let count = |k: &str| m(k).map_or("–".into(), |x| format!("{x:.0}"));
    vec![
        format!("Hausdorff {}", m("hausdorff").map_or("–".into(), fmt_num)),
        format!("boundary edges {}", count("boundary_edges")),
        format!(
            "self-int. {}, non-manif. {}",
            count("self_intersections"),
            count("non_manifold_edges")
        ),
    ]
}

/// The failed cells with their reasons.
fn write_failed(md: &mut String, failed: &[&Row]) {
    if failed.is_empty() {
        return;
    }
    md.push_str("## Failed cells\n\n| dataset | perturbation | method | seed | status | reason |\n|---|---|---|---:|---|---|\n");
    for r in failed {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} |",
            r.labels.dataset,
            r.labels.perturb,
            r.labels.method,
            r.spec.seed_index,
            r.status.as_str(),
            r.error.as_deref().unwrap_or("").replace('|', "\\|")
        );
    }
    md.push('\n');
}

fn list_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    v.sort();
    v
}

/// The plots of one method kind: `(file stem, caption, plot)`.
/// The metrics to plot on dataset `d`: `metrics`, except that on a shape without true
/// features (no ground-truth feature point in any of its rows) precision, recall and F1
/// are 0 for every detector that labelled anything and undefined for the others, so their
/// lines lie on top of each other at 0; the false positives are plotted instead.
fn featureless_metrics(gs: &[&Group], d: &str, metrics: &[String]) -> Vec<String> {
    let rows: Vec<&&Group> = gs.iter().filter(|g| g.labels.dataset == d).collect();
    let featureless = !rows.is_empty()
        && rows.iter().all(|g| {
            g.metrics
                .get("feature_gt_positives")
                .is_some_and(|s| s.mean == 0.0)
        });
    let mut out: Vec<String> = Vec::new();
    for m in metrics {
        let m = if featureless
            && ["feature_precision", "feature_recall", "feature_f1"]
                .iter()
                .any(|p| m.starts_with(p))
        {
            "feature_false_positives".to_string()
        } else {
            m.clone()
        };
        if !out.contains(&m) {
            out.push(m);
        }
    }
    out
}

fn kind_plots(
    kind: MethodKind,
    groups: &[Group],
    columns: &[String],
    opts: &ReportOptions,
    swept: &[String],
) -> Vec<(String, String, Plot)> {
    let gs: Vec<&Group> = groups.iter().filter(|g| g.kind == kind).collect();
    let mut out = Vec::new();
    let datasets: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for g in &gs {
            if !v.contains(&g.labels.dataset) {
                v.push(g.labels.dataset.clone());
            }
        }
        v
    };
    // Metric vs perturbation level.
    let x = opts.x.clone().or_else(|| swept.first().cloned());
    let metrics: Vec<String> = if opts.plot_metrics.is_empty() {
        columns
            .iter()
            .filter(|c| *c != TIME_COLUMN && *c != tables::PEER_RATIO_COLUMN)
            .take(2)
            .cloned()
            .collect()
    } else {
        opts.plot_metrics.clone()
    };
    if let Some(x) = &x {
        for d in &datasets {
            for m in featureless_metrics(&gs, d, &metrics) {
                if let Some(plot) = metric_plot(&gs, d, &m, x, swept) {
                    out.push((
                        format!("{}_{}_vs_{}_{}", kind.as_str(), slug(&m), slug(x), slug(d)),
                        format!("{m} vs {x} on {d} (mean, band = ± std over seeds)"),
                        Plot::Lines(plot),
                    ));
                }
            }
        }
    }
    // Time vs size (log-log) when sizes vary (files: their measured size).
    let sizes: BTreeSet<u64> = gs.iter().map(|g| group_points(g)).collect();
    if sizes.len() > 1 {
        let mut per: BTreeMap<String, BTreeMap<u64, Vec<f64>>> = BTreeMap::new();
        for g in &gs {
            if let Some(s) = g.cost.get("method_s") {
                per.entry(g.labels.method.clone())
                    .or_default()
                    .entry(group_points(g))
                    .or_default()
                    .push(s.mean);
            }
        }
        let series: Vec<Series> = per
            .into_iter()
            .map(|(name, by)| {
                let pts: Vec<(f64, f64)> = by
                    .into_iter()
                    .map(|(n, v)| (n as f64, v.iter().sum::<f64>() / v.len() as f64))
                    .filter(|(_, t)| *t > 0.0)
                    .collect();
                let slope = loglog_slope(&pts);
                Series {
                    name: match slope {
                        Some(s) => format!("{name} (slope {s:.2})"),
                        None => name.clone(),
                    },
                    colour_key: name,
                    points: pts.into_iter().map(|(x, y)| (x, y, y, y)).collect(),
                }
            })
            .filter(|s| !s.points.is_empty())
            .collect();
        if !series.is_empty() {
            out.push((
                format!("{}_time_vs_size", kind.as_str()),
                "method time vs number of points (log-log, fitted slope in the legend)".to_string(),
                Plot::Lines(LinePlot {
                    title: format!("{}: time vs size", kind_title(kind)),
                    x_label: "input points".into(),
                    y_label: "method time (s)".into(),
                    series,
                    log: true,
                    non_negative: true,
                }),
            ));
        }
    }
    // Box plots of per-point errors.
    for d in &datasets {
        let boxes: Vec<BoxEntry> = gs
            .iter()
            .filter(|g| &g.labels.dataset == d)
            .filter_map(|g| {
                g.dist.clone().map(|dist| BoxEntry {
                    label: format!("{} @ {}", g.labels.method, g.labels.perturb),
                    colour_key: g.labels.method.clone(),
                    dist,
                })
            })
            .collect();
        if boxes.is_empty() {
            continue;
        }
        let what = boxes[0].dist.what.clone();
        out.push((
            format!("{}_errors_box_{}", kind.as_str(), slug(d)),
            format!("per-point {what} on {d} (box = quartiles, whiskers = min and p95; averaged over seeds)"),
            Plot::Boxes(BoxPlot {
                title: format!("{d}: per-point {what}"),
                y_label: dist_axis_label(&what),
                boxes,
            }),
        ));
    }
    out
}

/// The line plot of metric `m` against `x` on dataset `d`: one series per method label
/// (and the other swept keys), `None` when no configuration has the metric or the
/// configurations share one x value (a plot of single dots says nothing).
fn metric_plot(gs: &[&Group], d: &str, m: &str, x: &str, swept: &[String]) -> Option<LinePlot> {
    let mut series: Vec<Series> = Vec::new();
    for g in gs.iter().filter(|g| g.labels.dataset == d) {
        let Some(s) = g.metrics.get(m) else { continue };
        let xv = if x == "points" {
            group_points(g) as f64
        } else {
            g.data.perturb.get(x).and_then(Value::as_f64).unwrap_or(0.0)
        };
        let rest: Vec<String> = g
            .data
            .perturb
            .iter()
            .filter(|(k, _)| *k != x && swept.contains(k))
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        let name = if rest.is_empty() {
            g.labels.method.clone()
        } else {
            format!("{} {}", g.labels.method, rest.join(" "))
        };
        let point = (xv, s.mean, s.mean - s.std, s.mean + s.std);
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                colour_key: g.labels.method.clone(),
                points: vec![point],
            }),
        }
    }
    let xs: BTreeSet<u64> = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0.to_bits()))
        .collect();
    if xs.len() < 2 {
        return None;
    }
    Some(LinePlot {
        title: format!("{d}: {m}"),
        x_label: x_axis_label(x),
        y_label: metric_axis_label(m),
        series,
        log: false,
        non_negative: metric_non_negative(m),
    })
}

/// The x axis label of a perturbation key (or `points`) with its unit
/// (`experiments/README.md`, perturbation keys).
pub fn x_axis_label(x: &str) -> String {
    let unit = match x {
        "points" => "count",
        "noise" | "ball" | "gaussian" | "normal-gaussian" => "fraction of diagonal",
        "ma-uniform" => "multiple of the local spacing",
        "decimate" => "share of points kept",
        "duplicate" | "copies" | "outliers" => "share of points",
        "holes" => "count",
        _ => return x.to_string(),
    };
    format!("{x} ({unit})")
}

/// The unit of a metric, from its name (`docs/METRICS.md`); empty for counts, flags and
/// ratios without one.
pub fn metric_unit(m: &str) -> &'static str {
    const DIST: &[&str] = &[
        "chamfer",
        "hausdorff",
        "accuracy_",
        "completeness_",
        "_dist",
        "rms_dist",
        "feature_radius",
    ];
    if m.ends_with("_deg") {
        "deg"
    } else if m.ends_with("_abs") {
        "absolute length"
    } else if m.ends_with("_s") {
        "s"
    } else if m.ends_with("_mib") {
        "MiB"
    } else if ["fscore_", "precision_0", "recall_0"]
        .iter()
        .any(|p| m.starts_with(p))
    {
        "%"
    } else if DIST.iter().any(|p| m.contains(p)) {
        "fraction of diagonal"
    } else {
        ""
    }
}

/// `metric (unit)`, or the metric alone when it has no unit.
pub fn metric_axis_label(m: &str) -> String {
    match metric_unit(m) {
        "" => m.to_string(),
        u => format!("{m} ({u})"),
    }
}

/// The axis label of a box plot's distribution, e.g. `surface distance (diag)` becomes
/// `surface distance (fraction of diagonal)`.
fn dist_axis_label(what: &str) -> String {
    what.replace("(diag)", "(fraction of diagonal)")
}

/// Whether a metric cannot be negative (every reported metric but the Euler
/// characteristic): its bands stop at 0.
pub fn metric_non_negative(m: &str) -> bool {
    m != "euler"
}
