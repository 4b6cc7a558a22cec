//! `reconbench datasets`: the vendored real data sets of the manifest
//! (`datasets/real/datasets.toml`).

use clap::Args;
use reconbench_synth::real::{Manifest, RealKind, RealSet};
use serde::Serialize;

use super::{CliError, CliResult, print_json};

/// Arguments of `datasets`.
#[derive(Debug, Args)]
pub struct DatasetsArgs {
    /// Print the manifest entries, each with its resolved file path, as JSON.
    #[arg(long)]
    json: bool,
}

/// A manifest entry with the path of its file.
#[derive(Debug, Serialize)]
struct Entry<'a> {
    #[serde(flatten)]
    set: &'a RealSet,
    path: String,
}

/// `reconbench datasets`.
pub fn datasets(a: DatasetsArgs) -> CliResult {
    let m = Manifest::locate(None).map_err(CliError::input)?;
    if a.json {
        let entries: Vec<Entry> = m
            .sets
            .iter()
            .map(|s| Entry {
                set: s,
                path: m.path_of(s).display().to_string(),
            })
            .collect();
        return print_json(&entries);
    }
    let yes_no = |b: bool| if b { "yes" } else { "no" }.to_string();
    let header = [
        "name",
        "kind",
        "vertices",
        "faces",
        "genus",
        "closed",
        "thesis_closed",
        "licence",
        "source",
        "seed tables",
    ];
    let rows: Vec<[String; 10]> = m
        .sets
        .iter()
        .map(|s| {
            [
                s.name.clone(),
                match s.kind {
                    RealKind::Mesh => "mesh",
                    RealKind::Cloud => "cloud",
                }
                .to_string(),
                s.vertices.to_string(),
                s.faces.to_string(),
                s.genus.to_string(),
                yes_no(s.closed),
                yes_no(s.thesis_closed),
                s.licence.clone(),
                format!(
                    "{}@{}:{}",
                    s.source_repository, s.source_commit, s.source_path
                ),
                if s.seed_tables.is_empty() {
                    "-".to_string()
                } else {
                    s.seed_tables.join(", ")
                },
            ]
        })
        .collect();
    let mut width = header.map(str::len);
    for r in &rows {
        for (w, c) in width.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    // Counts right-aligned, text left-aligned, the last column unpadded.
    let numeric = |i: usize| (2..=4).contains(&i);
    let line = |cells: &[String]| {
        let mut out = String::new();
        for (i, c) in cells.iter().enumerate() {
            if i > 0 {
                out.push_str("  ");
            }
            if i + 1 == cells.len() {
                out.push_str(c);
            } else if numeric(i) {
                out.push_str(&format!("{c:>w$}", w = width[i]));
            } else {
                out.push_str(&format!("{c:<w$}", w = width[i]));
            }
        }
        out
    };
    println!("{}", line(&header.map(String::from)));
    for r in &rows {
        println!("{}", line(r));
    }
    println!("({} data sets in {})", rows.len(), m.dir.display());
    Ok(())
}
