//! Acceptance tests of the foundation verbs through the real binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_reconbench"))
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../geom/tests/corpus")
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("binary runs")
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON on stdout")
}

#[test]
fn info_reports_genus_two_for_the_binary_double_torus() {
    let f = corpus().join("good/double_torus.ply");
    let v = json(&run(&["info", f.to_str().unwrap(), "--json"]));
    assert_eq!(v["genus"], 2);
    assert_eq!(v["components"], 1);
    assert_eq!(v["watertight"], true);
    assert_eq!(v["euler"], -2);
    for key in [
        "vertices",
        "faces",
        "boundary_edges",
        "boundary_loops",
        "non_manifold_edges",
        "non_manifold_vertices",
        "orientable",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
}

#[test]
fn every_broken_file_exits_2_with_one_line_naming_the_file() {
    let dir = corpus().join("broken");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let out = run(&["info", path.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {err}", path.display());
        assert!(!err.contains("panicked"), "{}: {err}", path.display());
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{}: {err}",
            path.display()
        );
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(err.contains(name), "error should name the file: {err}");
        n += 1;
    }
    assert!(n >= 15, "corpus has only {n} files");
}

#[test]
fn missing_file_and_unknown_extension_exit_2() {
    assert_eq!(run(&["info", "/nonexistent/x.ply"]).status.code(), Some(2));
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("a.unknown");
    std::fs::write(&f, "1 2 3\n").unwrap();
    assert_eq!(run(&["info", f.to_str().unwrap()]).status.code(), Some(2));
}

#[test]
fn convert_round_trips_the_double_torus_through_obj_and_ascii_ply() {
    let dir = tempfile::tempdir().unwrap();
    let src = corpus().join("good/double_torus.ply");
    let obj = dir.path().join("m.obj");
    let ply = dir.path().join("m.ply");
    assert!(
        run(&["convert", src.to_str().unwrap(), obj.to_str().unwrap()])
            .status
            .success()
    );
    let out = run(&[
        "convert",
        obj.to_str().unwrap(),
        ply.to_str().unwrap(),
        "--ply-encoding",
        "ascii",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        std::fs::read_to_string(&ply)
            .unwrap()
            .starts_with("ply\nformat ascii 1.0")
    );
    let v = json(&run(&["info", ply.to_str().unwrap(), "--json"]));
    assert_eq!(
        (v["genus"].as_u64(), v["faces"].as_u64()),
        (Some(2), Some(1156))
    );
}

#[test]
fn gen_is_deterministic_and_delaunay_and_eval_accept_its_output() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.ply");
    let b = dir.path().join("b.ply");
    for p in [&a, &b] {
        let out = run(&[
            "gen",
            "sphere",
            "--points",
            "2000",
            "--noise",
            "gaussian:sigma=0.001",
            "--seed",
            "9",
            "-o",
            p.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());

    let d = json(&run(&[
        "delaunay",
        a.to_str().unwrap(),
        "--validate",
        "--json",
    ]));
    assert_eq!(d["vertices"], 2000);

    let m = dir.path().join("ref.ply");
    assert!(
        run(&[
            "gen",
            "sphere",
            "--mesh",
            "--resolution",
            "48",
            "-o",
            m.to_str().unwrap()
        ])
        .status
        .success()
    );
    let e = json(&run(&[
        "eval",
        "--mesh",
        m.to_str().unwrap(),
        "--reference",
        "sphere",
        "--samples",
        "5000",
        "--json",
    ]));
    assert_eq!(e["watertight"], true);
    assert_eq!(e["genus"], 0);
    assert!(e["hausdorff"].as_f64().unwrap() < 0.01);
}

#[test]
fn bad_parameters_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("x.ply");
    let o = o.to_str().unwrap();
    assert_eq!(
        run(&["gen", "no-such-shape", "-o", o]).status.code(),
        Some(2)
    );
    assert_eq!(
        run(&["gen", "torus", "--noise", "bogus:x=1", "-o", o])
            .status
            .code(),
        Some(2)
    );
    assert_eq!(
        run(&["eval", "--mesh", "/nonexistent.ply", "--reference", "torus"])
            .status
            .code(),
        Some(2)
    );
}
