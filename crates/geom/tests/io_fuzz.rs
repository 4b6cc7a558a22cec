//! A deterministic, structure-aware fuzz run of every reader, on the stable toolchain.
//!
//! Seeds are the corpus files (`tests/corpus/{good,broken,hostile}`, the first 16 KiB of
//! each) and small valid files of every format written by this crate. Each round mutates
//! a seed the way broken files break: bytes flipped, the file truncated, lines duplicated,
//! removed or swapped, numbers replaced by huge, negative, zero, NaN, infinite,
//! overflowing or subnormal values, header counts and list counts changed, binary
//! payloads shortened, control bytes inserted, pieces of other seeds spliced in. Every
//! input goes to the in-memory reader of every format inside `catch_unwind`, and every
//! eighth also through a file on disk, asserting:
//!
//! - no panic; a panicking input is saved to the temporary directory and named in the
//!   failure, to be added to `tests/corpus/hostile/` as a regression file;
//! - every error is one line without raw control characters;
//! - what is accepted is bounded by the input: at most one vertex per 3 bytes and one
//!   triangle per byte (the densest encodings: binary PLY of `char` coordinates, faces of
//!   `uchar` indices);
//! - reading the file gives the same verdict as parsing the bytes (the bounded file
//!   reader refuses nothing the parser would accept);
//! - each parse is quick ([`PER_INPUT`]).
//!
//! The seed is fixed (`RECONBENCH_FUZZ_SEED` overrides it) and the number of rounds is
//! bounded ([`ROUNDS`], or `RECONBENCH_FUZZ_ROUNDS`), so the run is the same every time
//! and stays within seconds; deeper runs use the `cargo fuzz` targets in `fuzz/`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use proptest::prelude::RngExt;
use proptest::test_runner::{RngAlgorithm, TestRng};
use reconbench_geom::io::{self, Format, Loaded, PlyEncoding, WriteOptions};
use reconbench_geom::{DVec3, PointCloud, TriMesh};

/// Mutated inputs per run.
const ROUNDS: usize = 8000;
/// Default seed of the mutation stream.
const SEED: u64 = 0x5eed_0028;
/// Longest a single parse of a small input may take (it takes microseconds).
const PER_INPUT: Duration = Duration::from_secs(2);
/// Seeds are cut to this many bytes, to keep each parse cheap.
const MAX_SEED: usize = 16 << 10;

/// Numbers that break readers: counts beyond any file, negative and zero counts,
/// integer overflow, float specials, overflow to infinity, negative zero, subnormals.
const HOSTILE_NUMBERS: &[&str] = &[
    "4000000000",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775809",
    "-1",
    "-2147483649",
    "0",
    "1",
    "2",
    "255",
    "256",
    "65536",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "infinity",
    "1e309",
    "-1e309",
    "-0",
    "-0.0",
    "4.9e-324",
    "2.2250738585072014e-308",
    "1e-320",
    "0x10",
    "1.5",
    "1e",
    "+",
    "",
];

/// Bytes worth inserting: NUL, control and escape bytes, invalid UTF-8, separators.
const HOSTILE_BYTES: &[&[u8]] = &[
    b"\0",
    b"\x1b[2J",
    b"\r",
    b"\n",
    b"\t",
    b"\x0b",
    b"\x7f",
    b"\xff\xfe",
    b"\xc3",
    "\u{202e}".as_bytes(),
    b"#",
    b"{",
    b"}",
    b"/",
    b"//",
    b"-",
    b",",
    b" ",
];

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn corpus_seeds() -> Vec<(String, Vec<u8>)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
    let mut out = Vec::new();
    for sub in ["good", "broken", "hostile"] {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(root.join(sub))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        paths.sort();
        for p in paths {
            let mut bytes = std::fs::read(&p).unwrap();
            bytes.truncate(MAX_SEED);
            out.push((p.file_name().unwrap().to_string_lossy().into_owned(), bytes));
        }
    }
    out
}

