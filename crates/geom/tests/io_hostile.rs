//! Hostile input: header counts the file cannot hold, endless bodies of zeros (as files
//! and as streams), lines without end, control characters in quoted tokens, colours off
//! their scale. Each must fail with a one-line error naming the file and what is wrong,
//! quickly and without allocating what the header claims (an allocation of the 48 GB a
//! count of 4e9 points would ask for aborts the test process, so these tests fail when a
//! bound is missing).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use reconbench_geom::io::{self, Format, Loaded};
use reconbench_geom::{GeomError, Location};

/// Generous wall-clock bound of one hostile read (each takes milliseconds; the bound only
/// catches a read that buffers gigabytes or loops on a huge count).
const READ_BUDGET: Duration = Duration::from_secs(5);

fn hostile(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/corpus/hostile")
        .join(name)
}

/// Each hostile corpus file with a fragment its error must contain.
const HOSTILE: &[(&str, &str)] = &[
    (
        "huge_vertex_count_zeros.ply",
        "element 'vertex' declares 4000000000 records of 12 bytes (48000000000 bytes), but \
         only 4096 bytes remain",
    ),
    (
        "huge_vertex_count_ascii.ply",
        "element 'vertex' declares 4000000000 records of 3 properties",
    ),
    (
        "huge_face_count.ply",
        "element 'face' declares 4000000000 records of at least 1 bytes",
    ),
    ("huge_list_count.ply", "ends inside face 0"),
    (
        "trailing_zeros.ply",
        "found 4084 bytes after the last record of element 'vertex'",
    ),
    ("nul_body.ply", r"is '\x00\x00\x00"),
    (
        "escape_in_property_type.ply",
        r"unknown property type 'fl\x1b]0;pwned\x07oat'",
    ),
    (
        "huge_counts.off",
        "declares 4000000000 vertices and 4000000000 faces",
    ),
    (
        "huge_triangle_count.stl",
        "declares 4000000000 triangles, which take 200000000084 bytes, but the file has 184",
    ),
    ("nul_line.xyz", "found 1 values; expected 3 (x y z)"),
    ("escape_sequence_token.obj", r"found '\x1b[31mred'"),
    (
        "colour_255.obj",
        "vertex 2: colour component 255 is outside 0..1",
    ),
    (
        "colour_above_one.off",
        "colour component 1.5 is outside 0..1",
    ),
    (
        "colour_above_one.ply",
        "vertex 0: colour component 2 is outside 0..1",
    ),
    (
        "huge_count.pts",
        "declares 4000000000 points, but the file has 1 rows",
    ),
    ("nul_id.m", r"found '\x00'"),
    ("bidi_override.xyz", r"found '\u{202e}1'"),
    ("vertical_tab_token.obj", r"'1\x0b2'"),
];

/// The checks every hostile error must pass: a format error naming the file and its
/// location, on one line, with no raw control character.
fn check_error(name: &str, err: &GeomError, fragment: &str) {
    let text = err.to_string();
    assert!(
        matches!(err, GeomError::Format { .. }),
        "{name}: expected a format error, got {text}"
    );
    assert!(text.contains(name), "{name}: no file name in {text:?}");
    assert!(
        !text.chars().any(char::is_control),
        "{name}: raw control character in {text:?}"
    );
    assert!(
        text.contains(fragment),
        "{name}: expected {fragment:?} in {text:?}"
    );
}

fn timed<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let out = f();
    let dt = t.elapsed();
    assert!(dt < READ_BUDGET, "{what} took {dt:?}");
    out
}

#[test]
fn every_hostile_file_fails_fast_with_a_one_line_error_naming_it() {
    let dir = hostile("");
    let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = HOSTILE.iter().map(|(n, _)| n.to_string()).collect();
    listed.sort();
    assert_eq!(
        on_disk, listed,
        "every hostile file is listed, and only those"
    );
    for &(name, fragment) in HOSTILE {
        let path = hostile(name);
        let err = timed(name, || io::read_any(&path)).expect_err(name);
        check_error(name, &err, fragment);
        // The in-memory parser reaches the same verdict.
        let bytes = std::fs::read(&path).unwrap();
        let format = Format::from_path(&path).unwrap();
        let err = timed(name, || io::any_from_bytes(&bytes, format, name)).expect_err(name);
        check_error(name, &err, fragment.split(" (").next().unwrap());
    }
}

