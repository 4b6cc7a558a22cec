//! `list`, bad-input errors and the one-shot verbs.

mod harness_common;
use harness_common::*;

#[test]
fn list_shows_methods_params_and_seed_sections() {
    let text = ok(&reconbench(&["list"]));
    assert!(
        text.contains("gt-normals")
            && text.contains("reference-mesh")
            && text.contains("resolution = 64"),
        "{text}"
    );
    assert!(!text.contains("debug-panic"));
    let all = ok(&reconbench(&["list", "--all", "--json"]));
    let v: serde_json::Value = serde_json::from_str(&all).unwrap();
    let names: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"debug-panic") && names.contains(&"gt-features"),
        "{names:?}"
    );
    for m in v.as_array().unwrap() {
        assert!(m["seed"].is_string() && m["kind"].is_string() && m["params"].is_array());
    }
}

#[test]
fn unknown_keys_and_methods_are_input_errors_listing_valid_ones() {
    let dir = tempfile::tempdir().unwrap();
    let bad = write(
        dir.path(),
        "bad.toml",
        "[[datasets]]\nshape = \"sphere\"\npoints = 10\n[[methods]]\nname = \"nope\"\n",
    );
    let out = reconbench(&[
        "run",
        bad.to_str().unwrap(),
        "--out",
        dir.path().join("o").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("nope") && err.contains("gt-normals"), "{err}");
    let typo = write(dir.path(), "typo.toml", "seedz = 3\n");
    let out = reconbench(&["run", typo.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("seeds"));
    let bad_pert = write(
        dir.path(),
        "p.toml",
        "[[datasets]]\nshape = \"sphere\"\npoints = 10\n[[perturbations]]\nnoize = 0.1\n[[methods]]\nname = \"gt-normals\"\n",
    );
    let out = reconbench(&["run", bad_pert.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("noise"));
    // A file that is not UTF-8 text, and a missing one, are named input errors.
    let binary = dir.path().join("binary.toml");
    std::fs::write(&binary, [0xff, 0xfe, 0x00, 0x41]).unwrap();
    for (f, want) in [
        (binary.clone(), "not UTF-8"),
        (dir.path().join("missing.toml"), "no such file"),
    ] {
        let out = reconbench(&["run", f.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{}", f.display());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(want) && err.contains(f.file_name().unwrap().to_str().unwrap()),
            "{err}"
        );
    }
}

#[test]
fn one_shot_verbs_write_their_outputs() {
    let dir = tempfile::tempdir().unwrap();
    // A tiny cloud with normals (ASCII PLY) on the unit sphere.
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty double x\nproperty double y\nproperty double z\nproperty double nx\nproperty double ny\nproperty double nz\nend_header\n",
    );
    for (x, y, z) in [
        (1, 0, 0),
        (-1, 0, 0),
        (0, 1, 0),
        (0, -1, 0),
        (0, 0, 1),
        (0, 0, -1),
    ] {
        ply.push_str(&format!("{x} {y} {z} {x} {y} {z}\n"));
    }
    let cloud = write(dir.path(), "c.ply", &ply);
    let mesh = dir.path().join("m.off");
    let text = ok(&reconbench(&[
        "reconstruct",
        "--method",
        "reference-mesh",
        cloud.to_str().unwrap(),
        "-o",
        mesh.to_str().unwrap(),
        "--set",
        "shape=torus",
        "--set",
        "resolution=12",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(v["summary"]["faces"].as_f64().unwrap() > 0.0, "{text}");
    assert!(v["phases"][0][0] == "mesh", "{text}");
    assert!(mesh.exists());
    let human = ok(&reconbench(&[
        "reconstruct",
        "--method",
        "reference-mesh",
        cloud.to_str().unwrap(),
        "-o",
        mesh.to_str().unwrap(),
        "--set",
        "shape=sphere",
    ]));
    assert!(
        human.contains("phases: mesh") && human.contains("resolution = 64"),
        "{human}"
    );
    // Oracles without ground truth say what they need.
    let out = reconbench(&[
        "reconstruct",
        "--method",
        "reference-mesh",
        cloud.to_str().unwrap(),
        "-o",
        mesh.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "a missing parameter is bad input"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("shape"));
    // An output that cannot hold the result is refused before any work.
    for bad in ["mesh.txt", "mesh.xyz", "no/such/dir/mesh.ply"] {
        let out = reconbench(&[
            "reconstruct",
            "--method",
            "ufm",
            cloud.to_str().unwrap(),
            "-o",
            dir.path().join(bad).to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(2), "{bad}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    // What a method cannot do with its input is bad input too.
    let two = dir.path().join("two.xyz");
    std::fs::write(&two, "0 0 0\n1 0 0\n").unwrap();
    let out = reconbench(&[
        "reconstruct",
        "--method",
        "ufm",
        two.to_str().unwrap(),
        "-o",
        mesh.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Wrong kind and unknown parameters are input errors.
    let out = reconbench(&[
        "normals",
        "--method",
        "reference-mesh",
        cloud.to_str().unwrap(),
        "-o",
        "x.ply",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let out = reconbench(&[
        "normals",
        "--method",
        "gt-normals",
        cloud.to_str().unwrap(),
        "-o",
        "x.ply",
        "--set",
        "k=3",
    ]);
    assert_eq!(out.status.code(), Some(2));
    // Normals from the file (gt-normals outside experiments), features as a label channel.
    let normals = dir.path().join("n.ply");
    ok(&reconbench(&[
        "normals",
        "--method",
        "gt-normals",
        cloud.to_str().unwrap(),
        "-o",
        normals.to_str().unwrap(),
    ]));
    let mut fply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty double feature_distance\nend_header\n",
    );
    fply.push_str("0 0 0 0.0\n1 0 0 0.5\n0 1 0 0.001\n");
    let fcloud = write(dir.path(), "f.ply", &fply);
    let labelled = dir.path().join("l.ply");
    let text = ok(&reconbench(&[
        "features",
        "--method",
        "gt-features",
        fcloud.to_str().unwrap(),
        "-o",
        labelled.to_str().unwrap(),
        "--set",
        "radius=0.01",
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["summary"]["edges"], 2.0, "{text}");
    let header = std::fs::read(&labelled).unwrap();
    let header = String::from_utf8_lossy(&header[..header.len().min(400)]).to_string();
    assert!(header.contains("feature"), "{header}");
}
