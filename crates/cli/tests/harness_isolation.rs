//! A test-only method that panics, aborts, hangs or blows its memory fails only its own
//! cell, with the reason; the other cells of the sweep finish.

mod harness_common;
use harness_common::*;

#[test]
fn misbehaving_methods_fail_only_their_own_cells() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(
        dir.path(),
        "iso.toml",
        r#"
        seeds = 1
        timeout = 3
        memory_limit_mib = 200
        [[datasets]]
        shape = "sphere"
        points = 200
        [[methods]]
        name = "debug-panic"
        [[methods]]
        name = "debug-abort"
        [[methods]]
        name = "debug-hang"
        [[methods]]
        name = "debug-alloc"
        params = { mib = 2000 }
        [[methods]]
        name = "gt-normals"
        [report]
        plots = false
        "#,
    );
    let out_dir = dir.path().join("out");
    let stdout = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "-j",
        "2",
    ]));
    assert!(stdout.contains("5 cells"), "{stdout}");
    let rows = rows(&out_dir);
    assert_eq!(rows.len(), 5);
    let by = |m: &str| {
        rows.iter()
            .find(|r| r["spec"]["method"] == m)
            .unwrap()
            .clone()
    };
    let status = |m: &str| by(m)["status"].as_str().unwrap().to_string();
    let reason = |m: &str| by(m)["error"].as_str().unwrap_or("").to_string();
    assert_eq!(status("gt-normals"), "ok");
    assert_eq!(status("debug-panic"), "panic");
    assert!(
        reason("debug-panic").contains("deliberate panic"),
        "{}",
        reason("debug-panic")
    );
    assert_eq!(status("debug-abort"), "crash");
    assert!(
        reason("debug-abort").contains("SIGABRT"),
        "{}",
        reason("debug-abort")
    );
    assert_eq!(status("debug-hang"), "timeout");
    assert!(
        reason("debug-hang").contains("timeout"),
        "{}",
        reason("debug-hang")
    );
    assert_eq!(status("debug-alloc"), "oom");
    assert!(
        reason("debug-alloc").contains("200 MiB"),
        "{}",
        reason("debug-alloc")
    );
    // The report lists the failed cells.
    let report = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
    assert!(
        report.contains("## Failed cells") && report.contains("debug-hang"),
        "{report}"
    );
}
