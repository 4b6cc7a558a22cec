//! Tests of `qem-simplified` (seed 004's full-mesh + QEM baseline): the vertex budget is
//! met, the vertices are input points, and the simplified sphere stays close to it.

use reconbench_geom::PointCloud;
use reconbench_geom::method::{Describe, Reconstructor, RunCtx};
use reconbench_geom::spatial::MeshBvh;
use reconbench_recon::ebt::qem::{FullMesher, QemParams, QemSimplified};
use reconbench_testkit::feature_fixtures::sphere;

#[test]
fn budget_met_on_input_points_and_close_to_the_sphere() {
    let pts = sphere(3000);
    let cloud = PointCloud::new(pts.clone()).unwrap();
    let m = QemSimplified::from_params(QemParams {
        mesher: FullMesher::PriorityFront,
        target: 400,
    })
    .unwrap();
    let r = m.reconstruct(&cloud, &mut RunCtx::new(1)).unwrap();
    let nv = r.mesh.n_vertices();
    assert!(
        (380..=420).contains(&nv),
        "{nv} vertices for a budget of 400"
    );
    // Every vertex is an input point (edge collapses keep original vertices).
    for v in r.mesh.vertices() {
        assert!(
            pts.iter().any(|p| p == v),
            "vertex {v} is not an input point"
        );
    }
    // A closed sphere of about 2 * 400 faces; every input point near it: an inscribed
    // polyhedron of ~400 vertices sags by about (edge^2) / 8 ~ 0.01 at most.
    assert!(r.mesh.n_faces() > 600);
    let bvh = MeshBvh::new(&r.mesh).unwrap();
    let worst = pts
        .iter()
        .map(|&p| bvh.distance(p).unwrap())
        .fold(0.0, f64::max);
    assert!(worst < 0.05, "max distance {worst}");
}

#[test]
fn bad_target_is_an_error() {
    let err = QemSimplified::from_params(QemParams {
        mesher: FullMesher::Ufm,
        target: 2,
    })
    .unwrap_err()
    .to_string();
    assert!(err.contains("target"), "{err}");
}
