//! Hoppe's formats: `.m` meshes and A3d stream `.pts` points, round trips and the real
//! files of `/work/shared/data/real` (skipped when that folder is absent).

use std::path::Path;

use reconbench_geom::io::{self, Format, Loaded, WriteOptions};
use reconbench_geom::{DVec3, TriMesh};

#[test]
fn m_mesh_reads_ids_attributes_and_ignored_records() {
    let text = b"# comment\nVertex 10 0 0 0 {normal=(0 0 1)}\nVertex 4 1 0 0 {wid=3 normal=(0 0 1)}\n\
Vertex 7 0 1 0 {normal=(0 0 -1)}\nFace 2  10 4 7 {sharp}\nEdge 10 4 {sharp}\nCorner 10 2 {normal=(1 0 0)}\n";
    let m = io::mesh_from_bytes(text, Format::M, "a.m").unwrap();
    assert_eq!(m.n_vertices(), 3);
    assert_eq!(m.faces(), &[[0, 1, 2]]);
    assert_eq!(m.vertices()[1], DVec3::X);
    assert_eq!(m.vertex_normals().unwrap()[2], -DVec3::Z);
}

#[test]
fn m_mesh_round_trips_exactly() {
    let v = vec![
        DVec3::new(0.1, 0.2, 0.3),
        DVec3::new(1.0 / 3.0, 0.0, -1e-9),
        DVec3::new(0.0, 1.0, 2.5e20),
        DVec3::new(1.0, 1.0, 1.0),
    ];
    let mut m = TriMesh::new(v, vec![[0, 1, 2], [2, 1, 3]]).unwrap();
    let bytes = io::mesh_to_bytes(&m, Format::M, &WriteOptions::default()).unwrap();
    assert_eq!(io::mesh_from_bytes(&bytes, Format::M, "r.m").unwrap(), m);
    m.set_vertex_normals(Some(vec![DVec3::Z, DVec3::X, DVec3::Y, -DVec3::Z]))
        .unwrap();
    let bytes = io::mesh_to_bytes(&m, Format::M, &WriteOptions::default()).unwrap();
    assert_eq!(io::mesh_from_bytes(&bytes, Format::M, "r.m").unwrap(), m);
}

#[test]
fn m_polygon_is_refused_with_its_line() {
    let text = b"Vertex 1 0 0 0\nVertex 2 1 0 0\nVertex 3 1 1 0\nVertex 4 0 1 0\nFace 1 1 2 3 4\n";
    let e = io::mesh_from_bytes(text, Format::M, "q.m")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("q.m") && e.contains("line 5") && e.contains("4 vertices"),
        "{e}"
    );
}

#[test]
fn a3d_points_and_normals_read() {
    let text = b"# A3d\nd 0 0 0\ns 0 0 0\ng 1 0 0\np 0 0 0\nn 0 0 1\np 1 2 3\nn 0 1 0\n";
    let c = io::cloud_from_bytes(text, Format::Pts, "a.pts").unwrap();
    assert_eq!(c.positions(), &[DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0)]);
    assert_eq!(c.normals().unwrap(), &[DVec3::Z, DVec3::Y]);
    let c = io::cloud_from_bytes(b"p 0 0 0\np 1 0 0\n", Format::Pts, "b.pts").unwrap();
    assert_eq!(c.len(), 2);
    assert!(c.normals().is_none());
    // Plain PTS still reads.
    let c = io::cloud_from_bytes(b"2\n0 0 0\n1 0 0\n", Format::Pts, "c.pts").unwrap();
    assert_eq!(c.len(), 2);
    // Some points with normals, some without: refused, naming a line.
    let e = io::cloud_from_bytes(b"p 0 0 0\nn 0 0 1\np 1 0 0\n", Format::Pts, "d.pts")
        .unwrap_err()
        .to_string();
    assert!(e.contains("d.pts") && e.contains("line 3"), "{e}");
}

#[test]
fn real_files_read() {
    let dir = Path::new("/work/shared/data/real");
    if !dir.exists() {
        eprintln!("skipped: {} absent", dir.display());
        return;
    }
    let mech = io::read_mesh(dir.join("mechpart.recon.m")).unwrap();
    assert_eq!(mech.n_vertices(), 7612);
    let club = io::read_mesh(dir.join("club.orig.m")).unwrap();
    assert_eq!(club.n_vertices(), 9597);
    assert_eq!(club.n_faces(), 19136);
    let dist = io::read_cloud(dir.join("distcap.pts")).unwrap();
    assert_eq!(dist.len(), 12745);
    let cactus = io::read_cloud(dir.join("cactus.pts")).unwrap();
    assert_eq!(cactus.len(), 3318);
    assert!(matches!(
        io::read_any(dir.join("cactus.pts")).unwrap(),
        Loaded::Cloud(_)
    ));
}
