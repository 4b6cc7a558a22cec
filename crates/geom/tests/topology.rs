//! Topology analysis on meshes with known answers.

use reconbench_geom::topology::{
    MeshTopology, NO_EDGE, TopologyReport, analyze, orient_consistently,
};
use reconbench_geom::{DVec3, TriMesh};
use reconbench_testkit::meshes as examples;

/// Signed volume (positive for outward-oriented closed meshes).
fn signed_volume(m: &TriMesh) -> f64 {
    (0..m.n_faces())
        .map(|f| {
            let [a, b, c] = m.triangle(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Checks the invariants of a closed, orientable, consistently oriented single surface.
fn assert_closed_surface(r: &TopologyReport, genus: u32) {
    assert!(r.watertight, "{r:#?}");
    assert_eq!(r.components, 1);
    assert_eq!(r.boundary_edges, 0);
    assert!(r.boundary_loops.is_empty());
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.non_manifold_vertices, 0);
    assert!(r.orientable);
    assert!(r.consistently_oriented);
    assert_eq!(r.euler, 2 - 2 * genus as i64);
    assert_eq!(r.genus, Some(genus));
    assert_eq!(r.component_genus(), vec![Some(genus)]);
    assert_eq!(r.degenerate_faces, 0);
    assert_eq!(r.duplicate_faces, 0);
    assert_eq!(r.unreferenced_vertices, 0);
    // A closed triangle surface has 3F = 2E.
    assert_eq!(3 * r.faces, 2 * r.edges);
}

#[test]
fn tetrahedron() {
    let m = examples::tetrahedron();
    let r = analyze(&m);
    assert_eq!((r.vertices, r.edges, r.faces), (4, 6, 4));
    assert_closed_surface(&r, 0);
    assert!(signed_volume(&m) > 0.0);
}

#[test]
fn cube() {
    let m = examples::cube();
    let r = analyze(&m);
    assert_eq!((r.vertices, r.edges, r.faces), (8, 18, 12));
    assert_closed_surface(&r, 0);
    assert!((signed_volume(&m) - 1.0).abs() < 1e-15);
    for f in 0..12 {
        let expect = [
            -DVec3::Z,
            DVec3::Z,
            -DVec3::Y,
            DVec3::Y,
            -DVec3::X,
            DVec3::X,
        ][f / 2];
        assert_eq!(m.face_normal(f), expect, "face {f}");
    }
}

#[test]
fn uv_sphere() {
    let m = examples::uv_sphere(8, 12, 2.0);
    let r = analyze(&m);
    assert_eq!(r.vertices, 2 + 7 * 12);
    assert_eq!(r.faces, 2 * 12 * 7);
    assert_closed_surface(&r, 0);
    let v = signed_volume(&m);
    assert!(v > 0.0 && v < 4.0 / 3.0 * std::f64::consts::PI * 8.0);
}

#[test]
fn torus_genus_one() {
    let m = examples::torus_grid(16, 8, 2.0, 0.5);
    let r = analyze(&m);
    assert_eq!((r.vertices, r.faces), (128, 256));
    assert_closed_surface(&r, 1);
    assert!(signed_volume(&m) > 0.0);
}

#[test]
fn double_torus_genus_two() {
    let m = examples::double_torus(12, 6, 2.0, 0.5);
    let r = analyze(&m);
    assert_eq!(r.vertices, 144);
    assert_eq!(r.faces, 4 * 72 + 4);
    assert_closed_surface(&r, 2);
    assert!(signed_volume(&m) > 0.0);
}

#[test]
fn open_disk() {
    let m = examples::square_grid(5);
    let r = analyze(&m);
    assert!(!r.watertight);
    assert_eq!(r.euler, 1);
    assert_eq!(r.components, 1);
    assert_eq!(r.boundary_edges, 20);
    assert_eq!(r.boundary_loops.len(), 1);
    let l = &r.boundary_loops[0];
    assert!(l.closed);
    assert_eq!((l.vertices, l.edges), (20, 20));
    assert!((l.length - 4.0).abs() < 1e-12);
    assert_eq!(r.genus, Some(0));
    assert!(r.orientable && r.consistently_oriented);
    assert_eq!(r.non_manifold_edges + r.non_manifold_vertices, 0);
}

#[test]
fn annulus_has_two_loops_and_genus_zero() {
    // A square grid with the centre square removed: 2 boundary loops, genus 0.
    let m = examples::square_grid(3);
    let faces: Vec<[u32; 3]> = m
        .faces()
        .iter()
        .enumerate()
        .filter(|&(f, _)| f / 2 != 4)
        .map(|(_, &t)| t)
        .collect();
    let m = TriMesh::new(m.vertices().to_vec(), faces).unwrap();
    let r = analyze(&m);
    assert_eq!(r.boundary_loops.len(), 2);
    let mut lens: Vec<usize> = r.boundary_loops.iter().map(|l| l.vertices).collect();
    lens.sort();
    assert_eq!(lens, vec![4, 12]);
    assert_eq!(r.euler, 0);
    assert_eq!(r.genus, Some(0));
}

#[test]
fn two_disjoint_spheres() {
    let a = examples::uv_sphere(6, 8, 1.0);
    let b = examples::cube();
    let n = a.n_vertices() as u32;
    let mut v = a.vertices().to_vec();
    v.extend(b.vertices().iter().map(|p| *p + DVec3::splat(5.0)));
    let mut f = a.faces().to_vec();
    f.extend(b.faces().iter().map(|t| t.map(|i| i + n)));
    let r = analyze(&TriMesh::new(v, f).unwrap());
    assert_eq!(r.components, 2);
    assert_eq!(r.euler, 4);
    assert!(r.watertight);
    assert_eq!(r.genus, Some(0));
    assert_eq!(r.component_genus(), vec![Some(0), Some(0)]);
    assert_eq!(r.component_details[1].faces, 12);
    assert_eq!(r.component_details[1].vertices, 8);
}

#[test]
fn torus_plus_sphere_genus_sums() {
    let a = examples::torus_grid(8, 6, 2.0, 0.5);
    let b = examples::tetrahedron();
    let n = a.n_vertices() as u32;
    let mut v = a.vertices().to_vec();
    v.extend(b.vertices().iter().map(|p| *p + DVec3::splat(9.0)));
    let mut f = a.faces().to_vec();
    f.extend(b.faces().iter().map(|t| t.map(|i| i + n)));
    let r = analyze(&TriMesh::new(v, f).unwrap());
    assert_eq!(r.component_genus(), vec![Some(1), Some(0)]);
    assert_eq!(r.genus, Some(1));
}

#[test]
fn bow_tie_is_a_non_manifold_vertex() {
    let v = vec![
        DVec3::ZERO,
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(-1.0, -1.0, 0.0),
    ];
    let r = analyze(&TriMesh::new(v, vec![[0, 1, 2], [0, 3, 4]]).unwrap());
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.components, 1, "components are by shared vertices");
    assert!(!r.watertight);
    assert_eq!(r.genus, None);
    assert_eq!(r.component_details[0].genus, None);
    assert_eq!(r.boundary_edges, 6);
    // The pinch vertex is visited by the boundary walk; all six edges are covered.
    assert_eq!(r.boundary_loops.iter().map(|l| l.edges).sum::<usize>(), 6);
}

#[test]
fn two_tetrahedra_sharing_a_vertex() {
    let t = examples::tetrahedron();
    let mut v = t.vertices().to_vec();
    v.extend([
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(0.0, 0.0, -1.0),
    ]);
    let mut f = t.faces().to_vec();
    // Second tetrahedron 0, 4, 5, 6 (mirror of the first through the origin).
    f.extend([[0, 4, 5], [0, 5, 6], [0, 6, 4], [4, 6, 5]]);
    let r = analyze(&TriMesh::new(v, f).unwrap());
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.boundary_edges, 0);
    assert!(!r.watertight);
    assert_eq!(r.components, 1);
    assert_eq!(r.genus, None);
}

#[test]
fn three_faces_on_one_edge() {
    let v = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(0.0, -1.0, 0.0),
    ];
    let m = TriMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    let r = analyze(&m);
    assert_eq!(r.non_manifold_edges, 1);
    assert_eq!(r.non_manifold_vertices, 0);
    assert!(!r.watertight);
    assert_eq!(r.genus, None);
    let t = MeshTopology::new(&m);
    let e = t.find_edge(1, 0).unwrap();
    assert_eq!(t.edge_faces(e as usize), &[0, 1, 2]);
    assert_eq!(t.edge_valence(e as usize), 3);
    assert_eq!(t.opposite_face(0, 0), None);
}

