//! The rendered picture: a grid of glyphs with optional colours, and its text writers.

use std::fmt::{self, Write};
use std::str::FromStr;

use crate::{ColorDepth, RenderError};

/// Fewest columns a frame may have: below this a cloth is a smudge.
pub const MIN_WIDTH: usize = 8;
/// Fewest rows a frame may have.
pub const MIN_HEIGHT: usize = 4;
/// Most columns a frame may have (no terminal is wider; braille mode holds 4 pixels per column
/// in each of its buffers, so this also caps memory).
pub const MAX_WIDTH: usize = 1000;
/// Most rows a frame may have.
pub const MAX_HEIGHT: usize = 500;

/// A 24-bit colour; writers quantise it to what the terminal supports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rgb(pub u8, pub u8, pub u8);

/// One character cell: a glyph that carries the picture, and colours that only decorate it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cell {
    /// The character shown (always one column wide).
    pub glyph: char,
    /// Foreground colour, or the terminal's default.
    pub fg: Option<Rgb>,
    /// Background colour, or the terminal's default.
    pub bg: Option<Rgb>,
}

impl Cell {
    /// An empty cell: a space in the default colours.
    pub const BLANK: Cell = Cell {
        glyph: ' ',
        fg: None,
        bg: None,
    };
}

impl Default for Cell {
    fn default() -> Self {
        Self::BLANK
    }
}

/// A validated frame size in character cells, parsed from `WxH` (e.g. `80x40`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FrameSize {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl FrameSize {
    /// Checks that `width` x `height` is drawable: at least [`MIN_WIDTH`] x [`MIN_HEIGHT`],
    /// at most [`MAX_WIDTH`] x [`MAX_HEIGHT`].
    ///
    /// # Errors
    /// [`RenderError::ZeroSize`], [`RenderError::TooSmall`] or [`RenderError::TooLarge`].
    pub fn new(width: usize, height: usize) -> Result<Self, RenderError> {
        if width == 0 || height == 0 {
            Err(RenderError::ZeroSize { width, height })
        } else if width < MIN_WIDTH || height < MIN_HEIGHT {
            Err(RenderError::TooSmall { width, height })
        } else if width > MAX_WIDTH || height > MAX_HEIGHT {
            Err(RenderError::TooLarge { width, height })
        } else {
            Ok(Self { width, height })
        }
    }
}

impl FromStr for FrameSize {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || RenderError::Unknown {
            what: "frame size",
            value: s.to_owned(),
            allowed: "WIDTHxHEIGHT in character cells, e.g. 80x40",
        };
        let (w, h) = s.trim().split_once(['x', 'X']).ok_or_else(unknown)?;
        // Huge digit strings overflow usize; they are "too large" (as typed), not "unknown".
        let parse = |t: &str| -> Result<usize, RenderError> {
            let t = t.trim();
            if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit()) {
                return Err(unknown());
            }
            t.parse::<usize>()
                .map_err(|_| RenderError::TooLargeAsTyped {
                    value: s.trim().to_owned(),
                })
        };
        Self::new(parse(w)?, parse(h)?)
    }
}

impl fmt::Display for FrameSize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// A rendered picture: `height` rows of `width` [`Cell`]s.
///
/// Produced by [`crate::Renderer::render`] and shared by the TUI, the headless `render` command
/// and the snapshot tests. Every glyph is one terminal column wide, so the plain text of a frame
/// is exactly `height` lines of `width` columns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AsciiFrame {
    width: usize,
    height: usize,
    cells: Vec<Cell>,
}

impl AsciiFrame {
    /// A blank frame of a validated size.
    #[must_use]
    pub fn new(size: FrameSize) -> Self {
        Self {
            width: size.width,
            height: size.height,
            cells: vec![Cell::BLANK; size.width * size.height],
        }
    }

    /// A blank frame of `width` x `height` cells.
    ///
    /// # Errors
    /// As [`FrameSize::new`].
    pub fn with_size(width: usize, height: usize) -> Result<Self, RenderError> {
        FrameSize::new(width, height).map(Self::new)
    }

    /// Changes the size (keeping the allocation when it shrinks) and blanks every cell.
    pub fn resize(&mut self, size: FrameSize) {
        self.width = size.width;
        self.height = size.height;
        self.cells.clear();
        self.cells.resize(size.width * size.height, Cell::BLANK);
    }

    /// The frame's size.
    #[must_use]
    pub fn size(&self) -> FrameSize {
        FrameSize {
            width: self.width,
            height: self.height,
        }
    }

    /// Columns.
    #[must_use]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    #[must_use]
    pub fn height(&self) -> usize {
        self.height
    }

    /// Sets every cell blank.
    pub fn clear(&mut self) {
        self.cells.fill(Cell::BLANK);
    }

    /// The cell at column `x`, row `y` (row 0 at the top), or `None` outside the frame.
    #[must_use]
    pub fn get(&self, x: usize, y: usize) -> Option<&Cell> {
        (x < self.width && y < self.height).then(|| &self.cells[y * self.width + x])
    }

    /// The cell at column `x`, row `y`, mutably, or `None` outside the frame.
    pub fn get_mut(&mut self, x: usize, y: usize) -> Option<&mut Cell> {
        (x < self.width && y < self.height).then(|| &mut self.cells[y * self.width + x])
    }

