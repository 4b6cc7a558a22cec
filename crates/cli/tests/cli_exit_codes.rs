//! Exit codes of bad input through the real binary (issue 28): every experiment file the
//! issue lists is refused by `run --dry-run`, and a method that refuses its cloud (too
//! few points, all coplanar, a result that would collapse to nothing on distinct
//! points) exits 2, not 1; each with one line on stderr naming the file, quickly.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Wall-clock bound of one refused run: loading and checking take milliseconds; the
/// margin is for process start-up on a loaded machine. A file accepted and expanded
/// (10^7 cells, 10^12 points) would take far longer or run out of memory.
const BUDGET: Duration = Duration::from_secs(3);

fn run(args: &[&str], cwd: &Path) -> (Output, Duration) {
    let t = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_reconbench"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("binary runs");
    (out, t.elapsed())
}

/// Exit code 2, one line on stderr holding every one of `want`, in time.
fn check_refused(what: &str, (out, took): &(Output, Duration), want: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err:?}");
    for w in want {
        assert!(err.contains(w), "{what}: no '{w}' in {err:?}");
    }
    assert!(*took < BUDGET, "{what} took {took:?}");
}

const DATA: &str = "[[datasets]]\nname = \"s\"\nshape = \"sphere\"\npoints = 200\n";
const METHOD: &str = "[[methods]]\nname = \"pf\"\n";

#[test]
fn every_listed_experiment_file_is_refused_by_a_dry_run() {
    let dir = tempfile::tempdir().unwrap();
    let long = "a".repeat(300);
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "points_neg",
            DATA.replace("points = 200", "points = -100") + METHOD,
            "points = -100",
        ),
        (
            "points_1e12",
            DATA.replace("points = 200", "points = 1000000000000") + METHOD,
            "points",
        ),
        (
            "points_i64max",
            DATA.replace("points = 200", "points = 9223372036854775807") + METHOD,
            "points",
        ),
        (
            "grid",
            DATA.replace(
                "points = 200",
                "points = 200\nsampler = \"grid:nu=1000000,nv=1000000\"",
            ) + METHOD,
            "1000000 x 1000000 grid",
        ),
        (
            "duplicate",
            format!("{DATA}[[perturbations]]\nduplicate = 1e9\n{METHOD}"),
            "points added per input point",
        ),
        (
            "outliers",
            format!("{DATA}[[perturbations]]\noutliers = 1e9\n{METHOD}"),
            "points added per input point",
        ),
        (
            "min_samples",
            format!("{DATA}{METHOD}[metrics.mesh.distance]\nmin_samples = 100000000000\n"),
            "need about",
        ),
        (
            "k",
            format!("{DATA}[[methods]]\nname = \"pf\"\nparams = {{ k = 1000000000000 }}\n"),
            "neighbours per point",
        ),
        (
            "timeout",
            format!("timeout = 1e300\n{DATA}{METHOD}"),
            "timeout",
        ),
        (
            "memory",
            format!("memory_limit_mib = 0\n{DATA}{METHOD}"),
            "memory_limit_mib = 0",
        ),
        (
            "seeds",
            format!("seeds = 10000000\n{DATA}{METHOD}"),
            "seeds = 10000000",
        ),
        ("dotdot", format!("name = \"..\"\n{DATA}{METHOD}"), "'..'"),
        ("dot", format!("name = \".\"\n{DATA}{METHOD}"), "'.'"),
        (
            "long_name",
            format!("name = \"{long}\"\n{DATA}{METHOD}"),
            "experiment name",
        ),
        (
            "metrics_key",
            format!("{DATA}{METHOD}[metrics.mesh]\nbogus_key = 1\n"),
            "bogus_key",
        ),
        (
            "report_metric",
            format!("{DATA}{METHOD}[report]\nmetrics = [\"chamfer_l7\"]\n"),
            "chamfer_l7",
        ),
        (
            "expect_where",
            format!(
                "{DATA}{METHOD}[[expect]]\nwhere = {{ methd = \"pf\" }}\n\
                 metric = \"normal_mean_deg\"\nvalue = 1.0\n"
            ),
            "methd",
        ),
        (
            "expect_tol",
            format!(
                "{DATA}{METHOD}[[expect]]\nwhere = {{ method = \"pf\" }}\n\
                 metric = \"normal_mean_deg\"\nvalue = 1.0\ntol = \"rel:abc\"\n"
            ),
            "rel:abc",
        ),
    ];
    for (stem, text, want) in &cases {
        let path = dir.path().join(format!("{stem}.toml"));
        std::fs::write(&path, text).unwrap();
        let p = path.to_str().unwrap();
        let r = run(&["run", "--dry-run", p], dir.path());
        check_refused(stem, &r, &[p, want]);
    }
    let path = dir.path().join("binary.toml");
    std::fs::write(&path, b"name = \"x\"\n# \xff\xfe\n").unwrap();
    let p = path.to_str().unwrap();
    let r = run(&["run", "--dry-run", p], dir.path());
    check_refused("non-UTF-8", &r, &[p, "not UTF-8"]);
    // Nothing was written next to the files or in the working directory.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| !n.to_string_lossy().ends_with(".toml"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    // The same grid with honest values runs dry (the refusals above are the values').
    let path = dir.path().join("ok.toml");
    std::fs::write(&path, format!("{DATA}{METHOD}")).unwrap();
    let (out, _) = run(&["run", "--dry-run", path.to_str().unwrap()], dir.path());
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_method_refusing_its_cloud_is_bad_input_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.ply");
    let out = out.to_str().unwrap();
    std::fs::write(d.join("two.xyz"), "0 0 0 0 0 1\n1 0 0 0 0 1\n").unwrap();
    let plane: String = (0..36)
        .map(|i| {
            format!(
                "{} {} 0\n",
                (i % 6) as f64 * 0.1,
                (i / 6) as f64 * 0.1 + 0.01 * (i % 6) as f64
            )
        })
        .collect();
    std::fs::write(d.join("plane.xyz"), plane).unwrap();
    let (g, _) = run(
        &[
            "gen",
            "sphere",
            "--points",
            "300",
            "--seed",
            "1",
            "-o",
            "sphere.ply",
        ],
        d,
    );
    assert!(g.status.success(), "{}", String::from_utf8_lossy(&g.stderr));
    for (what, args, want) in [
        (
            "ball-pivoting on 2 points",
            vec!["reconstruct", "--method", "ball-pivoting", "two.xyz"],
            vec!["two.xyz", "needs at least 3 points"],
        ),
        (
            "poisson on 2 points",
            vec!["reconstruct", "--method", "poisson", "two.xyz"],
            vec!["two.xyz", "needs at least 3 points"],
        ),
        (
            "ufm on a plane",
            vec!["reconstruct", "--method", "ufm", "plane.xyz"],
            vec!["plane.xyz", "coplanar"],
        ),
        (
            "cocone on a plane",
            vec!["reconstruct", "--method", "cocone", "plane.xyz"],
            vec!["plane.xyz", "coplanar"],
        ),
        (
            // A ball far smaller than the spacing touches no three points: the mesh
            // would be empty on a sphere, which is refused, not written.
            "ball-pivoting collapsing to nothing",
            vec![
                "reconstruct",
                "--method",
                "ball-pivoting",
                "sphere.ply",
                "--set",
                "radii_spacing=[0.01]",
            ],
            vec!["sphere.ply", "no face on 300 points"],
        ),
    ] {
        let mut args = args;
        args.extend(["-o", out]);
        check_refused(what, &run(&args, d), &want);
        assert!(!Path::new(out).exists(), "{what}: wrote {out}");
    }
}

