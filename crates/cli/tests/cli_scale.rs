//! Hostile scales through the real binary (issue 28): 1,000 points on a sphere at
//! 1e-300 … 1e300, near 1e308 and subnormal. Each verb either succeeds with a valid,
//! non-empty result or exits 2 with a one-line message, and every run ends within a few
//! seconds.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use reconbench_geom::{Channel, DVec3, PointCloud, io};

/// Longest a run may take (debug build, 2 shared cores).
const LIMIT: Duration = Duration::from_secs(20);

/// The scales of the issue: factors of a unit sphere, and a label for messages.
fn scales() -> Vec<(String, f64)> {
    let mut v: Vec<(String, f64)> = [1e-300, 1e-160, 1e-60, 1e80, 1e200, 1e300, 1.7e308]
        .iter()
        .map(|&f| (format!("{f:e}"), f))
        .collect();
    // Subnormal: 2^-1040 (coordinates keep about 34 significant bits).
    v.push(("2^-1040".into(), 2f64.powi(-520) * 2f64.powi(-520)));
    v
}

/// 1,000 points of a Fibonacci sphere of radius `f`.
fn sphere(f: f64) -> Vec<DVec3> {
    let n = 1000;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            DVec3::new(r * t.cos(), r * t.sin(), z) * f
        })
        .collect()
}

/// Runs the binary, asserting the time limit.
fn run(args: &[&str]) -> Output {
    let t = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_reconbench"))
        .args(args)
        .output()
        .expect("binary runs");
    assert!(t.elapsed() < LIMIT, "{args:?} took {:?}", t.elapsed());
    out
}

/// Success, or exit 2 with exactly one line on stderr and no panic. Returns success.
fn ok_or_refused(out: &Output, what: &str) -> bool {
    let err = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        return true;
    }
    assert_eq!(out.status.code(), Some(2), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
    false
}

fn write(dir: &Path, name: &str, pts: Vec<DVec3>, labelled: bool) -> String {
    let mut cloud = PointCloud::new(pts).unwrap();
    if labelled {
        let labels = (0..cloud.len() as i64)
            .map(|i| i64::from(i % 10 == 0))
            .collect();
        cloud
            .set_channel("feature", Channel::Label(labels))
            .unwrap();
    }
    let p = dir.join(name);
    io::write_cloud(&p, &cloud).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn delaunay_validates_at_every_scale() {
    let dir = tempfile::tempdir().unwrap();
    for (label, f) in scales() {
        let input = write(dir.path(), "in.ply", sphere(f), false);
        let out = run(&["delaunay", &input]);
        let text = String::from_utf8_lossy(&out.stdout);
        if ok_or_refused(&out, &format!("delaunay at {label}")) {
            // Small inputs are validated by default.
            assert!(text.contains("validated: ok"), "{label}: {text}");
            assert!(text.contains("vertices           1000"), "{label}: {text}");
        }
    }
}

#[test]
fn normal_estimators_give_unit_normals_or_refuse() {
    let dir = tempfile::tempdir().unwrap();
    for (label, f) in scales() {
        let input = write(dir.path(), "in.ply", sphere(f), false);
        for method in ["pf", "jet", "ufm-mesh"] {
            let output = dir.path().join("n.ply");
            let out = run(&[
                "normals",
                "--method",
                method,
                &input,
                "-o",
                output.to_str().unwrap(),
            ]);
            if ok_or_refused(&out, &format!("{method} at {label}")) {
                let c = io::read_cloud(&output).unwrap();
                let n = c.normals().expect("normals written");
                assert_eq!(n.len(), 1000);
                for v in n {
                    assert!((v.length() - 1.0).abs() < 1e-6, "{method} at {label}: {v}");
                }
            }
        }
    }
}

#[test]
fn ufm_gives_a_mesh_on_the_input_points_or_refuses() {
    let dir = tempfile::tempdir().unwrap();
    for (label, f) in scales() {
        let pts = sphere(f);
        let input = write(dir.path(), "in.ply", pts.clone(), false);
        let output = dir.path().join("m.ply");
        let out = run(&[
            "reconstruct",
            "--method",
            "ufm",
            &input,
            "-o",
            output.to_str().unwrap(),
        ]);
        if ok_or_refused(&out, &format!("ufm at {label}")) {
            let m = io::read_mesh(&output).unwrap();
            assert!(m.n_faces() >= 1000, "ufm at {label}: {} faces", m.n_faces());
            assert_eq!(m.vertices(), &pts[..], "ufm at {label}");
        }
    }
}

#[test]
fn eval_features_refuses_clouds_not_at_the_reference_scale() {
    let dir = tempfile::tempdir().unwrap();
    for (label, f) in scales().into_iter().chain([("0.5".to_string(), 0.5)]) {
        let input = write(dir.path(), "in.ply", sphere(f), true);
        let out = run(&["eval-features", "--cloud", &input, "--reference", "box"]);
        let refused = !ok_or_refused(&out, &format!("eval-features at {label}"));
        // At the reference's own scale it evaluates; far below it must refuse.
        if f == 0.5 {
            assert!(!refused, "at the reference scale");
        }
        if f < 1e-100 {
            assert!(refused, "eval-features at {label} must refuse");
        }
    }
}
