//! Hoppe's `.m` mesh format (Mesh-processing-library): one record per line.
//!
//! - `Vertex i x y z {attrs}`: vertex with 1-based id `i` (ids need not be contiguous
//!   nor sorted, but must be unique); a `normal=(nx ny nz)` attribute becomes the vertex
//!   normal (kept only when every vertex has one; other attributes are ignored).
//! - `Face j a b c {attrs}`: a triangle on vertex ids `a b c` (face ids are not used).
//!   Hoppe's real files hold triangles only, so a polygon is refused with a clear error.
//! - `Corner v f {attrs}` and `Edge a b {attrs}` records are accepted and ignored.
//! - `#` starts a comment line.
//!
//! Writing numbers vertices and faces from 1 and writes normals as `{normal=(...)}`.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;

use super::text::{Lines, Num, line_str, parse_finite, parse_i64, show};
use super::{Geometry, Parsed, format_err};
use crate::error::{Location, Result};

/// Splits a record into its plain fields and the text inside `{...}`, if any.
fn split_attrs<'a>(path: &Path, n: usize, line: &'a str) -> Result<(&'a str, Option<&'a str>)> {
    match line.find('{') {
        None => Ok((line, None)),
        Some(open) => {
            let rest = &line[open + 1..];
            let close = rest.find('}').ok_or_else(|| {
                format_err(
                    path,
                    Location::Line(n),
                    "found '{' without a closing '}'; expected attributes like {normal=(0 0 1)}",
                )
            })?;
            Ok((&line[..open], Some(&rest[..close])))
        }
    }
}

/// The `normal=(nx ny nz)` attribute, if present.
fn parse_normal(path: &Path, n: usize, attrs: &str) -> Result<Option<DVec3>> {
    let Some(at) = attrs.find("normal=(") else {
        return Ok(None);
    };
    let rest = &attrs[at + "normal=(".len()..];
    let close = rest.find(')').ok_or_else(|| {
        format_err(
            path,
            Location::Line(n),
            "the normal attribute has no closing ')'; expected normal=(nx ny nz)",
        )
    })?;
    let vals: Vec<&str> = rest[..close].split_ascii_whitespace().collect();
    if vals.len() != 3 {
        return Err(format_err(
            path,
            Location::Line(n),
            format!(
                "the normal attribute has {} values; expected normal=(nx ny nz)",
                vals.len()
            ),
        ));
    }
    Ok(Some(DVec3::new(
        parse_finite(path, n, vals[0], "nx")?,
        parse_finite(path, n, vals[1], "ny")?,
        parse_finite(path, n, vals[2], "nz")?,
    )))
}

fn parse_id(path: &Path, n: usize, tok: &str, what: &str) -> Result<i64> {
    let id = parse_i64(path, n, tok, what)?;
    if id < 1 {
        return Err(format_err(
            path,
            Location::Line(n),
            format!("{what} is {id}; ids of .m files are 1-based (at least 1)"),
        ));
    }
    Ok(id)
}

pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let mut positions = Vec::new();
    let mut normals: Vec<Option<DVec3>> = Vec::new();
    let mut ids: HashMap<i64, (u32, usize)> = HashMap::new(); // id -> (index, line)
    let mut faces_by_id: Vec<([i64; 3], usize)> = Vec::new(); // vertex ids, line
    for (n, raw) in Lines::new(bytes) {
        let line = line_str(path, n, raw)?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let err = |m: String| format_err(path, Location::Line(n), m);
        let (plain, attrs) = split_attrs(path, n, t)?;
        let fields: Vec<&str> = plain.split_ascii_whitespace().collect();
        match fields.first().copied().unwrap_or("") {
            "Vertex" => {
                if fields.len() != 5 {
                    return Err(err(format!(
                        "a Vertex record has {} values; expected 'Vertex id x y z'",
                        fields.len() - 1
                    )));
                }
                let id = parse_id(path, n, fields[1], "the vertex id")?;
                let p = DVec3::new(
                    parse_finite(path, n, fields[2], "x")?,
                    parse_finite(path, n, fields[3], "y")?,
                    parse_finite(path, n, fields[4], "z")?,
                );
                let index = u32::try_from(positions.len())
                    .map_err(|_| err("more than 2^32 - 1 vertices".into()))?;
                match ids.entry(id) {
                    Entry::Occupied(e) => {
                        return Err(err(format!(
                            "vertex id {id} is defined twice (first on line {})",
                            e.get().1
                        )));
                    }
                    Entry::Vacant(e) => {
                        e.insert((index, n));
                    }
                }
                positions.push(p);
                normals.push(match attrs {
                    Some(a) => parse_normal(path, n, a)?,
                    None => None,
                });
            }
            "Face" => {
                if fields.len() < 5 {
                    return Err(err(format!(
                        "a face has {} vertices; expected 'Face id a b c'",
                        fields.len().saturating_sub(2)
                    )));
                }
                if fields.len() > 5 {
                    return Err(err(format!(
                        "a face has {} vertices; only triangles are supported \
                         (Hoppe's data sets hold triangles only)",
                        fields.len() - 2
                    )));
                }
                parse_id(path, n, fields[1], "the face id")?;
                let mut f = [0i64; 3];
                for (k, slot) in f.iter_mut().enumerate() {
                    *slot = parse_id(path, n, fields[2 + k], "a face vertex id")?;
                }
                faces_by_id.push((f, n));
            }
            "Corner" | "Edge" => {}
            other => {
                return Err(err(format!(
                    "unknown record {}; expected Vertex, Face, Corner, Edge or a # comment",
                    show(other)
                )));
            }
        }
    }
    // Faces may precede the vertices they use, so they are resolved at the end.
    let mut faces = Vec::with_capacity(faces_by_id.len());
    for (f, n) in faces_by_id {
        let mut tri = [0u32; 3];
        for (k, id) in f.into_iter().enumerate() {
            tri[k] = ids.get(&id).map(|e| e.0).ok_or_else(|| {
                format_err(
                    path,
                    Location::Line(n),
                    format!(
                        "the face refers to vertex id {id}, but the file defines no such \
                         vertex ({} vertices)",
                        positions.len()
                    ),
                )
            })?;
        }
        faces.push(tri);
    }
    let normals = if !normals.is_empty() && normals.iter().all(Option::is_some) {
        Some(normals.into_iter().flatten().collect())
    } else {
        None
    };
    Ok(Parsed {
        positions,
        normals,
        faces,
        ..Parsed::default()
    })
}

pub(crate) fn write(w: &mut dyn Write, g: &Geometry) -> io::Result<()> {
    for (i, p) in g.positions.iter().enumerate() {
        write!(w, "Vertex {} {} {} {}", i + 1, Num(p.x), Num(p.y), Num(p.z))?;
        if let Some(nr) = g.normals {
            let v = nr[i];
            write!(w, " {{normal=({} {} {})}}", Num(v.x), Num(v.y), Num(v.z))?;
        }
        w.write_all(b"\n")?;
    }
    for (j, f) in g.faces.unwrap_or(&[]).iter().enumerate() {
        writeln!(w, "Face {} {} {} {}", j + 1, f[0] + 1, f[1] + 1, f[2] + 1)?;
    }
    Ok(())
}
