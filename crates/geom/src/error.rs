//! The one error type of `reconbench-geom`.
//!
//! Every variant names what is at fault (the file, the line or byte offset, the index of
//! the offending element, or the parameter) so that the CLI can print a single useful line.

use std::borrow::Cow;
use std::fmt;
use std::path::{Path, PathBuf};

/// Where in an input a format error was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number of a text file.
    Line(usize),
    /// 0-based byte offset in a binary file (or binary section of a file).
    Byte(u64),
    /// The problem concerns the file as a whole (e.g. it is empty).
    File,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Byte(b) => write!(f, "byte {b}"),
            Location::File => write!(f, "file"),
        }
    }
}

/// Errors of the geometry crate.
#[derive(Debug, thiserror::Error)]
pub enum GeomError {
    /// A coordinate (position, normal, ...) is NaN or infinite.
    #[error("{what} {index} has a non-finite coordinate {value:?}")]
    NonFinite {
        /// What kind of element, e.g. "point", "vertex", "normal".
        what: &'static str,
        /// Index of the element.
        index: usize,
        /// The offending value.
        value: [f64; 3],
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {vertex}, but the mesh has {n_vertices} vertices")]
    FaceIndexOutOfRange {
        /// Index of the face.
        face: usize,
        /// The out-of-range vertex index.
        vertex: u64,
        /// Number of vertices of the mesh.
        n_vertices: usize,
    },
    /// A per-element attribute has the wrong length.
    #[error("{what} has {got} values, expected {expected} (one per {per})")]
    LengthMismatch {
        /// Name of the attribute, e.g. "normals" or "channel 'curvature'".
        what: String,
        /// Number of values given.
        got: usize,
        /// Number of values expected.
        expected: usize,
        /// The element the attribute is attached to, e.g. "point".
        per: &'static str,
    },
    /// The input is too small or otherwise unusable for the requested operation.
    #[error("invalid input: {}", escape_control(.0))]
    InvalidInput(String),
    /// A parameter value is out of its valid range.
    #[error("parameter '{name}': {}", escape_control(message))]
    InvalidParameter {
        /// Parameter name as the user spells it.
        name: &'static str,
        /// What is wrong and what is expected.
        message: String,
    },
    /// A linear system has (numerically) dependent columns, so its least-squares solution
    /// is not unique; e.g. a polynomial fit on too few or collinear samples.
    #[error("rank-deficient system: numerical rank {rank} < {cols} unknowns")]
    RankDeficient {
        /// Numerical rank found.
        rank: usize,
        /// Number of unknowns (columns).
        cols: usize,
    },
    /// A file could not be parsed.
    #[error("{}: {location}: {}", Shown(path), escape_control(message))]
    Format {
        /// The file (or a placeholder such as `<memory>` for in-memory input).
        path: PathBuf,
        /// Where in the file.
        location: Location,
        /// What was found and what was expected.
        message: String,
    },
    /// The file format could not be determined or is not supported for this operation.
    #[error("{}: {}", Shown(path), escape_control(message))]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// Explanation, listing the supported choices.
        message: String,
    },
    /// An operating-system I/O error, with the file it concerns.
    #[error("{}: {source}", Shown(path))]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl GeomError {
    /// True for errors about what the caller handed in: unusable input
    /// ([`GeomError::InvalidInput`]: too few points, a degenerate cloud), a bad parameter,
    /// a malformed or unsupported file. Non-finite values, length mismatches, face
    /// indices out of range and rank-deficient systems are not: inside a method they
    /// mean the method built something wrong; the readers report bad files as
    /// [`GeomError::Format`].
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            Self::InvalidInput(_)
                | Self::InvalidParameter { .. }
                | Self::Format { .. }
                | Self::UnsupportedFormat { .. }
        )
    }
}

