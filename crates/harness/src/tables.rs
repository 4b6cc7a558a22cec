//! Tables of aggregated results: Markdown, LaTeX (booktabs) and CSV.
//!
//! One table per method kind. Rows are configurations (dataset, perturbation, method);
//! cells show `mean ± std` over seeds. The best mean of each column within a block of
//! rows sharing dataset and perturbation (the methods compared on the same input) is
//! bold in Markdown and LaTeX. CSV has full precision: mean, std, 95 % CI and n.

use std::fmt::Write as _;

use crate::aggregate::{Group, Stat};
use crate::metric_spec::{default_metrics, higher_is_better};
use crate::registry::MethodKind;

/// Column of method time (from `cost`).
pub const TIME_COLUMN: &str = "method_s";

/// Column of method time over the fastest external program's on the same input, added
/// after [`TIME_COLUMN`] when a table holds external methods (the peers).
pub const PEER_RATIO_COLUMN: &str = "time_vs_fastest_peer";

/// A table for one method kind.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Method kind.
    pub kind: MethodKind,
    /// Metric columns, then [`TIME_COLUMN`] (and [`PEER_RATIO_COLUMN`] with peers).
    pub columns: Vec<String>,
    /// Rows.
    pub rows: Vec<TableRow>,
}

/// One row.
#[derive(Debug, Clone, PartialEq)]
pub struct TableRow {
    /// Dataset label.
    pub dataset: String,
    /// Perturbation label.
    pub perturb: String,
    /// Method label.
    pub method: String,
    /// Ok cells.
    pub ok: usize,
    /// Cells.
    pub cells: usize,
    /// One statistic per column.
    pub values: Vec<Option<Stat>>,
    /// Whether the value is the best of its block.
    pub best: Vec<bool>,
    /// Whether the method is an oracle (handed the ground truth): shown apart, in
    /// italics, and never counted as best.
    pub oracle: bool,
}

/// Metric columns for `kind`: the requested ones that occur, else the defaults that occur.
pub fn columns_for(kind: MethodKind, groups: &[&Group], requested: &[String]) -> Vec<String> {
    let present = |m: &str| groups.iter().any(|g| g.metrics.contains_key(m));
    let from_req: Vec<String> = requested.iter().filter(|m| present(m)).cloned().collect();
    if !from_req.is_empty() {
        return from_req;
    }
    default_metrics(kind)
        .iter()
        .filter(|m| present(m))
        .map(|m| (*m).to_string())
        .collect()
}

/// Builds one table per method kind present in `groups`.
pub fn build(groups: &[Group], requested: &[String]) -> Vec<Table> {
    let mut out = Vec::new();
    for kind in [
        MethodKind::Normals,
        MethodKind::Features,
        MethodKind::Filter,
        MethodKind::Reconstruct,
    ] {
        let gs: Vec<&Group> = groups.iter().filter(|g| g.kind == kind).collect();
        if gs.is_empty() {
            continue;
        }
        let mut columns = columns_for(kind, &gs, requested);
        columns.push(TIME_COLUMN.to_string());
        let mut rows: Vec<TableRow> = gs
            .iter()
            .map(|g| TableRow {
                dataset: g.labels.dataset.clone(),
                perturb: g.labels.perturb.clone(),
                method: g.labels.method.clone(),
                ok: g.ok,
                cells: g.cells,
                values: columns
                    .iter()
                    .map(|c| {
                        if c == TIME_COLUMN {
                            g.cost.get("method_s").copied()
                        } else {
                            g.metrics.get(c).copied()
                        }
                    })
                    .collect(),
                best: vec![false; columns.len()],
                oracle: crate::registry::find(&g.method).is_ok_and(|e| e.needs_ground_truth),
            })
            .collect();
        if gs.iter().any(|g| g.method.starts_with("external")) {
            add_peer_ratio(&gs, &mut columns, &mut rows);
        }
        // Best per column within each (dataset, perturbation) block, among the methods
        // that had to work for it (not the oracles).
        for ci in 0..columns.len() {
            let up = higher_is_better(&columns[ci]);
            let mut blocks: Vec<(String, String)> = rows
                .iter()
                .map(|r| (r.dataset.clone(), r.perturb.clone()))
                .collect();
            blocks.dedup();
            for (d, p) in blocks {
                let idx: Vec<usize> = (0..rows.len())
                    .filter(|&i| rows[i].dataset == d && rows[i].perturb == p && !rows[i].oracle)
                    .collect();
                // A block where a method lacks the value (e.g. F1 undefined for a method
                // that rightly labelled nothing on a featureless shape) has no winner.
                if idx.len() < 2 || idx.iter().any(|&i| rows[i].values[ci].is_none()) {
                    continue;
                }
                let best = idx
                    .iter()
                    .filter_map(|&i| rows[i].values[ci].map(|s| s.mean))
                    .fold(None, |acc: Option<f64>, x| {
                        Some(match acc {
                            None => x,
                            Some(a) if (up && x > a) || (!up && x < a) => x,
                            Some(a) => a,
                        })
                    });
                if let Some(b) = best {
                    for &i in &idx {
                        if rows[i].values[ci].is_some_and(|s| s.mean == b) {
                            rows[i].best[ci] = true;
                        }
                    }
                }
            }
        }
        oracles_last(&mut rows);
        out.push(Table {
            kind,
            columns,
            rows,
        });
    }
    out
}

