//! The metrics the reports of issue 26 need: `topology_ok` that a self-intersection
//! fails, false positives on a featureless shape, and the mesh error over the surface.

use reconbench_testkit::metric_fixtures as common;

use common::{TestSphere, concat, translate};
use glam::DVec3;
use reconbench_metrics::distance::{DistanceOptions, eval_distance};
use reconbench_metrics::features::{FeatureOptions, eval_features};
use reconbench_metrics::topology::{GroundTruthTopology, TopologyOptions, eval_topology};
use reconbench_metrics::{Reference, Report};
use reconbench_testkit::meshes::{cube, uv_sphere};

#[test]
fn a_self_intersecting_mesh_of_the_right_type_is_not_topology_ok() {
    // Two overlapping closed cubes: watertight, two components, genus 0 each.
    let both = concat(&cube(), &translate(&cube(), DVec3::splat(0.5)));
    let gt = GroundTruthTopology {
        genus: Some(0),
        components: 2,
        closed: true,
    };
    let t = eval_topology(&both, Some(gt), &TopologyOptions::default());
    assert!(t.self_intersections.unwrap() > 0);
    assert_eq!(
        (t.topology_type_ok(), t.topology_ok()),
        (Some(true), Some(false))
    );
    let row = t.to_row();
    assert_eq!((row["topology_type_ok"], row["topology_ok"]), (1.0, 0.0));
    // Apart, the same cubes are fine on both counts.
    let apart = concat(&cube(), &translate(&cube(), DVec3::splat(3.0)));
    let t = eval_topology(&apart, Some(gt), &TopologyOptions::default());
    assert_eq!(
        (t.topology_type_ok(), t.topology_ok()),
        (Some(true), Some(true))
    );
}

#[test]
fn detections_on_a_featureless_shape_are_false_positives() {
    let pts: Vec<DVec3> = uv_sphere(6, 12, 1.0).vertices().to_vec();
    let mut detected = vec![false; pts.len()];
    let ev = eval_features(
        &pts,
        &pts,
        &detected,
        &[],
        2.0 * 3f64.sqrt(),
        &FeatureOptions::default(),
    )
    .unwrap();
    assert_eq!((ev.false_positives(0), ev.f1(0)), (0, None));
    for d in detected.iter_mut().take(7) {
        *d = true;
    }
    let ev = eval_features(
        &pts,
        &pts,
        &detected,
        &[],
        2.0 * 3f64.sqrt(),
        &FeatureOptions::default(),
    )
    .unwrap();
    let row = ev.to_row();
    assert_eq!(row["feature_false_positives"], 7.0);
    assert_eq!(row["feature_false_positives_2r"], 7.0);
    // F1 is 0 here, which a table must not read as "as good as no detection".
    assert_eq!(ev.f1(0), Some(0.0));
}

#[test]
fn surface_error_measures_the_faces_not_only_the_vertices() {
    // A coarse polyhedron inscribed in the unit sphere: vertices exactly on the sphere,
    // faces inside it, so the vertex error is 0 and the surface error is not.
    let sphere = TestSphere::unit();
    let reference = Reference::analytic(&sphere);
    let mesh = uv_sphere(4, 8, 1.0);
    let opts = DistanceOptions {
        min_samples: 5_000,
        ..DistanceOptions::default()
    };
    let e = eval_distance(&mesh, &reference, &opts).unwrap();
    let s = e.sample_error.as_ref().unwrap();
    assert_eq!(s.len(), e.recon_area_samples);
    let v = e.vertex_error.as_ref().unwrap();
    assert!(v.iter().all(|&x| x < 1e-9), "vertices lie on the sphere");
    let mean = s.iter().sum::<f64>() / s.len() as f64;
    assert!(mean > 1e-3, "faces lie inside the sphere: {mean}");
    let off = DistanceOptions {
        vertex_error: false,
        ..opts
    };
    assert!(
        eval_distance(&mesh, &reference, &off)
            .unwrap()
            .sample_error
            .is_none()
    );
}
