//! The UI recording its own screen as an asciinema v2 `.cast` file.
//!
//! After each draw the loop hands the screen's cells to [`Recording::frame`], which writes
//! them as one event: the cursor home, each row's characters with their colours and
//! attributes as SGR escapes, rows separated by `\r\n`. Event times are wall-clock seconds
//! since the first drawn frame, so `asciinema play` replays the screen at the speed it was
//! seen.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use ratatui::buffer::{Buffer, CellDiffOption};
use ratatui::style::{Color, Modifier};

use cloth_run::export::Cast;

/// A recording in progress.
#[derive(Debug)]
pub struct Recording {
    cast: Cast,
    start: Option<Instant>,
}

impl Recording {
    /// Starts a recording of a `width` x `height` screen at `path`.
    ///
    /// # Errors
    /// A file that cannot be created, naming it.
    pub fn start(path: &Path, width: u16, height: u16, title: &str) -> anyhow::Result<Self> {
        Ok(Self {
            cast: Cast::create(path, usize::from(width), usize::from(height), title)?,
            start: None,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        self.cast.path()
    }

    /// Adds the screen `buffer` drawn at `now`.
    ///
    /// # Errors
    /// A failed write, naming the file.
    pub fn frame(&mut self, buffer: &Buffer, now: Instant) -> anyhow::Result<()> {
        let start = *self.start.get_or_insert(now);
        let time = now.saturating_duration_since(start).as_secs_f64();
        self.cast.push(time, &screen_text(buffer))
    }

    /// Ends the recording and puts the file in place; returns its path.
    ///
    /// # Errors
    /// A failed write or rename, naming the file.
    pub fn finish(self) -> anyhow::Result<PathBuf> {
        let path = self.cast.path().to_owned();
        self.cast.finish()?;
        Ok(path)
    }
}

/// The first name of `stem.cast`, `stem-2.cast`, ... in `dir` that no file has.
pub fn free_name(dir: &Path, stem: &str, ext: &str) -> PathBuf {
    let mut n = 1u32;
    loop {
        let name = if n == 1 {
            format!("{stem}.{ext}")
        } else {
            format!("{stem}-{n}.{ext}")
        };
        let path = dir.join(name);
        if !path.exists() && std::fs::symlink_metadata(&path).is_err() {
            return path;
        }
        n += 1;
    }
}

/// The screen as text with SGR escapes: rows separated by `\n`, each row's style changes as
/// escapes, everything reset at the end of each row.
pub fn screen_text(buffer: &Buffer) -> String {
    let area = buffer.area;
    let mut out = String::with_capacity(usize::from(area.width) * usize::from(area.height) * 2);
    for y in area.top()..area.bottom() {
        if y > area.top() {
            out.push('\n');
        }
        let mut current: Option<(Color, Color, Modifier)> = None;
        for x in area.left()..area.right() {
            let Some(cell) = buffer.cell((x, y)) else {
                continue;
            };
            if cell.diff_option == CellDiffOption::Skip {
                continue;
            }
            let style = (cell.fg, cell.bg, cell.modifier);
            if current != Some(style) {
                out.push_str("\x1b[0");
                push_color(&mut out, cell.fg, false);
                push_color(&mut out, cell.bg, true);
                for (m, code) in [
                    (Modifier::BOLD, "1"),
                    (Modifier::DIM, "2"),
                    (Modifier::ITALIC, "3"),
                    (Modifier::UNDERLINED, "4"),
                    (Modifier::REVERSED, "7"),
                ] {
                    if cell.modifier.contains(m) {
                        out.push(';');
                        out.push_str(code);
                    }
                }
                out.push('m');
                current = Some(style);
            }
            out.push_str(cell.symbol());
        }
        out.push_str("\x1b[0m");
    }
    out
}

/// `;N...` for `color` as a foreground (or background) SGR parameter; nothing for the
/// terminal's default.
fn push_color(out: &mut String, color: Color, background: bool) {
    let base = if background { 40 } else { 30 };
    let named = |i: u8| {
        if i < 8 {
            base + u32::from(i)
        } else {
            base + 60 + u32::from(i - 8)
        }
    };
    let _ = match color {
        Color::Reset => Ok(()),
        Color::Black => write!(out, ";{}", named(0)),
        Color::Red => write!(out, ";{}", named(1)),
        Color::Green => write!(out, ";{}", named(2)),
        Color::Yellow => write!(out, ";{}", named(3)),
        Color::Blue => write!(out, ";{}", named(4)),
        Color::Magenta => write!(out, ";{}", named(5)),
        Color::Cyan => write!(out, ";{}", named(6)),
        Color::Gray => write!(out, ";{}", named(7)),
        Color::DarkGray => write!(out, ";{}", named(8)),
        Color::LightRed => write!(out, ";{}", named(9)),
        Color::LightGreen => write!(out, ";{}", named(10)),
        Color::LightYellow => write!(out, ";{}", named(11)),
        Color::LightBlue => write!(out, ";{}", named(12)),
        Color::LightMagenta => write!(out, ";{}", named(13)),
        Color::LightCyan => write!(out, ";{}", named(14)),
        Color::White => write!(out, ";{}", named(15)),
        Color::Indexed(i) => write!(out, ";{};5;{i}", base + 8),
        Color::Rgb(r, g, b) => write!(out, ";{};2;{r};{g};{b}", base + 8),
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::layout::Rect;
    use ratatui::style::Style;

    #[test]
    fn the_screen_becomes_rows_of_text_with_style_changes_as_escapes() {
        let mut b = Buffer::empty(Rect::new(0, 0, 3, 2));
        b.set_string(0, 0, "ab", Style::default().fg(Color::Red));
        b.set_string(0, 1, "xyz", Style::default().bg(Color::Indexed(17)));
        let text = screen_text(&b);
        assert_eq!(
            text,
            "\x1b[0;31mab\x1b[0m \x1b[0m\n\x1b[0;48;5;17mxyz\x1b[0m"
        );
        let plain: String = {
            let mut s = String::new();
            let mut in_escape = false;
            for c in text.chars() {
                match (in_escape, c) {
                    (false, '\x1b') => in_escape = true,
                    (true, 'm') => in_escape = false,
                    (false, c) => s.push(c),
                    _ => {}
                }
            }
            s
        };
        assert_eq!(plain, "ab \nxyz");
    }

    #[test]
    fn a_free_name_skips_the_files_there() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(
            free_name(dir.path(), "pinned4", "cast"),
            dir.path().join("pinned4.cast")
        );
        std::fs::write(dir.path().join("pinned4.cast"), "").unwrap();
        assert_eq!(
            free_name(dir.path(), "pinned4", "cast"),
            dir.path().join("pinned4-2.cast")
        );
    }
}
