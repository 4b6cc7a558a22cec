//! A run stopped by SIGINT or SIGTERM kills its workers, keeps the finished rows, says
//! how to resume and exits 130 / 143; a runner killed outright leaves no worker behind;
//! without a terminal, progress goes to stderr as lines.

mod harness_common;
use harness_common::*;

use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const SLOW: &str = r#"
    seeds = 12
    [[datasets]]
    shape = "sphere"
    points = 100
    [[methods]]
    name = "debug-sleep"
    params = { seconds = 0.4 }
    [report]
    plots = false
"#;

/// Four quick cells (grid indices 0-3), then four that would sleep 30 s: a stop must
/// kill those, not wait for them.
const QUICK_THEN_LONG: &str = r#"
    seeds = 4
    [[datasets]]
    shape = "sphere"
    points = 100
    [[methods]]
    name = "debug-sleep"
    params = { seconds = [0.2, 30] }
    [report]
    plots = false
"#;

/// Starts `reconbench run` on `exp` with a marker in its environment (inherited by the
/// workers, so they can be found in /proc later).
fn start(exp: &Path, out: &Path, marker: &str, extra: &[&str]) -> Child {
    Command::new(BIN)
        .args(["run", exp.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .args(["-j", "2"])
        .args(extra)
        .env("RECONBENCH_TEST_MARKER", marker)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn rows_in(out: &Path) -> usize {
    std::fs::read_to_string(out.join("results.jsonl"))
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

fn wait_rows(out: &Path, n: usize) {
    let t0 = Instant::now();
    while rows_in(out) < n {
        assert!(t0.elapsed() < Duration::from_secs(60), "no progress");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Processes whose environment holds `marker` (the runner and its workers).
fn marked(marker: &str) -> Vec<u32> {
    let needle = format!("RECONBENCH_TEST_MARKER={marker}");
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    dir.filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            std::fs::read(format!("/proc/{pid}/environ"))
                .map(|env| env.split(|&b| b == 0).any(|v| v == needle.as_bytes()))
                .unwrap_or(false)
        })
        .collect()
}

/// Waits (at most 5 s) until no marked process is left; returns the ones left.
fn wait_gone(marker: &str) -> Vec<u32> {
    let t0 = Instant::now();
    loop {
        let left = marked(marker);
        if left.is_empty() || t0.elapsed() > Duration::from_secs(5) {
            return left;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn signal(pid: u32, sig: &str) {
    let st = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap();
    assert!(st.success());
}

/// Waits (at most 20 s) for the child and collects its output.
fn finish(child: Child) -> Output {
    let pid = child.id();
    let t0 = Instant::now();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    loop {
        if let Ok(out) = rx.try_recv() {
            return out.unwrap();
        }
        if t0.elapsed() > Duration::from_secs(20) {
            signal(pid, "-KILL");
            panic!("the run did not stop within 20 s of the signal");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn interrupt_then_resume(sig: &str, name: &str, code: i32) {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "slow.toml", QUICK_THEN_LONG);
    let out = dir.path().join("out");
    let marker = format!("{name}-{}", std::process::id());
    let child = start(&exp, &out, &marker, &[]);
    wait_rows(&out, 4);
    // Let the long cells start.
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(marked(&marker).len(), 3, "the runner and two workers run");
    signal(child.id(), sig);
    let t0 = Instant::now();
    let res = finish(child);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(code), "stderr: {stderr}");
    assert!(
        t0.elapsed() < Duration::from_secs(5),
        "stopping took {:?}",
        t0.elapsed()
    );
    assert!(
        stderr.contains(&format!("interrupted by {name}")) && stderr.contains("--resume"),
        "stderr: {stderr}"
    );
    assert!(wait_gone(&marker).is_empty(), "workers left running");
    // Only finished cells were recorded: no row of a killed worker.
    let saved = rows(&out);
    assert_eq!(saved.len(), 4);
    assert!(saved.iter().all(|r| r["status"] == "ok"), "{saved:?}");
    assert!(
        !out.join("report.md").exists(),
        "a partial run writes no report"
    );
    // Resume runs exactly the rest (cut short by a 1 s timeout).
    let again = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resume",
        "--timeout",
        "1",
        "-j",
        "2",
    ]));
    assert!(again.contains("4 skipped (resume), 4 run"), "{again}");
    let all = rows(&out);
    let keys: BTreeSet<String> = all.iter().map(|r| r["key"].to_string()).collect();
    assert_eq!((all.len(), keys.len()), (8, 8));
}

#[test]
fn sigint_stops_the_run_cleanly_and_resume_finishes_it() {
    interrupt_then_resume("-INT", "SIGINT", 130);
}

#[test]
fn sigterm_stops_the_run_cleanly_with_code_143() {
    interrupt_then_resume("-TERM", "SIGTERM", 143);
}

#[test]
fn a_runner_killed_outright_leaves_no_worker_running() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "slow.toml", QUICK_THEN_LONG);
    let out = dir.path().join("out");
    let marker = format!("kill9-{}", std::process::id());
    let child = start(&exp, &out, &marker, &[]);
    wait_rows(&out, 4);
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(marked(&marker).len(), 3, "the runner and two workers run");
    signal(child.id(), "-KILL");
    let _ = finish(child);
    assert!(wait_gone(&marker).is_empty(), "orphaned workers");
}

#[test]
fn progress_goes_to_stderr_as_lines_without_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "slow.toml", SLOW);
    let out = dir.path().join("out");
    let child = start(&exp, &out, "log", &["--log-every", "0.3"]);
    let res = finish(child);
    assert!(res.status.success());
    let stderr = String::from_utf8_lossy(&res.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("progress: "))
        .collect();
    assert!(lines.len() >= 3, "stderr: {stderr}");
    assert!(
        lines
            .iter()
            .all(|l| l.contains("/12 cells done (0 failed)")),
        "{lines:?}"
    );
    assert!(lines.iter().any(|l| l.contains("ETA ")), "{lines:?}");
}

/// As `scancel` does: SIGTERM to the runner and its workers at once. The cells that
/// were running are not recorded as crashed (a resume must run them).
#[test]
fn sigterm_to_the_whole_process_tree_records_no_crashed_cell() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "slow.toml", QUICK_THEN_LONG);
    let out = dir.path().join("out");
    let marker = format!("tree-{}", std::process::id());
    let child = start(&exp, &out, &marker, &[]);
    wait_rows(&out, 4);
    std::thread::sleep(Duration::from_millis(500));
    let procs = marked(&marker);
    assert_eq!(procs.len(), 3, "the runner and two workers run");
    // Workers first, so they die before the runner hears of it.
    for pid in procs.iter().filter(|&&p| p != child.id()) {
        signal(*pid, "-TERM");
    }
    signal(child.id(), "-TERM");
    let res = finish(child);
    assert_eq!(res.status.code(), Some(143));
    let saved = rows(&out);
    assert_eq!(saved.len(), 4, "{saved:?}");
    assert!(saved.iter().all(|r| r["status"] == "ok"), "{saved:?}");
}
