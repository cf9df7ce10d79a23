//! asciinema recordings (the v2 `.cast` format): a header line, then one event per frame.
//!
//! ```text
//! {"version": 2, "width": 80, "height": 40}
//! [0.011111111111111112, "o", "\u001b[H\u001b[2J...frame..."]
//! ```
//!
//! Each event's data is what a terminal is sent to show the frame: the cursor home, the frame's
//! lines separated by `\r\n` (a recording holds what the terminal receives, where a line feed
//! alone would not return the cursor), and its colour escapes. `asciinema play FILE` replays it
//! in any terminal of at least the header's size.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use super::write_error;
use crate::output::StreamFile;

/// The header line of a recording `width` x `height` cells, newline included.
pub fn header(width: usize, height: usize, title: &str) -> String {
    #[derive(Serialize)]
    struct Header<'a> {
        version: u8,
        width: usize,
        height: usize,
        title: &'a str,
        env: Env,
    }
    #[derive(Serialize)]
    struct Env {
        #[serde(rename = "TERM")]
        term: &'static str,
    }
    let mut line = serde_json::to_string(&Header {
        version: 2,
        width,
        height,
        title,
        env: Env {
            term: "xterm-256color",
        },
    })
    .unwrap_or_default();
    line.push('\n');
    line
}

/// The event line showing `text` (lines separated by `\n`) at `time` seconds: the screen
/// cleared on the first frame, the cursor home, the lines joined by `\r\n`.
pub fn cast_frame(time: f64, text: &str, first: bool) -> String {
    let mut data = String::with_capacity(text.len() + text.len() / 40 + 16);
    if first {
        data.push_str("\x1b[2J");
    }
    data.push_str("\x1b[H");
    for (i, line) in text.trim_end_matches('\n').split('\n').enumerate() {
        if i > 0 {
            data.push_str("\r\n");
        }
        data.push_str(line);
    }
    let mut line = serde_json::to_string(&(time, "o", data)).unwrap_or_default();
    line.push('\n');
    line
}

/// A recording being written to its file, put in place by [`Cast::finish`].
#[derive(Debug)]
pub struct Cast {
    file: StreamFile,
    events: u64,
}

impl Cast {
    /// Starts a recording `width` x `height` cells at `path`, titled `title`.
    ///
    /// # Errors
    /// A name not ending in `.cast`, or a file that cannot be created, naming it.
    pub fn create(path: &Path, width: usize, height: usize, title: &str) -> anyhow::Result<Self> {
        if !path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("cast"))
        {
            anyhow::bail!("{}: a recording's name must end in .cast", path.display());
        }
        let mut file = StreamFile::create(path)?;
        file.write_all(header(width, height, title).as_bytes())
            .map_err(|e| write_error(path, e))?;
        Ok(Self { file, events: 0 })
    }

    /// The recording's path.
    pub fn path(&self) -> &Path {
        self.file.path()
    }

    /// Adds `text` shown at `time` seconds.
    ///
    /// # Errors
    /// A failed write, naming the file.
    pub fn push(&mut self, time: f64, text: &str) -> anyhow::Result<()> {
        let line = cast_frame(time, text, self.events == 0);
        self.events += 1;
        self.file
            .write_all(line.as_bytes())
            .map_err(|e| write_error(self.file.path(), e))
    }

    /// Ends the recording and puts it in place.
    ///
    /// # Errors
    /// A failed write or rename, naming the file.
    pub fn finish(self) -> anyhow::Result<()> {
        self.file.finish().map(drop)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_is_a_v2_header_then_output_events_in_time_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.cast");
        let mut cast = Cast::create(&path, 4, 2, "test").unwrap();
        cast.push(0.0, "ab\ncd\n").unwrap();
        cast.push(0.5, "\x1b[31mxy\x1b[0m\nzw\n").unwrap();
        cast.finish().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines();
        let head: serde_json::Value = serde_json::from_str(lines.next().unwrap()).unwrap();
        assert_eq!(head["version"], 2);
        assert_eq!(
            (head["width"].as_u64(), head["height"].as_u64()),
            (Some(4), Some(2))
        );
        let events: Vec<(f64, String, String)> =
            lines.map(|l| serde_json::from_str(l).unwrap()).collect();
        assert_eq!(events.len(), 2);
        assert_eq!(
            events[0],
            (0.0, "o".to_owned(), "\x1b[2J\x1b[Hab\r\ncd".to_owned())
        );
        assert_eq!(events[1].0, 0.5);
        assert_eq!(events[1].2, "\x1b[H\x1b[31mxy\x1b[0m\r\nzw");
    }

    #[test]
    fn a_recording_must_be_named_cast() {
        let e = Cast::create(Path::new("run.txt"), 1, 1, "")
            .unwrap_err()
            .to_string();
        assert!(e.contains("must end in .cast"), "{e}");
    }
}
