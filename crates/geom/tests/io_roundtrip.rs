//! Round trips through every format and encoding, in memory and through files.

use reconbench_geom::io::{
    self, Format, Loaded, PlyEncoding, WriteOptions, cloud_from_bytes, cloud_to_bytes,
    mesh_from_bytes, mesh_to_bytes,
};
use reconbench_geom::{Channel, DVec3, GeomError, PointCloud, TriMesh};

/// Values that stress exactness: thirds, tiny and huge magnitudes, negative zero.
fn awkward(i: usize) -> f64 {
    let k = i as f64;
    match i % 5 {
        0 => k / 3.0,
        1 => -k * 1e-7 - 0.1,
        2 => 1e200 / (k + 1.0),
        3 => -0.0,
        _ => std::f64::consts::PI * k,
    }
}

fn rich_cloud(n: usize) -> PointCloud {
    let positions = (0..n)
        .map(|i| DVec3::new(awkward(i), awkward(i + 1), awkward(i + 2)))
        .collect();
    let normals = (0..n)
        .map(|i| DVec3::new(1.0 / (i as f64 + 3.0), -0.5, 0.25 * i as f64))
        .collect();
    let mut c = PointCloud::new(positions)
        .unwrap()
        .with_normals(normals)
        .unwrap();
    c.set_colors(Some(
        (0..n)
            .map(|i| [i as u8, (255 - i) as u8, (i * 7) as u8])
            .collect(),
    ))
    .unwrap();
    c.set_source_ids(Some((0..n as u32).map(|i| i * 1000 + 7).collect()))
        .unwrap();
    c.set_channel(
        "curvature",
        Channel::Scalar((0..n).map(|i| awkward(i + 3)).collect()),
    )
    .unwrap();
    c.set_channel(
        "feature_class",
        Channel::Label((0..n as i64).map(|i| i - 2_000_000_000).collect()),
    )
    .unwrap();
    c
}

fn octahedron() -> TriMesh {
    let v = vec![
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::new(0.0, 0.0, 1.0 / 3.0),
        DVec3::new(0.0, 0.0, -0.1),
    ];
    let f = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    TriMesh::new(v, f).unwrap()
}

fn decorated_octahedron() -> TriMesh {
    let mut m = octahedron();
    let n = m.angle_weighted_normals();
    m.set_vertex_normals(Some(n)).unwrap();
    m.set_vertex_colors(Some((0..6).map(|i| [i * 40, 255 - i, 3]).collect()))
        .unwrap();
    m
}

fn ply(enc: PlyEncoding) -> WriteOptions {
    WriteOptions {
        ply_encoding: enc,
        ..WriteOptions::default()
    }
}

const ENCODINGS: [PlyEncoding; 3] = [
    PlyEncoding::Ascii,
    PlyEncoding::BinaryLittleEndian,
    PlyEncoding::BinaryBigEndian,
];

fn assert_bits_equal(a: &[DVec3], b: &[DVec3]) {
    assert_eq!(a.len(), b.len());
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        let (p, q) = (
            p.to_array().map(f64::to_bits),
            q.to_array().map(f64::to_bits),
        );
        assert_eq!(p, q, "point {i} differs");
    }
}

#[test]
fn ply_cloud_round_trip_keeps_everything_in_every_encoding() {
    let c = rich_cloud(50);
    for enc in ENCODINGS {
        let bytes = cloud_to_bytes(&c, Format::Ply, &ply(enc)).unwrap();
        let back = cloud_from_bytes(&bytes, Format::Ply, "rt.ply").unwrap();
        assert_eq!(back, c, "{enc}");
        assert_bits_equal(back.positions(), c.positions());
    }
}

#[test]
fn ply_mesh_round_trip_in_every_encoding() {
    let m = decorated_octahedron();
    for enc in ENCODINGS {
        let bytes = mesh_to_bytes(&m, Format::Ply, &ply(enc)).unwrap();
        let back = mesh_from_bytes(&bytes, Format::Ply, "rt.ply").unwrap();
        assert_eq!(back, m, "{enc}");
        // The same file read as a cloud gives the vertices with their attributes.
        let cloud = cloud_from_bytes(&bytes, Format::Ply, "rt.ply").unwrap();
        assert_eq!(cloud.positions(), m.vertices());
        assert_eq!(cloud.normals(), m.vertex_normals());
        assert_eq!(cloud.colors(), m.vertex_colors());
    }
}

