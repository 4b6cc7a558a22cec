//! The vendored real data sets through the binary: `datasets`, `gen --mesh-input`, and the
//! provenance that `gen` records and the evaluation verbs check.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_reconbench"))
}

fn real(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../datasets/real")
        .join(file)
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("binary runs")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn json(out: &Output) -> serde_json::Value {
    serde_json::from_str(&ok(out)).expect("valid JSON on stdout")
}

/// Exit code 2 with one line on stderr (no panic), returned.
fn bad_input(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    err
}

/// The JSON of the cloud's provenance header comment.
fn provenance(ply: &Path) -> serde_json::Value {
    let bytes = std::fs::read(ply).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .expect("a PLY header");
    let header = String::from_utf8(bytes[..end].to_vec()).unwrap();
    let line = header
        .lines()
        .find_map(|l| l.strip_prefix("comment reconbench-provenance "))
        .unwrap_or_else(|| panic!("no provenance in {header}"));
    serde_json::from_str(line).unwrap()
}

const SETS: [&str; 8] = [
    "fandisk",
    "rocker-arm",
    "bunny",
    "3holes",
    "mechpart",
    "golf-club",
    "distcap",
    "cactus",
];

#[test]
fn info_reports_genus_three_and_watertight_for_mechpart() {
    let f = real("mechpart.ply");
    let v = json(&run(&["info", f.to_str().unwrap(), "--json"]));
    assert_eq!(v["genus"], 3);
    assert_eq!(v["watertight"], true);
}

#[test]
fn datasets_lists_every_vendored_set_with_its_source() {
    let table = ok(&run(&["datasets"]));
    for name in SETS {
        assert!(
            table.lines().any(|l| l.starts_with(&format!("{name} "))),
            "{name} missing:\n{table}"
        );
    }
    assert!(table.contains("libigl/libigl-tutorial-data@c1f9ede3:3holes.off"));
    assert!(table.contains("hhoppe/Mesh-processing-library@0c166b18:demos/data/mechpart.recon.m"));

    let v = json(&run(&["datasets", "--json"]));
    let sets = v.as_array().expect("an array of data sets");
    assert_eq!(
        sets.iter()
            .map(|s| s["name"].as_str().unwrap())
            .collect::<Vec<_>>(),
        SETS
    );
    for s in sets {
        assert!(!s["source_repository"].as_str().unwrap().is_empty());
        let path = Path::new(s["path"].as_str().unwrap());
        assert!(path.is_file(), "{}", path.display());
    }
    let holes = sets.iter().find(|s| s["name"] == "3holes").unwrap();
    assert_eq!(
        (holes["vertices"].as_u64(), holes["genus"].as_u64()),
        (Some(3596), Some(3))
    );
}

#[test]
fn gen_from_a_mesh_takes_its_vertices_or_samples_it_and_records_the_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = real("3holes.ply");
    let mesh = mesh.to_str().unwrap();
    let v = dir.path().join("v.ply");
    ok(&run(&[
        "gen",
        "--mesh-input",
        mesh,
        "--sampler",
        "vertices",
        "-o",
        v.to_str().unwrap(),
    ]));
    let info = json(&run(&["info", v.to_str().unwrap(), "--json"]));
    assert_eq!(info["points"], 3596);
    assert_eq!(info["has_normals"], true);
    let p = provenance(&v);
    assert_eq!(p["source"]["kind"], "mesh");
    assert_eq!(p["source"]["file"], "3holes.ply");
    let hash = format!(
        "{:016x}",
        std::fs::read(real("3holes.ply"))
            .unwrap()
            .iter()
            .fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| (h ^ u64::from(b))
                .wrapping_mul(0x0000_0100_0000_01b3))
    );
    assert_eq!(p["source"]["hash"], hash.as_str());
    assert_eq!(p["sampler"], "vertices");
    assert_eq!(p["seed"], 0);
    assert_eq!(p["version"], env!("CARGO_PKG_VERSION"));

    let s = dir.path().join("s.ply");
    ok(&run(&[
        "gen",
        "--mesh-input",
        mesh,
        "--points",
        "500",
        "--noise",
        "gaussian:sigma=0.001",
        "--seed",
        "3",
        "-o",
        s.to_str().unwrap(),
    ]));
    let info = json(&run(&["info", s.to_str().unwrap(), "--json"]));
    assert_eq!(info["points"], 500);
    let p = provenance(&s);
    assert_eq!(
        (p["points"].as_u64(), p["seed"].as_u64()),
        (Some(500), Some(3))
    );
    assert_eq!(p["perturbations"][0], "gaussian:sigma=0.001,rel=diagonal");

    let t = dir.path().join("t.ply");
    ok(&run(&[
        "gen",
        "torus",
        "--points",
        "100",
        "-o",
        t.to_str().unwrap(),
    ]));
    assert_eq!(provenance(&t)["source"]["spec"], "torus:R=2,r=1");
}