/// Small valid files of every format, with normals and colours where the format has them.
fn written_seeds() -> Vec<(String, Vec<u8>)> {
    let v = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    ];
    let faces = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let normals: Vec<DVec3> = v
        .iter()
        .map(|p| (*p - DVec3::splat(0.25)).normalize())
        .collect();
    let mut mesh = TriMesh::new(v.clone(), faces).unwrap();
    mesh.set_vertex_normals(Some(normals.clone())).unwrap();
    mesh.set_vertex_colors(Some(vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]]))
        .unwrap();
    let mut cloud = PointCloud::new(v).unwrap();
    cloud.set_normals(Some(normals)).unwrap();
    let mut out = Vec::new();
    for enc in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let o = WriteOptions {
            ply_encoding: enc,
            ..WriteOptions::default()
        };
        out.push((
            format!("mesh_{enc}.ply"),
            io::mesh_to_bytes(&mesh, Format::Ply, &o).unwrap(),
        ));
        out.push((
            format!("cloud_{enc}.ply"),
            io::cloud_to_bytes(&cloud, Format::Ply, &o).unwrap(),
        ));
    }
    for stl_binary in [true, false] {
        let o = WriteOptions {
            stl_binary,
            ..WriteOptions::default()
        };
        out.push((
            format!("mesh_{stl_binary}.stl"),
            io::mesh_to_bytes(&mesh, Format::Stl, &o).unwrap(),
        ));
    }
    let o = WriteOptions::default();
    for f in [Format::Obj, Format::Off] {
        out.push((
            format!("mesh.{f}"),
            io::mesh_to_bytes(&mesh, f, &o).unwrap(),
        ));
    }
    for f in [
        Format::Obj,
        Format::Off,
        Format::Xyz,
        Format::Pts,
        Format::M,
    ] {
        out.push((
            format!("cloud.{f}"),
            io::cloud_to_bytes(&cloud, f, &o).unwrap(),
        ));
    }
    out.push((
        "a3d.pts".into(),
        b"p 0 0 0\nn 0 0 1\np 1 0 0\nn 0 0 1\n".to_vec(),
    ));
    out.push((
        "colours.obj".into(),
        b"v 0 0 0 0.1 0.2 0.3\nv 1 0 0 1 1 1\nv 0 1 0 0 0 0\nf 1 2 3\n".to_vec(),
    ));
    out.push((
        "mesh.m".into(),
        b"Vertex 1 0 0 0 {normal=(0 0 1)}\nVertex 2 1 0 0\nVertex 3 0 1 0\nFace 1 1 2 3\n".to_vec(),
    ));
    out
}

/// Byte ranges of the whitespace-separated tokens of `data`.
fn tokens(data: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &b) in data.iter().enumerate() {
        let sep = b.is_ascii_whitespace() || b == b',';
        match (start, sep) {
            (None, false) => start = Some(i),
            (Some(s), true) => {
                out.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, data.len()));
    }
    out
}

/// Byte ranges of the lines of `data`, line breaks included.
fn lines(data: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (i, &b) in data.iter().enumerate() {
        if b == b'\n' {
            out.push((s, i + 1));
            s = i + 1;
        }
    }
    if s < data.len() {
        out.push((s, data.len()));
    }
    out
}

fn pick<'a, T>(rng: &mut TestRng, v: &'a [T]) -> Option<&'a T> {
    (!v.is_empty()).then(|| &v[rng.random_range(0..v.len())])
}

fn splice(data: &[u8], (s, e): (usize, usize), with: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + with.len());
    out.extend_from_slice(&data[..s]);
    out.extend_from_slice(with);
    out.extend_from_slice(&data[e..]);
    out
}

/// Offset of the body of a binary PLY (after `end_header\n`), if `data` is one.
fn ply_body(data: &[u8]) -> Option<usize> {
    let at = data.windows(11).position(|w| w == b"end_header\n")?;
    (data.starts_with(b"ply") && !data[..at].windows(5).any(|w| w == b"ascii")).then_some(at + 11)
}