fn ply_header(encoding: &str, vertices: u64) -> Vec<u8> {
    format!(
        "ply\nformat {encoding} 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nend_header\n"
    )
    .into_bytes()
}

fn write_file(dir: &Path, name: &str, parts: &[&[u8]]) -> PathBuf {
    let path = dir.join(name);
    let mut f = std::fs::File::create(&path).unwrap();
    for p in parts {
        f.write_all(p).unwrap();
    }
    path
}

#[test]
fn a_header_count_the_file_cannot_hold_names_the_count_and_the_bytes_left() {
    let dir = tempfile::tempdir().unwrap();
    let zeros = vec![0u8; 5 << 20];
    let path = write_file(
        dir.path(),
        "big.ply",
        &[&ply_header("binary_little_endian", 4_000_000_000), &zeros],
    );
    let err = timed("big.ply", || io::read_any(&path)).unwrap_err();
    check_error(
        "big.ply",
        &err,
        "element 'vertex' declares 4000000000 records of 12 bytes (48000000000 bytes), but \
         only 5242880 bytes remain after the header in the file",
    );
    // A count that fits is read, and a count one record too large is refused.
    let fits = write_file(
        dir.path(),
        "fits.ply",
        &[
            &ply_header("binary_little_endian", (5 << 20) / 12),
            &zeros[..(5 << 20) / 12 * 12],
        ],
    );
    match io::read_any(&fits).unwrap() {
        Loaded::Cloud(c) => assert_eq!(c.len(), (5 << 20) / 12),
        Loaded::Mesh(_) => panic!("no faces were declared"),
    }
    let one_more = write_file(
        dir.path(),
        "one_more.ply",
        &[
            &ply_header("binary_little_endian", (5 << 20) / 12 + 1),
            &zeros[..(5 << 20) / 12 * 12],
        ],
    );
    let err = io::read_any(&one_more).unwrap_err().to_string();
    assert!(err.contains("only 5242872 bytes remain"), "{err}");
}

#[test]
fn a_file_without_line_breaks_is_refused_after_the_line_limit_in_every_text_format() {
    let dir = tempfile::tempdir().unwrap();
    let zeros = vec![0u8; io::MAX_LINE_BYTES + (64 << 10)];
    let header = ply_header("ascii", 1);
    let cases: [(&str, &[u8], usize); 6] = [
        ("endless.xyz", b"", 1),
        ("endless.obj", b"v 0 0 0\n", 2),
        ("endless.off", b"OFF\n", 2),
        ("endless.m", b"", 1),
        ("endless.pts", b"", 1),
        ("endless.ply", &header, 8),
    ];
    for (name, head, line) in cases {
        let path = write_file(dir.path(), name, &[head, &zeros]);
        let err = timed(name, || io::read_any(&path)).unwrap_err();
        check_error(
            name,
            &err,
            &format!("is longer than {} bytes", io::MAX_LINE_BYTES),
        );
        let GeomError::Format { location, .. } = err else {
            unreachable!()
        };
        assert_eq!(location, Location::Line(line), "{name}");
    }
    // A long line under the limit is fine: the limit is on the line, not on the file.
    let mut row = "0 0 0".to_string();
    row.push_str(&" ".repeat(io::MAX_LINE_BYTES - 10));
    row.push('\n');
    let path = write_file(dir.path(), "wide.xyz", &[row.as_bytes(), row.as_bytes()]);
    match io::read_any(&path).unwrap() {
        Loaded::Cloud(c) => assert_eq!(c.len(), 2),
        Loaded::Mesh(_) => panic!("xyz has no faces"),
    }
}

#[test]
fn fixed_size_records_followed_by_megabytes_of_zeros_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let zeros = vec![0u8; 4 << 20];
    let path = write_file(
        dir.path(),
        "tail.ply",
        &[&ply_header("binary_big_endian", 2), &zeros],
    );
    let err = timed("tail.ply", || io::read_any(&path)).unwrap_err();
    check_error(
        "tail.ply",
        &err,
        &format!(
            "found {} bytes after the last record of element 'vertex'",
            (4 << 20) - 24
        ),
    );
}

