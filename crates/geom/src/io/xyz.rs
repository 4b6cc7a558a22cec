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
