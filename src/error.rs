//! The one error type of the `grainline` library.
//!
//! User errors (a bad file, a bad option) name the file, the line or the element, and what is
//! wrong, in one line. Internal errors (a factorization that fails on valid input) say so.

use std::path::PathBuf;

/// Everything that can go wrong in the `grainline` library.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A syntax error in an input file, with the 1-based line where it was found (0 if unknown).
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number, 0 when the parser could not tell.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The mesh is structurally unusable (empty, non-finite, bad indices, non-manifold, ...).
    #[error("{path}: {message}")]
    InvalidMesh {
        /// The mesh file (or a description of where the mesh came from).
        path: PathBuf,
        /// What is wrong, naming the element (vertex, face, edge) and, where known, the line.
        message: String,
    },
    /// A coordinate (`v`, `vt`, `vn`) that is NaN or infinite, with its 1-based line.
    #[error("{path}:{line}: {message}")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A face refers to a vertex, texture coordinate or normal that does not exist.
    #[error("{path}:{line}: {message}")]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// 1-based line number of the face.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The mesh has no faces left (an empty file, or every face dropped).
    #[error("{path}: {message}")]
    EmptyMesh {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The object asked for is not in the file.
    #[error("{path}: no object or group named {name:?}; available: {available}")]
    ObjectNotFound {
        /// The file.
        path: PathBuf,
        /// The name asked for.
        name: String,
        /// The names in the file, comma-separated.
        available: String,
    },
    /// Zero-area faces refused by [`DegeneratePolicy::Error`](crate::mesh::load::DegeneratePolicy).
    #[error("{path}: {message}")]
    DegenerateFaces {
        /// The file.
        path: PathBuf,
        /// Which faces (with their lines).
        message: String,
    },
    /// Non-manifold edges (three or more faces) or vertices (several fans of faces).
    #[error("{path}: {message}")]
    NonManifold {
        /// The file.
        path: PathBuf,
        /// Which elements.
        message: String,
    },
    /// Two faces traverse a shared edge in the same direction (their normals disagree).
    #[error("{path}: {message}")]
    InconsistentOrientation {
        /// The file.
        path: PathBuf,
        /// Which faces and edge.
        message: String,
    },
    /// An option or argument is out of its valid range.
    #[error("invalid {name}: {message}")]
    InvalidArgument {
        /// The option's name as the user wrote it.
        name: String,
        /// What is wrong with it.
        message: String,
    },
    /// A setting (of a scene file or an options struct) is missing, out of range or
    /// inconsistent. `key` is its path in the scene, e.g. `edits[2].radius`.
    #[error("{key}: {message}")]
    Setting {
        /// The key path, as the user wrote it in the scene.
        key: String,
        /// What is wrong with it.
        message: String,
    },
    /// A scene file could not be read: a syntax error (with its line) or a bad setting.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// The line of a syntax error, when known.
        line: Option<usize>,
        /// What is wrong, starting with the key path.
        message: String,
    },
    /// A numerical procedure failed on valid input.
    #[error("numerical failure in {stage}: {message}")]
    Numerical {
        /// The stage that failed.
        stage: &'static str,
        /// What happened.
        message: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An [`Error::InvalidArgument`].
    pub fn invalid_arg(name: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidArgument { name: name.into(), message: message.into() }
    }

    /// An [`Error::Setting`].
    pub fn setting(key: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Setting { key: key.into(), message: message.into() }
    }
}
