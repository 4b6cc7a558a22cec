//! Same seed gives identical result files apart from `cost`; tables, plots, renders and
//! the report are written; published figures are checked; baselines catch regressions;
//! shards merge into the full result.

mod harness_common;
use harness_common::*;

use std::path::Path;

const EXP: &str = r#"
    name = "small"
    seed = 11
    seeds = 2
    [[datasets]]
    shape = "box"
    points = [300, 600]
    [[perturbations]]
    noise = [0.0, 0.005]
    [[methods]]
    name = "gt-normals"
    [[methods]]
    name = "gt-features"
    [[methods]]
    name = "reference-mesh"
    params = { resolution = [8, 16] }
    [metrics.mesh.distance]
    min_samples = 2000
    [report]
    plot_size = [400, 300]
    render_size = 64
    [[expect]]
    where = { method = "gt-features", dataset = "box n=300" }
    metric = "feature_f1"
    value = 1.0
    source = "floor"
    tol = "abs:1e-9"
    [[expect]]
    where = { method = "reference-mesh", "params.resolution" = 8, noise = 0.0 }
    metric = "topology_ok"
    value = 0.5
    source = "deliberately wrong"
"#;

fn run(exp: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-j",
        "2",
    ];
    args.extend_from_slice(extra);
    ok(&reconbench(&args))
}

#[test]
fn same_seed_same_rows_and_every_output_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "small.toml", EXP);
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let stdout = run(&exp, &a, &[]);
    assert!(
        stdout.contains("32 cells") && stdout.contains("0 failed"),
        "{stdout}"
    );
    assert!(
        stdout.contains("published figures: 1 outside tolerance"),
        "{stdout}"
    );
    run(&exp, &b, &[]);
    assert_eq!(rows(&a).len(), 32);
    assert_same_rows(&a, &b);
    // Tables.
    for kind in ["normals", "features", "reconstruct"] {
        for ext in ["md", "tex", "csv"] {
            let p = a.join("tables").join(format!("{kind}.{ext}"));
            assert!(p.exists(), "{}", p.display());
        }
    }
    let tex = std::fs::read_to_string(a.join("tables/reconstruct.tex")).unwrap();
    // Every method here is an oracle: shown in italics, none counted as best.
    assert!(
        tex.contains("\\toprule")
            && tex.contains("\\bottomrule")
            && tex.contains("\\textit{reference-mesh")
            && !tex.contains("\\textbf{"),
        "{tex}"
    );
    let csv = std::fs::read_to_string(a.join("tables/reconstruct.csv")).unwrap();
    assert!(
        csv.starts_with("dataset,perturbation,method,ok,cells,chamfer_l1_mean"),
        "{csv}"
    );
    // Plots at the requested size, in both formats; the time-vs-size plot exists.
    let plots = a.join("plots");
    let png = plots.join("reconstruct_chamfer-l1_vs_noise_box-n-300.png");
    assert_eq!(png_size(&png), (400, 300));
    assert!(
        plots
            .join("reconstruct_chamfer-l1_vs_noise_box-n-300.svg")
            .exists()
    );
    assert_eq!(
        png_size(&plots.join("normals_time_vs_size.png")),
        (400, 300)
    );
    assert!(plots.join("normals_errors_box_box-n-300.png").exists());
    // Renders: the data of each reconstruction of seed 0, and one image per
    // configuration with its two methods side by side, three views each.
    let renders: Vec<_> = std::fs::read_dir(a.join("renders"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    let ext = |e: &str| -> Vec<&std::path::PathBuf> {
        renders
            .iter()
            .filter(|p| p.extension().is_some_and(|x| x == e))
            .collect()
    };
    assert_eq!(ext("rbr").len(), 8, "2 sizes x 2 noise x 2 resolutions");
    let images = ext("png");
    assert_eq!(images.len(), 4, "2 sizes x 2 noise");
    let (w, h) = png_size(images[0]);
    assert!(w > 2 * 64 && h > 3 * 64, "{w} x {h}");
    // The report links everything and flags the miss.
    let report = std::fs::read_to_string(a.join("report.md")).unwrap();
    for needle in [
        "## Published figures",
        "**MISS**",
        "| ok |",
        "tables/normals.tex",
        "plots/",
        "renders/",
        "manifest.json",
    ] {
        assert!(report.contains(needle), "report lacks {needle}:\n{report}");
    }
    // Manifest provenance.
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("manifest.json")).unwrap()).unwrap();
    let run0 = &m["runs"][0];
    for k in ["git_commit", "rustc", "cpu_model", "started"] {
        assert!(run0[k].is_string(), "manifest lacks {k}");
    }
    assert_eq!(m["cells"].as_array().unwrap().len(), 32);
    assert_eq!(m["threads_per_worker"], 1);
    // --strict turns the miss into exit code 1; `report` regenerates.
    let strict = reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        a.to_str().unwrap(),
        "--resume",
        "--strict",
    ]);
    assert_eq!(strict.status.code(), Some(1));
    ok(&reconbench(&["report", a.to_str().unwrap()]));
}

