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

/// Result with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