/// One structure-aware mutation of `data`; `other` is another seed for splicing.
fn mutate(rng: &mut TestRng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let n = data.len();
    let mut out = data.to_vec();
    match rng.random_range(0..12u32) {
        // Flip a few bytes.
        0 if n > 0 => {
            for _ in 0..rng.random_range(1..4) {
                let i = rng.random_range(0..n);
                out[i] = rng.random();
            }
        }
        // Truncate.
        1 if n > 0 => out.truncate(rng.random_range(0..n)),
        // Duplicate, remove or swap lines.
        2..=4 => {
            let ls = lines(data);
            if let (Some(&a), Some(&b)) = (pick(rng, &ls), pick(rng, &ls)) {
                out = match rng.random_range(0..3u32) {
                    0 => splice(data, (a.0, a.0), &data[a.0..a.1]),
                    1 => splice(data, a, b""),
                    _ if a.0 < b.0 && a.1 <= b.0 => {
                        let mut v = data[..a.0].to_vec();
                        v.extend_from_slice(&data[b.0..b.1]);
                        v.extend_from_slice(&data[a.1..b.0]);
                        v.extend_from_slice(&data[a.0..a.1]);
                        v.extend_from_slice(&data[b.1..]);
                        v
                    }
                    _ => out,
                };
            }
        }
        // Replace a number (header counts included) by a hostile one.
        5..=7 => {
            let numeric: Vec<_> = tokens(data)
                .into_iter()
                .filter(|&(s, e)| {
                    data[s..e]
                        .iter()
                        .all(|b| b.is_ascii_digit() || b"+-.eE".contains(b))
                })
                .collect();
            if let Some(&t) = pick(rng, &numeric) {
                let with = pick(rng, HOSTILE_NUMBERS).unwrap().as_bytes();
                out = splice(data, t, with);
            }
        }
        // Binary payloads: shorten, or overwrite a count-sized field with extremes
        // (the STL triangle count, a PLY list count, a coordinate).
        8 => {
            let body =
                ply_body(data).or((data.len() >= 84 && !data.starts_with(b"solid")).then_some(80));
            if let Some(b) = body.filter(|&b| b < n) {
                if rng.random() {
                    out.truncate(n - rng.random_range(1..=(n - b).min(16)));
                } else {
                    let at = rng.random_range(b..n);
                    let val: [u8; 4] = match rng.random_range(0..5u32) {
                        0 => [0xff; 4],
                        1 => [0; 4],
                        2 => 3u32.to_le_bytes(),
                        3 => f32::NAN.to_le_bytes(),
                        _ => 0x8000_0000u32.to_le_bytes(),
                    };
                    for (k, v) in val.iter().enumerate() {
                        if let Some(slot) = out.get_mut(at + k) {
                            *slot = *v;
                        }
                    }
                }
            }
        }
        // Insert hostile bytes.
        9 => {
            let at = rng.random_range(0..=n);
            out = splice(data, (at, at), pick(rng, HOSTILE_BYTES).unwrap());
        }
        // Splice in a piece of another seed.
        10 if !other.is_empty() => {
            let s = rng.random_range(0..other.len());
            let e = rng.random_range(s..=other.len().min(s + 256));
            let at = rng.random_range(0..=n);
            out = splice(data, (at, at), &other[s..e]);
        }
        // Several mutations at once.
        _ => {
            let once = mutate(rng, data, other);
            out = mutate(rng, &once, other);
        }
    }
    out
}

/// Sizes of what was read, for the bound check.
fn counts(l: &Loaded) -> (usize, usize) {
    match l {
        Loaded::Cloud(c) => (c.len(), 0),
        Loaded::Mesh(m) => (m.n_vertices(), m.n_faces()),
    }
}

