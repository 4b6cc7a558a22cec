//! The file corpus: every broken file must fail with a located error naming the file, and
//! the good corpus holds a closed genus-2 mesh used by CLI acceptance tests.
//!
//! To regenerate `corpus/good/double_torus.ply` after changing the generator, run
//! `RECONBENCH_BLESS_CORPUS=1 cargo test -p reconbench-geom --test io_corpus`.

use std::collections::{HashMap, HashSet};
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use reconbench_geom::io::{self, Format};
use reconbench_geom::{DVec3, GeomError, Location, TriMesh};

fn corpus(sub: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/corpus")
        .join(sub)
}

/// Each broken file with a fragment its error message must contain, so that every file
/// fails for the reason its name gives, not for some other reason.
const BROKEN: &[(&str, &str)] = &[
    ("empty.off", "the file is empty"),
    ("empty.ply", "the file is empty"),
    ("empty.stl", "the file is empty"),
    ("empty.xyz", "the file is empty"),
    ("truncated_binary.ply", "only 30 bytes remain"),
    ("truncated_face_list.ply", "ends inside face 1"),
    (
        "wrong_face_count_binary.ply",
        "found 13 bytes after the last record",
    ),
    ("negative_face_index.ply", "refers to vertex -1"),
    ("huge_vertex_count.ply", "declares 4000000000 records"),
    ("wrong_vertex_count.ply", "vertex 4 has 4 values"),
    ("non_numeric_token.ply", "'abc'"),
    ("nan_coordinate.ply", "non-finite coordinate"),
    ("face_with_two_vertices.ply", "face 0 has 2 vertex indices"),
    ("bad_face_index.ply", "refers to vertex 9"),
    (
        "unknown_property_type.ply",
        "unknown property type 'float128'",
    ),
    ("bad_magic.ply", "starts with the line 'ply'"),
    ("missing_end_header.ply", "end_header"),
    (
        "unknown_encoding.ply",
        "unknown PLY encoding 'binary_middle_endian'",
    ),
    ("float_list_count.ply", "count type float"),
    ("missing_z_property.ply", "no 'z' property"),
    (
        "bad_face_index.obj",
        "refers to vertex 4, but the file defines only 3",
    ),
    ("zero_index.obj", "index 0 is invalid"),
    (
        "relative_index_out_of_range.obj",
        "relative vertex index -4",
    ),
    ("non_numeric_vertex.obj", "'zero'"),
    ("face_with_two_vertices.obj", "a face has 2 vertices"),
    ("unknown_statement.obj", "unknown statement 'vx'"),
    ("infinite_coordinate.obj", "'inf'"),
    ("bad_header.off", "'OFX'"),
    ("wrong_face_count.off", "ends after 1 of 2 faces"),
    ("bad_face_index.off", "refers to vertex 3"),
    ("non_numeric_vertex.off", "'O'"),
    ("short_vertex_line.off", "vertex 1 has 5 values"),
    ("short_binary.stl", "declares 2 triangles"),
    (
        "binary_with_solid_header_wrong_length.stl",
        "contains binary data",
    ),
    (
        "nan_vertex_binary.stl",
        "triangle 0 vertex 1 has a non-finite",
    ),
    ("too_short.stl", "needs at least 84"),
    ("truncated_ascii.stl", "ends inside a solid"),
    ("loop_with_two_vertices.stl", "loop has 2 vertices"),
    ("nan_coordinate.xyz", "'NaN'"),
    ("inconsistent_columns.xyz", "found 6 values; expected 3"),
    ("four_columns.xyz", "found 4 values; expected 3 (x y z)"),
    ("non_numeric_token.xyz", "'x'"),
    (
        "count_mismatch.pts",
        "declares 3 points, but the file has 2",
    ),
    ("non_numeric_count.pts", "'three'"),
    (
        "zero_vertex_id.m",
        "vertex id is 0; ids of .m files are 1-based",
    ),
    ("unknown_vertex_id.m", "refers to vertex id 9"),
    (
        "duplicate_vertex_id.m",
        "vertex id 2 is defined twice (first on line 2)",
    ),
    ("unclosed_attribute.m", "without a closing '}'"),
    ("unknown_record_a3d.pts", "unknown A3d record 'q'"),
    ("normal_before_point_a3d.pts", "before any point"),
];

