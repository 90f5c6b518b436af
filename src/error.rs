//! The error type every fallible library call returns. Each variant names the
//! file involved, so a message alone tells the user what to fix.

use std::path::PathBuf;

pub type Result<T> = std::result::Result<T, Error>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene that breaks the contract: `file: key.path: what was expected`.
    #[error("{}: {path}: {message}", file.display())]
    Scene {
        file: PathBuf,
        /// Path of the offending key, e.g. `objects[3].material`; empty for the whole file.
        path: String,
        message: String,
    },
    /// Malformed JSON, with the position serde_json reports.
    #[error("{}: line {line}, column {column}: {message}", file.display())]
    Syntax {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An image that could not be encoded or decoded.
    #[error("{}: {message}", path.display())]
    Image { path: PathBuf, message: String },
    /// A request the renderer cannot honour (e.g. an integrator not built yet).
    #[error("{0}")]
    Unsupported(String),
    /// Ctrl-C or SIGTERM stopped work that cannot be kept in part.
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    pub fn scene(
        file: impl Into<PathBuf>,
        path: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::Scene {
            file: file.into(),
            path: path.into(),
            message: message.into(),
        }
    }

    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