#[test]
fn gen_refuses_a_shape_with_a_mesh_input_and_names_a_missing_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("o.ply");
    let o = o.to_str().unwrap();
    let mesh = real("3holes.ply");
    let mesh = mesh.to_str().unwrap();
    let e = bad_input(&run(&["gen", "torus", "--mesh-input", mesh, "-o", o]));
    assert!(e.contains("--mesh-input"), "{e}");
    bad_input(&run(&["gen", "-o", o]));
    let e = bad_input(&run(&[
        "gen",
        "--mesh-input",
        mesh,
        "--sampler",
        "vertices",
        "--points",
        "10",
        "-o",
        o,
    ]));
    assert!(e.contains("--points"), "{e}");
    let missing = dir.path().join("no-such-mesh.obj");
    let e = bad_input(&run(&[
        "gen",
        "--mesh-input",
        missing.to_str().unwrap(),
        "-o",
        o,
    ]));
    assert!(e.contains("no-such-mesh.obj"), "{e}");
    assert!(!Path::new(o).exists());
}

#[test]
fn evaluation_refuses_a_cloud_generated_from_another_reference() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_string();
    ok(&run(&[
        "gen",
        "sphere",
        "--points",
        "300",
        "-o",
        &p("s.ply"),
    ]));
    ok(&run(&[
        "gen",
        "sphere",
        "--mesh",
        "--resolution",
        "24",
        "-o",
        &p("m.ply"),
    ]));
    let holes = real("3holes.ply");
    let holes = holes.to_str().unwrap();
    let mechpart = real("mechpart.ply");
    let mechpart = mechpart.to_str().unwrap();
    ok(&run(&[
        "gen",
        "--mesh-input",
        holes,
        "--points",
        "300",
        "-o",
        &p("h.ply"),
    ]));

    let eval = |input: &str, reference: &str| {
        run(&[
            "eval",
            "--mesh",
            &p("m.ply"),
            "--reference",
            reference,
            "--input",
            input,
            "--samples",
            "1000",
        ])
    };
    let e = bad_input(&eval(&p("s.ply"), "torus"));
    assert!(
        e.contains("sphere:r=1") && e.contains("torus:R=2,r=1"),
        "{e}"
    );
    let e = bad_input(&eval(&p("h.ply"), mechpart));
    assert!(
        e.contains("3holes.ply") && e.contains("mechpart.ply"),
        "{e}"
    );
    // The same shape spelled differently, and the same mesh file, pass.
    ok(&eval(&p("s.ply"), "sphere:r=1"));
    ok(&eval(&p("h.ply"), holes));

    let e = bad_input(&run(&[
        "eval-normals",
        "--cloud",
        &p("s.ply"),
        "--gt-cloud",
        &p("s.ply"),
        "--reference",
        "box",
    ]));
    assert!(e.contains("box:a=1,b=1,c=1"), "{e}");
    bad_input(&run(&[
        "eval-features",
        "--cloud",
        &p("s.ply"),
        "--reference",
        "box",
        "--gt-cloud",
        &p("s.ply"),
    ]));
}
