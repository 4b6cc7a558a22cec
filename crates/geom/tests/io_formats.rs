//! Reader features per format: the variants and corner cases each parser must accept.

use std::path::PathBuf;

use reconbench_geom::io::{Format, cloud_from_bytes, mesh_from_bytes, read_cloud, read_mesh};
use reconbench_geom::{Channel, DVec3, GeomError, Location};

fn good(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/corpus/good")
        .join(name)
}

fn format_location(err: &GeomError) -> Location {
    match err {
        GeomError::Format { location, .. } => *location,
        other => panic!("expected a format error, got {other}"),
    }
}

// ---------------------------------------------------------------------------------------
// PLY

/// A typed PLY value, to build the same file in all three encodings.
#[derive(Debug, Clone, Copy)]
enum V {
    C(i8),
    Uc(u8),
    S(i16),
    Us(u16),
    I(i32),
    Ui(u32),
    F(f32),
    D(f64),
}

fn encode_ply(header: &str, records: &[Vec<V>], enc: &str) -> Vec<u8> {
    let mut out = header.replace("{enc}", enc).into_bytes();
    let big = enc == "binary_big_endian";
    for rec in records {
        if enc == "ascii" {
            let toks: Vec<String> = rec
                .iter()
                .map(|v| match *v {
                    V::C(x) => x.to_string(),
                    V::Uc(x) => x.to_string(),
                    V::S(x) => x.to_string(),
                    V::Us(x) => x.to_string(),
                    V::I(x) => x.to_string(),
                    V::Ui(x) => x.to_string(),
                    V::F(x) => x.to_string(),
                    V::D(x) => format!("{x:e}"),
                })
                .collect();
            out.extend_from_slice(toks.join(" ").as_bytes());
            out.push(b'\n');
        } else {
            for v in rec {
                macro_rules! put {
                    ($x:expr) => {
                        if big {
                            out.extend_from_slice(&$x.to_be_bytes())
                        } else {
                            out.extend_from_slice(&$x.to_le_bytes())
                        }
                    };
                }
                match *v {
                    V::C(x) => put!(x),
                    V::Uc(x) => put!(x),
                    V::S(x) => put!(x),
                    V::Us(x) => put!(x),
                    V::I(x) => put!(x),
                    V::Ui(x) => put!(x),
                    V::F(x) => put!(x),
                    V::D(x) => put!(x),
                }
            }
        }
    }
    out
}

const MIXED_HEADER: &str = "ply
format {enc} 1.0
comment every integer type, lists in skipped elements and in the vertex element
element vertex 4
property double x
property float y
property short z
property list uchar int extra_list
property float red
property float green
property float blue
property ushort label16
property char label8
property double weight
property uint source_id
element edge 1
property int vertex1
property list uint short path
element face 2
property list ushort char vertex_index
property uint material_id
element material 2
property list int double coefficients
end_header
";

fn mixed_records() -> Vec<Vec<V>> {
    use V::*;
    let vertex = |x: f64, y: f32, z: i16, list: &[i32], c: [f32; 3], l16, l8, w, sid| {
        let mut r = vec![D(x), F(y), S(z), Uc(list.len() as u8)];
        r.extend(list.iter().map(|&i| I(i)));
        r.extend([F(c[0]), F(c[1]), F(c[2]), Us(l16), C(l8), D(w), Ui(sid)]);
        r
    };
    vec![
        vertex(
            0.5,
            1.25,
            -3,
            &[7, 8],
            [0.0, 1.0, 0.5],
            65535,
            -5,
            1e-300,
            4,
        ),
        vertex(-1.0 / 3.0, 0.0, 0, &[], [1.0, 1.0, 1.0], 0, 127, 2.5, 3),
        vertex(1e10, -2.5, 300, &[1], [0.2, 0.4, 0.6], 7, -128, -0.0, 2),
        vertex(4.0, 5.0, 6, &[], [0.0, 0.0, 0.0], 1, 0, 7.0, 4_000_000_000),
        vec![I(0), Ui(3), S(0), S(1), S(2)],
        vec![Us(4), C(0), C(1), C(2), C(3), Ui(9)],
        vec![Us(3), C(3), C(2), C(1), Ui(1)],
        vec![I(2), D(0.5), D(0.25)],
        vec![I(0)],
    ]
}

