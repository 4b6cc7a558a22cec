//! Two runs of one experiment give byte-identical rows apart from `cost`, and no
//! timing is left outside `cost`.

mod harness_common;
use harness_common::*;

const EXP: &str = r#"
    seeds = 2
    [[datasets]]
    shape = "torus"
    points = 1500
    [[methods]]
    name = "priority-front"
    [[methods]]
    name = "ufm"
    [report]
    plots = false
    renders = false
"#;

#[test]
fn rows_are_identical_apart_from_cost_and_timings_live_in_cost() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "det.toml", EXP);
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for out in [&a, &b] {
        ok(&reconbench(&[
            "run",
            exp.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-j",
            "2",
            "--no-report",
        ]));
    }
    assert_eq!(rows_without_cost(&a), rows_without_cost(&b));
    for r in rows(&a) {
        let diag = r["diagnostics"].as_object().unwrap();
        let timing: Vec<&String> = diag
            .keys()
            .filter(|k| k.ends_with("_s") || k.ends_with("_per_second") || *k == "seconds")
            .collect();
        assert!(timing.is_empty(), "timings outside cost: {timing:?}");
        let timings = r["cost"]["timings"].as_object().unwrap();
        let want = if r["spec"]["method"] == "ufm" {
            "dt_s"
        } else {
            "triangles_per_second"
        };
        assert!(timings.contains_key(want), "{timings:?}");
    }
}

#[test]
fn provenance_names_the_commit_of_the_binary_wherever_it_runs() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "tiny.toml",
        "[[datasets]]\nshape = \"sphere\"\npoints = 50\n[[methods]]\nname = \"debug-sleep\"\nparams = { seconds = 0 }\n[report]\nplots = false\n",
    );
    // Run from a directory outside any git checkout.
    let out = std::process::Command::new(BIN)
        .args(["run", "tiny.toml", "--out", "out", "--no-report"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    ok(&out);
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/manifest.json")).unwrap(),
    )
    .unwrap();
    let commit = manifest["runs"][0]["git_commit"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(
        commit.len() == 40 && commit.chars().all(|c| c.is_ascii_hexdigit()),
        "{commit}"
    );
    let repo = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let known = std::process::Command::new("git")
        .args([
            "-C",
            repo,
            "cat-file",
            "-e",
            &format!("{commit}^{{commit}}"),
        ])
        .status()
        .unwrap();
    assert!(
        known.success(),
        "{commit} is not a commit of this repository"
    );
}

#[test]
fn a_method_timing_can_be_an_expectation() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(
        dir.path(),
        "rate.toml",
        "[[datasets]]\nshape = \"torus\"\npoints = 1500\n[[methods]]\nname = \"priority-front\"\n[report]\nplots = false\nrenders = false\n[[expect]]\nmetric = \"cost.triangles_per_second\"\nvalue = 1.0\ntol = \"rel:1e12\"\n",
    );
    let out = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        dir.path().join("out").to_str().unwrap(),
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["expect_misses"], 0, "{out}");
}
