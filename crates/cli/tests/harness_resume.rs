//! `kill -9` of the runner (and its workers) mid-run never leaves a partial line, and
//! `--resume` finishes the grid without redoing finished cells. A worker killed from
//! outside fails only its cell.

mod harness_common;
use harness_common::*;

use std::collections::BTreeSet;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SLOW: &str = r#"
    seeds = 10
    [[datasets]]
    shape = "sphere"
    points = 100
    [[methods]]
    name = "debug-sleep"
    params = { seconds = 0.25 }
    [report]
    plots = false
"#;

#[test]
fn resume_after_the_run_is_killed() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "slow.toml", SLOW);
    let out_dir = dir.path().join("out");
    let results = out_dir.join("results.jsonl");
    let mut child = Command::new(BIN)
        .args([
            "run",
            exp.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
            "-j",
            "2",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        let n = std::fs::read_to_string(&results)
            .map(|t| t.lines().count())
            .unwrap_or(0);
        if n >= 3 {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(20));
    }
    let workers = children(child.id());
    kill9(child.id());
    for w in workers {
        kill9(w);
    }
    let _ = child.wait();
    let text = std::fs::read_to_string(&results).unwrap();
    assert!(
        text.is_empty() || text.ends_with('\n'),
        "partial line left: {text:?}"
    );
    let done: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert!(done.len() >= 3 && done.len() < 10, "{} rows", done.len());

    let stdout = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--resume",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(
        v["summary"]["skipped"].as_u64().unwrap() as usize,
        done.len(),
        "{stdout}"
    );
    assert_eq!(
        v["summary"]["ran"].as_u64().unwrap() as usize,
        10 - done.len()
    );
    let all = rows(&out_dir);
    assert_eq!(all.len(), 10);
    let keys: BTreeSet<&str> = all.iter().map(|r| r["key"].as_str().unwrap()).collect();
    assert_eq!(keys.len(), 10);
    assert!(all.iter().all(|r| r["status"] == "ok"));
    // Finished cells were not redone: their rows are unchanged, cost included.
    for d in &done {
        assert!(all.contains(d), "row of {} was rewritten", d["key"]);
    }
}

#[test]
fn a_worker_killed_from_outside_fails_only_its_cell() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(
        dir.path(),
        "k.toml",
        r#"
        seeds = 1
        [[datasets]]
        shape = "sphere"
        points = 100
        [[methods]]
        name = "debug-sleep"
        params = { seconds = 30.0 }
        [[methods]]
        name = "gt-normals"
        [report]
        plots = false
        "#,
    );
    let out_dir = dir.path().join("out");
    let mut child = Command::new(BIN)
        .args([
            "run",
            exp.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
            "-j",
            "1",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let worker = loop {
        if let Some(&w) = workers(child.id()).first() {
            break w;
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "no worker started");
        std::thread::sleep(Duration::from_millis(10));
    };
    // Let the worker get into the method, then kill it.
    std::thread::sleep(Duration::from_millis(300));
    kill9(worker);
    assert!(child.wait().unwrap().success());
    let rows = rows(&out_dir);
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["status"], "crash");
    assert!(
        rows[0]["error"].as_str().unwrap().contains("SIGKILL"),
        "{}",
        rows[0]["error"]
    );
    assert_eq!(rows[1]["status"], "ok");
}

/// A second run into the same results neither overwrites nor appends silently: it
/// refuses (exit 2, one line, before any work) unless told to resume or to start afresh,
/// and `--fresh` keeps the earlier rows under `previous/`.
#[test]
fn earlier_results_are_never_overwritten_silently() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(
        dir.path(),
        "quick.toml",
        "seeds = 2\n[[datasets]]\nshape = \"sphere\"\npoints = 100\n[[methods]]\nname = \"gt-normals\"\n[report]\nplots = false\nrenders = false\n",
    );
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        let mut args = vec!["run", exp.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        reconbench(&args)
    };
    ok(&run(&[]));
    let before = std::fs::read(out.join("results.jsonl")).unwrap();
    let again = run(&[]);
    assert_eq!(again.status.code(), Some(2));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("--resume") && err.contains("--fresh"), "{err}");
    assert_eq!(std::fs::read(out.join("results.jsonl")).unwrap(), before);
    ok(&run(&["--resume"]));
    ok(&run(&["--fresh"]));
    let prev: Vec<_> = std::fs::read_dir(out.join("previous"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(prev.len(), 1);
    assert_eq!(
        std::fs::read(prev[0].join("results.jsonl")).unwrap(),
        before
    );
    assert!(prev[0].join("manifest.json").is_file());
    assert_eq!(rows(&out).len(), 2);
}
