//! The error type every fallible library call returns. Each variant names the
//! file involved, so a message alone tells the user what to fix.

use std::path::PathBuf;

/// A result whose error is this crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// What went wrong, with the file it concerns; `Display` gives the message
/// shown to the user.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene that breaks the contract: `file: key.path: what was expected`.
    #[error("{}: {path}: {message}", file.display())]
    Scene {
        /// The scene file.
        file: PathBuf,
        /// Path of the offending key, e.g. `objects[3].material`; empty for the whole file.
        path: String,
        /// What was expected, and what was found.
        message: String,
    },
    /// Malformed JSON, with the position serde_json reports.
    #[error("{}: line {line}, column {column}: {message}", file.display())]
    Syntax {
        /// The file being parsed.
        file: PathBuf,
        /// Line of the error, counting from 1.
        line: usize,
        /// Column of the error, counting from 1.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// A file that could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// An image that could not be encoded or decoded.
    #[error("{}: {message}", path.display())]
    Image {
        /// The image file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A mesh or ray file whose contents cannot be used.
    #[error("{}: {message}", path.display())]
    Data {
        /// The file.
        path: PathBuf,
        /// What is wrong with its contents.
        message: String,
    },
    /// Render settings (from a scene or from flags) that cannot be honoured
    /// together, e.g. a crop outside the image.
    #[error("{0}")]
    Settings(String),
    /// Partial renders that do not add up to one image.
    #[error("cannot merge: {0}")]
    Merge(String),
    /// The preview window could not be shown.
    #[error("{0}")]
    Preview(String),
    /// The scene cache has no folder to live in.
    #[error("no cache folder: pass --cache-dir or set TRACER_CACHE_DIR")]
    NoCacheDir,
    /// The render would need more memory than the machine has.
    #[error("this render needs about {} ({triangles} triangles, {pixels} pixels) but {} is available; make the scene smaller, or pass --memory-limit to allow more", human_bytes(*needed), human_bytes(*available))]
    Memory {
        /// Estimated bytes.
        needed: u64,
        /// Bytes available (or the limit given).
        available: u64,
        /// Triangles the scene would make.
        triangles: u64,
        /// Pixels of the image.
        pixels: u64,
    },
    /// The worker threads could not be started.
    #[error("cannot start worker threads: {0}")]
    Threads(String),
    /// Ctrl-C or SIGTERM stopped work that cannot be kept in part.
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    /// An [`Error::Scene`] at key path `path` of `file`.
    pub fn scene(
        file: impl Into<PathBuf>,
        path: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::Scene {
            file: file.into(),
            path: clip(path.into()),
            message: clip(message.into()),
        }
    }

    /// An [`Error::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// The longest message or key path an error repeats from its input.
const MAX_ECHO: usize = 400;

/// `text` cut to 400 characters, saying how long it was: a
/// 100 MB string in a scene file is not echoed whole into the terminal.
pub fn clip(text: String) -> String {
    match text.char_indices().nth(MAX_ECHO) {
        Some((cut, _)) => format!("{}… (cut; {} bytes in all)", &text[..cut], text.len()),
        None => text,
    }
}

/// `n` bytes as a person reads them: `1.5 GiB`.
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut x = n as f64;
    let mut unit = 0;
    while x >= 1024.0 && unit < UNITS.len() - 1 {
        x /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} B")
    } else {
        format!("{x:.1} {}", UNITS[unit])
    }
}