#[test]
fn evaluation_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (g, _) = run(
        &[
            "gen", "box", "--points", "500", "--seed", "1", "-o", "box.ply",
        ],
        d,
    );
    assert!(g.status.success(), "{}", String::from_utf8_lossy(&g.stderr));
    // Labels on a cloud 1e9 times smaller than the box it is compared with: refused
    // (nothing lies near the curves), naming the cloud.
    let (f, _) = run(
        &[
            "features",
            "--method",
            "gt-features",
            "box.ply",
            "-o",
            "lab.ply",
        ],
        d,
    );
    assert!(f.status.success(), "{}", String::from_utf8_lossy(&f.stderr));
    let (c, _) = run(
        &[
            "convert",
            "lab.ply",
            "lab.ply.txt.ply",
            "--ply-encoding",
            "ascii",
        ],
        d,
    );
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    let text = std::fs::read_to_string(d.join("lab.ply.txt.ply")).unwrap();
    let (head, body) = text.split_once("end_header\n").unwrap();
    let scaled: String = body
        .lines()
        .map(|l| {
            let mut v: Vec<String> = l.split_whitespace().map(str::to_string).collect();
            for c in v.iter_mut().take(3) {
                *c = format!("{:e}", c.parse::<f64>().unwrap() * 1e-9);
            }
            v.join(" ") + "\n"
        })
        .collect();
    std::fs::write(d.join("tiny.ply"), format!("{head}end_header\n{scaled}")).unwrap();
    let r = run(
        &["eval-features", "--cloud", "tiny.ply", "--reference", "box"],
        d,
    );
    check_refused("eval-features at 1e-9", &r, &["tiny.ply"]);
}

#[test]
fn a_second_run_into_a_held_directory_refuses_naming_the_holder_and_touches_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("e.toml"),
        "name = \"e\"\n[[datasets]]\nshape = \"sphere\"\npoints = 100\n\
         [[methods]]\nname = \"gt-normals\"\n[report]\nplots = false\nrenders = false\n",
    )
    .unwrap();
    let (first, _) = run(&["run", "e.toml", "--out", "out", "--no-report"], d);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let results = d.join("out/results.jsonl");
    let before = std::fs::read(&results).unwrap();
    // A live run holds the directory (PID 1 always exists).
    std::fs::write(d.join("out/results.jsonl.lock"), "1\n").unwrap();
    for extra in [&[][..], &["--fresh"][..], &["--resume"][..]] {
        let mut args = vec!["run", "e.toml", "--out", "out", "--no-report"];
        args.extend(extra);
        let what = format!("run {extra:?} while held");
        check_refused(&what, &run(&args, d), &["PID 1", "out"]);
        assert_eq!(std::fs::read(&results).unwrap(), before, "{what}");
        assert!(!d.join("out/previous").exists(), "{what}: moved aside");
    }
}