/// Text for an error message with every character that could corrupt a terminal or a
/// one-line log rendered visibly: ASCII control bytes (NUL, ESC, line breaks, tabs, DEL)
/// as `\x00`, `\x1b`, ...; other Unicode control and invisible formatting characters
/// (C1 controls, zero-width and bidirectional marks, BOM) as `\u{200b}`, ... Everything
/// else, backslashes included, is kept, so escaping twice changes nothing. Used for every
/// message that quotes file content or a file name: hostile input must not be able to
/// split a message into lines or send escape sequences to the user's terminal.
pub fn escape_control(s: &str) -> Cow<'_, str> {
    if !s.chars().any(needs_escape) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if !needs_escape(c) {
            out.push(c);
        } else if c.is_ascii() {
            out.push_str(&format!("\\x{:02x}", c as u32));
        } else {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        }
    }
    Cow::Owned(out)
}

/// True for the characters [`escape_control`] renders as an escape.
fn needs_escape(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{200b}'..='\u{200f}'
                | '\u{2028}'..='\u{202e}'
                | '\u{2060}'..='\u{2069}'
                | '\u{feff}'
        )
}

/// A path in an error message, with control characters escaped (see [`escape_control`]).
struct Shown<'a>(&'a Path);

impl fmt::Display for Shown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&escape_control(&self.0.to_string_lossy()))
    }
}

/// Result alias of this crate.
pub type Result<T, E = GeomError> = std::result::Result<T, E>;

/// Checks that every vector is finite, naming the first offender.
pub(crate) fn check_finite(what: &'static str, values: &[glam::DVec3]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(index) => Err(GeomError::NonFinite {
            what,
            index,
            value: values[index].to_array(),
        }),
    }
}

/// Checks an attribute length against the element count.
pub(crate) fn check_len(
    what: impl Into<String>,
    got: usize,
    expected: usize,
    per: &'static str,
) -> Result<()> {
    if got == expected {
        Ok(())
    } else {
        Err(GeomError::LengthMismatch {
            what: what.into(),
            got,
            expected,
            per,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_control_renders_control_and_invisible_characters() {
        assert_eq!(
            escape_control("a\0b\x1b[31m\n\t\x7f"),
            "a\\x00b\\x1b[31m\\x0a\\x09\\x7f"
        );
        assert_eq!(
            escape_control("x\u{85}y\u{202e}z\u{feff}"),
            "x\\u{85}y\\u{202e}z\\u{feff}"
        );
        assert!(matches!(
            escape_control("plain 'ok' é \\x00"),
            Cow::Borrowed(_)
        ));
        let once = escape_control("\0\u{1b}").into_owned();
        assert_eq!(escape_control(&once), once, "escaping is idempotent");
    }

    #[test]
    fn input_errors_are_told_apart_from_internal_ones() {
        use crate::method::MethodError;
        let fmt = GeomError::Format {
            path: PathBuf::from("a.ply"),
            location: Location::File,
            message: "x".into(),
        };
        assert!(fmt.is_input());
        assert!(GeomError::InvalidInput("too few points".into()).is_input());
        let inner = GeomError::NonFinite {
            what: "vertex",
            index: 0,
            value: [f64::NAN; 3],
        };
        assert!(
            !inner.is_input(),
            "a NaN a method produced is its own failure"
        );
        assert!(MethodError::InvalidInput("coplanar".into()).is_input());
        assert!(MethodError::from(GeomError::InvalidInput("k".into())).is_input());
        assert!(!MethodError::from(inner).is_input());
        assert!(!MethodError::Failed("solver".into()).is_input());
    }

    #[test]
    fn format_errors_escape_the_path_and_the_message() {
        let e = GeomError::Format {
            path: PathBuf::from("evil\u{1b}]0;x\u{7}.ply"),
            location: Location::Line(1),
            message: "found '\0\r\n'".into(),
        };
        let text = e.to_string();
        assert!(!text.chars().any(needs_escape), "{text:?}");
        assert_eq!(
            text,
            "evil\\x1b]0;x\\x07.ply: line 1: found '\\x00\\x0d\\x0a'"
        );
    }
}
