//! Scene errors: each names the file, the key, the value and what is allowed.

use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{}: cannot read the scene file", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Neither a file nor a bundled scene has this name.
    #[error("no scene file or bundled scene named {name:?}; bundled scenes: {available}")]
    UnknownScene {
        /// What was asked for.
        name: String,
        /// The bundled names, comma-separated.
        available: String,
    },
    /// The text is not JSON.
    #[error("{origin}: invalid JSON at line {line}, column {column}: {message}")]
    Syntax {
        /// File or scene name.
        origin: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// A key is missing, unknown or of the wrong type.
    #[error("{origin}: {key}: {message}{}", location.map(|(l, c)| format!(" (line {l}, column {c})")).unwrap_or_default())]
    Field {
        /// File or scene name.
        origin: String,
        /// Dotted path of the key (`cloth.ks`), or `.` for the top level.
        key: String,
        /// What is wrong and what is expected.
        message: String,
        /// Line and column, when known (not after `--set` edits).
        location: Option<(usize, usize)>,
    },
    /// A value has the right type but is out of range.
    #[error("{origin}: {key} is {value}, but it must be {allowed}")]
    Invalid {
        /// File or scene name.
        origin: String,
        /// Dotted path of the key.
        key: String,
        /// The bad value, as written.
        value: String,
        /// What is allowed.
        allowed: String,
    },
    /// A `--set KEY=VALUE` override cannot be applied.
    #[error("--set {arg}: {reason}")]
    BadSet {
        /// The argument as given.
        arg: String,
        /// Why it cannot be applied.
        reason: String,
    },
}