#[test]
fn obj_and_off_round_trip_meshes_with_attributes() {
    for format in [Format::Obj, Format::Off] {
        for m in [octahedron(), decorated_octahedron()] {
            let bytes = mesh_to_bytes(&m, format, &WriteOptions::default()).unwrap();
            let back = mesh_from_bytes(&bytes, format, "rt").unwrap();
            assert_eq!(back, m, "{format}");
            assert_bits_equal(back.vertices(), m.vertices());
        }
    }
}

#[test]
fn obj_and_off_round_trip_clouds_as_vertex_only_files() {
    let full = rich_cloud(20);
    let mut c = PointCloud::new(full.positions().to_vec())
        .unwrap()
        .with_normals(full.normals().unwrap().to_vec())
        .unwrap();
    c.set_colors(full.colors().map(<[_]>::to_vec)).unwrap();
    for format in [Format::Obj, Format::Off] {
        let bytes = cloud_to_bytes(&c, format, &WriteOptions::default()).unwrap();
        let back = cloud_from_bytes(&bytes, format, "rt").unwrap();
        assert_eq!(back, c, "{format}");
        // ... and such a file is no mesh.
        let err = mesh_from_bytes(&bytes, format, "rt").unwrap_err();
        assert!(err.to_string().contains("no faces"), "{err}");
    }
}

#[test]
fn stl_round_trip_binary_and_ascii() {
    let m = octahedron();
    // Binary STL stores f32: use a mesh whose coordinates are exact in f32.
    let exact = TriMesh::new(
        m.vertices()
            .iter()
            .map(|p| p.as_vec3().as_dvec3())
            .collect(),
        m.faces().to_vec(),
    )
    .unwrap();
    for binary in [true, false] {
        let opts = WriteOptions {
            stl_binary: binary,
            ..WriteOptions::default()
        };
        let src = if binary { &exact } else { &m };
        let bytes = mesh_to_bytes(src, Format::Stl, &opts).unwrap();
        if binary {
            assert_eq!(bytes.len(), 84 + 50 * 8);
            assert!(!bytes.starts_with(b"solid"));
        }
        let back = mesh_from_bytes(&bytes, Format::Stl, "rt.stl").unwrap();
        // Welding numbers the vertices in order of first use; the triangles are unchanged.
        assert_eq!(back.n_vertices(), src.n_vertices(), "binary={binary}");
        assert_eq!(back.n_faces(), src.n_faces());
        for f in 0..src.n_faces() {
            assert_eq!(back.triangle(f), src.triangle(f), "face {f}");
        }
    }
}

#[test]
fn xyz_and_pts_round_trip_positions_and_normals_exactly() {
    let c = rich_cloud(40);
    let plain = PointCloud::new(c.positions().to_vec()).unwrap();
    let with_normals = plain
        .clone()
        .with_normals(c.normals().unwrap().to_vec())
        .unwrap();
    for format in [Format::Xyz, Format::Pts] {
        for cloud in [&plain, &with_normals] {
            let bytes = cloud_to_bytes(cloud, format, &WriteOptions::default()).unwrap();
            let back = cloud_from_bytes(&bytes, format, "rt").unwrap();
            assert_eq!(&back, cloud, "{format}");
            assert_bits_equal(back.positions(), cloud.positions());
        }
        // Attributes the format cannot hold are dropped, the rest survives.
        let bytes = cloud_to_bytes(&c, format, &WriteOptions::default()).unwrap();
        assert_eq!(
            cloud_from_bytes(&bytes, format, "rt").unwrap(),
            with_normals
        );
    }
}

#[test]
fn file_functions_choose_the_format_from_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    let m = decorated_octahedron();
    for ext in ["ply", "PLY", "obj", "Off"] {
        let p = dir.path().join(format!("m.{ext}"));
        io::write_mesh(&p, &m).unwrap();
        assert_eq!(io::read_mesh(&p).unwrap(), m, "{ext}");
    }
    let p = dir.path().join("m.stl");
    io::write_mesh(&p, &m).unwrap();
    assert_eq!(io::read_mesh(&p).unwrap().n_faces(), 8);
    assert_eq!(std::fs::metadata(&p).unwrap().len(), 84 + 50 * 8);

    let c = rich_cloud(10);
    for ext in ["ply", "xyz", "pts"] {
        let p = dir.path().join(format!("c.{ext}"));
        io::write_cloud(&p, &c).unwrap();
        assert_eq!(io::read_cloud(&p).unwrap().positions(), c.positions());
    }
    let p = dir.path().join("c.ply");
    assert_eq!(io::read_cloud(&p).unwrap(), c);

    // Explicit formats override the extension.
    let p = dir.path().join("cloud.dat");
    let opts = ply(PlyEncoding::Ascii);
    io::write_cloud_with(&p, &c, Format::Ply, &opts).unwrap();
    assert!(
        std::fs::read(&p)
            .unwrap()
            .starts_with(b"ply\nformat ascii 1.0\n")
    );
    assert_eq!(io::read_cloud_as(&p, Format::Ply).unwrap(), c);
    assert!(matches!(
        io::read_cloud(&p),
        Err(GeomError::UnsupportedFormat { .. })
    ));
    let p = dir.path().join("mesh.txt");
    io::write_mesh_with(&p, &m, Format::Off, &WriteOptions::default()).unwrap();
    assert_eq!(io::read_mesh_as(&p, Format::Off).unwrap(), m);
}

