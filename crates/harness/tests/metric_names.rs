//! Every metric key a row can hold is known to the load-time check of `report.metrics`
//! and `[[expect]] metric`, and unknown names and option keys are refused.

use std::collections::BTreeSet;
use std::time::Duration;

use reconbench_harness::Experiment;
use reconbench_harness::metric_spec::is_metric_name;

/// One or two cells of every method kind, on a shape with sharp features.
const ALL_KINDS: &str = r#"
    name = "metric_names"
    [[datasets]]
    shape = "box"
    points = 600
    [[perturbations]]
    noise = 0.002
    outliers = 0.02
    [[methods]]
    name = "pf"
    [[methods]]
    name = "gauss-map"
    [[methods]]
    name = "statistical-outliers"
    [[methods]]
    name = "ebt-thinning"
    [[methods]]
    name = "ufm"
    [[methods]]
    name = "ebt"
"#;

#[test]
fn every_key_the_cells_produce_is_a_known_metric_name() {
    let exp = Experiment::parse(ALL_KINDS, "metric_names").unwrap();
    let mut unknown = BTreeSet::new();
    let mut seen = 0;
    for cell in &exp.cells {
        let out = reconbench_harness::cell::execute(cell, Duration::from_secs(60))
            .unwrap_or_else(|e| panic!("{}: {e}", cell.labels.method));
        seen += out.metrics.len();
        unknown.extend(out.metrics.keys().filter(|k| !is_metric_name(k)).cloned());
    }
    assert!(seen > 100, "only {seen} metric values");
    assert!(unknown.is_empty(), "unknown to metric_spec: {unknown:?}");
}

const SMALL: &str = r#"
    [[datasets]]
    shape = "sphere"
    points = 100
    [[methods]]
    name = "pf"
"#;

fn refused(extra: &str) -> String {
    match Experiment::parse(&format!("{SMALL}\n{extra}"), "x") {
        Ok(_) => panic!("accepted: {extra}"),
        Err(e) => {
            assert!(e.is_input(), "{e}");
            e.to_string()
        }
    }
}

#[test]
fn unknown_metric_names_and_option_keys_are_refused_when_the_file_loads() {
    let e = refused("[report]\nmetrics = [\"hausdorf\"]");
    assert!(
        e.contains("unknown metric 'hausdorf'") && e.contains("hausdorff"),
        "{e}"
    );
    let e = refused("[report]\nplot_metrics = [\"normal_mean_dg\"]");
    assert!(e.contains("normal_mean_deg"), "{e}");
    let e = refused("[[expect]]\nmetric = \"chamfer\"\nvalue = 1.0\ntol = \"abs:1\"");
    assert!(e.contains("expect[0].metric"), "{e}");
    let e = refused("[metrics.mesh.distance]\nsampels = 1000");
    assert!(
        e.contains("unknown key 'sampels' in [metrics.mesh.distance]"),
        "{e}"
    );
    let e = refused("[metrics.normals]\nk_neighbours = 3");
    assert!(e.contains("[metrics.normals]"), "{e}");
    // Family members and the known names pass.
    for ok in [
        "fscore_0.02",
        "accuracy_p95_abs",
        "normal_oriented_rms_deg",
        "matching",
        "feature_false_positives",
    ] {
        Experiment::parse(&format!("{SMALL}\n[report]\nmetrics = [\"{ok}\"]"), "x")
            .unwrap_or_else(|e| panic!("{ok}: {e}"));
    }
}
