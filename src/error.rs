//! The library's error type. Every error that comes from user input names the file (when there is
//! one) and the problem in one line, so the CLI can print it as it is and exit with status 2.

use std::path::{Path, PathBuf};

/// Errors of the vesselmsr library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused a read or write.
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file's extension names no format we read or write.
    #[error("{}: unknown mesh format (expected extension .stl, .obj, .ply, .vtp or .vtk)", .path.display())]
    UnknownFormat { path: PathBuf },
    /// The file's contents are malformed or describe no usable mesh.
    #[error("{}: {message}", .path.display())]
    Format { path: PathBuf, message: String },
    /// A mesh handed to an operation does not meet that operation's requirements.
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// A geometric operation could not be carried out.
    #[error("{0}")]
    Geometry(String),
    /// An option of a request is out of range (named as the library names it, e.g. `voxel`;
    /// the CLI and the Python package print their own spelling of the name).
    #[error("{option} {problem}")]
    BadOption {
        option: &'static str,
        problem: String,
    },
    /// Work refused before it starts: its memory estimate exceeds the budget, or it asks for
    /// more than a limit allows (too many regions).
    #[error("{0}")]
    Refused(String),
    /// An error with what was being done when it happened (e.g. the mesh's name).
    #[error("{context}: {source}")]
    Context {
        context: String,
        #[source]
        source: Box<Error>,
    },
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    /// A malformed-content error on `path`.
    pub fn format(path: &Path, message: impl Into<String>) -> Self {
        Error::Format {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

impl Error {
    /// This error with `context` (what was being done, or on what) before it.
    pub fn context(self, context: impl Into<String>) -> Self {
        let context = context.into();
        if context.is_empty() {
            return self;
        }
        Error::Context {
            context,
            source: Box::new(self),
        }
    }
}

/// `v` with 6 significant digits, in exponent form when very large or small (numbers in
/// messages).
pub fn short_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor();
    if !(-4.0..15.0).contains(&magnitude) {
        return format!("{v:.5e}");
    }
    let decimals = (5.0 - magnitude).max(0.0) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Result with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
