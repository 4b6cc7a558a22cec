//! XYZ and PTS: one point per line, values separated by white space and/or commas.
//!
//! XYZ rows are `x y z` or `x y z nx ny nz`. PTS files may start with a line holding the
//! point count (checked against the rows), and their rows are `x y z`,
//! `x y z intensity`, `x y z nx ny nz` or `x y z intensity r g b` (intensity becomes the
//! scalar channel `intensity`, colours are integers 0..=255 or floats 0..1). Every row
//! must have as many columns as the first. Lines starting with `#` or `//` are comments.
//!
//! Only positions and normals are written (PTS with its count line), with exact
//! shortest-round-trip numbers.

use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;

use super::text::{Lines, Num, line_str, parse_color, parse_finite, split_fields};
use super::{Geometry, Parsed, format_err};
use crate::cloud::Channel;
use crate::error::{Location, Result};

/// Column layouts: (columns, description).
const XYZ_LAYOUTS: &[(usize, &str)] = &[(3, "x y z"), (6, "x y z nx ny nz")];
const PTS_LAYOUTS: &[(usize, &str)] = &[
    (3, "x y z"),
    (4, "x y z intensity"),
    (6, "x y z nx ny nz"),
    (7, "x y z intensity r g b"),
];

fn describe(layouts: &[(usize, &str)]) -> String {
    layouts
        .iter()
        .map(|(n, d)| format!("{n} ({d})"))
        .collect::<Vec<_>>()
        .join(", ")
}

pub(crate) fn parse(bytes: &[u8], path: &Path, pts: bool) -> Result<Parsed> {
    if pts && is_a3d(bytes) {
        return parse_a3d(bytes, path);
    }
    let layouts = if pts { PTS_LAYOUTS } else { XYZ_LAYOUTS };
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut intensity = Vec::new();
    let mut colors = Vec::new();
    let mut columns: Option<(usize, usize)> = None; // (count, line of the first row)
    let mut count_line: Option<(usize, usize)> = None; // (declared count, line)
    let mut fields: Vec<&str> = Vec::with_capacity(8);
    for (n, raw) in Lines::new(bytes) {
        let line = line_str(path, n, raw)?;
        let t = line.trim_start();
        if t.is_empty() || t.starts_with('#') || t.starts_with("//") {
            continue;
        }
        let err = |m: String| format_err(path, Location::Line(n), m);
        fields.clear();
        fields.extend(split_fields(t));
        if pts && columns.is_none() && count_line.is_none() && fields.len() == 1 {
            let c = fields[0].parse::<usize>().map_err(|_| {
                err(format!(
                    "found a single value {} where a PTS file has its point count or a row \
                     of {}",
                    super::text::show(fields[0]),
                    describe(layouts)
                ))
            })?;
            count_line = Some((c, n));
            continue;
        }
        let (cols, first) = *columns.get_or_insert((fields.len(), n));
        if fields.len() != cols {
            return Err(err(format!(
                "found {} values; expected {cols} like the first row (line {first})",
                fields.len()
            )));
        }
        if !layouts.iter().any(|&(c, _)| c == cols) {
            return Err(err(format!(
                "found {cols} values; expected {}",
                describe(layouts)
            )));
        }
        let num = |i: usize, what: &str| parse_finite(path, n, fields[i], what);
        positions.push(DVec3::new(num(0, "x")?, num(1, "y")?, num(2, "z")?));
        match cols {
            6 => normals.push(DVec3::new(num(3, "nx")?, num(4, "ny")?, num(5, "nz")?)),
            4 => intensity.push(num(3, "intensity")?),
            7 => {
                intensity.push(num(3, "intensity")?);
                colors.push([
                    parse_color(path, n, fields[4])?,
                    parse_color(path, n, fields[5])?,
                    parse_color(path, n, fields[6])?,
                ]);
            }
            _ => {}
        }
    }
    if let Some((declared, line)) = count_line
        && declared != positions.len()
    {
        return Err(format_err(
            path,
            Location::Line(line),
            format!(
                "the count line declares {declared} points, but the file has {} rows",
                positions.len()
            ),
        ));
    }
    let cols = columns.map_or(3, |c| c.0);
    Ok(Parsed {
        positions,
        normals: (cols == 6).then_some(normals),
        colors: (cols == 7).then_some(colors),
        channels: if matches!(cols, 4 | 7) {
            vec![("intensity".to_string(), Channel::Scalar(intensity))]
        } else {
            Vec::new()
        },
        ..Parsed::default()
    })
}

