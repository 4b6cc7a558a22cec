//! The vendored real data sets agree with their manifest: every file exists, is read by
//! geom's readers, and has the vertex/face counts and topology the manifest states; and
//! as mesh shapes they give exact ground truth.

use std::path::Path;

use reconbench_geom::topology;
use reconbench_synth::real::{Manifest, RealKind};
use reconbench_synth::{MeshShape, MeshShapeOptions, SamplerSpec, Shape};

fn manifest() -> Manifest {
    Manifest::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/real")).unwrap()
}

#[test]
fn every_vendored_file_matches_its_manifest_entry() {
    let m = manifest();
    assert!(m.sets.len() >= 8);
    for s in &m.sets {
        let path = m.path_of(s);
        match s.kind {
            RealKind::Mesh => {
                let mesh = reconbench_geom::io::read_mesh(&path).unwrap();
                let r = topology::analyze(&mesh);
                assert_eq!(mesh.n_vertices() as u64, s.vertices, "{}", s.name);
                assert_eq!(mesh.n_faces() as u64, s.faces, "{}", s.name);
                assert_eq!(r.genus, Some(s.genus), "{}", s.name);
                assert_eq!(r.components as u32, s.components, "{}", s.name);
                assert_eq!(r.n_boundary_loops() as u32, s.boundary_loops, "{}", s.name);
                assert_eq!(r.watertight, s.closed, "{}", s.name);
            }
            RealKind::Cloud => {
                let c = reconbench_geom::io::read_cloud(&path).unwrap();
                assert_eq!(c.len() as u64, s.vertices, "{}", s.name);
                assert_eq!(s.faces, 0, "{}", s.name);
            }
        }
    }
}

#[test]
fn a_mesh_shape_is_exact_on_its_own_vertices_and_off_them() {
    let m = manifest();
    let s = m.find("3holes").unwrap();
    let mesh = reconbench_geom::io::read_mesh(m.path_of(s)).unwrap();
    let shape = MeshShape::new("3holes", mesh.clone()).unwrap();
    assert_eq!(shape.genus(), 3);
    assert!(shape.is_closed());
    // Every vertex lies on the surface.
    for &v in mesh.vertices().iter().step_by(7) {
        assert!(shape.distance(v) <= 1e-12 * shape.aabb().diagonal());
    }
    // A point pushed off a face centroid along the face normal is at the push distance.
    let f = (0..mesh.n_faces())
        .max_by(|&a, &b| mesh.face_area(a).total_cmp(&mesh.face_area(b)))
        .unwrap();
    let [a, b, c] = mesh.triangle(f);
    let h = 1e-4 * shape.aabb().diagonal();
    let q = (a + b + c) / 3.0 + mesh.face_normal(f) * h;
    assert!(
        (shape.distance(q) - h).abs() < 1e-9 * h.max(1.0),
        "{} vs {h}",
        shape.distance(q)
    );
    // The vertices sampler gives every distinct vertex once, with unit normals.
    let cloud = reconbench_synth::sampler::sample(
        &shape,
        &SamplerSpec::Vertices,
        reconbench_synth::Density::Count(1),
        0,
    )
    .unwrap();
    assert_eq!(cloud.positions.len(), mesh.n_vertices());
    assert!(
        cloud
            .normals
            .iter()
            .all(|n| (n.length() - 1.0).abs() < 1e-9)
    );
}

#[test]
fn declared_closedness_overrides_the_measured_one() {
    let m = manifest();
    let s = m.find("golf-club").unwrap();
    let mesh = reconbench_geom::io::read_mesh(m.path_of(s)).unwrap();
    let open = MeshShape::new("golf", mesh.clone()).unwrap();
    assert!(!open.is_closed());
    let opts = MeshShapeOptions {
        closed: Some(true),
        ..Default::default()
    };
    assert!(
        MeshShape::with_options("golf", mesh, opts)
            .unwrap()
            .is_closed()
    );
}

#[test]
fn fandisk_sharp_edges_chain_into_curves_and_vertices_on_them_have_zero_feature_distance() {
    let m = manifest();
    let s = m.find("fandisk").unwrap();
    let mesh = reconbench_geom::io::read_mesh(m.path_of(s)).unwrap();
    let shape = MeshShape::new("fandisk", mesh.clone()).unwrap();
    let curves = shape.feature_curves();
    let polylines: Vec<_> = curves.iter().filter(|c| !c.is_corner).collect();
    assert!(!polylines.is_empty());
    // Chaining: far fewer curves than sharp edges.
    let n_seg: usize = polylines.iter().map(|c| c.points.len() - 1).sum();
    assert!(
        polylines.len() * 3 < n_seg,
        "{} curves, {n_seg} edges",
        polylines.len()
    );
    for c in &polylines {
        assert!(180.0 - c.dihedral_deg >= 30.0);
        assert_eq!(shape.feature_distance(c.points[0]), 0.0);
    }
    // A stricter angle keeps a subset.
    let strict = MeshShape::with_options(
        "fandisk",
        mesh,
        MeshShapeOptions {
            feature_angle_deg: 60.0,
            ..Default::default()
        },
    )
    .unwrap();
    let n_strict: usize = strict
        .feature_curves()
        .iter()
        .filter(|c| !c.is_corner)
        .map(|c| c.points.len() - 1)
        .sum();
    assert!(n_strict < n_seg);
}