/// Saves an input that broke a reader, for a regression file.
fn save_finding(data: &[u8], format: Format) -> PathBuf {
    let hash = io::content_hash(data);
    let path = std::env::temp_dir().join(format!("reconbench-fuzz-{hash}.{format}"));
    std::fs::write(&path, data).unwrap();
    path
}

/// Parses `data` as `format`, checking every property of the module doc; returns
/// whether it was accepted.
fn check_one(data: &[u8], format: Format, name: &str) -> bool {
    let t = Instant::now();
    let result = catch_unwind(AssertUnwindSafe(|| io::any_from_bytes(data, format, name)));
    let dt = t.elapsed();
    let Ok(result) = result else {
        panic!(
            "reader {format} panicked on {} (saved to {})",
            name,
            save_finding(data, format).display()
        );
    };
    assert!(
        dt < PER_INPUT,
        "reader {format} took {dt:?} on {} bytes (saved to {})",
        data.len(),
        save_finding(data, format).display()
    );
    match result {
        Ok(loaded) => {
            let (v, f) = counts(&loaded);
            assert!(
                v <= data.len() / 3 && f <= data.len(),
                "reader {format} made {v} vertices and {f} faces of {} bytes (saved to {})",
                data.len(),
                save_finding(data, format).display()
            );
            true
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(
                !msg.chars().any(char::is_control),
                "reader {format}: raw control character in {msg:?} (input saved to {})",
                save_finding(data, format).display()
            );
            false
        }
    }
}

/// Reading from a file gives the same verdict (and the same data) as parsing the bytes.
fn check_file(dir: &Path, data: &[u8], format: Format, in_memory: bool) {
    let path = dir.join(format!("input.{format}"));
    std::fs::write(&path, data).unwrap();
    let from_file = catch_unwind(AssertUnwindSafe(|| io::read_any_as(&path, format)))
        .unwrap_or_else(|_| {
            panic!(
                "file reader {format} panicked (saved to {})",
                save_finding(data, format).display()
            )
        });
    assert_eq!(
        from_file.is_ok(),
        in_memory,
        "file and memory readers of {format} disagree ({:?}; input saved to {})",
        from_file.as_ref().err().map(|e| e.to_string()),
        save_finding(data, format).display()
    );
    if let Ok(l) = from_file {
        assert_eq!(
            Some(l),
            io::any_from_bytes(data, format, &path).ok(),
            "{format}: file and memory results differ"
        );
    }
}

#[test]
fn mutated_corpus_files_never_panic_and_stay_bounded_in_every_reader() {
    let seed = env_u64("RECONBENCH_FUZZ_SEED", SEED);
    let rounds = env_u64("RECONBENCH_FUZZ_ROUNDS", ROUNDS as u64) as usize;
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let mut rng = TestRng::from_seed(RngAlgorithm::ChaCha, &key);
    let mut seeds = corpus_seeds();
    seeds.extend(written_seeds());
    let dir = tempfile::tempdir().unwrap();
    let start = Instant::now();
    let mut accepted = 0usize;
    for round in 0..rounds + seeds.len() {
        // Every seed once as it is, then mutations of random seeds.
        let (name, data) = if round < seeds.len() {
            seeds[round].clone()
        } else {
            let (name, data) = pick(&mut rng, &seeds).unwrap();
            let (_, other) = pick(&mut rng, &seeds).unwrap();
            (name.clone(), mutate(&mut rng, data, other))
        };
        for format in Format::ALL {
            let ok = check_one(&data, format, &name);
            accepted += usize::from(ok);
            if round % 8 == 0 {
                check_file(dir.path(), &data, format, ok);
            }
        }
    }
    // Visible with --nocapture: how much the run exercised.
    eprintln!(
        "io fuzz: {} inputs x {} readers, {accepted} accepted, {:?}",
        rounds + seeds.len(),
        Format::ALL.len(),
        start.elapsed()
    );
    // The mutations must leave some inputs valid, or the run tests only error paths.
    assert!(accepted > rounds / 10, "only {accepted} inputs accepted");
}