    /// Row `y`, left to right.
    ///
    /// # Panics
    /// When `y >= height`.
    #[must_use]
    pub fn row(&self, y: usize) -> &[Cell] {
        &self.cells[y * self.width..(y + 1) * self.width]
    }

    /// All cells, row-major from the top-left.
    #[must_use]
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// Writes `text` into row `y` from column `x`, clipped to the frame, with colour `fg`.
    pub fn put_str(&mut self, x: usize, y: usize, text: &str, fg: Option<Rgb>) {
        for (i, glyph) in text.chars().enumerate() {
            if let Some(cell) = self.get_mut(x + i, y) {
                *cell = Cell {
                    glyph,
                    fg,
                    bg: None,
                };
            }
        }
    }

    /// Writes the glyphs only: exactly `height` lines of `width` characters, each ending in
    /// `\n`. No escape sequences.
    ///
    /// # Errors
    /// Only those of `out`.
    pub fn write_plain(&self, out: &mut impl Write) -> fmt::Result {
        for y in 0..self.height {
            for c in self.row(y) {
                out.write_char(c.glyph)?;
            }
            out.write_char('\n')?;
        }
        Ok(())
    }

    /// The glyphs as text (see [`AsciiFrame::write_plain`]).
    #[must_use]
    pub fn to_plain(&self) -> String {
        let mut s = String::with_capacity((self.width + 1) * self.height);
        // Writing to a String cannot fail.
        let _ = self.write_plain(&mut s);
        s
    }

    /// Writes the frame with SGR colour escapes for `depth`, emitting an escape only where the
    /// colour changes and resetting at the end of every line (so a pager or a cut line never
    /// bleeds colour). With [`ColorDepth::None`] this is [`AsciiFrame::write_plain`].
    ///
    /// # Errors
    /// Only those of `out`.
    pub fn write_ansi(&self, out: &mut impl Write, depth: ColorDepth) -> fmt::Result {
        if depth == ColorDepth::None {
            return self.write_plain(out);
        }
        for y in 0..self.height {
            let (mut fg, mut bg) = (None, None);
            for c in self.row(y) {
                let (want_fg, want_bg) = (
                    c.fg.map(|rgb| depth.quantise(rgb)),
                    c.bg.map(|rgb| depth.quantise(rgb)),
                );
                if want_fg != fg {
                    match want_fg {
                        Some(code) => code.write_sgr(out, false)?,
                        None => out.write_str("\x1b[39m")?,
                    }
                    fg = want_fg;
                }
                if want_bg != bg {
                    match want_bg {
                        Some(code) => code.write_sgr(out, true)?,
                        None => out.write_str("\x1b[49m")?,
                    }
                    bg = want_bg;
                }
                out.write_char(c.glyph)?;
            }
            if fg.is_some() || bg.is_some() {
                out.write_str("\x1b[0m")?;
            }
            out.write_char('\n')?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_outside_the_drawable_range_are_named_errors() {
        assert_eq!(
            FrameSize::new(0, 40),
            Err(RenderError::ZeroSize {
                width: 0,
                height: 40
            })
        );
        assert!(matches!(
            FrameSize::new(3, 40),
            Err(RenderError::TooSmall { .. })
        ));
        assert!(matches!(
            FrameSize::new(80, 100_000),
            Err(RenderError::TooLarge { .. })
        ));
        assert_eq!(
            "80x40".parse::<FrameSize>(),
            Ok(FrameSize {
                width: 80,
                height: 40
            })
        );
        // A number too large to hold is reported as typed, not as the largest integer.
        assert_eq!(
            "99999999999999999999999x4"
                .parse::<FrameSize>()
                .unwrap_err()
                .to_string(),
            format!(
                "frame size 99999999999999999999999x4 is too large; it must be at most \
                 {MAX_WIDTH}x{MAX_HEIGHT}"
            )
        );
        let e = "80by40".parse::<FrameSize>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown frame size '80by40'; expected WIDTHxHEIGHT in character cells, e.g. 80x40"
        );
        assert!("-3x4".parse::<FrameSize>().is_err());
    }

    #[test]
    fn plain_text_is_exactly_height_lines_of_width_columns() {
        let mut f = AsciiFrame::with_size(9, 5).unwrap();
        f.put_str(7, 2, "abcdef", None);
        let text = f.to_plain();
        let lines: Vec<&str> = text.split_terminator('\n').collect();
        assert_eq!(lines.len(), 5);
        assert!(lines.iter().all(|l| l.chars().count() == 9));
        assert_eq!(lines[2], "       ab");
    }

    #[test]
    fn ansi_output_emits_colour_only_where_it_changes() {
        let mut f = AsciiFrame::with_size(8, 4).unwrap();
        let red = Some(Rgb(255, 0, 0));
        f.put_str(0, 0, "aaa", red);
        f.put_str(3, 0, "b", None);
        let mut s = String::new();
        f.write_ansi(&mut s, ColorDepth::TrueColor).unwrap();
        let first = s.lines().next().unwrap();
        assert_eq!(first, "\x1b[38;2;255;0;0maaa\x1b[39mb    ");
        // Rows without colour carry no escapes at all.
        assert_eq!(s.lines().nth(1).unwrap(), "        ");
        let mut plain = String::new();
        f.write_ansi(&mut plain, ColorDepth::None).unwrap();
        assert_eq!(plain, f.to_plain());
    }
}