/// True when the first record that is not blank or a comment starts with a one-letter
/// token: Hoppe's A3d stream form (`p x y z`), not a plain `x y z` PTS file.
fn is_a3d(bytes: &[u8]) -> bool {
    for (_, raw) in Lines::new(bytes) {
        let Ok(line) = std::str::from_utf8(raw) else {
            return false;
        };
        let t = line.trim_start();
        if t.is_empty() || t.starts_with('#') || t.starts_with("//") {
            continue;
        }
        let first = t.split_ascii_whitespace().next().unwrap_or("");
        return first.len() == 1 && first.as_bytes()[0].is_ascii_alphabetic();
    }
    false
}

/// Hoppe's A3d stream points: `p x y z` is a point, `n x y z` the normal of the point
/// before it; `d`, `s`, `g` (and `#` comment) records are skipped; any other record is
/// an error naming its line. Normals are kept when every point has one; a file where
/// only some points have one is refused.
fn parse_a3d(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let mut positions = Vec::new();
    let mut normals: Vec<Option<DVec3>> = Vec::new();
    let mut first_normal: Option<usize> = None;
    let mut first_without: Option<usize> = None;
    let mut point_lines = Vec::new();
    for (n, raw) in Lines::new(bytes) {
        let line = line_str(path, n, raw)?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let err = |m: String| format_err(path, Location::Line(n), m);
        let fields: Vec<&str> = t.split_ascii_whitespace().collect();
        let three = |what: [&str; 3]| -> Result<DVec3> {
            if fields.len() != 4 {
                return Err(err(format!(
                    "a '{}' record has {} values; expected 3",
                    fields[0],
                    fields.len() - 1
                )));
            }
            Ok(DVec3::new(
                parse_finite(path, n, fields[1], what[0])?,
                parse_finite(path, n, fields[2], what[1])?,
                parse_finite(path, n, fields[3], what[2])?,
            ))
        };
        match fields[0] {
            "p" => {
                positions.push(three(["x", "y", "z"])?);
                normals.push(None);
                point_lines.push(n);
            }
            "n" => {
                let v = three(["nx", "ny", "nz"])?;
                match normals.last_mut() {
                    None => {
                        return Err(err(
                            "found a normal ('n' record) before any point; in an A3d stream \
                             a normal follows its 'p' record"
                                .into(),
                        ));
                    }
                    Some(Some(_)) => {
                        return Err(err(
                            "found a second normal ('n' record) for the same point".into()
                        ));
                    }
                    Some(slot) => *slot = Some(v),
                }
                first_normal.get_or_insert(n);
            }
            "d" | "s" | "g" => {}
            other => {
                return Err(err(format!(
                    "unknown A3d record {}; expected p (point), n (normal), d, s, g or a # \
                     comment",
                    super::text::show(other)
                )));
            }
        }
    }
    if let Some(nl) = first_normal {
        if let Some(i) = normals.iter().position(Option::is_none) {
            first_without.get_or_insert(point_lines[i]);
        }
        if let Some(pl) = first_without {
            return Err(format_err(
                path,
                Location::Line(pl),
                format!(
                    "this point has no normal, but the point before line {nl} has one; \
                     expected a normal for every point or for none"
                ),
            ));
        }
    }
    let normals = first_normal.map(|_| normals.into_iter().flatten().collect());
    Ok(Parsed {
        positions,
        normals,
        ..Parsed::default()
    })
}

pub(crate) fn write(w: &mut dyn Write, g: &Geometry, pts: bool) -> io::Result<()> {
    if pts {
        writeln!(w, "{}", g.positions.len())?;
    }
    for (i, p) in g.positions.iter().enumerate() {
        write!(w, "{} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
        if let Some(n) = g.normals {
            write!(w, " {} {} {}", Num(n[i].x), Num(n[i].y), Num(n[i].z))?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}
