//! STL, ascii and binary.
//!
//! A file is binary when its size is exactly `84 + 50 n` bytes, `n` being the triangle
//! count at byte 80: many binary files start with `solid` in their header, so that prefix
//! proves nothing. Otherwise a text file starting with `solid` is parsed as ascii, and
//! anything else is reported as a binary file of the wrong length.
//!
//! STL repeats each vertex in every triangle; vertices are welded by their exact
//! coordinates (bit patterns, with `-0.0` taken as `0.0`), which recovers the shared
//! vertices of any mesh written by a sane exporter without merging distinct points.
//! Facet normals are ignored on input and recomputed on output. Binary STL stores 32-bit
//! floats, so writing rounds coordinates; ascii output keeps full `f64` precision.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;

use super::text::{Lines, Num, line_str, parse_f64, parse_finite, show};
use super::{Geometry, Parsed, format_err};
use crate::error::{GeomError, Location, Result};

const HEADER: usize = 80;
const RECORD: usize = 50;

/// A small multiplicative hasher for the welding map (keys are coordinate bits, not
/// attacker-controlled in any way that matters here, and SipHash is several times slower).
#[derive(Default)]
struct WeldHasher(u64);

impl Hasher for WeldHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// Merges vertices with identical coordinates.
#[derive(Default)]
struct Welder {
    map: HashMap<[u64; 3], u32, BuildHasherDefault<WeldHasher>>,
    positions: Vec<DVec3>,
}

impl Welder {
    fn with_capacity(n: usize) -> Self {
        Self {
            map: HashMap::with_capacity_and_hasher(n, Default::default()),
            positions: Vec::with_capacity(n),
        }
    }

    fn index(&mut self, p: DVec3) -> u32 {
        // Adding 0.0 turns -0.0 into 0.0 and leaves every other value unchanged.
        let key = [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ];
        let positions = &mut self.positions;
        *self.map.entry(key).or_insert_with(|| {
            positions.push(p);
            (positions.len() - 1) as u32
        })
    }
}

/// True when the bytes look like text (no control characters but white space).
fn is_text(bytes: &[u8]) -> bool {
    bytes
        .iter()
        .all(|&b| b >= 0x20 || matches!(b, b'\t' | b'\n' | b'\r' | 0x0c))
}

/// Bytes before the first triangle of a binary file: the header and the count.
pub(crate) const PREFIX: usize = HEADER + 4;

/// The triangle count of a binary file, if there are enough bytes to hold one.
pub(crate) fn declared_triangles(bytes: &[u8]) -> Option<u64> {
    let b = bytes.get(HEADER..PREFIX)?;
    Some(u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
}

/// Size of a binary file of `n` triangles.
pub(crate) fn binary_size(n: u64) -> u64 {
    PREFIX as u64 + RECORD as u64 * n
}

/// True when the file starts with `solid` (after white space), as ascii STL does; judged
/// from its first bytes, which may all be white space.
pub(crate) fn may_be_ascii(start: &[u8]) -> bool {
    let t = start.trim_ascii_start();
    t.len() < 5 || t[..5].eq_ignore_ascii_case(b"solid")
}

/// The error for a file that is not binary STL of the size its count declares, and not
/// ascii STL either (`len` is the file size).
pub(crate) fn size_error(n: u64, len: u64, starts_solid: bool, path: &Path) -> GeomError {
    let hint = if starts_solid {
        " (it starts with 'solid' like ascii STL, but contains binary data)"
    } else {
        " (and it does not start with 'solid' as ascii STL does)"
    };
    format_err(
        path,
        Location::Byte(HEADER as u64),
        format!(
            "binary STL header declares {n} triangles, which take {} bytes, but the file \
             has {len} bytes{hint}",
            binary_size(n)
        ),
    )
}

pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let declared = declared_triangles(bytes);
    if let Some(n) = declared
        && binary_size(n) == bytes.len() as u64
    {
        return parse_binary(bytes, n as usize, path);
    }
    let starts_solid = bytes
        .trim_ascii_start()
        .get(..5)
        .is_some_and(|s| s.eq_ignore_ascii_case(b"solid"));
    if starts_solid && is_text(bytes) {
        return parse_ascii(bytes, path);
    }
    Err(match declared {
        None => format_err(
            path,
            Location::File,
            format!(
                "the file has {} bytes; a binary STL needs at least 84 (an 80-byte header and \
                 a triangle count){}",
                bytes.len(),
                if starts_solid {
                    " (it starts with 'solid' like ascii STL, but contains binary data)"
                } else {
                    " (and it does not start with 'solid' as ascii STL does)"
                }
            ),
        ),
        Some(n) => size_error(n, bytes.len() as u64, starts_solid, path),
    })
}