/// Moves the oracle rows of each (dataset, perturbation) block behind the methods that
/// had to work for their result, keeping the order otherwise.
fn oracles_last(rows: &mut [TableRow]) {
    let mut start = 0;
    while start < rows.len() {
        let key = (rows[start].dataset.clone(), rows[start].perturb.clone());
        let end = (start..rows.len())
            .find(|&i| (&rows[i].dataset, &rows[i].perturb) != (&key.0, &key.1))
            .unwrap_or(rows.len());
        rows[start..end].sort_by_key(|r| r.oracle);
        start = end;
    }
}

/// Appends [`PEER_RATIO_COLUMN`]: each row's mean method time over the smallest mean
/// method time of an external method in its (dataset, perturbation) block.
fn add_peer_ratio(gs: &[&Group], columns: &mut Vec<String>, rows: &mut [TableRow]) {
    let ti = columns.len() - 1;
    columns.push(PEER_RATIO_COLUMN.to_string());
    let fastest = |d: &str, p: &str| {
        gs.iter()
            .zip(rows.iter())
            .filter(|(g, r)| g.method.starts_with("external") && r.dataset == d && r.perturb == p)
            .filter_map(|(_, r)| r.values[ti].map(|s| s.mean))
            .filter(|t| *t > 0.0)
            .fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.min(t))))
    };
    let ratios: Vec<Option<Stat>> = rows
        .iter()
        .map(|r| {
            let f = fastest(&r.dataset, &r.perturb)?;
            let t = r.values[ti]?.mean;
            Stat::of(&[t / f])
        })
        .collect();
    for (r, v) in rows.iter_mut().zip(ratios) {
        r.values.push(v);
        r.best.push(false);
    }
}

/// A number with 4 significant digits.
pub fn fmt_num(x: f64) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.3e}")
    }
}

fn cell_text(s: &Option<Stat>) -> String {
    match s {
        None => "–".into(),
        Some(s) if s.n > 1 => format!("{} ± {}", fmt_num(s.mean), fmt_num(s.std)),
        Some(s) => fmt_num(s.mean),
    }
}

/// Column heading with its direction.
pub fn heading(c: &str) -> String {
    if c == TIME_COLUMN {
        "time (s)".into()
    } else if c == PEER_RATIO_COLUMN {
        "time / fastest peer".into()
    } else if higher_is_better(c) {
        format!("{c} ↑")
    } else {
        format!("{c} ↓")
    }
}