#[test]
fn moebius_strip_is_non_orientable() {
    let mut m = examples::moebius_strip(10, 2.0, 0.5);
    let r = analyze(&m);
    assert!(!r.orientable);
    assert!(!r.consistently_oriented);
    assert_eq!(r.boundary_loops.len(), 1);
    assert_eq!(r.boundary_loops[0].vertices, 20);
    assert_eq!(r.euler, 0);
    assert_eq!(r.non_manifold_edges + r.non_manifold_vertices, 0);
    assert_eq!(r.genus, None);
    assert!(!r.watertight);
    let before = m.clone();
    let o = orient_consistently(&mut m).unwrap();
    assert_eq!(o.patches, 1);
    assert_eq!(o.non_orientable_patches, vec![0]);
    assert_eq!(o.flipped_faces, 0);
    assert_eq!(m, before);
}

#[test]
fn cube_with_a_flipped_face_is_fixed() {
    let mut m = examples::cube();
    let mut flip = vec![false; 12];
    flip[7] = true;
    m.flip_faces(&flip);
    let r = analyze(&m);
    assert!(r.orientable);
    assert!(!r.consistently_oriented);
    assert!(r.watertight);
    assert_eq!(r.genus, Some(0));
    let o = orient_consistently(&mut m).unwrap();
    assert_eq!(o.flipped_faces, 1, "the minority face is flipped back");
    assert!(o.non_orientable_patches.is_empty());
    assert_eq!(m, examples::cube());
    assert!(analyze(&m).consistently_oriented);
}

