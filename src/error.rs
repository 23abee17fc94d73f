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
    #[error("{}{}: {message}", path.display(), line_suffix(*line))]
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
    /// A coordinate (`v`, `vt`, `vn`) that is NaN or infinite, or a position coordinate too
    /// large for areas to stay finite (`limits::MAX_COORDINATE`), with its 1-based line.
    #[error("{path}:{line}: {message}")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A binary mesh file (binary STL or PLY) that is truncated, inconsistent with its own
    /// counts, or holds a bad value; `offset` is the byte where the problem was found and the
    /// message names the element (e.g. `triangle 12`, `vertex element 7`).
    #[error("{path}: byte {offset}: {message}")]
    BinaryFile {
        /// The file.
        path: PathBuf,
        /// 0-based byte offset of the element or field at fault.
        offset: u64,
        /// What is wrong, naming the element.
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
    /// The work was cancelled from outside ([`crate::cancel`]) at a check point in `stage`:
    /// not a failure of the input; the caller keeps nothing of it.
    #[error("cancelled during {stage}")]
    Cancelled {
        /// The check point that saw the flag.
        stage: &'static str,
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

/// `:L` for a known 1-based line, nothing when the line is unknown (0): no message names a
/// "line 0".
fn line_suffix(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}")
    }
}

/// `text` with its control characters escaped (`\u{1b}` for ESC, `\n` for a newline), for
/// printing paths and messages to a terminal: a scene's path may hold escape sequences.
///
/// ```
/// assert_eq!(grainline::error::escape_control("a\u{1b}[31mb\nc"), "a\\u{1b}[31mb\\nc");
/// ```
pub fn escape_control(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// A number as messages print it: the shortest text that reads back as the same `f64`, in
/// exponent form when it is very small or very large (`1e-300`, not 300 digits), without a
/// trailing `.0` (`5`, `0.25`, `1.5e20`).
///
/// ```
/// use grainline::error::fmt_num;
/// assert_eq!(fmt_num(5.0), "5");
/// assert_eq!(fmt_num(179.9999), "179.9999");
/// assert_eq!(fmt_num(1e-300), "1e-300");
/// assert_eq!(fmt_num(-2.5e20), "-2.5e20");
/// assert_eq!(fmt_num(f64::NAN), "NaN");
/// ```
pub fn fmt_num(x: f64) -> String {
    let s = format!("{x:?}");
    match s.strip_suffix(".0") {
        Some(t) => t.to_string(),
        None => s,
    }
}

/// A long text (a path) as messages echo it: whole when it has at most 80 characters, else
/// its first 48 and last 24 characters around `…`, with its length in bytes.
///
/// ```
/// use grainline::error::shorten;
/// assert_eq!(shorten("out/x.svg"), "out/x.svg");
/// let long = "a/".repeat(3000);
/// assert_eq!(shorten(&long).chars().count(), 48 + 1 + 24 + " (6000 bytes)".len());
/// ```
pub fn shorten(text: &str) -> String {
    let n = text.chars().count();
    if n <= 80 {
        return text.to_string();
    }
    let head: String = text.chars().take(48).collect();
    let tail: String = text.chars().skip(n - 24).collect();
    format!("{head}…{tail} ({} bytes)", text.len())
}

/// Three numbers as messages print them: `(x, y, z)` with [`fmt_num`].
pub fn fmt_vec3(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", fmt_num(v[0]), fmt_num(v[1]), fmt_num(v[2]))
}

/// A numeric Cholesky failure in words.
pub(crate) fn describe_pivot(e: &faer::linalg::cholesky::llt::factor::LltError) -> String {
    match e {
        faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => format!(
            "the system is not positive definite (pivot {index} of the factorization is not > 0)"
        ),
    }
}

/// A faer allocation or indexing failure in words.
pub(crate) fn describe_faer(e: &faer::sparse::FaerError) -> String {
    match e {
        faer::sparse::FaerError::IndexOverflow => "the system is too large to index".into(),
        faer::sparse::FaerError::OutOfMemory => "out of memory".into(),
        _ => "the sparse solver failed".into(),
    }
}

/// A faer sparse-matrix assembly failure in words.
pub(crate) fn describe_creation(e: &faer::sparse::CreationError) -> String {
    match e {
        faer::sparse::CreationError::Generic(g) => describe_faer(g),
        faer::sparse::CreationError::OutOfBounds { row, col } => {
            format!("entry ({row}, {col}) lies outside the matrix")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn item15_solver_failures_are_described_in_words() {
        use faer::linalg::cholesky::llt::factor::LltError as Numeric;
        let e = describe_pivot(&Numeric::NonPositivePivot { index: 1 });
        assert_eq!(
            e,
            "the system is not positive definite (pivot 1 of the factorization is not > 0)"
        );
        let e = describe_faer(&faer::sparse::FaerError::OutOfMemory);
        assert_eq!(e, "out of memory");
        let e = describe_creation(&faer::sparse::CreationError::OutOfBounds { row: 3, col: 9 });
        assert_eq!(e, "entry (3, 9) lies outside the matrix");
    }

    #[test]
    fn item15_numbers_are_short_and_exact() {
        assert_eq!(fmt_num(1e-300), "1e-300");
        assert_eq!(fmt_num(1e300), "1e300");
        assert_eq!(fmt_num(0.5), "0.5");
        assert_eq!(fmt_num(-3.0), "-3");
        assert_eq!(fmt_num(f64::INFINITY), "inf");
        // Exact: the text reads back as the same number.
        for x in [0.1 + 0.2, 179.9999, 1.0 / 3.0, 6.02e23] {
            assert_eq!(fmt_num(x).parse::<f64>().unwrap(), x);
        }
        assert_eq!(fmt_vec3(&[1e-200, 0.0, -2.5]), "(1e-200, 0, -2.5)");
    }
}