#[test]
fn a_binary_stl_count_beyond_the_file_is_refused_and_an_exact_one_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut head = vec![0u8; 80];
    head.extend_from_slice(&u32::MAX.to_le_bytes());
    let path = write_file(dir.path(), "big.stl", &[&head, &[0u8; 1000]]);
    let err = timed("big.stl", || io::read_any(&path)).unwrap_err();
    check_error(
        "big.stl",
        &err,
        "declares 4294967295 triangles, which take 214748364834 bytes, but the file has 1084",
    );
    let mut one = vec![0u8; 80];
    one.extend_from_slice(&1u32.to_le_bytes());
    let mut tri = [0u8; 50];
    for (k, v) in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .iter()
        .enumerate()
    {
        for (a, c) in v.iter().enumerate() {
            let at = 12 + 12 * k + 4 * a;
            tri[at..at + 4].copy_from_slice(&c.to_le_bytes());
        }
    }
    let path = write_file(dir.path(), "one.stl", &[&one, &tri]);
    match io::read_any(&path).unwrap() {
        Loaded::Mesh(m) => assert_eq!((m.n_vertices(), m.n_faces()), (3, 1)),
        Loaded::Cloud(_) => panic!("an STL triangle is a mesh"),
    }
}

/// A stream that never ends: every format must give up on `/dev/zero` at once (a PLY or
/// a text file at its first line, an STL after the triangles its count declares), not
/// read until memory runs out.
#[cfg(target_os = "linux")]
#[test]
fn dev_zero_is_refused_quickly_in_every_format() {
    for format in Format::ALL {
        let what = format!("/dev/zero as {format}");
        let err = timed(&what, || io::read_any_as("/dev/zero", format)).unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with("/dev/zero: "), "{what}: {text}");
        assert!(!text.chars().any(char::is_control), "{what}: {text:?}");
    }
}

/// Writes `head` and then zeros to a FIFO until the reader hangs up; returns the FIFO's
/// path and the writer thread (which ends when the reader closes the FIFO).
#[cfg(unix)]
fn endless_fifo(dir: &Path, name: &str, head: Vec<u8>) -> (PathBuf, std::thread::JoinHandle<u64>) {
    let path = dir.join(name);
    let status = std::process::Command::new("mkfifo")
        .arg(&path)
        .status()
        .expect("mkfifo runs");
    assert!(status.success(), "mkfifo failed");
    let p = path.clone();
    let writer = std::thread::spawn(move || {
        let mut f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
        let zeros = vec![0u8; 1 << 16];
        let mut sent = 0u64;
        if f.write_all(&head).is_err() {
            return sent;
        }
        // Stop at 4 GiB in any case, so that a reader without bounds fails the test by
        // its memory or time, not by hanging forever.
        while sent < 4 << 30 {
            if f.write_all(&zeros).is_err() {
                break;
            }
            sent += zeros.len() as u64;
        }
        sent
    });
    (path, writer)
}

#[cfg(unix)]
#[test]
fn an_endless_stream_of_zeros_after_a_ply_header_is_refused_without_reading_it() {
    let dir = tempfile::tempdir().unwrap();
    // Binary: the count is refused from the header alone.
    let (path, writer) = endless_fifo(
        dir.path(),
        "stream.ply",
        ply_header("binary_little_endian", 4_000_000_000),
    );
    let err = timed("binary stream", || io::read_any(&path)).unwrap_err();
    check_error(
        "stream.ply",
        &err,
        &format!(
            "within the {} bytes read from a stream (not a regular file)",
            io::MAX_STREAM_BYTES
        ),
    );
    let sent = writer.join().unwrap();
    assert!(sent < 64 << 20, "the reader took {sent} bytes of zeros");

    // Ascii: the first body line has no end.
    let (path, writer) = endless_fifo(dir.path(), "stream_ascii.ply", ply_header("ascii", 3));
    let err = timed("ascii stream", || io::read_any(&path)).unwrap_err();
    check_error("stream_ascii.ply", &err, "is longer than 1048576 bytes");
    let sent = writer.join().unwrap();
    assert!(sent < 64 << 20, "the reader took {sent} bytes of zeros");

    // Binary with a count that fits the stream limit: exactly the records (and one byte
    // more, to see the trailing data) are read.
    let (path, writer) = endless_fifo(
        dir.path(),
        "stream_small.ply",
        ply_header("binary_little_endian", 1000),
    );
    let err = timed("small stream", || io::read_any(&path)).unwrap_err();
    check_error(
        "stream_small.ply",
        &err,
        "bytes after the last record of element 'vertex'",
    );
    assert!(err.to_string().contains("found at least "), "{err}");
    let sent = writer.join().unwrap();
    assert!(sent < 64 << 20, "the reader took {sent} bytes of zeros");
}

