//! Wavefront OBJ: `v`, `vn` and `f` statements.
//!
//! Faces accept every corner form (`v`, `v/vt`, `v//vn`, `v/vt/vn`) and negative
//! (relative) indices; polygons are fan-triangulated. Texture coordinates, groups,
//! objects, smoothing groups, materials and the other statements of the format that carry
//! no geometry we keep are ignored; an unknown statement is an error, because it more
//! likely means a wrong file than an exotic extension.
//!
//! OBJ normals belong to face corners, not vertices. They become vertex normals when
//! that is unambiguous: when there is one `vn` per `v` and corners pair them by index
//! (what reconbench writes, also for clouds without faces), or else when every vertex is
//! referenced with a normal (the first reference wins). Otherwise they are dropped.
//! Vertex colours use the common `v x y z r g b` extension (components in 0..1); they are
//! kept when every vertex has one. A component outside 0..1 is an error naming the line
//! and the value, not clamped: files with 0..255 components exist, and clamping would
//! turn them white without a word; such a file is refused with the advice to divide by
//! 255.

use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;

use super::text::{Lines, Num, line_str, parse_finite, show, unit_to_u8};
use super::{Geometry, Parsed, format_err};
use crate::error::{Location, Result};

/// Statements that are valid OBJ but carry nothing reconbench keeps.
const IGNORED: &[&str] = &[
    "vt",
    "vp",
    "g",
    "o",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "l",
    "p",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "trace_obj",
    "shadow_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
];

const NONE: u32 = u32::MAX;

/// Resolves an OBJ index token (1-based, or negative relative to the `defined` elements
/// so far) to a 0-based index. Forward references are allowed here and checked at the
/// end of the file.
fn resolve(path: &Path, line: usize, tok: &str, defined: usize, what: &str) -> Result<u32> {
    let err = |m: String| format_err(path, Location::Line(line), m);
    let i: i64 = tok.parse().map_err(|_| {
        err(format!(
            "expected an integer {what} index, found {}",
            show(tok)
        ))
    })?;
    let idx = match i {
        0 => {
            return Err(err(format!(
                "{what} index 0 is invalid; OBJ indices start at 1 (or are negative, \
                 counting back from the last {what})"
            )));
        }
        i if i > 0 => i - 1,
        i => {
            let r = defined as i64 + i;
            if r < 0 {
                return Err(err(format!(
                    "relative {what} index {i} reaches before the first {what}; only \
                     {defined} are defined so far"
                )));
            }
            r
        }
    };
    u32::try_from(idx)
        .ok()
        .filter(|&v| v != NONE)
        .ok_or_else(|| err(format!("{what} index {i} is too large")))
}

/// Remembers the largest index referenced and where, to check forward references.
#[derive(Default)]
struct MaxRef(Option<(u32, usize)>);

impl MaxRef {
    fn note(&mut self, idx: u32, line: usize) {
        if self.0.is_none_or(|(m, _)| idx > m) {
            self.0 = Some((idx, line));
        }
    }

    fn check(&self, path: &Path, defined: usize, what: &str) -> Result<()> {
        match self.0 {
            Some((m, line)) if m as usize >= defined => Err(format_err(
                path,
                Location::Line(line),
                format!(
                    "a face refers to {what} {}, but the file defines only {defined}",
                    m as u64 + 1
                ),
            )),
            _ => Ok(()),
        }
    }
}

pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut colors: Vec<[u8; 3]> = Vec::new();
    let mut normals: Vec<DVec3> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    // Per vertex, the first normal referenced with it.
    let mut vertex_normal: Vec<u32> = Vec::new();
    let mut normals_are_identity = true;
    let mut normal_refs = false;
    let mut max_v = MaxRef::default();
    let mut max_vn = MaxRef::default();
    let mut corners: Vec<(u32, u32)> = Vec::new();

    for (n, raw) in Lines::new(bytes) {
        let raw = match raw.iter().position(|&b| b == b'#') {
            Some(i) => &raw[..i],
            None => raw,
        };
        let line = line_str(path, n, raw)?;
        let mut toks = line.split_ascii_whitespace();
        let Some(kw) = toks.next() else { continue };
        let err = |m: String| format_err(path, Location::Line(n), m);
        match kw {
            "v" => {
                let mut vals = [0.0f64; 6];
                let mut k = 0;
                for tok in toks {
                    if k == 6 {
                        return Err(err(
                            "a vertex has more than 6 values; expected x y z, x y z w or \
                             x y z r g b"
                                .into(),
                        ));
                    }
                    vals[k] = parse_finite(path, n, tok, "a vertex coordinate")?;
                    k += 1;
                }
                match k {
                    3 | 4 => {}
                    6 => {
                        let mut c = [0u8; 3];
                        for (slot, &v) in c.iter_mut().zip(&vals[3..6]) {
                            *slot = unit_to_u8(v).map_err(|m| {
                                err(format!(
                                    "vertex {}: {m} (OBJ vertex colours 'v x y z r g b' are \
                                     0..1; divide 0..255 colours by 255)",
                                    positions.len() + 1
                                ))
                            })?;
                        }
                        if colors.len() == positions.len() {
                            colors.push(c);
                        }
                    }
                    _ => {
                        return Err(err(format!(
                            "a vertex has {k} values; expected x y z, x y z w or x y z r g b"
                        )));
                    }
                }
                positions.push(DVec3::new(vals[0], vals[1], vals[2]));
            }
            "vn" => {
                let vals: Vec<&str> = toks.collect();
                if vals.len() != 3 {
                    return Err(err(format!(
                        "a normal has {} values; expected nx ny nz",
                        vals.len()
                    )));
                }
                let mut v = [0.0; 3];
                for (slot, tok) in v.iter_mut().zip(vals) {
                    *slot = parse_finite(path, n, tok, "a normal component")?;
                }
                normals.push(DVec3::from_array(v));
            }
            "f" => {
                corners.clear();
                for tok in toks {
                    let mut parts = tok.split('/');
                    let v = parts.next().unwrap_or("");
                    let _vt = parts.next();
                    let vn = parts.next().filter(|s| !s.is_empty());
                    if parts.next().is_some() {
                        return Err(err(format!(
                            "face corner {} has more than three '/'-separated parts; expected \
                             v, v/vt, v//vn or v/vt/vn",
                            show(tok)
                        )));
                    }
                    let vi = resolve(path, n, v, positions.len(), "vertex")?;
                    max_v.note(vi, n);
                    let ni = match vn {
                        Some(t) => {
                            let ni = resolve(path, n, t, normals.len(), "normal")?;
                            max_vn.note(ni, n);
                            normal_refs = true;
                            normals_are_identity &= ni == vi;
                            ni
                        }
                        None => NONE,
                    };
                    corners.push((vi, ni));
                }
                if corners.len() < 3 {
                    return Err(err(format!(
                        "a face has {} vertices; expected at least 3",
                        corners.len()
                    )));
                }
                for &(vi, ni) in &corners {
                    // Forward references get no per-vertex normal: growing the table to an
                    // index not yet defined would let one bad line allocate gigabytes.
                    if ni != NONE && (vi as usize) < positions.len() {
                        let vi = vi as usize;
                        if vertex_normal.len() <= vi {
                            vertex_normal.resize(vi + 1, NONE);
                        }
                        if vertex_normal[vi] == NONE {
                            vertex_normal[vi] = ni;
                        }
                    }
                }
                for k in 1..corners.len() - 1 {
                    faces.push([corners[0].0, corners[k].0, corners[k + 1].0]);
                }
            }
            kw if IGNORED.contains(&kw) => {}
            other => {
                return Err(err(format!(
                    "unknown statement {}; expected v, vn, f or another OBJ statement",
                    show(other)
                )));
            }
        }
    }
    max_v.check(path, positions.len(), "vertex")?;
    max_vn.check(path, normals.len(), "normal")?;

    let n = positions.len();
    let vertex_normals = if !normals.is_empty() && normals.len() == n && normals_are_identity {
        Some(normals)
    } else if normal_refs && vertex_normal.len() == n && vertex_normal.iter().all(|&i| i != NONE) {
        Some(vertex_normal.iter().map(|&i| normals[i as usize]).collect())
    } else {
        None
    };
    Ok(Parsed {
        normals: vertex_normals,
        colors: (n > 0 && colors.len() == n).then_some(colors),
        positions,
        faces,
        ..Parsed::default()
    })
}

pub(crate) fn write(w: &mut dyn Write, g: &Geometry) -> io::Result<()> {
    writeln!(w, "# written by reconbench ({})", g.what())?;
    for (i, p) in g.positions.iter().enumerate() {
        write!(w, "v {} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
        if let Some(c) = g.colors {
            let [r, gr, b] = c[i].map(|x| Num(f64::from(x) / 255.0));
            write!(w, " {r} {gr} {b}")?;
        }
        w.write_all(b"\n")?;
    }
    if let Some(normals) = g.normals {
        for nrm in normals {
            writeln!(w, "vn {} {} {}", Num(nrm.x), Num(nrm.y), Num(nrm.z))?;
        }
    }
    for f in g.faces.unwrap_or(&[]) {
        let [a, b, c] = f.map(|v| v as u64 + 1);
        if g.normals.is_some() {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}
