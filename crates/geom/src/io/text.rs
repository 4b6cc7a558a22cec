//! Helpers shared by the text formats: numbered line iteration, number parsing with
//! located errors, and exact float formatting.

use std::fmt;
use std::path::Path;

use super::format_err;
use crate::error::{Location, Result};

/// Iterates over the lines of a byte buffer as `(1-based number, bytes)`, without the
/// line terminator (`\n` or `\r\n`). Works on bytes so that binary data after a text
/// header, or stray non-UTF-8 comments, do not stop the iteration.
#[derive(Debug, Clone)]
pub(crate) struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    /// Lines of the whole buffer.
    pub fn new(data: &'a [u8]) -> Self {
        Self::starting_at(data, 0, 0)
    }

    /// Lines from byte `pos`, numbering the first one `lines_before + 1`.
    pub fn starting_at(data: &'a [u8], pos: usize, lines_before: usize) -> Self {
        Self {
            data,
            pos,
            line: lines_before,
        }
    }

    /// Byte offset of the next line.
    pub fn offset(&self) -> usize {
        self.pos
    }

    /// Number of bytes not yet returned.
    pub fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    /// Number of the last line returned (0 before the first).
    pub fn line_number(&self) -> usize {
        self.line
    }

    /// The next line that is not blank, as text.
    pub fn next_nonblank(&mut self, path: &Path) -> Result<Option<(usize, &'a str)>> {
        for (n, bytes) in self.by_ref() {
            let s = line_str(path, n, bytes)?;
            if !s.trim().is_empty() {
                return Ok(Some((n, s)));
            }
        }
        Ok(None)
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let (mut line, advance) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        if let [head @ .., b'\r'] = line {
            line = head;
        }
        self.pos += advance;
        self.line += 1;
        Some((self.line, line))
    }
}

/// A line as UTF-8 text, or an error suggesting the file is binary.
pub(crate) fn line_str<'a>(path: &Path, line: usize, bytes: &'a [u8]) -> Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|_| {
        format_err(
            path,
            Location::Line(line),
            "found bytes that are not text (invalid UTF-8); expected a text line \
             (is this a binary file, or the wrong format?)",
        )
    })
}

/// A token quoted for an error message, shortened if long (garbage can be huge).
pub(crate) fn show(tok: &str) -> String {
    const MAX: usize = 32;
    if tok.chars().count() <= MAX {
        format!("'{tok}'")
    } else {
        let head: String = tok.chars().take(MAX).collect();
        format!("'{head}...'")
    }
}

/// Parses a number token (any float syntax Rust accepts, including `nan`/`inf`).
pub(crate) fn parse_f64(path: &Path, line: usize, tok: &str, what: &str) -> Result<f64> {
    tok.parse::<f64>().map_err(|_| {
        format_err(
            path,
            Location::Line(line),
            format!("expected a number for {what}, found {}", show(tok)),
        )
    })
}

/// Parses a number token that must be finite (coordinates, normals).
pub(crate) fn parse_finite(path: &Path, line: usize, tok: &str, what: &str) -> Result<f64> {
    let v = parse_f64(path, line, tok, what)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format_err(
            path,
            Location::Line(line),
            format!("{what} is {}; expected a finite number", show(tok)),
        ))
    }
}

/// Parses an integer token.
pub(crate) fn parse_i64(path: &Path, line: usize, tok: &str, what: &str) -> Result<i64> {
    tok.parse::<i64>().map_err(|_| {
        format_err(
            path,
            Location::Line(line),
            format!("expected an integer for {what}, found {}", show(tok)),
        )
    })
}

/// Parses a non-negative count (header counts), bounded by `usize`.
pub(crate) fn parse_count(path: &Path, line: usize, tok: &str, what: &str) -> Result<usize> {
    tok.parse::<usize>().map_err(|_| {
        format_err(
            path,
            Location::Line(line),
            format!(
                "expected a non-negative integer for {what}, found {}",
                show(tok)
            ),
        )
    })
}

/// Converts a colour component given either as an integer 0..=255 or as a float in
/// 0..=1 (the latter recognised by a `.` or exponent in the token); a float outside 0..=1
/// is an error, not clamped.
pub(crate) fn parse_color(path: &Path, line: usize, tok: &str) -> Result<u8> {
    if tok.contains(['.', 'e', 'E']) {
        let v = parse_finite(path, line, tok, "a colour component")?;
        unit_to_u8(v).map_err(|m| format_err(path, Location::Line(line), m))
    } else {
        let v = parse_i64(path, line, tok, "a colour component")?;
        u8::try_from(v).map_err(|_| {
            format_err(
                path,
                Location::Line(line),
                format!("colour component {v} is out of range; expected 0..=255"),
            )
        })
    }
}

/// Maps a colour component in 0..=1 to 0..=255. A value outside 0..=1 (or NaN) is an
/// error naming it: clamping would silently change the colours of a file written on
/// another scale (0..255 integers written as floats, say).
pub(crate) fn unit_to_u8(v: f64) -> std::result::Result<u8, String> {
    if (0.0..=1.0).contains(&v) {
        Ok((v * 255.0).round() as u8)
    } else {
        Err(format!(
            "colour component {v} is outside 0..1; expected a float colour in 0..1"
        ))
    }
}

/// Formats an `f64` with the shortest digits that parse back to the same value (at most
/// 17 significant digits), switching to exponent notation for very large or small
/// magnitudes so that no value needs hundreds of characters.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-5..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Splits a line into tokens separated by white space and/or commas.
pub(crate) fn split_fields(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c == ',' || c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn num_round_trips_exactly() {
        for v in [
            0.0,
            -0.0,
            0.1,
            1.0 / 3.0,
            1e300,
            -2.5e-310,
            f64::MIN_POSITIVE,
            f64::MAX,
            123456.789,
        ] {
            let s = Num(v).to_string();
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
            assert!(s.len() < 26, "{s}");
        }
    }

    #[test]
    fn lines_strip_crlf_and_count() {
        let v: Vec<_> = Lines::new(b"a\r\nb\n\nc").collect();
        assert_eq!(
            v,
            vec![
                (1, &b"a"[..]),
                (2, &b"b"[..]),
                (3, &b""[..]),
                (4, &b"c"[..])
            ]
        );
    }
}
