//! The harness error type.

use std::path::{Path, PathBuf};

/// Why a harness operation failed.
#[derive(Debug, thiserror::Error)]
pub enum HarnessError {
    /// Bad input: a malformed experiment file, an unknown method or key, a bad parameter.
    /// The CLI exits with code 2 for these.
    #[error("{0}")]
    Input(String),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory at fault.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Anything else (a worker could not be started, a plot could not be drawn, ...).
    #[error("{0}")]
    Failure(String),
}

impl HarnessError {
    /// Bad-input error with a message.
    pub fn input(msg: impl Into<String>) -> Self {
        Self::Input(msg.into())
    }

    /// Other failure with a message.
    pub fn failure(msg: impl Into<String>) -> Self {
        Self::Failure(msg.into())
    }

    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// True for bad input (exit code 2 in the CLI).
    pub fn is_input(&self) -> bool {
        matches!(self, Self::Input(_))
    }
}

/// Result alias of the harness.
pub type Result<T, E = HarnessError> = std::result::Result<T, E>;

/// Reads a whole text file, naming it on error; a missing file or one that is not UTF-8
/// text is bad input (exit code 2 on the CLI).
pub(crate) fn read_to_string(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => {
            HarnessError::input(format!("{}: no such file", path.display()))
        }
        std::io::ErrorKind::InvalidData => HarnessError::input(format!(
            "{}: not UTF-8 text (a TOML or JSON file is expected)",
            path.display()
        )),
        _ => HarnessError::io(path, e),
    })
}

/// Creates a directory and its parents, naming it on error.
pub(crate) fn create_dir_all(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).map_err(|e| HarnessError::io(path, e))
}

/// Writes a file atomically (temporary file in the same directory, then rename).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        create_dir_all(dir)?;
    }
    let tmp = path.with_extension(format!(
        "{}.tmp{}",
        path.extension().and_then(|e| e.to_str()).unwrap_or(""),
        std::process::id()
    ));
    let mut f = std::fs::File::create(&tmp).map_err(|e| HarnessError::io(&tmp, e))?;
    f.write_all(bytes).map_err(|e| HarnessError::io(&tmp, e))?;
    f.sync_all().map_err(|e| HarnessError::io(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| HarnessError::io(path, e))
}