#[test]
fn ply_reads_all_types_and_skips_unknown_elements_in_every_encoding() {
    let records = mixed_records();
    for enc in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let bytes = encode_ply(MIXED_HEADER, &records, enc);
        let m = mesh_from_bytes(&bytes, Format::Ply, "mixed.ply").unwrap();
        assert_eq!(m.faces(), &[[0, 1, 2], [0, 2, 3], [3, 2, 1]], "{enc}");
        let c = cloud_from_bytes(&bytes, Format::Ply, "mixed.ply").unwrap();
        assert_eq!(
            c.positions(),
            &[
                DVec3::new(0.5, 1.25, -3.0),
                DVec3::new(-1.0 / 3.0, 0.0, 0.0),
                DVec3::new(1e10, -2.5, 300.0),
                DVec3::new(4.0, 5.0, 6.0),
            ],
            "{enc}"
        );
        assert_eq!(
            c.colors().unwrap(),
            &[[0, 255, 128], [255, 255, 255], [51, 102, 153], [0, 0, 0]]
        );
        assert_eq!(c.source_ids().unwrap(), &[4, 3, 2, 4_000_000_000]);
        assert_eq!(
            c.channel("label16"),
            Some(&Channel::Label(vec![65535, 0, 7, 1]))
        );
        assert_eq!(
            c.channel("label8"),
            Some(&Channel::Label(vec![-5, 127, -128, 0]))
        );
        assert_eq!(
            c.channel("weight"),
            Some(&Channel::Scalar(vec![1e-300, 2.5, -0.0, 7.0]))
        );
        assert!(c.channel("extra_list").is_none());
        assert_eq!(c.channels().len(), 3);
        assert!(c.normals().is_none());
    }
}

#[test]
fn ply_good_corpus_file_with_extra_elements() {
    let c = read_cloud(good("extra_elements_ascii.ply")).unwrap();
    assert_eq!(c.len(), 4);
    assert_eq!(c.source_ids().unwrap(), &[10, 11, 12, 13]);
    assert_eq!(
        c.colors().unwrap(),
        &[[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128]]
    );
    assert_eq!(
        c.channel("quality"),
        Some(&Channel::Scalar(vec![0.5, 1.5, 2.5, 3.5]))
    );
    assert_eq!(c.channel("flags"), Some(&Channel::Label(vec![1, 2, 3, 4])));
    let m = read_mesh(good("extra_elements_ascii.ply")).unwrap();
    assert_eq!(m.faces(), &[[0, 1, 2], [0, 2, 3], [0, 2, 1]]);
}

#[test]
fn ply_truncation_is_reported_at_the_byte_where_data_runs_out() {
    let bytes = encode_ply(MIXED_HEADER, &mixed_records(), "binary_little_endian");
    let body = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    for cut in [body + 5, bytes.len() - 20, bytes.len() - 1] {
        let err = mesh_from_bytes(&bytes[..cut], Format::Ply, "cut.ply").unwrap_err();
        match format_location(&err) {
            Location::Byte(b) => assert!(b as usize >= body && b as usize <= cut, "{err}"),
            other => panic!("expected a byte offset, got {other:?}: {err}"),
        }
    }
    // Every prefix fails cleanly, never panics, never reads partially.
    for cut in 0..bytes.len() {
        assert!(cloud_from_bytes(&bytes[..cut], Format::Ply, "cut.ply").is_err());
    }
}

#[test]
fn ply_huge_declared_counts_do_not_allocate() {
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 18446744073709551615\n\
                  property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    let err = cloud_from_bytes(ascii, Format::Ply, "huge.ply").unwrap_err();
    assert!(
        err.to_string()
            .contains("declares 18446744073709551615 records of 3 properties"),
        "{err}"
    );
    let binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n\
                   property float x\nproperty float y\nproperty float z\nend_header\n0000";
    let err = cloud_from_bytes(binary, Format::Ply, "huge.ply").unwrap_err();
    assert!(err.to_string().contains("only 4 bytes remain"), "{err}");
}

