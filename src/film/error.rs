//! The film module's error type.

use std::path::PathBuf;

/// Everything that can go wrong while building, writing or reading a film.
///
/// Every variant that concerns a file names that file's path.
#[derive(Debug, thiserror::Error)]
pub enum FilmError {
    /// The folder an output should be written into does not exist (or something else,
    /// a file, is in its place: the message says which).
    #[error("{}: {}", .path.display(), folder_problem(.folder))]
    MissingDirectory {
        /// The output file.
        path: PathBuf,
        /// Its folder, which was expected to exist.
        folder: PathBuf,
    },

    /// An I/O operation on `path` failed. The underlying error is part of the message,
    /// not a `source`: an error chain printed whole would repeat it.
    #[error("{}: cannot {op}: {error}", .path.display())]
    Io {
        /// The file or folder the operation was about (the target, not its temporary file).
        path: PathBuf,
        /// What was attempted ("create a temporary file for it", "open", ...).
        op: &'static str,
        /// The underlying error.
        error: std::io::Error,
    },

    /// The EXR encoder or decoder failed.
    #[error("{}: EXR error: {error}", .path.display())]
    Exr {
        /// The EXR file.
        path: PathBuf,
        /// The underlying error.
        error: exr::error::Error,
    },

    /// The PNG encoder failed.
    #[error("{}: PNG error: {error}", .path.display())]
    Png {
        /// The PNG file.
        path: PathBuf,
        /// The underlying error.
        error: png::EncodingError,
    },

    /// A file was read successfully but its content is not what we expect
    /// (missing RGB channels, an AOV of the wrong sample type, bad metadata, ...),
    /// or the film or metadata about to be written cannot be represented.
    #[error("{}: {message}", .path.display())]
    Invalid {
        /// The file being read or written.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },

    /// A buffer handed to the film has the wrong number of elements.
    #[error("{what}: got {got} elements, expected {expected} ({width}x{height} film)")]
    SizeMismatch {
        /// Which buffer ("pass buffer", "depth AOV", ...).
        what: &'static str,
        /// Its length.
        got: usize,
        /// The film's pixel count.
        expected: usize,
        /// Film width.
        width: u32,
        /// Film height.
        height: u32,
    },
}

/// What is wrong with `folder`, an output's missing folder: a file in its place, or
/// nothing there. Decided when the error is shown (the variant is the same for both), so
/// a user is never told that a file they can see does not exist.
fn folder_problem(folder: &std::path::Path) -> String {
    match folder.exists() {
        true => format!("{} is not a folder", folder.display()),
        false => format!("the folder {} does not exist", folder.display()),
    }
}

impl FilmError {
    pub(crate) fn io(path: impl Into<PathBuf>, op: &'static str, error: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            op,
            error,
        }
    }

    pub(crate) fn invalid(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Invalid {
            path: path.into(),
            message: message.into(),
        }
    }
}
