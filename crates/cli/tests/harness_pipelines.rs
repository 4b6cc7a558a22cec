//! Pipelines in experiment files: steps run in order, outputs flow into the next step,
//! each step is timed, needs are checked when the file loads, filters carry the ground
//! truth along.

mod harness_common;
use harness_common::*;

const PIPES: &str = r#"
    name = "pipes"
    seed = 5
    seeds = 1
    [[datasets]]
    shape = "sphere"
    points = 400
    [[perturbations]]
    outliers = 0.05
    [[methods]]
    steps = ["jet", "priority-front"]
    [[methods]]
    steps = ["gt-normals", "debug-splats"]
    [[methods]]
    steps = [{ name = "statistical-outliers", params = { k = [8, 16] } }, "pf"]
    [[methods]]
    name = "statistical-outliers"
    [[methods]]
    name = "priority-front"
    [metrics.mesh.distance]
    min_samples = 2000
    [report]
    plots = false
    renders = false
"#;

fn row<'a>(rows: &'a [serde_json::Value], label: &str) -> &'a serde_json::Value {
    rows.iter()
        .find(|r| r["labels"]["method"] == label)
        .unwrap_or_else(|| panic!("no row labelled {label}"))
}

#[test]
fn chains_run_and_time_every_step() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "pipes.toml", PIPES);
    let out = dir.path().join("out");
    let text = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-j",
        "2",
    ]));
    assert!(text.contains("0 failed"), "{text}");
    let rows = rows(&out);
    assert_eq!(rows.len(), 6);

    // jet -> priority-front: a mesh, both steps timed, jet's phases prefixed.
    let r = row(&rows, "jet -> priority-front");
    assert_eq!(r["spec"]["pre"][0]["method"], "jet");
    let steps = r["cost"]["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    assert_eq!(steps[0][0], "jet");
    assert_eq!(steps[1][0], "priority-front");
    let phases = r["cost"]["phases"].as_array().unwrap();
    assert!(
        phases
            .iter()
            .any(|p| p[0].as_str().unwrap().starts_with("jet/"))
    );
    assert!(r["metrics"]["chamfer_l1"].as_f64().unwrap() < 0.05, "{r}");

    // The splat reconstructor got the oracle's normals through the chain.
    let r = row(&rows, "gt-normals -> debug-splats");
    assert_eq!(r["status"], "ok", "{r}");
    assert_eq!(r["cost"]["steps"][0][0], "gt-normals");

    // statistical-outliers alone removes most of the generator's outliers and keeps the
    // sphere's points near the surface.
    let r = row(&rows, "statistical-outliers");
    let m = &r["metrics"];
    assert!(m["outliers_removed"].as_f64().unwrap() > 0.3, "{m}");
    assert!(m["points_out"].as_f64().unwrap() < m["points_in"].as_f64().unwrap());
    assert!(m["cloud_max_dist"].as_f64().unwrap() < 1e-9, "{m}");

    // A swept step parameter expands and is labelled with its step.
    for k in [8, 16] {
        let r = row(
            &rows,
            &format!("statistical-outliers -> pf statistical-outliers.k={k}"),
        );
        assert_eq!(r["spec"]["pre"][0]["params"]["k"], k);
        assert!(r["metrics"]["normal_mean_deg"].as_f64().unwrap() < 30.0);
    }

    // A single method's key has no `pre` (so single-method keys did not change).
    let r = row(&rows, "priority-front");
    assert!(r["spec"].get("pre").is_none());
}

#[test]
fn unmet_needs_and_misplaced_reconstructors_fail_when_the_file_loads() {
    let dir = tempfile::tempdir().unwrap();
    for (steps, want) in [
        (r#"["debug-splats"]"#, "needs oriented normals"),
        (r#"["priority-front", "pf"]"#, "only the last step"),
        (r#"["jet", "nope"]"#, "step 2: unknown method 'nope'"),
    ] {
        let exp = write(
            dir.path(),
            "bad.toml",
            &format!(
                "name = \"bad\"\n[[datasets]]\nshape = \"sphere\"\npoints = 100\n[[methods]]\nsteps = {steps}\n"
            ),
        );
        let o = reconbench(&["run", exp.to_str().unwrap(), "--dry-run"]);
        assert_eq!(o.status.code(), Some(2), "{steps}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(want), "{steps}: {err}");
    }
    let exp = write(
        dir.path(),
        "both.toml",
        "[[datasets]]\nshape = \"sphere\"\npoints = 100\n[[methods]]\nname = \"pf\"\nsteps = [\"pf\"]\n",
    );
    let o = reconbench(&["run", exp.to_str().unwrap(), "--dry-run"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not both"));
}