/// Markdown table.
pub fn markdown(t: &Table) -> String {
    let mut s = String::new();
    let _ = write!(s, "| dataset | perturbation | method | ok |");
    for c in &t.columns {
        let _ = write!(s, " {} |", heading(c));
    }
    s.push('\n');
    s.push_str("|---|---|---|---|");
    for _ in &t.columns {
        s.push_str("---:|");
    }
    s.push('\n');
    for r in &t.rows {
        let _ = write!(
            s,
            "| {} | {} | {} | {}/{} |",
            md_escape(&r.dataset),
            md_escape(&r.perturb),
            if r.oracle {
                format!("*{}* (oracle)", md_escape(&r.method))
            } else {
                md_escape(&r.method)
            },
            r.ok,
            r.cells
        );
        for (v, b) in r.values.iter().zip(&r.best) {
            let text = cell_text(v);
            if r.oracle && text != "–" {
                // Markdown has no grey: the whole oracle row is in italics.
                let _ = write!(s, " *{text}* |");
            } else if *b {
                let _ = write!(s, " **{text}** |");
            } else {
                let _ = write!(s, " {text} |");
            }
        }
        s.push('\n');
    }
    s
}

fn md_escape(s: &str) -> String {
    s.replace('|', "\\|")
}

/// LaTeX escaping of plain text.
pub fn tex_escape(s: &str) -> String {
    let mut out = String::new();
    for ch in s.chars() {
        match ch {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(ch);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            '↑' => out.push_str("$\\uparrow$"),
            '↓' => out.push_str("$\\downarrow$"),
            _ => out.push(ch),
        }
    }
    out
}

