//! The error type of `reconbench-synth`.

use reconbench_geom::GeomError;

/// Errors of the synthetic-data crate. Every variant names what is wrong and, for
/// unknown names, lists the valid choices so that the CLI can print one useful line.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// An error of the geometry crate (cloud/mesh construction, spatial queries).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// A name (shape, sampler, perturbation, ...) that does not exist.
    #[error("unknown {what} '{name}'; valid: {valid}")]
    UnknownName {
        /// What kind of name, e.g. "shape".
        what: &'static str,
        /// The name given.
        name: String,
        /// Comma-separated valid names.
        valid: String,
    },
    /// A parameter that the named item does not have.
    #[error("{owner} has no parameter '{name}'; valid: {valid}")]
    UnknownParameter {
        /// The item, e.g. "shape 'torus'".
        owner: String,
        /// The parameter given.
        name: String,
        /// Comma-separated valid parameters with their defaults.
        valid: String,
    },
    /// A parameter value out of its valid range.
    #[error("{owner}: parameter '{name}': {message}")]
    InvalidParameter {
        /// The item, e.g. "shape 'torus'".
        owner: String,
        /// Parameter name.
        name: String,
        /// What is wrong and what is expected.
        message: String,
    },
    /// A spec string that could not be parsed.
    #[error("cannot parse {what} spec '{input}': {message}")]
    Parse {
        /// What kind of spec, e.g. "noise".
        what: &'static str,
        /// The input string.
        input: String,
        /// What is wrong.
        message: String,
    },
    /// The request cannot be satisfied (e.g. a scan that hits nothing).
    #[error("{0}")]
    Unsatisfiable(String),
}

/// Result alias of this crate.
pub type Result<T, E = SynthError> = std::result::Result<T, E>;

impl SynthError {
    /// Shorthand for [`SynthError::InvalidParameter`].
    pub fn invalid(
        owner: impl Into<String>,
        name: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SynthError::InvalidParameter {
            owner: owner.into(),
            name: name.into(),
            message: message.into(),
        }
    }
}
