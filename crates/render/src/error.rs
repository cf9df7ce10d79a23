//! The one error type of the renderer.

use crate::frame::{MAX_HEIGHT, MAX_WIDTH, MIN_HEIGHT, MIN_WIDTH};

/// Why a frame cannot be rendered, or an option cannot be parsed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A frame size with a zero dimension.
    #[error(
        "frame size {width}x{height} has a zero dimension; it must be at least {MIN_WIDTH}x{MIN_HEIGHT}"
    )]
    ZeroSize {
        /// Columns asked for.
        width: usize,
        /// Rows asked for.
        height: usize,
    },
    /// A frame too small to draw anything recognisable in.
    #[error(
        "frame size {width}x{height} is too small to draw in; it must be at least {MIN_WIDTH}x{MIN_HEIGHT}"
    )]
    TooSmall {
        /// Columns asked for.
        width: usize,
        /// Rows asked for.
        height: usize,
    },
    /// A frame larger than any terminal (and than memory would like).
    #[error(
        "frame size {width}x{height} is too large; it must be at most {MAX_WIDTH}x{MAX_HEIGHT}"
    )]
    TooLarge {
        /// Columns asked for.
        width: usize,
        /// Rows asked for.
        height: usize,
    },
    /// A frame size with a number too large to hold, as typed.
    #[error("frame size {value} is too large; it must be at most {MAX_WIDTH}x{MAX_HEIGHT}")]
    TooLargeAsTyped {
        /// The size as typed.
        value: String,
    },
    /// The state does not belong to the mesh.
    #[error("the cloth state has {positions} positions but the mesh has {points} points")]
    StateMismatch {
        /// Length of `state.positions`.
        positions: usize,
        /// `mesh.len()`.
        points: usize,
    },
    /// A point whose position is NaN or infinite: there is nothing sensible to frame.
    #[error("point {index} has a non-finite position, so the cloth cannot be drawn")]
    NonFinite {
        /// Index of the first bad point.
        index: usize,
    },
    /// A rendering or camera option out of its range.
    #[error("{name} is {value}, but it must be {allowed}")]
    BadOption {
        /// The option's name.
        name: &'static str,
        /// The bad value, as text.
        value: String,
        /// What is allowed.
        allowed: &'static str,
    },
    /// A name (view, mode, colour choice, size) that is not one of the known ones.
    #[error("unknown {what} '{value}'; expected {allowed}")]
    Unknown {
        /// What was being parsed (`view`, `mode`, ...).
        what: &'static str,
        /// The text given.
        value: String,
        /// The accepted spellings.
        allowed: &'static str,
    },
}
