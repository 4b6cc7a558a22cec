//! CI's regression gate: the README's quickstart experiment runs and matches the
//! committed baseline `results/baselines/quickstart.json` (refresh it with
//! `reconbench baseline save results/quickstart -o results/baselines/quickstart.json`
//! after an intended change of a method, a generator or a metric).

mod harness_common;
use harness_common::*;

use std::path::Path;

#[test]
fn quickstart_matches_the_committed_baseline() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let exp = root.join("experiments/quickstart.toml");
    let baseline = root.join("results/baselines/quickstart.json");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("quickstart");
    let text = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-report",
    ]));
    assert!(text.contains("0 failed"), "{text}");
    let cmp = reconbench(&[
        "compare",
        "--baseline",
        baseline.to_str().unwrap(),
        "--current",
        out.to_str().unwrap(),
    ]);
    assert!(
        cmp.status.success(),
        "quickstart regressed against {}:\n{}\n{}\nIf the change is intended, refresh the baseline \
         (see this test's doc comment).",
        baseline.display(),
        String::from_utf8_lossy(&cmp.stdout),
        String::from_utf8_lossy(&cmp.stderr)
    );
}