fn check_broken_error(path: &Path, err: GeomError, fragment: &str) {
    let name = path.file_name().unwrap().to_str().unwrap();
    let text = err.to_string();
    let GeomError::Format { location, .. } = &err else {
        panic!("{name}: expected a format error, got {text}");
    };
    let loc = location.to_string();
    // Visible with `--nocapture`: the messages users will see.
    eprintln!("{text}");
    match location {
        Location::Line(n) => assert!(*n >= 1, "{name}: {text}"),
        Location::Byte(_) | Location::File => {}
    }
    assert!(
        text.contains(name),
        "{name}: message lacks the file name: {text}"
    );
    assert!(
        text.contains(&loc),
        "{name}: message lacks the location: {text}"
    );
    assert!(
        text.contains(fragment),
        "{name}: expected the message to mention {fragment:?}, got: {text}"
    );
}

#[test]
fn every_broken_file_fails_with_a_located_error_naming_it() {
    let dir = corpus("broken");
    let on_disk: HashSet<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    let listed: HashSet<String> = BROKEN.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(on_disk, listed, "corpus files and the BROKEN table differ");
    assert!(BROKEN.len() >= 15);
    for &(name, fragment) in BROKEN {
        let path = dir.join(name);
        assert!(
            std::fs::metadata(&path).unwrap().len() < 100_000,
            "{name} too big"
        );
        let format = Format::from_path(&path).unwrap();
        // Reading as a cloud still parses and validates the faces.
        let err = io::read_cloud(&path).expect_err(name);
        check_broken_error(&path, err, fragment);
        if format.stores_faces() {
            let err = io::read_mesh(&path).expect_err(name);
            check_broken_error(&path, err, fragment);
        }
    }
}

#[test]
fn every_good_file_reads() {
    for entry in std::fs::read_dir(corpus("good")).unwrap() {
        let path = entry.unwrap().path();
        assert!(std::fs::metadata(&path).unwrap().len() < 100_000);
        let format = Format::from_path(&path).unwrap();
        let cloud = io::read_cloud(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!cloud.is_empty(), "{}", path.display());
        if format.stores_faces() {
            let mesh = io::read_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(mesh.vertices(), cloud.positions());
        }
    }
}

// ---------------------------------------------------------------------------------------
// The double torus.

/// A closed genus-2 surface: two torus grids, each with one quad removed, joined by a
/// short square tube between the two holes.
///
/// Torus `t` has `N * M` vertices `(i, j)` (`i` around the main axis, `j` around the
/// tube) and quads `(i, j) (i+1, j) (i+1, j+1) (i, j+1)` split into two triangles, which
/// face outwards. The removed quads face each other across the gap between the tori;
/// the tube quads reuse their boundary edges in the direction the removed quads had, so
/// that orientation stays consistent. Euler: V = 2NM, F = 2 * 2NM - 4 + 8,
/// E = 3F / 2, so V - E + F = -2 and the genus is 2.
fn double_torus() -> TriMesh {
    const N: usize = 24;
    const M: usize = 12;
    let (big_r, small_r) = (1.0, 0.4);
    let centres = [DVec3::ZERO, DVec3::new(3.2, 0.0, 0.0)];
    let id = |t: usize, i: usize, j: usize| (t * N * M + (i % N) * M + (j % M)) as u32;
    let mut vertices = Vec::with_capacity(2 * N * M);
    for c in centres {
        for i in 0..N {
            for j in 0..M {
                let (u, w) = (TAU * i as f64 / N as f64, TAU * j as f64 / M as f64);
                let ring = big_r + small_r * w.cos();
                vertices.push(c + DVec3::new(ring * u.cos(), ring * u.sin(), small_r * w.sin()));
            }
        }
    }
    // Torus 0's quad just below +x (u in [-du, 0]) faces torus 1's quad just past -x
    // (u in [pi, pi + du]); both span the outer equator upwards (j = 0).
    let hole = [(0, N - 1, 0), (1, N / 2, 0)];
    let mut faces = Vec::new();
    for t in 0..2 {
        for i in 0..N {
            for j in 0..M {
                if hole.contains(&(t, i, j)) {
                    continue;
                }
                let (a, b, c, d) = (
                    id(t, i, j),
                    id(t, i + 1, j),
                    id(t, i + 1, j + 1),
                    id(t, i, j + 1),
                );
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            }
        }
    }
    let quad = |(t, i, j): (usize, usize, usize)| {
        [
            id(t, i, j),
            id(t, i + 1, j),
            id(t, i + 1, j + 1),
            id(t, i, j + 1),
        ]
    };
    let [a, b, c, d] = quad(hole[0]);
    let [a2, b2, c2, d2] = quad(hole[1]);
    // Geometric correspondence across the gap: a~b2, b~a2, c~d2, d~c2.
    for [p, q, r, s] in [
        [a, b, a2, b2],
        [b, c, d2, a2],
        [c, d, c2, d2],
        [d, a, b2, c2],
    ] {
        faces.push([p, q, r]);
        faces.push([p, r, s]);
    }
    TriMesh::new(vertices, faces).unwrap()
}