#[test]
fn baseline_compare_and_shards() {
    let dir = tempfile::tempdir().unwrap();
    let exp = write(dir.path(), "small.toml", EXP);
    let full = dir.path().join("full");
    run(&exp, &full, &["--no-report"]);
    let base = dir.path().join("base.json");
    ok(&reconbench(&[
        "baseline",
        "save",
        full.to_str().unwrap(),
        "-o",
        base.to_str().unwrap(),
    ]));
    let same = ok(&reconbench(&[
        "compare",
        "--baseline",
        base.to_str().unwrap(),
        "--current",
        full.to_str().unwrap(),
    ]));
    assert!(same.contains("0 regressed"), "{same}");
    // A baseline that was better on chamfer_l1 makes the current run a regression (the
    // box's reference mesh is exact, so make the baseline better by an absolute amount).
    let mut b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&base).unwrap()).unwrap();
    for c in b["configs"].as_array_mut().unwrap() {
        if let Some(v) = c["metrics"].get_mut("chamfer_l1") {
            *v = serde_json::json!(v.as_f64().unwrap() - 0.01);
        }
    }
    std::fs::write(&base, serde_json::to_string(&b).unwrap()).unwrap();
    let worse = reconbench(&[
        "compare",
        "--baseline",
        base.to_str().unwrap(),
        "--current",
        full.to_str().unwrap(),
    ]);
    assert_eq!(worse.status.code(), Some(1));
    let text = String::from_utf8_lossy(&worse.stdout);
    assert!(
        text.contains("REGRESSED") && text.contains("chamfer_l1"),
        "{text}"
    );
    // A loose tolerance accepts it.
    ok(&reconbench(&[
        "compare",
        "--baseline",
        base.to_str().unwrap(),
        "--current",
        full.to_str().unwrap(),
        "--tol",
        "chamfer_l1=rel:2",
    ]));

    // Shards 0/3, 1/3, 2/3 into one directory, then merge = the full run.
    let sh = dir.path().join("sharded");
    for i in 0..3 {
        let s = format!("{i}/3");
        run(&exp, &sh, &["--shard", &s]);
    }
    assert!(!sh.join("results.jsonl").exists());
    let merged = ok(&reconbench(&[
        "merge",
        sh.to_str().unwrap(),
        "--out",
        sh.to_str().unwrap(),
    ]));
    assert!(merged.contains("32 written"), "{merged}");
    assert_same_rows(&sh, &full);
    assert!(sh.join("report.md").exists());
    // Merged elsewhere (shards from other machines), the render data comes along and
    // the report draws the renders from it.
    let elsewhere = dir.path().join("elsewhere");
    ok(&reconbench(&[
        "merge",
        sh.to_str().unwrap(),
        "--out",
        elsewhere.to_str().unwrap(),
    ]));
    let count = |ext: &str| {
        std::fs::read_dir(elsewhere.join("renders"))
            .unwrap()
            .flatten()
            .filter(|e| e.path().extension().is_some_and(|x| x == ext))
            .count()
    };
    assert_eq!((count("rbr"), count("png")), (8, 4));
    let report = std::fs::read_to_string(elsewhere.join("report.md")).unwrap();
    assert!(
        report.contains("## Renders") && !report.contains("No render data"),
        "{report}"
    );
}