/// LaTeX table (needs `\usepackage{booktabs}` and `\usepackage{xcolor}`: oracle rows
/// are grey).
pub fn latex(t: &Table, caption: &str) -> String {
    let mut s = String::from("% needs \\usepackage{booktabs} and \\usepackage{xcolor}\n");
    s.push_str("\\begin{table}[t]\n\\centering\n\\small\n");
    let _ = writeln!(
        s,
        "\\begin{{tabular}}{{lll{}}}",
        "r".repeat(t.columns.len())
    );
    s.push_str("\\toprule\n");
    s.push_str("dataset & perturbation & method");
    for c in &t.columns {
        let _ = write!(s, " & {}", tex_escape(&heading(c)));
    }
    s.push_str(" \\\\\n\\midrule\n");
    let mut last = None;
    for r in &t.rows {
        if last.is_some() && last != Some(&r.dataset) {
            s.push_str("\\midrule\n");
        }
        last = Some(&r.dataset);
        let _ = write!(
            s,
            "{} & {} & {}",
            tex_escape(&r.dataset),
            tex_escape(&r.perturb),
            if r.oracle {
                format!(
                    "\\textcolor{{gray}}{{\\textit{{{}}} (oracle)}}",
                    tex_escape(&r.method)
                )
            } else {
                tex_escape(&r.method)
            }
        );
        for (v, b) in r.values.iter().zip(&r.best) {
            let text = match v {
                None => "--".to_string(),
                Some(st) if st.n > 1 => format!("{} $\\pm$ {}", fmt_num(st.mean), fmt_num(st.std)),
                Some(st) => fmt_num(st.mean),
            };
            let text = text.replace('–', "--");
            if r.oracle {
                let _ = write!(s, " & \\textcolor{{gray}}{{{text}}}");
            } else if *b {
                let _ = write!(s, " & \\textbf{{{text}}}");
            } else {
                let _ = write!(s, " & {text}");
            }
        }
        s.push_str(" \\\\\n");
    }
    s.push_str("\\bottomrule\n\\end{tabular}\n");
    let _ = writeln!(s, "\\caption{{{}}}", tex_escape(caption));
    s.push_str("\\end{table}\n");
    s
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn csv_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

/// CSV table: full precision, `mean, std, ci95, n` per column.
pub fn csv(t: &Table) -> String {
    let mut s = String::from("dataset,perturbation,method,ok,cells");
    for c in &t.columns {
        let _ = write!(s, ",{c}_mean,{c}_std,{c}_ci95,{c}_n");
    }
    s.push('\n');
    for r in &t.rows {
        let _ = write!(
            s,
            "{},{},{},{},{}",
            csv_field(&r.dataset),
            csv_field(&r.perturb),
            csv_field(&r.method),
            r.ok,
            r.cells
        );
        for v in &r.values {
            match v {
                Some(st) => {
                    let _ = write!(
                        s,
                        ",{},{},{},{}",
                        csv_num(st.mean),
                        csv_num(st.std),
                        csv_num(st.ci95),
                        st.n
                    );
                }
                None => s.push_str(",,,,0"),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_escaping() {
        assert_eq!(fmt_num(0.012345), "0.01235");
        assert_eq!(fmt_num(123.456), "123.5");
        assert_eq!(fmt_num(1.0e-6), "1.000e-6");
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(tex_escape("a_b & 5%"), "a\\_b \\& 5\\%");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
    }

    fn group(method: &str, mean: f64) -> Group {
        let stat = Stat {
            n: 1,
            mean,
            std: 0.0,
            ci95: f64::NAN,
            min: mean,
            max: mean,
        };
        Group {
            config: method.into(),
            index: 0,
            labels: crate::experiment::Labels {
                dataset: "sphere".into(),
                perturb: "clean".into(),
                method: method.into(),
            },
            method: method.into(),
            kind: MethodKind::Normals,
            params: serde_json::Value::Null,
            data: crate::inputs::DataSpec {
                shape: "sphere".into(),
                sampler: "uniform".into(),
                points: 10,
                perturb: Default::default(),
                scan: None,
                file: None,
            },
            cells: 1,
            ok: 1,
            metrics: [("normal_mean_deg".to_string(), stat)].into(),
            cost: [("method_s".to_string(), stat)].into(),
            dist: None,
        }
    }

    #[test]
    fn oracles_are_shown_apart_and_never_best() {
        let groups = vec![
            group("gt-normals", 0.0),
            group("pf", 2.0),
            group("jet", 1.0),
        ];
        let t = &build(&groups, &[])[0];
        let row = |m: &str| t.rows.iter().find(|r| r.method == m).unwrap();
        assert!(row("gt-normals").oracle && !row("pf").oracle);
        assert!(row("gt-normals").best.iter().all(|b| !b));
        assert!(row("jet").best[0], "the best real method is bold");
        let md = markdown(t);
        assert!(md.contains("*gt-normals* (oracle)"), "{md}");
    }

    #[test]
    fn no_bold_where_a_method_lacks_the_value_and_oracles_come_last() {
        let mut none = group("pca-variation", 0.0);
        none.metrics.clear();
        let groups = vec![group("gt-normals", 0.0), group("gauss-map", 0.0), none];
        let t = &build(&groups, &[])[0];
        let methods: Vec<&str> = t.rows.iter().map(|r| r.method.as_str()).collect();
        assert_eq!(methods, ["gauss-map", "pca-variation", "gt-normals"]);
        assert!(
            !t.rows[0].best[0],
            "0 is not best against an undefined value"
        );
        let md = markdown(t);
        assert!(md.contains("| *0* |"), "oracle values in italics: {md}");
        assert!(latex(t, "c").contains("\\textcolor{gray}"));
    }

    #[test]
    fn times_are_divided_by_the_fastest_peer_of_the_block() {
        let mut peer = group("external-normals", 4.0);
        peer.labels.method = "CGAL jet".into();
        let mut slow = group("external-normals", 8.0);
        slow.labels.method = "slow peer".into();
        let groups = vec![group("pf", 2.0), peer, slow];
        let t = &build(&groups, &[])[0];
        assert_eq!(t.columns.last().unwrap(), PEER_RATIO_COLUMN);
        let ratio = |m: &str| {
            t.rows
                .iter()
                .find(|r| r.method == m)
                .unwrap()
                .values
                .last()
                .unwrap()
                .unwrap()
                .mean
        };
        assert_eq!(
            (ratio("pf"), ratio("CGAL jet"), ratio("slow peer")),
            (0.5, 1.0, 2.0)
        );
        assert!(markdown(t).contains("time / fastest peer"));
        // Without an external method there is no such column.
        let t = &build(&[group("pf", 2.0), group("jet", 1.0)], &[])[0];
        assert_eq!(t.columns.last().unwrap(), TIME_COLUMN);
    }
}