/// Euler characteristic, after checking that `m` is a closed, consistently oriented,
/// connected 2-manifold without degenerate faces (each directed edge once, its reverse
/// once, every vertex link a single cycle).
fn closed_manifold_euler(m: &TriMesh) -> i64 {
    let mut directed = HashSet::new();
    for f in 0..m.n_faces() {
        assert!(m.face_area(f) > 1e-6, "face {f} is degenerate");
        let t = m.faces()[f];
        for k in 0..3 {
            assert!(
                directed.insert((t[k], t[(k + 1) % 3])),
                "directed edge repeated: inconsistent orientation or non-manifold edge"
            );
        }
    }
    for &(u, v) in &directed {
        assert!(directed.contains(&(v, u)), "boundary edge {u}-{v}");
    }
    let edges = directed.len() / 2;
    // Vertex links: the map next -> next-next around each vertex is one cycle.
    let mut link: HashMap<u32, HashMap<u32, u32>> = HashMap::new();
    for t in m.faces() {
        for k in 0..3 {
            let prev = link
                .entry(t[k])
                .or_default()
                .insert(t[(k + 1) % 3], t[(k + 2) % 3]);
            assert!(prev.is_none(), "vertex {} is not manifold", t[k]);
        }
    }
    assert_eq!(link.len(), m.n_vertices(), "isolated vertices");
    for (v, l) in &link {
        let start = *l.keys().next().unwrap();
        let (mut cur, mut steps) = (start, 0);
        loop {
            cur = l[&cur];
            steps += 1;
            if cur == start {
                break;
            }
            assert!(steps <= l.len(), "vertex {v}: link is not a cycle");
        }
        assert_eq!(steps, l.len(), "vertex {v}: link has several cycles");
    }
    // Connectivity by union-find over edges.
    let mut parent: Vec<usize> = (0..m.n_vertices()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for &(u, v) in &directed {
        let (ru, rv) = (find(&mut parent, u as usize), find(&mut parent, v as usize));
        parent[ru] = rv;
    }
    let root = find(&mut parent, 0);
    assert!(
        (0..m.n_vertices()).all(|v| find(&mut parent, v) == root),
        "not connected"
    );
    m.n_vertices() as i64 - edges as i64 + m.n_faces() as i64
}

#[test]
fn generated_double_torus_is_a_closed_genus_2_manifold() {
    let m = double_torus();
    assert_eq!(closed_manifold_euler(&m), -2);
    // Outward orientation: positive enclosed volume.
    let vol: f64 = (0..m.n_faces())
        .map(|f| {
            let [a, b, c] = m.triangle(f);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!(vol > 0.0, "{vol}");
}

#[test]
fn double_torus_corpus_file_is_current_and_genus_2() {
    let path = corpus("good").join("double_torus.ply");
    let m = double_torus();
    if std::env::var_os("RECONBENCH_BLESS_CORPUS").is_some() {
        io::write_mesh(&path, &m).unwrap();
    }
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    assert!(bytes.len() < 100_000);
    let stored = io::read_mesh(&path).unwrap();
    assert_eq!(stored.faces(), m.faces());
    for (p, q) in stored.vertices().iter().zip(m.vertices()) {
        assert!(p.distance(*q) < 1e-12);
    }
    assert_eq!(closed_manifold_euler(&stored), -2);
}
