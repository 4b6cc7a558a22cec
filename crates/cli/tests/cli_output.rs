//! What the one-shot verbs print is legible: no e-notation for ordinary values, each
//! distance once with its unit, unreferenced vertices counted, long series summarised.

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_reconbench");

fn run(args: &[&str]) -> String {
    let out = Command::new(BIN).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn reconstruct_and_eval_print_legible_values() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("torus.ply");
    let mesh = dir.path().join("mesh.ply");
    let (c, m) = (cloud.to_str().unwrap(), mesh.to_str().unwrap());
    run(&["gen", "torus", "--points", "1500", "--seed", "1", "-o", c]);
    let rec = run(&["reconstruct", "--method", "ufm", c, "-o", m]);
    assert!(rec.contains("unreferenced vertices 0"), "{rec}");
    assert!(
        rec.lines().all(|l| l.len() < 240),
        "a raw series or text was printed whole:\n{rec}"
    );
    let ev = run(&["eval", "--mesh", m, "--reference", "torus"]);
    assert!(!ev.contains("e-") && !ev.contains("e2"), "{ev}");
    assert!(!ev.lines().any(|l| l.starts_with("hausdorff_abs")), "{ev}");
    let h = ev.lines().find(|l| l.starts_with("hausdorff ")).unwrap();
    assert!(
        h.contains("x diagonal") && h.contains("(input units)"),
        "{h}"
    );
}