#[test]
fn ply_crlf_header_and_ascii_body_are_accepted() {
    let text = "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\n\
                property float y\r\nproperty float z\r\nelement face 1\r\n\
                property list uchar uint vertex_indices\r\nend_header\r\n\
                0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n";
    let m = mesh_from_bytes(text.as_bytes(), Format::Ply, "crlf.ply").unwrap();
    assert_eq!(m.faces(), &[[0, 1, 2]]);
}

#[test]
fn ply_non_finite_normal_is_rejected_with_its_line() {
    let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                end_header\n0 0 0 0 0 1\n1 0 0 0 inf 1\n";
    let err = cloud_from_bytes(text.as_bytes(), Format::Ply, "n.ply").unwrap_err();
    assert_eq!(format_location(&err), Location::Line(12), "{err}");
    assert!(err.to_string().contains("vertex 1"), "{err}");
}

// ---------------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_cube_with_every_corner_form_and_relative_indices() {
    let m = read_mesh(good("cube_polygons.obj")).unwrap();
    assert_eq!(m.n_vertices(), 8);
    assert_eq!(m.n_faces(), 12);
    assert!((m.area() - 6.0).abs() < 1e-12);
    // Outward orientation throughout: the signed volume is +1.
    let vol: f64 = (0..12)
        .map(|f| {
            let [a, b, c] = m.triangle(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!((vol - 1.0).abs() < 1e-12, "{vol}");
    // Only some vertices are referenced with a normal: no vertex normals.
    assert!(m.vertex_normals().is_none());
    assert_eq!(read_cloud(good("cube_polygons.obj")).unwrap().len(), 8);
}

#[test]
fn obj_vertex_normals_from_corner_references_and_colours() {
    let text = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\nvn 0 0 1\nvn 0 0 -1\n\
                f 1//1 2//1 3//1\nf 3//2 2//2 1//2\n";
    let m = mesh_from_bytes(text.as_bytes(), Format::Obj, "n.obj").unwrap();
    assert_eq!(m.vertex_normals().unwrap(), &[DVec3::Z; 3]);
    assert_eq!(
        m.vertex_colors().unwrap(),
        &[[255, 0, 0], [0, 255, 0], [0, 0, 128]]
    );
    // Forward references are legal as long as the vertex exists by the end of the file.
    let text = "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let m = mesh_from_bytes(text.as_bytes(), Format::Obj, "fwd.obj").unwrap();
    assert_eq!(m.faces(), &[[0, 1, 2]]);
}

#[test]
fn obj_forward_reference_beyond_the_end_names_its_line() {
    let text = "f 1 2 3\nf 1 2 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let err = mesh_from_bytes(text.as_bytes(), Format::Obj, "fwd.obj").unwrap_err();
    assert_eq!(format_location(&err), Location::Line(2), "{err}");
    assert!(err.to_string().contains("vertex 9"), "{err}");
}

// ---------------------------------------------------------------------------------------
// OFF

#[test]
fn off_cnoff_cube_with_comments_and_face_colours() {
    let m = read_mesh(good("cube_cnoff.off")).unwrap();
    assert_eq!(m.n_vertices(), 8);
    assert_eq!(m.n_faces(), 12);
    assert!((m.area() - 6.0).abs() < 1e-12);
    assert_eq!(m.vertex_normals().unwrap()[0], DVec3::splat(-1.0));
    let colors = m.vertex_colors().unwrap();
    assert_eq!(colors[0], [255, 0, 0]);
    assert_eq!(colors[3], [255, 255, 0]);
    assert_eq!(colors[7], [10, 20, 30]);
}

#[test]
fn off_variants() {
    let cases: [(&str, bool, bool); 5] = [
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", false, false),
        ("OFF 3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", false, false),
        (
            "COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0 255 0 1\n0 1 0 0 0 255 255\n3 0 1 2\n",
            true,
            false,
        ),
        (
            "NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2 0.1 0.2 0.3\n",
            false,
            true,
        ),
        (
            "STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n",
            false,
            false,
        ),
    ];
    for (text, color, normal) in cases {
        let m = mesh_from_bytes(text.as_bytes(), Format::Off, "v.off").unwrap();
        assert_eq!(m.faces(), &[[0, 1, 2]], "{text}");
        assert_eq!(m.vertex_colors().is_some(), color, "{text}");
        assert_eq!(m.vertex_normals().is_some(), normal, "{text}");
    }
    let err = mesh_from_bytes(b"4OFF\n0 0 0\n", Format::Off, "4d.off").unwrap_err();
    assert!(err.to_string().contains("not supported"), "{err}");
}

// ---------------------------------------------------------------------------------------
// STL

#[test]
fn stl_ascii_tetra_is_welded_and_closed() {
    let m = read_mesh(good("tetra_ascii.stl")).unwrap();
    assert_eq!(m.n_vertices(), 4);
    assert_eq!(m.n_faces(), 4);
    assert_eq!(read_cloud(good("tetra_ascii.stl")).unwrap().len(), 4);
}

fn binary_stl(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut out = header.to_vec();
    out.resize(80, b' ');
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        out.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

#[test]
fn stl_binary_is_detected_by_size_even_with_a_solid_header() {
    let tris = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        // -0.0 welds with 0.0.
        [[-0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
    ];
    let bytes = binary_stl(b"solid but actually binary", &tris);
    let m = mesh_from_bytes(&bytes, Format::Stl, "b.stl").unwrap();
    assert_eq!(m.n_vertices(), 4);
    assert_eq!(m.faces(), &[[0, 1, 2], [2, 1, 3]]);
    // Zero triangles: a valid, empty cloud, but no mesh.
    let empty = binary_stl(b"nothing", &[]);
    assert!(
        cloud_from_bytes(&empty, Format::Stl, "e.stl")
            .unwrap()
            .is_empty()
    );
    let err = mesh_from_bytes(&empty, Format::Stl, "e.stl").unwrap_err();
    assert!(err.to_string().contains("no faces"), "{err}");
}

#[test]
fn stl_ascii_polygon_loops_are_fanned_and_keywords_case_insensitive() {
    let text = "SOLID quad\nFACET NORMAL 0 0 1\nOUTER LOOP\nVERTEX 0 0 0\nVERTEX 1 0 0\n\
                VERTEX 1 1 0\nVERTEX 0 1 0\nENDLOOP\nENDFACET\nENDSOLID quad\n";
    let m = mesh_from_bytes(text.as_bytes(), Format::Stl, "q.stl").unwrap();
    assert_eq!(m.faces(), &[[0, 1, 2], [0, 2, 3]]);
}

// ---------------------------------------------------------------------------------------
// XYZ / PTS

#[test]
fn xyz_commas_comments_and_normals() {
    let c = read_cloud(good("points_comma.xyz")).unwrap();
    assert_eq!(
        c.positions(),
        &[
            DVec3::new(0.25, 0.5, 0.75),
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(-4.0, -5.0, -6.0)
        ]
    );
    assert_eq!(c.normals().unwrap(), &[DVec3::Z, DVec3::X, DVec3::Y]);
}

#[test]
fn pts_count_line_intensity_and_colours() {
    let c = read_cloud(good("points_with_intensity.pts")).unwrap();
    assert_eq!(c.len(), 3);
    assert_eq!(c.positions()[2], DVec3::new(-1e-3, 2e10, 0.0));
    assert_eq!(
        c.colors().unwrap(),
        &[[255, 0, 0], [0, 255, 0], [0, 0, 255]]
    );
    assert_eq!(
        c.channel("intensity"),
        Some(&Channel::Scalar(vec![-120.0, 40.0, 7.0]))
    );
    let c = cloud_from_bytes(b"1 2 3 0.5\n4 5 6 0.25\n", Format::Pts, "i.pts").unwrap();
    assert_eq!(
        c.channel("intensity"),
        Some(&Channel::Scalar(vec![0.5, 0.25]))
    );
    // Only comments: an empty cloud, not an error.
    let c = cloud_from_bytes(b"# nothing yet\n", Format::Xyz, "e.xyz").unwrap();
    assert!(c.is_empty());
}
