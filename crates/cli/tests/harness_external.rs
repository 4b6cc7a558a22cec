//! External programs as methods: tiny shell commands written in the test stand in for a
//! researcher's binary (one that writes a mesh, one that fails, one that hangs, one that
//! writes garbage, one that writes nothing), run through `reconbench run`; no peer needed.
//! The peers themselves run in `peers_run_when_set_up`, skipped when scripts/peers/setup.sh
//! has not been run.

mod harness_common;
use harness_common::*;

/// A command writing a tetrahedron as ASCII OFF (what a user's program would write).
const TETRA: &str = r"printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n' > {output}";

fn experiment(methods: &str) -> String {
    format!(
        r#"
name = "ext"
seeds = 1
timeout = 3
[[datasets]]
shape = "sphere"
points = 300
{methods}
[metrics.mesh.topology]
self_intersections = false
[report]
plots = false
renders = false
"#
    )
}

#[test]
fn external_commands_run_fail_and_stop_like_any_method() {
    let dir = tempfile::tempdir().unwrap();
    let marker = format!("{}.25", 40 + std::process::id() % 50);
    let exp = write(
        dir.path(),
        "ext.toml",
        &experiment(&format!(
            r#"
[[methods]]
name = "external"
label = "tetra"
params = {{ command = "{TETRA} # {{k}} points from {{input}}", output = "off", k = [1, 2] }}
[[methods]]
name = "external"
label = "fails"
params = {{ command = "echo boom-from-the-program >&2; exit 7" }}
[[methods]]
name = "external"
label = "hangs"
params = {{ command = "sleep {marker}" }}
[[methods]]
name = "external"
label = "garbage"
params = {{ command = "echo not a mesh > {{output}}" }}
[[methods]]
name = "external"
label = "silent"
params = {{ command = "true" }}
"#
        )),
    );
    let out = dir.path().join("out");
    let t0 = std::time::Instant::now();
    let text = ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    assert!(t0.elapsed().as_secs() < 60, "{text}");
    let rows = rows(&out);
    assert_eq!(rows.len(), 6, "{text}");
    let find = |label: &str| {
        rows.iter()
            .find(|r| r["labels"]["method"].as_str().unwrap().starts_with(label))
            .unwrap_or_else(|| panic!("no row {label}"))
    };
    // The parameter sweeps like any method's: two cells, both read back as meshes.
    let tetra: Vec<_> = rows
        .iter()
        .filter(|r| r["labels"]["method"].as_str().unwrap().starts_with("tetra"))
        .collect();
    assert_eq!(tetra.len(), 2);
    for r in tetra {
        assert_eq!(r["status"], "ok", "{r}");
        assert_eq!(r["metrics"]["faces"], 4.0, "{r}");
        assert_eq!(r["metrics"]["watertight"], 1.0, "{r}");
    }
    let fails = find("fails");
    assert_eq!(fails["status"], "error", "{fails}");
    let e = fails["error"].as_str().unwrap();
    assert!(
        e.contains("boom-from-the-program") && e.contains("7"),
        "{e}"
    );
    let hangs = find("hangs");
    assert!(
        hangs["status"] == "timeout" || hangs["status"] == "error",
        "{hangs}"
    );
    assert!(
        !std::fs::read_dir("/proc").unwrap().flatten().any(|p| {
            std::fs::read_to_string(p.path().join("cmdline"))
                .is_ok_and(|c| c.contains(&format!("sleep\0{marker}")))
        }),
        "the hanging program outlived its cell"
    );
    let g = find("garbage")["error"].as_str().unwrap().to_string();
    assert!(g.contains("not a readable mesh"), "{g}");
    let s = find("silent")["error"].as_str().unwrap().to_string();
    assert!(s.contains("wrote no output file"), "{s}");
}

#[test]
fn bad_external_entries_are_refused_when_the_file_loads() {
    let dir = tempfile::tempdir().unwrap();
    for (methods, needle) in [
        (
            "[[methods]]\nname = \"external\"\nlabel = \"x\"\nparams = { command = \"prog {input} {radius}\" }",
            "radius",
        ),
        (
            "[[methods]]\nname = \"external\"\nparams = { command = \"prog {input} {output}\" }",
            "label",
        ),
        (
            "[[methods]]\nname = \"external\"\nlabel = \"x\"\nparams = { command = \"\" }",
            "command",
        ),
        (
            "[[methods]]\nname = \"external\"\nlabel = \"x\"\nparams = { command = \"p\", input = \"las\" }",
            "las",
        ),
    ] {
        let exp = write(dir.path(), "bad.toml", &experiment(methods));
        let o = reconbench(&[
            "run",
            exp.to_str().unwrap(),
            "--out",
            dir.path().join("o").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{methods}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{methods}: {err}");
    }
}

#[test]
fn peers_run_when_set_up() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    if !root.join(".peers/venv/bin/python").is_file() {
        eprintln!("skipped: the peers are not set up (scripts/peers/setup.sh)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let run = root.join("scripts/peers/run");
    let exp = write(
        dir.path(),
        "peers.toml",
        &experiment(&format!(
            r#"
[[methods]]
steps = ["gt-normals", {{ name = "external", params = {{ command = "{} open3d poisson {{input}} {{output}} --depth 6" }} }}]
label = "open3d-poisson"
[[methods]]
name = "external"
label = "cgal-afront"
params = {{ command = "{} cgal afront {{input}} {{output}}" }}
"#,
            run.display(),
            run.display()
        ))
        .replace("timeout = 3", "timeout = 120"),
    );
    let out = dir.path().join("out");
    ok(&reconbench(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    for r in rows(&out) {
        assert_eq!(r["status"], "ok", "{r}");
        assert_eq!(r["metrics"]["genus"], 0.0, "{r}");
    }
}