fn parse_binary(bytes: &[u8], n: usize, path: &Path) -> Result<Parsed> {
    let mut welder = Welder::with_capacity(n / 2 + 3);
    let mut faces = Vec::with_capacity(n);
    let body = &bytes[HEADER + 4..];
    for (t, rec) in body.chunks_exact(RECORD).enumerate() {
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let mut v = [0.0f64; 3];
            for (a, c) in v.iter_mut().enumerate() {
                let at = 12 + 12 * k + 4 * a;
                let mut b = [0u8; 4];
                b.copy_from_slice(&rec[at..at + 4]);
                *c = f64::from(f32::from_le_bytes(b));
            }
            if !v.iter().all(|c| c.is_finite()) {
                let offset = HEADER + 4 + t * RECORD + 12 + 12 * k;
                return Err(format_err(
                    path,
                    Location::Byte(offset as u64),
                    format!(
                        "triangle {t} vertex {k} has a non-finite coordinate ({}, {}, {}); \
                         expected finite numbers",
                        v[0], v[1], v[2]
                    ),
                ));
            }
            *slot = welder.index(DVec3::from_array(v));
        }
        faces.push(tri);
    }
    Ok(Parsed {
        positions: welder.positions,
        faces,
        ..Parsed::default()
    })
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Outside,
    Solid,
    Facet,
    Loop,
    EndLoop,
}

impl State {
    fn expected(self) -> &'static str {
        match self {
            State::Outside => "'solid'",
            State::Solid => "'facet normal' or 'endsolid'",
            State::Facet => "'outer loop'",
            State::Loop => "'vertex' or 'endloop'",
            State::EndLoop => "'endfacet'",
        }
    }
}

fn parse_ascii(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let mut welder = Welder::default();
    let mut faces = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut state = State::Outside;
    let mut last = 1;
    for (n, raw) in Lines::new(bytes) {
        last = n;
        let line = line_str(path, n, raw)?;
        let toks: Vec<&str> = line.split_ascii_whitespace().collect();
        let Some(&kw) = toks.first() else { continue };
        let err = |m: String| format_err(path, Location::Line(n), m);
        let kw_l = kw.to_ascii_lowercase();
        state = match (state, kw_l.as_str()) {
            (State::Outside, "solid") => State::Solid,
            (State::Solid, "endsolid") => State::Outside,
            (State::Solid, "facet") => {
                // The normal is recomputed from the vertices; only check it is numeric.
                if toks.len() != 1 {
                    if toks.len() != 5 || !toks[1].eq_ignore_ascii_case("normal") {
                        return Err(err(format!(
                            "malformed facet line {}; expected 'facet normal nx ny nz'",
                            show(line.trim())
                        )));
                    }
                    for tok in &toks[2..] {
                        parse_f64(path, n, tok, "a facet normal component")?;
                    }
                }
                State::Facet
            }
            (State::Facet, "outer") => {
                if toks.len() != 2 || !toks[1].eq_ignore_ascii_case("loop") {
                    return Err(err(format!(
                        "found {}; expected 'outer loop'",
                        show(line.trim())
                    )));
                }
                corners.clear();
                State::Loop
            }
            (State::Loop, "vertex") => {
                if toks.len() != 4 {
                    return Err(err(format!(
                        "a vertex line has {} values; expected 'vertex x y z'",
                        toks.len() - 1
                    )));
                }
                let mut v = [0.0; 3];
                for k in 0..3 {
                    v[k] = parse_finite(path, n, toks[1 + k], "a vertex coordinate")?;
                }
                corners.push(welder.index(DVec3::from_array(v)));
                State::Loop
            }
            (State::Loop, "endloop") => {
                if corners.len() < 3 {
                    return Err(err(format!(
                        "a facet loop has {} vertices; expected at least 3",
                        corners.len()
                    )));
                }
                for k in 1..corners.len() - 1 {
                    faces.push([corners[0], corners[k], corners[k + 1]]);
                }
                State::EndLoop
            }
            (State::EndLoop, "endfacet") => State::Solid,
            (s, _) => {
                return Err(err(format!(
                    "found {}; expected {}",
                    show(kw),
                    s.expected()
                )));
            }
        };
    }
    if state != State::Outside {
        return Err(format_err(
            path,
            Location::Line(last),
            format!(
                "the file ends inside a solid; expected {} (truncated file?)",
                state.expected()
            ),
        ));
    }
    Ok(Parsed {
        positions: welder.positions,
        faces,
        ..Parsed::default()
    })
}