#[test]
fn orient_inverted_majority() {
    // Flip all but 2 faces of a torus: orient_consistently flips those 2 back.
    let mut m = examples::torus_grid(8, 6, 2.0, 0.5);
    let n = m.n_faces();
    let flips: Vec<bool> = (0..n).map(|f| f >= 2).collect();
    m.flip_faces(&flips);
    let o = orient_consistently(&mut m).unwrap();
    assert_eq!(o.flipped_faces, 2);
    let r = analyze(&m);
    assert!(r.consistently_oriented);
    assert!(
        signed_volume(&m) < 0.0,
        "majority (inward) orientation kept"
    );
}

#[test]
fn degenerate_duplicate_and_unreferenced() {
    let mut v = examples::tetrahedron().vertices().to_vec();
    v.push(DVec3::new(0.5, 0.0, 0.0)); // 4: on the edge 0-1 (zero-area face)
    v.push(DVec3::splat(7.0)); // 5: unreferenced
    let mut f = examples::tetrahedron().faces().to_vec();
    f.push([0, 0, 1]); // collapsed
    f.push([0, 1, 4]); // zero area, distinct indices
    f.push([2, 1, 0]); // duplicate of face 0 ([0, 2, 1]) with the opposite orientation
    let r = analyze(&TriMesh::new(v, f).unwrap());
    assert_eq!(r.faces, 7);
    assert_eq!(r.valid_faces, 6);
    assert_eq!(r.collapsed_faces, 1);
    assert_eq!(r.degenerate_faces, 2);
    assert_eq!(r.duplicate_faces, 1);
    assert_eq!(r.unreferenced_vertices, 1);
    assert_eq!(r.vertices, 6);
    assert_eq!(r.referenced_vertices, 5);
    assert_eq!(r.euler_raw, 6 - r.edges as i64 + 7);
    assert_eq!(r.euler, 5 - r.edges as i64 + 6);
    assert!(r.non_manifold_edges > 0);
}

#[test]
fn pillow_of_two_opposite_triangles_is_a_sphere() {
    let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    let r = analyze(&TriMesh::new(v, vec![[0, 1, 2], [0, 2, 1]]).unwrap());
    assert!(r.watertight);
    assert_eq!(r.duplicate_faces, 1);
    assert_eq!(r.genus, Some(0));
}

#[test]
fn empty_mesh() {
    let r = analyze(&TriMesh::default());
    assert_eq!(r.components, 0);
    assert!(!r.watertight);
    assert_eq!(r.genus, None);
    let r = analyze(&TriMesh::new(vec![DVec3::ZERO; 3], vec![]).unwrap());
    assert_eq!(r.unreferenced_vertices, 3);
    assert_eq!(r.euler, 0);
    assert_eq!(r.euler_raw, 3);
}

#[test]
fn mesh_topology_api() {
    let m = examples::cube();
    let t = MeshTopology::new(&m);
    assert_eq!(t.n_edges(), 18);
    assert!(t.edges().windows(2).all(|w| w[0] < w[1]));
    assert!(t.edges().iter().all(|e| e[0] < e[1]));
    for f in 0..12 {
        let face = m.faces()[f];
        for k in 0..3 {
            let e = t.face_edges()[f][k];
            assert_ne!(e, NO_EDGE);
            assert_eq!(Some(e), t.find_edge(face[k], face[(k + 1) % 3]));
            assert!(t.edge_faces(e as usize).contains(&(f as u32)));
            let g = t.opposite_face(f, k).unwrap() as usize;
            assert_ne!(g, f);
            assert!(m.faces()[g].contains(&face[k]));
        }
    }
    for v in 0..8 {
        let fs = t.vertex_faces(v);
        assert!(fs.windows(2).all(|w| w[0] < w[1]));
        assert!(
            fs.iter()
                .all(|&f| m.faces()[f as usize].contains(&(v as u32)))
        );
    }
    assert_eq!(t.vertex_face_indices().len(), 36);
    assert_eq!(t.edge_face_offsets().len(), 19);
    assert_eq!(t.find_edge(0, 7), None);
    assert_eq!(t.find_edge(0, 100), None);
    // from_faces tolerates out-of-range indices (treated as collapsed).
    let t = MeshTopology::from_faces(3, &[[0, 1, 2], [0, 1, 9]]);
    assert!(t.is_face_valid(0) && !t.is_face_valid(1));
    assert_eq!(t.n_edges(), 3);
}

#[test]
fn report_serializes() {
    // serde_json is not a dependency of this crate: check the bound at compile time.
    fn is_serialize<T: serde::Serialize>(_: &T) {}
    is_serialize(&analyze(&examples::cube()));
}

#[test]
fn large_torus_is_fast_enough_and_correct() {
    // 2 * 400 * 250 = 200k faces; correctness at scale (timing is covered by the bench).
    let m = examples::torus_grid(400, 250, 3.0, 1.0);
    let r = analyze(&m);
    assert_closed_surface(&r, 1);
}
