//! The examples in `--help` work as printed: every vendored file they name exists, and
//! the examples of the first verbs a newcomer tries run from a fresh directory.

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_reconbench");
const VERBS: &[&str] = &[
    "info",
    "convert",
    "gen",
    "shapes",
    "datasets",
    "delaunay",
    "eval",
    "eval-normals",
    "eval-features",
    "run",
    "list",
    "reconstruct",
    "normals",
    "features",
    "filter",
    "report",
    "baseline",
    "compare",
    "merge",
];

/// The `reconbench ...` example lines of a verb's help, without trailing comments.
fn examples(verb: &str) -> Vec<String> {
    let out = Command::new(BIN).args([verb, "--help"]).output().unwrap();
    assert!(out.status.success(), "{verb} --help");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("reconbench "))
        .map(|l| l.split(" #").next().unwrap_or(l).trim().to_string())
        .collect()
}

fn repo() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

#[test]
fn every_file_an_example_names_in_the_repository_exists() {
    let mut n = 0;
    for verb in VERBS {
        for ex in examples(verb) {
            n += 1;
            for tok in ex.split_whitespace() {
                if tok.starts_with("datasets/") || tok.starts_with("experiments/") {
                    assert!(repo().join(tok).exists(), "`{ex}` names {tok}");
                }
            }
        }
    }
    assert!(n >= VERBS.len(), "only {n} examples");
}

#[test]
fn the_first_examples_run_as_printed() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(repo().join("datasets"), dir.path().join("datasets")).unwrap();
    let mut ran = 0;
    for verb in ["info", "convert", "reconstruct"] {
        for ex in examples(verb) {
            // The bunny with priority-front is too slow for a debug test build.
            if ex.contains("bunny") {
                continue;
            }
            let args: Vec<&str> = ex.split_whitespace().skip(1).collect();
            let out = Command::new(BIN)
                .args(&args)
                .current_dir(dir.path())
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "`{ex}` failed: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            ran += 1;
        }
    }
    assert!(ran >= 5, "ran {ran} examples");
}
