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
    /// The path is not a regular file (a folder, a FIFO, a device...), so it is not read.
    #[error("{} is {kind}, not a scene file", path.display())]
    NotRegular {
        /// The path.
        path: PathBuf,
        /// What it is, in words (`a FIFO (named pipe)`).
        kind: &'static str,
    },
    /// The file is larger than any scene file needs to be.
    #[error("{} is {size} bytes; scene files are read up to 64 MiB ({limit} bytes)", path.display())]
    TooLarge {
        /// The path.
        path: PathBuf,
        /// Its size in bytes.
        size: u64,
        /// The cap, [`crate::MAX_SCENE_BYTES`].
        limit: u64,
    },
    /// The file is not UTF-8 text.
    #[error("{}: {reason}", path.display())]
    NotText {
        /// The path.
        path: PathBuf,
        /// What the bytes are instead.
        reason: String,
    },
    /// Neither a file nor a bundled scene has this name.
    #[error(
        "no bundled scene named {name:?} and no file {name}; bundled scenes: {available} \
         (a path with a folder, such as ./{name}, or ending in .json is always read as a file)"
    )]
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