#[test]
fn read_any_returns_a_mesh_when_there_are_faces_and_a_cloud_otherwise() {
    let m = decorated_octahedron();
    let c = rich_cloud(7);
    for format in [Format::Ply, Format::Obj, Format::Off] {
        let bytes = mesh_to_bytes(&m, format, &WriteOptions::default()).unwrap();
        assert_eq!(
            io::any_from_bytes(&bytes, format, "m").unwrap(),
            Loaded::Mesh(m.clone())
        );
        let bytes = cloud_to_bytes(&c, format, &WriteOptions::default()).unwrap();
        assert!(matches!(
            io::any_from_bytes(&bytes, format, "c").unwrap(),
            Loaded::Cloud(_)
        ));
    }
    let bytes = cloud_to_bytes(&c, Format::Ply, &WriteOptions::default()).unwrap();
    assert_eq!(
        io::any_from_bytes(&bytes, Format::Ply, "c").unwrap(),
        Loaded::Cloud(c.clone())
    );
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("points.xyz");
    io::write_cloud(&p, &c).unwrap();
    assert!(matches!(io::read_any(&p).unwrap(), Loaded::Cloud(_)));
    assert!(matches!(
        io::read_any_as(&p, Format::Xyz).unwrap(),
        Loaded::Cloud(_)
    ));
    assert!(io::any_from_bytes(b"", Format::Ply, "e.ply").is_err());
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let err = io::read_cloud("/nonexistent/dir/points.xyz").unwrap_err();
    assert!(matches!(err, GeomError::Io { .. }), "{err}");
    assert!(err.to_string().contains("points.xyz"));
}

#[test]
fn formats_refuse_what_they_cannot_hold() {
    let c = rich_cloud(3);
    let err = cloud_to_bytes(&c, Format::Stl, &WriteOptions::default()).unwrap_err();
    assert!(
        err.to_string()
            .contains("format stl stores meshes; use ply or xyz"),
        "{err}"
    );
    let m = octahedron();
    for format in [Format::Xyz, Format::Pts] {
        assert!(mesh_to_bytes(&m, format, &WriteOptions::default()).is_err());
        let err = mesh_from_bytes(b"0 0 0\n", format, "p.xyz").unwrap_err();
        assert!(matches!(err, GeomError::UnsupportedFormat { .. }), "{err}");
    }
    // A refused write leaves no file behind.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("c.stl");
    assert!(io::write_cloud(&p, &c).is_err());
    assert!(!p.exists());
}

#[test]
fn ply_refuses_labels_beyond_int_and_reserved_channel_names() {
    let mut c = PointCloud::new(vec![DVec3::ZERO; 2]).unwrap();
    c.set_channel("big", Channel::Label(vec![0, 1 << 40]))
        .unwrap();
    let err = cloud_to_bytes(&c, Format::Ply, &WriteOptions::default()).unwrap_err();
    assert!(err.to_string().contains("point 1"), "{err}");
    let mut c = PointCloud::new(vec![DVec3::ZERO; 2]).unwrap();
    c.set_channel("nx", Channel::Scalar(vec![0.0, 1.0]))
        .unwrap();
    assert!(cloud_to_bytes(&c, Format::Ply, &WriteOptions::default()).is_err());
}

#[test]
fn binary_stl_refuses_coordinates_beyond_f32() {
    let m = TriMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, 1e300, 0.0)],
        vec![[0, 1, 2]],
    )
    .unwrap();
    assert!(mesh_to_bytes(&m, Format::Stl, &WriteOptions::default()).is_err());
    let ascii = WriteOptions {
        stl_binary: false,
        ..WriteOptions::default()
    };
    let bytes = mesh_to_bytes(&m, Format::Stl, &ascii).unwrap();
    assert_eq!(mesh_from_bytes(&bytes, Format::Stl, "a.stl").unwrap(), m);
}

