//! The one error type of `reconbench-geom`.
//!
//! Every variant names what is at fault (the file, the line or byte offset, the index of
//! the offending element, or the parameter) so that the CLI can print a single useful line.

use std::fmt;
use std::path::PathBuf;

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
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A parameter value is out of its valid range.
    #[error("parameter '{name}': {message}")]
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
    #[error("{}: {location}: {message}", path.display())]
    Format {
        /// The file (or a placeholder such as `<memory>` for in-memory input).
        path: PathBuf,
        /// Where in the file.
        location: Location,
        /// What was found and what was expected.
        message: String,
    },
    /// The file format could not be determined or is not supported for this operation.
    #[error("{}: {message}", path.display())]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// Explanation, listing the supported choices.
        message: String,
    },
    /// An operating-system I/O error, with the file it concerns.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
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
