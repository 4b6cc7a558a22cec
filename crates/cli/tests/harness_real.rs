//! Real data end to end: an experiment over two vendored real sets (one as its own
//! vertices, one sampled) and a point-cloud file, with reconstructors, a normal estimator
//! and the oracles; the mesh is exact ground truth, the cloud has none.

mod harness_common;
use harness_common::*;

fn real(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../datasets/real")
        .join(name);
    p.to_str().unwrap().to_string()
}

fn row<'a>(rows: &'a [serde_json::Value], data: &str, method: &str) -> &'a serde_json::Value {
    rows.iter()
        .find(|r| r["labels"]["dataset"] == data && r["labels"]["method"] == method)
        .unwrap_or_else(|| panic!("no row {data} / {method}"))
}

#[test]
fn real_sets_and_a_cloud_run_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(
        dir.path(),
        "real.toml",
        &format!(
            r#"
    name = "real"
    seeds = 1
    [[datasets]]
    real = "3holes"
    [[datasets]]
    real = "fandisk"
    input = "sample"
    points = 1500
    [[datasets]]
    name = "cactus"
    cloud = "{}"
    [[methods]]
    name = "ufm"
    label = "ufm-fold"
    params = {{ max_fold_deg = 90.0, escapes = 20 }}
    [[methods]]
    name = "pf"
    [[methods]]
    name = "gt-normals"
    [[methods]]
    name = "reference-mesh"
    [metrics.mesh.topology]
    self_intersections = false
    [report]
    plots = false
    renders = false
"#,
            real("cactus.ply")
        ),
    );
    let out = dir.path().join("out");
    let text = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let rows = rows(&out);
    assert_eq!(rows.len(), 12);
    // Only the oracles on the cloud fail: they have no ground truth to hand out.
    let failed: Vec<String> = rows
        .iter()
        .filter(|r| r["status"] != "ok")
        .map(|r| format!("{} / {}", r["labels"]["dataset"], r["labels"]["method"]))
        .collect();
    assert_eq!(
        failed,
        [
            "\"cactus\" / \"gt-normals\"",
            "\"cactus\" / \"reference-mesh\""
        ],
        "{text}"
    );

    // 3holes as its own vertices: UFM with the fold and escape extensions closes it with
    // the right genus, every vertex used.
    let m = &row(&rows, "3holes", "ufm-fold")["metrics"];
    assert_eq!(m["input_points"], 3596.0, "{m}");
    assert_eq!(m["watertight"], 1.0, "{m}");
    assert_eq!(m["genus"], 3.0, "{m}");
    assert_eq!(m["delta_f"], 0.0, "{m}");
    assert_eq!(m["topology_ok"], 1.0, "{m}");
    // The oracle's normals are the ground truth (area-weighted vertex normals): zero error.
    let m = &row(&rows, "3holes", "gt-normals")["metrics"];
    // (acos rounds: identical unit vectors read as up to ~1e-6 degrees apart)
    assert!(m["normal_max_deg"].as_f64().unwrap() < 1e-5, "{m}");
    // The reference mesh of a mesh set is the mesh: no distance to itself.
    let m = &row(&rows, "3holes", "reference-mesh")["metrics"];
    assert!(m["hausdorff"].as_f64().unwrap() < 1e-9, "{m}");
    assert_eq!(m["topology_ok"], 1.0, "{m}");
    // Fandisk sampled: 1500 points, its sharp edges are the feature ground truth.
    let m = &row(&rows, "fandisk", "pf")["metrics"];
    assert_eq!(m["input_points"], 1500.0, "{m}");
    let e = m["normal_mean_deg"].as_f64().unwrap();
    assert!(e > 0.5 && e < 30.0, "{m}");
    let m = &row(&rows, "fandisk", "reference-mesh")["metrics"];
    assert!(m["feature_recovery"].as_f64().unwrap() > 0.99, "{m}");

    // The cloud: reconstructions measured without ground truth, nothing invented.
    let m = &row(&rows, "cactus", "ufm-fold")["metrics"];
    assert!(m["faces"].as_f64().unwrap() > 1000.0, "{m}");
    for absent in ["chamfer_l1", "hausdorff", "delta_f", "topology_ok"] {
        assert!(
            m.get(absent).is_none(),
            "{absent} without ground truth: {m}"
        );
    }
    let m = &row(&rows, "cactus", "pf")["metrics"];
    assert!(m.get("normal_mean_deg").is_none(), "{m}");

    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("## Data"), "{report}");
    assert!(report.contains("cactus has no ground truth"), "{report}");
    assert!(
        report.contains("| 3holes | real `3holes.ply` | mesh vertices | 3596 |"),
        "{report}"
    );
}