/// Refuses meshes binary STL cannot hold (too many faces, coordinates beyond `f32`).
pub(crate) fn check_writable(g: &Geometry, binary: bool, path: &Path) -> Result<()> {
    let unsupported = |message: String| GeomError::UnsupportedFormat {
        path: path.to_path_buf(),
        message,
    };
    let faces = g.faces.unwrap_or(&[]);
    if binary && faces.len() > u32::MAX as usize {
        return Err(unsupported(format!(
            "{} faces exceed the binary STL limit of {}",
            faces.len(),
            u32::MAX
        )));
    }
    if binary {
        let limit = f64::from(f32::MAX);
        if let Some(i) = g
            .positions
            .iter()
            .position(|p| p.abs().max_element() > limit)
        {
            return Err(unsupported(format!(
                "vertex {i} {:?} does not fit the 32-bit floats of binary STL; write ascii STL",
                g.positions[i].to_array()
            )));
        }
    }
    Ok(())
}

fn face_normal(g: &Geometry, f: &[u32; 3]) -> DVec3 {
    let [a, b, c] = f.map(|v| g.positions[v as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

/// Writes STL (call [`check_writable`] first).
pub(crate) fn write(w: &mut dyn Write, g: &Geometry, binary: bool) -> io::Result<()> {
    let faces = g.faces.unwrap_or(&[]);
    if binary {
        let mut header = [b' '; HEADER];
        let tag = b"binary STL written by reconbench";
        header[..tag.len()].copy_from_slice(tag);
        w.write_all(&header)?;
        w.write_all(&(faces.len() as u32).to_le_bytes())?;
        let mut buf = Vec::with_capacity(1 << 16);
        for f in faces {
            let n = face_normal(g, f);
            for v in std::iter::once(n).chain(f.iter().map(|&v| g.positions[v as usize])) {
                for c in v.to_array() {
                    buf.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
            buf.extend_from_slice(&0u16.to_le_bytes());
            if buf.len() >= 1 << 16 {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        w.write_all(&buf)
    } else {
        writeln!(w, "solid reconbench")?;
        for f in faces {
            let n = face_normal(g, f);
            writeln!(w, "  facet normal {} {} {}", Num(n.x), Num(n.y), Num(n.z))?;
            writeln!(w, "    outer loop")?;
            for &v in f {
                let p = g.positions[v as usize];
                writeln!(w, "      vertex {} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
            }
            writeln!(w, "    endloop")?;
            writeln!(w, "  endfacet")?;
        }
        writeln!(w, "endsolid reconbench")
    }
}