#[cfg(unix)]
#[test]
fn a_stream_is_read_like_the_file_it_carries() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = reconbench_geom::PointCloud::new(vec![
        reconbench_geom::DVec3::new(0.0, 1.0, 2.0),
        reconbench_geom::DVec3::new(-1.0, 0.5, 3.0),
    ])
    .unwrap();
    for format in [Format::Ply, Format::Xyz, Format::Obj, Format::Off] {
        let bytes = io::cloud_to_bytes(&cloud, format, &io::WriteOptions::default()).unwrap();
        let path = dir.path().join(format!("cloud_stream.{format}"));
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&path)
                .status()
                .unwrap()
                .success()
        );
        let p = path.clone();
        let writer = std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
            f.write_all(&bytes).unwrap();
        });
        let read = io::read_cloud(&path).unwrap();
        writer.join().unwrap();
        assert_eq!(read.positions(), cloud.positions(), "{format}");
    }
}

#[test]
fn control_characters_in_any_quoted_token_are_escaped() {
    // A raw byte of every ASCII control value (and DEL) in a token of each text format.
    for b in (0u8..0x20).chain([0x7f]) {
        if matches!(b, b'\n' | b'\r' | b'\t' | 0x0c | b' ') {
            continue; // separators, not token bytes
        }
        let tok = format!("1{}x", b as char);
        let inputs: [(&str, Format, String); 6] = [
            ("t.xyz", Format::Xyz, format!("0 0 {tok}\n")),
            ("t.obj", Format::Obj, format!("v 0 0 {tok}\n")),
            ("t.off", Format::Off, format!("OFF\n1 0 0\n0 0 {tok}\n")),
            ("t.m", Format::M, format!("Vertex 1 0 0 {tok}\n")),
            ("t.pts", Format::Pts, format!("{tok}\n")),
            (
                "t.ply",
                Format::Ply,
                format!("ply\nformat ascii 1.0\nelement vertex 1\nproperty f{tok} x\nend_header\n"),
            ),
        ];
        for (name, format, text) in inputs {
            let err = io::any_from_bytes(text.as_bytes(), format, name).unwrap_err();
            let msg = err.to_string();
            assert!(
                !msg.chars().any(char::is_control),
                "{name} byte {b:#04x}: {msg:?}"
            );
            assert!(
                msg.contains(&format!("\\x{b:02x}")),
                "{name} byte {b:#04x}: {msg:?}"
            );
        }
    }
}

#[test]
fn obj_colours_off_the_unit_scale_are_refused_not_clamped() {
    let ok = io::any_from_bytes(b"v 0 0 0 0 0.5 1\n", Format::Obj, "ok.obj").unwrap();
    let Loaded::Cloud(c) = ok else {
        panic!("no faces")
    };
    assert_eq!(c.colors().unwrap(), &[[0, 128, 255]]);
    for bad in ["1.0001", "-0.5", "255", "1e309"] {
        let text = format!("v 0 0 0\nv 0 0 0 0 {bad} 0\n");
        let err = io::any_from_bytes(text.as_bytes(), Format::Obj, "c.obj")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("c.obj: line 2: "), "{bad}: {err}");
        assert!(
            err.contains("outside 0..1") || err.contains("finite"),
            "{bad}: {err}"
        );
    }
    let err = io::any_from_bytes(b"v 0 0 0 255 128 0\n", Format::Obj, "c.obj")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("colour component 255 is outside 0..1") && err.contains("divide"),
        "{err}"
    );
}
