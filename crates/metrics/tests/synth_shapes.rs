//! The metrics against reconbench-synth's real shapes (through `from_spec`).

use reconbench_metrics::distance::DistanceOptions;
use reconbench_metrics::eval::{MeshEvalOptions, eval_mesh};
use reconbench_metrics::{Reference, Report};

fn opts() -> MeshEvalOptions {
    MeshEvalOptions {
        distance: DistanceOptions {
            min_samples: 20_000,
            ..DistanceOptions::default()
        },
        ..MeshEvalOptions::default()
    }
}

#[test]
fn reference_meshes_of_synth_shapes_evaluate_cleanly() {
    for spec in ["sphere", "torus", "box", "double-torus"] {
        let shape = reconbench_synth::from_spec(spec).unwrap();
        let reference = Reference::analytic(&*shape);
        let mesh = shape.reference_mesh(48);
        let e = eval_mesh(&mesh, &reference, &opts()).unwrap();
        let row = e.to_row();
        eprintln!(
            "{spec}: faces {} hausdorff {:.2e} chamfer {:.2e} genus {:?} recovery {:?}",
            mesh.n_faces(),
            row["hausdorff"],
            row["chamfer_l1"],
            row.get("genus"),
            row.get("feature_recovery")
        );
        eprintln!(
            "  accuracy max {:.2e} p95 {:.2e}; completeness max {:.2e} p95 {:.2e}",
            row["accuracy_max"],
            row["accuracy_p95"],
            row["completeness_max"],
            row["completeness_p95"]
        );
        // A reference mesh is close to its shape (relative to the unit diagonal).
        assert!(row["hausdorff"] < 0.02, "{spec}: {}", row["hausdorff"]);
        assert_eq!(row["topology_ok"], 1.0, "{spec}");
        assert_eq!(row["delta_f"], 0.0, "{spec}");
        assert_eq!(row["self_intersections"], 0.0, "{spec}");
        if spec == "box" {
            assert!(row["feature_recovery"] > 0.99, "{spec}");
        }
    }
}

#[test]
fn reference_from_a_command_line_argument() {
    let r = Reference::from_arg("sphere").unwrap();
    assert!(r.as_shape().is_some());
    assert_eq!(r.genus(), Some(0));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.ply");
    reconbench_geom::io::write_mesh(&path, &reconbench_testkit::meshes::cube()).unwrap();
    let r = Reference::from_arg(path.to_str().unwrap()).unwrap();
    assert_eq!(
        (r.n_faces(), r.genus(), r.is_closed()),
        (Some(12), Some(0), true)
    );
    assert_eq!(r.feature_curves(20.0).len(), 12);
    let err = Reference::from_arg("no-such-shape-or-file").unwrap_err();
    assert!(err.to_string().contains("neither"), "{err}");
}
