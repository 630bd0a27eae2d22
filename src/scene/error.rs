//! The one error type of the scene module.
//!
//! Every message starts with where the problem is — `file`, `file:line` or
//! `file:line:col` — followed by what is wrong, so it can be shown to a user as is.
//! Built-in scenes use `builtin:<name>` as their file.

use std::fmt;
use std::path::PathBuf;

/// A place in an input file: the file, and the 1-based line and column where known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: String,
    pub line: Option<usize>,
    pub col: Option<usize>,
}

impl Location {
    pub fn file(file: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            line: None,
            col: None,
        }
    }

    pub fn line(file: impl Into<String>, line: usize) -> Self {
        Self {
            file: file.into(),
            line: Some(line),
            col: None,
        }
    }

    pub fn line_col(file: impl Into<String>, line: usize, col: usize) -> Self {
        Self {
            file: file.into(),
            line: Some(line),
            col: Some(col),
        }
    }

    /// The location of byte offset `offset` in `text` (1-based line and column in chars).
    pub fn at_offset(file: impl Into<String>, text: &str, offset: usize) -> Self {
        let (line, col) = line_col(text, offset);
        Self::line_col(file, line, col)
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.col {
                write!(f, ":{col}")?;
            }
        }
        Ok(())
    }
}

/// 1-based (line, column) of byte `offset` in `text`; the column counts chars.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = before[line_start..].chars().count() + 1;
    (line, col)
}

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file that does not exist or cannot be read.
    /// The message carries the cause: it is not also a `source`, which would print it
    /// twice in a chain (`{:#}`).
    #[error("{path}: cannot read file: {error}", path = .path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    /// A file referenced from another one (mesh from a TOML, MTL from an OBJ) is missing.
    #[error("{at}: {what} '{name}' not found (looked for {path})", path = .path.display())]
    MissingReference {
        at: Location,
        what: &'static str,
        name: String,
        path: PathBuf,
    },
    /// A file referenced from another one is there but cannot be read (a folder, a
    /// FIFO, a name the file system refuses): named with the reference, since the
    /// mistake may be the reference's.
    #[error("{at}: {what} {path} cannot be read: {error}", path = .path.display())]
    UnreadableReference {
        at: Location,
        what: &'static str,
        path: PathBuf,
        error: std::io::Error,
    },
    /// Malformed OBJ, MTL or TOML text.
    #[error("{at}: {message}")]
    Syntax { at: Location, message: String },
    /// A NaN or infinite number where a finite one is needed.
    #[error("{at}: {what} is not finite ({value})")]
    NonFinite {
        at: Location,
        what: String,
        value: String,
    },
    /// A face index that points outside the vertex / texcoord / normal arrays.
    #[error(
        "{at}: face {face} references {kind} {index} but the file has {count} {kinds}",
        kinds = plural(.kind, *.count)
    )]
    IndexOutOfRange {
        at: Location,
        face: usize,
        kind: &'static str,
        index: i64,
        count: usize,
    },
    /// A name that does not resolve (material override, built-in scene …).
    #[error("{at}: unknown {what} '{name}'{hint}")]
    Unknown {
        at: Location,
        what: &'static str,
        name: String,
        hint: String,
    },
    /// An invalid camera.
    #[error("{at}: invalid camera: {message}")]
    Camera { at: Location, message: String },
    /// An invalid film size.
    #[error("{at}: invalid film size: {message}")]
    Film { at: Location, message: String },
    /// Any other invalid value (material parameter, light, transform …).
    #[error("{at}: {message}")]
    Invalid { at: Location, message: String },
    /// No usable triangles.
    #[error("{at}: empty scene: {message}")]
    Empty { at: Location, message: String },
    /// `load` got something that is neither a built-in name nor a .toml / .obj path.
    #[error("'{spec}': {message}")]
    BadSpec { spec: String, message: String },
}

fn plural(kind: &str, count: usize) -> String {
    match (kind, count) {
        (k, 1) => k.to_string(),
        ("vertex", _) => "vertices".to_string(),
        (k, _) => format!("{k}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_from_one() {
        let t = "ab\ncd\né f";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 4), (2, 2));
        assert_eq!(line_col(t, 6), (3, 1));
        // 'é' is two bytes: the space after it is column 2.
        assert_eq!(line_col(t, 8), (3, 2));
        assert_eq!(line_col(t, 999), (3, 4));
    }
}
