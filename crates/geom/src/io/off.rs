//! Geomview OFF with the `C` (vertex colours), `N` (vertex normals) and `ST` (texture
//! coordinates, ignored) prefixes: OFF, COFF, NOFF, CNOFF, STOFF, ...
//!
//! Layout: the keyword line, a counts line `n_vertices n_faces [n_edges]` (it may also
//! follow the keyword on the same line), one line per vertex
//! (`x y z [nx ny nz] [r g b [a]] [s t]`), one line per face (`k i_1 ... i_k [colour]`,
//! the optional face colour ignored). `#` starts a comment. Polygons are fan-triangulated.
//! Colours are integers 0..=255 or floats 0..1; reconbench writes integers with alpha 255.

use std::io::{self, Write};
use std::path::Path;

use glam::DVec3;

use super::text::{Lines, Num, line_str, parse_color, parse_count, parse_f64, parse_finite, show};
use super::{Geometry, Parsed, format_err};
use crate::error::{Location, Result};

/// Non-blank lines with `#` comments removed, tokenized.
struct Records<'a> {
    path: &'a Path,
    lines: Lines<'a>,
    last: usize,
}

impl<'a> Records<'a> {
    fn next(&mut self) -> Result<Option<(usize, Vec<&'a str>)>> {
        for (n, raw) in self.lines.by_ref() {
            self.last = n;
            let raw = match raw.iter().position(|&b| b == b'#') {
                Some(i) => &raw[..i],
                None => raw,
            };
            let toks: Vec<&str> = line_str(self.path, n, raw)?
                .split_ascii_whitespace()
                .collect();
            if !toks.is_empty() {
                return Ok(Some((n, toks)));
            }
        }
        Ok(None)
    }
}

/// The prefixes of an OFF keyword.
struct Variant {
    texture: bool,
    color: bool,
    normal: bool,
}

fn parse_keyword(kw: &str) -> Option<std::result::Result<Variant, String>> {
    let mut rest = kw.strip_suffix("OFF")?;
    let mut take = |p: &str| match rest.strip_prefix(p) {
        Some(r) => {
            rest = r;
            true
        }
        None => false,
    };
    let v = Variant {
        texture: take("ST"),
        color: take("C"),
        normal: take("N"),
    };
    if take("4") || take("n") {
        return Some(Err(format!(
            "{} (higher-dimensional OFF) is not supported; expected OFF, COFF, NOFF or CNOFF",
            show(kw)
        )));
    }
    rest.is_empty().then_some(Ok(v))
}

/// Refuses counts the rest of the file cannot hold, before any record is read: every
/// record is a line of at least two bytes. (A tighter bound, from the values per line,
/// would preempt the more precise error of the first short record for files that are a
/// few bytes short.)
fn check_counts(recs: &Records, line: usize, nv: usize, nf: usize) -> Result<()> {
    let left = recs.lines.remaining() as u128;
    let need = ((nv as u128 + nf as u128) * 2).saturating_sub(1);
    if need > left {
        return Err(format_err(
            recs.path,
            Location::Line(line),
            format!(
                "the counts line declares {nv} vertices and {nf} faces, at least {need} bytes, \
                 but only {left} bytes follow; the file is truncated or the counts are wrong"
            ),
        ));
    }
    Ok(())
}

pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<Parsed> {
    let mut recs = Records {
        path,
        lines: Lines::new(bytes),
        last: 0,
    };
    let err = |line: usize, m: String| format_err(path, Location::Line(line), m);
    let Some((n0, head)) = recs.next()? else {
        return Err(err(
            recs.last.max(1),
            "found only comments and blank lines; expected an OFF header".into(),
        ));
    };
    let variant = match parse_keyword(head[0]) {
        Some(Ok(v)) => v,
        Some(Err(m)) => return Err(err(n0, m)),
        None => {
            return Err(err(
                n0,
                format!(
                    "found {} where an OFF file starts with OFF, COFF, NOFF or CNOFF",
                    show(head[0])
                ),
            ));
        }
    };
    let (nc, counts) = if head.len() > 1 {
        (n0, head[1..].to_vec())
    } else {
        recs.next()?.ok_or_else(|| {
            err(
                recs.last,
                "the file ends before the counts line 'n_vertices n_faces n_edges'".into(),
            )
        })?
    };
    if !(2..=3).contains(&counts.len()) {
        return Err(err(
            nc,
            format!(
                "the counts line has {} values; expected 'n_vertices n_faces [n_edges]'",
                counts.len()
            ),
        ));
    }
    let nv = parse_count(path, nc, counts[0], "the vertex count")?;
    let nf = parse_count(path, nc, counts[1], "the face count")?;
    if let Some(ne) = counts.get(2) {
        parse_count(path, nc, ne, "the edge count")?;
    }

    let fixed = 3 + if variant.normal { 3 } else { 0 } + if variant.texture { 2 } else { 0 };
    check_counts(&recs, nc, nv, nf)?;
    // Each record takes at least two bytes, whatever the counts claim.
    let bound = bytes.len() / 2 + 1;
    let mut positions = Vec::with_capacity(nv.min(bound));
    let mut normals = variant.normal.then(|| Vec::with_capacity(nv.min(bound)));
    let mut colors = variant.color.then(|| Vec::with_capacity(nv.min(bound)));
    let expected = || {
        let mut s = String::from("x y z");
        if variant.normal {
            s.push_str(" nx ny nz");
        }
        if variant.color {
            s.push_str(" r g b [a]");
        }
        if variant.texture {
            s.push_str(" s t");
        }
        s
    };
    for i in 0..nv {
        let Some((n, toks)) = recs.next()? else {
            return Err(err(
                recs.last,
                format!("the file ends after {i} of {nv} vertices"),
            ));
        };
        let n_color = toks.len().wrapping_sub(fixed);
        let ok = if variant.color {
            toks.len() >= fixed && (3..=4).contains(&n_color)
        } else {
            toks.len() == fixed
        };
        if !ok {
            return Err(err(
                n,
                format!(
                    "vertex {i} has {} values; expected {}",
                    toks.len(),
                    expected()
                ),
            ));
        }
        let mut v = [0.0; 3];
        for k in 0..3 {
            v[k] = parse_finite(path, n, toks[k], "a vertex coordinate")?;
        }
        positions.push(DVec3::from_array(v));
        let mut at = 3;
        if let Some(normals) = &mut normals {
            let mut nn = [0.0; 3];
            for k in 0..3 {
                nn[k] = parse_finite(path, n, toks[at + k], "a normal component")?;
            }
            normals.push(DVec3::from_array(nn));
            at += 3;
        }
        if let Some(colors) = &mut colors {
            let mut c = [0u8; 3];
            for k in 0..3 {
                c[k] = parse_color(path, n, toks[at + k])?;
            }
            if n_color == 4 {
                parse_color(path, n, toks[at + 3])?;
            }
            colors.push(c);
            at += n_color;
        }
        for tok in &toks[at..] {
            parse_f64(path, n, tok, "a texture coordinate")?;
        }
    }

    let mut faces = Vec::with_capacity(nf.min(bound));
    for i in 0..nf {
        let Some((n, toks)) = recs.next()? else {
            return Err(err(
                recs.last,
                format!("the file ends after {i} of {nf} faces"),
            ));
        };
        let k = parse_count(path, n, toks[0], "the face vertex count")?;
        if k < 3 {
            return Err(err(
                n,
                format!("face {i} has {k} vertices; expected at least 3"),
            ));
        }
        if toks.len() - 1 < k {
            return Err(err(
                n,
                format!(
                    "face {i} declares {k} vertices but lists {}",
                    toks.len() - 1
                ),
            ));
        }
        let extra = toks.len() - 1 - k;
        if extra > 4 {
            return Err(err(
                n,
                format!(
                    "face {i} has {extra} values after its {k} indices; expected at most a \
                     colour (up to 4 values)"
                ),
            ));
        }
        for tok in &toks[1 + k..] {
            parse_f64(path, n, tok, "a face colour component")?;
        }
        let idx = |j: usize| -> Result<u32> {
            let tok = toks[1 + j];
            let v: i64 = tok.parse().map_err(|_| {
                err(
                    n,
                    format!("face {i}: expected a vertex index, found {}", show(tok)),
                )
            })?;
            if v < 0 || v as u64 >= nv as u64 {
                return Err(err(
                    n,
                    format!(
                        "face {i} refers to vertex {v}; expected an index in 0..{nv} \
                         (the file has {nv} vertices)"
                    ),
                ));
            }
            Ok(v as u32)
        };
        let first = idx(0)?;
        let mut prev = idx(1)?;
        for j in 2..k {
            let cur = idx(j)?;
            faces.push([first, prev, cur]);
            prev = cur;
        }
    }
    if let Some((n, toks)) = recs.next()? {
        return Err(err(
            n,
            format!(
                "found {} after the last of the {nf} faces; expected the end of the file \
                 (the counts line may be wrong)",
                show(toks[0])
            ),
        ));
    }
    Ok(Parsed {
        positions,
        normals,
        colors,
        faces,
        ..Parsed::default()
    })
}

pub(crate) fn write(w: &mut dyn Write, g: &Geometry) -> io::Result<()> {
    let kw = match (g.colors.is_some(), g.normals.is_some()) {
        (false, false) => "OFF",
        (true, false) => "COFF",
        (false, true) => "NOFF",
        (true, true) => "CNOFF",
    };
    let faces = g.faces.unwrap_or(&[]);
    writeln!(w, "{kw}")?;
    writeln!(w, "# written by reconbench ({})", g.what())?;
    writeln!(w, "{} {} 0", g.positions.len(), faces.len())?;
    for (i, p) in g.positions.iter().enumerate() {
        write!(w, "{} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
        if let Some(n) = g.normals {
            write!(w, " {} {} {}", Num(n[i].x), Num(n[i].y), Num(n[i].z))?;
        }
        if let Some(c) = g.colors {
            write!(w, " {} {} {} 255", c[i][0], c[i][1], c[i][2])?;
        }
        w.write_all(b"\n")?;
    }
    for f in faces {
        writeln!(w, "3 {} {} {}", f[0], f[1], f[2])?;
    }
    Ok(())
}