#[test]
fn empty_cloud_round_trips_through_ply() {
    let c = PointCloud::default();
    for enc in ENCODINGS {
        let bytes = cloud_to_bytes(&c, Format::Ply, &ply(enc)).unwrap();
        assert_eq!(cloud_from_bytes(&bytes, Format::Ply, "e.ply").unwrap(), c);
    }
}

#[test]
fn format_names_parse_and_print() {
    for f in Format::ALL {
        assert_eq!(f.to_string().parse::<Format>().unwrap(), f);
        assert_eq!(f.name().to_uppercase().parse::<Format>().unwrap(), f);
        assert_eq!(
            Format::from_path(format!("a/b.{}", f.name().to_uppercase())).unwrap(),
            f
        );
    }
    let err = "vrml".parse::<Format>().unwrap_err();
    assert!(
        err.to_string().contains("ply, obj, off, stl, xyz, pts"),
        "{err}"
    );
    assert!(Format::from_path("noext").is_err());
    for e in ENCODINGS {
        assert_eq!(e.to_string().parse::<PlyEncoding>().unwrap(), e);
    }
    assert_eq!(
        WriteOptions::default().ply_encoding,
        PlyEncoding::BinaryLittleEndian
    );
    assert!(WriteOptions::default().stl_binary);
}

/// Run with `cargo test --release -p reconbench-geom --test io_roundtrip -- --ignored`.
#[test]
#[ignore = "timing check, meaningful in release builds only"]
fn million_point_binary_ply_is_fast() {
    let n = 1_000_000;
    let positions: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new(i as f64, (i as f64).sqrt(), 1.0 / (i as f64 + 1.0)))
        .collect();
    let mut c = PointCloud::new(positions)
        .unwrap()
        .with_normals(vec![DVec3::Z; n])
        .unwrap();
    c.set_colors(Some(vec![[1, 2, 3]; n])).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.ply");
    let t = std::time::Instant::now();
    io::write_cloud(&p, &c).unwrap();
    let write = t.elapsed();
    let t = std::time::Instant::now();
    let back = io::read_cloud(&p).unwrap();
    let read = t.elapsed();
    eprintln!("1M points: write {write:?}, read {read:?}");
    assert_eq!(back, c);
    assert!(write.as_secs_f64() < 1.0 && read.as_secs_f64() < 1.0);
}

#[test]
fn ply_header_comments_round_trip_in_every_encoding_and_through_a_file() {
    let cloud = rich_cloud(50);
    let comments = vec![
        "reconbench-provenance {\"seed\":7,\"sampler\":\"uniform\"}".to_string(),
        String::new(),
        "  two leading spaces kept".to_string(),
    ];
    for enc in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let opts = WriteOptions {
            ply_encoding: enc,
            ..WriteOptions::default()
        };
        let bytes =
            io::cloud_to_bytes_with_comments(&cloud, Format::Ply, &opts, &comments).unwrap();
        let read = io::ply_comments_from_bytes(&bytes, "c.ply").unwrap();
        assert_eq!(read[0], "written by reconbench (point cloud)", "{enc}");
        assert_eq!(&read[1..], &comments[..], "{enc}");
        // The comments do not disturb the data.
        assert_eq!(
            cloud_from_bytes(&bytes, Format::Ply, "c.ply").unwrap(),
            cloud
        );
    }

    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("c.ply");
    io::write_cloud_with_comments(&ply, &cloud, &comments).unwrap();
    assert_eq!(&io::read_ply_comments(&ply).unwrap()[1..], &comments[..]);
    assert_eq!(io::read_cloud(&ply).unwrap(), cloud);
    // Other formats have no header comments: written without them.
    let xyz = dir.path().join("c.xyz");
    io::write_cloud_with_comments(&xyz, &cloud, &comments).unwrap();
    assert!(io::read_cloud(&xyz).is_ok());
    // A file that is not PLY is an error naming it; a comment with a line break is refused.
    let e = io::read_ply_comments(&xyz).unwrap_err().to_string();
    assert!(e.contains("c.xyz"), "{e}");
    let e = io::write_cloud_with_comments(&ply, &cloud, &["a\nb".to_string()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("line break"), "{e}");
}

#[test]
fn content_hash_is_fnv1a_64_in_hex() {
    assert_eq!(io::content_hash(b""), "cbf29ce484222325");
    assert_eq!(io::content_hash(b"a"), "af63dc4c8601ec8c");
    assert_eq!(io::content_hash(b"foobar"), "85944171f73967e8");
}
