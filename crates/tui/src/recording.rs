//! The UI recording its own screen as an asciinema v2 `.cast` file.
//!
//! After each draw the loop hands the screen's cells to [`Recording::frame`], which writes
//! what changed since the last event: the first event clears the screen and draws it whole,
//! each later one moves the cursor to the cells that changed and writes them with their
//! colours and attributes ([`crate::screen::Painter`], as the terminal itself is sent); a draw
//! that changed nothing writes no event. Event times are wall-clock seconds since the first
//! drawn frame, so `asciinema play` replays the screen at the speed it was seen.

use std::path::{Path, PathBuf};
use std::time::Instant;

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;

use cloth_run::export::Cast;

use crate::screen::Painter;

/// A recording in progress.
#[derive(Debug)]
pub struct Recording {
    cast: Cast,
    start: Option<Instant>,
    /// What the recording shows so far.
    painter: Painter,
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
            painter: Painter::new(Rect::new(0, 0, width, height), false),
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        self.cast.path()
    }

    /// Adds the screen `buffer` drawn at `now`: the cells that changed since the last event.
    ///
    /// # Errors
    /// A failed write, naming the file.
    pub fn frame(&mut self, buffer: &Buffer, now: Instant) -> anyhow::Result<()> {
        let start = *self.start.get_or_insert(now);
        let time = now.saturating_duration_since(start).as_secs_f64();
        let mut data = Vec::new();
        let painted = self.painter.paint(buffer, None, &[], &mut data);
        if painted.bytes == 0 {
            return Ok(());
        }
        // NOTE: the cast's events are text; the painter writes whole UTF-8 characters.
        self.cast.push(time, &String::from_utf8_lossy(&data))
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

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::style::{Color, Style};

    /// The screen a recording's events leave, replayed by a small terminal model.
    fn replay(text: &str, width: u16, height: u16) -> Vec<String> {
        crate::screen::tests::Model::replay(text.as_bytes(), width, height).rows()
    }

    #[test]
    fn events_hold_what_changed_and_replay_to_the_screen_drawn() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.cast");
        let mut rec = Recording::start(&path, 20, 3, "t").unwrap();
        let t0 = Instant::now();
        let mut b = Buffer::empty(Rect::new(0, 0, 20, 3));
        b.set_string(0, 0, "RUNNING t 0.000", Style::default().fg(Color::Red));
        b.set_string(0, 2, "cloth ####", Style::default().bg(Color::Indexed(17)));
        rec.frame(&b, t0).unwrap();
        b.set_string(0, 0, "PAUSED ", Style::default().fg(Color::Yellow));
        rec.frame(&b, t0 + std::time::Duration::from_millis(40))
            .unwrap();
        // Nothing changed: no event.
        rec.frame(&b, t0 + std::time::Duration::from_millis(80))
            .unwrap();
        let path = rec.finish().unwrap();
        let text = std::fs::read_to_string(path).unwrap();
        let events: Vec<(f64, String, String)> = text
            .lines()
            .skip(1)
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(events.len(), 2, "{text}");
        let second = &events[1].2;
        // The second event holds the changed cells, not the whole screen.
        assert!(!second.contains("cloth"), "{second:?}");
        assert!(second.len() < 40, "{second:?}");
        let all: String = events.iter().map(|e| e.2.as_str()).collect();
        assert_eq!(
            replay(&all, 20, 3),
            vec![
                "PAUSED  t 0.000     ".to_owned(),
                " ".repeat(20),
                "cloth ####          ".to_owned(),
            ]
        );
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
