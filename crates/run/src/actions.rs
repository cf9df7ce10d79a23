//! Timed touches of the cloth read from a file (`--actions FILE`), so an interaction can be
//! replayed headless, exported and snapshot-tested.
//!
//! One JSON object per line; blank lines and lines starting with `#` are skipped:
//!
//! ```text
//! {"frame": 10, "action": "grab", "point": 1275, "to": [0.5, 0.2, 0.5]}
//! {"frame": 20, "action": "drag", "to": [0.6, 0.2, 0.5]}
//! {"frame": 40, "action": "release"}
//! {"frame": 60, "action": "poke", "point": 1275, "velocity": [0, 0, 2]}
//! ```
//!
//! An action at frame `k` is applied once `k` frames have been stepped, before the next one
//! (frame 0: before the first); actions of one frame in the order they are written. Positions
//! are in metres, velocities in m/s, points by index (`row * num_width_points + column`).

use std::path::Path;

use anyhow::Context as _;
use cloth_mesh::Vec3;
use serde::Deserialize;

use crate::{Command, Run, Touch};

/// The largest actions file read, bytes: far more than any hand can do in a run.
pub const MAX_BYTES: u64 = 16 * 1024 * 1024;

/// One line of an actions file.
#[derive(Debug, Deserialize)]
#[serde(tag = "action", rename_all = "lowercase", deny_unknown_fields)]
enum Line {
    Grab {
        frame: u64,
        point: usize,
        to: [f64; 3],
    },
    Drag {
        frame: u64,
        to: [f64; 3],
    },
    Release {
        frame: u64,
    },
    Poke {
        frame: u64,
        point: usize,
        velocity: [f64; 3],
    },
}

/// The touches of a file, by frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Actions {
    /// `(frame, line number, touch)`, in the file's order.
    items: Vec<(u64, usize, Touch)>,
    /// Where they came from, for messages.
    origin: String,
}

impl Actions {
    /// Reads the actions of `path` for a cloth of `points` points.
    ///
    /// # Errors
    /// A file that is not a regular file, is over [`MAX_BYTES`], is not UTF-8, or has a line
    /// that is not an action (naming the line, and what is allowed), a point the cloth does
    /// not have, or a number that is not finite.
    pub fn read(path: &Path, points: usize) -> anyhow::Result<Self> {
        let origin = path.display().to_string();
        let meta = std::fs::metadata(path).with_context(|| format!("{origin}: cannot read"))?;
        anyhow::ensure!(
            meta.is_file(),
            "{origin}: not a regular file; --actions reads a file of JSON lines"
        );
        anyhow::ensure!(
            meta.len() <= MAX_BYTES,
            "{origin}: {} bytes, over the {} MiB an actions file may have",
            meta.len(),
            MAX_BYTES / 1024 / 1024
        );
        let bytes = std::fs::read(path).with_context(|| format!("{origin}: cannot read"))?;
        let text = String::from_utf8(bytes).map_err(|_| {
            anyhow::anyhow!("{origin}: not UTF-8 text; write one JSON object per line")
        })?;
        Self::parse(&text, &origin, points)
    }

    /// The actions of `text` (see the module's documentation), named `origin` in messages.
    ///
    /// # Errors
    /// As [`Self::read`].
    pub fn parse(text: &str, origin: &str, points: usize) -> anyhow::Result<Self> {
        let mut items = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let n = i + 1;
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let parsed: Line = serde_json::from_str(line).map_err(|e| {
                anyhow::anyhow!(
                    "{origin}:{n}: {e}; an action is an object with \"frame\" and \"action\" \
                     (grab with point and to, drag with to, release, poke with point and \
                     velocity)"
                )
            })?;
            let vec = |what: &str, v: [f64; 3]| {
                let v = Vec3::from(v);
                anyhow::ensure!(
                    v.iter().all(|c| c.is_finite()),
                    "{origin}:{n}: {what} must be three finite numbers"
                );
                Ok(v)
            };
            let point_ok = |point: usize| {
                anyhow::ensure!(
                    point < points,
                    "{origin}:{n}: point {point} is not on the cloth: its points are 0 to {}",
                    points.saturating_sub(1)
                );
                Ok(point)
            };
            let (frame, touch) = match parsed {
                Line::Grab { frame, point, to } => (
                    frame,
                    Touch::Grab {
                        point: point_ok(point)?,
                        to: vec("to", to)?,
                    },
                ),
                Line::Drag { frame, to } => (frame, Touch::Drag { to: vec("to", to)? }),
                Line::Release { frame } => (frame, Touch::Release),
                Line::Poke {
                    frame,
                    point,
                    velocity,
                } => (
                    frame,
                    Touch::Poke {
                        point: point_ok(point)?,
                        velocity: vec("velocity", velocity)?,
                    },
                ),
            };
            items.push((frame, n, touch));
        }
        // NOTE: stable, so the actions of one frame keep the file's order.
        items.sort_by_key(|(frame, _, _)| *frame);
        Ok(Self {
            items,
            origin: origin.to_owned(),
        })
    }

    /// Applies to `run` every action due once `run.frames` frames have been stepped (those
    /// of earlier frames too, when the run starts later, as from a state): call it before each
    /// frame.
    ///
    /// # Errors
    /// An action the run refuses (a drag with no point held), naming its line.
    pub fn apply_due(&mut self, run: &mut Run) -> anyhow::Result<()> {
        let due = self
            .items
            .iter()
            .take_while(|(frame, _, _)| *frame <= run.frames)
            .count();
        for (_, n, touch) in self.items.drain(..due) {
            run.apply(Command::Touch(touch))
                .map_err(|e| anyhow::anyhow!("{}:{n}: {e}", self.origin))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_reads_by_frame_and_bad_lines_are_named() {
        let a = Actions::parse(
            "# a comment\n\n{\"frame\": 5, \"action\": \"release\"}\n\
             {\"frame\": 2, \"action\": \"grab\", \"point\": 3, \"to\": [0, 1, 0]}\n",
            "hand.jsonl",
            10,
        )
        .unwrap();
        assert_eq!(a.items[0].0, 2, "sorted by frame");
        assert_eq!(a.items[1].2, Touch::Release);
        let e = Actions::parse("{\"frame\": 1, \"action\": \"cut\"}", "h", 10).unwrap_err();
        assert!(
            e.to_string().starts_with("h:1: unknown variant `cut`"),
            "{e}"
        );
        let e = Actions::parse(
            "\n{\"frame\": 1, \"action\": \"poke\", \"point\": 10, \"velocity\": [0,0,1]}",
            "h",
            10,
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("h:2: point 10 is not on the cloth: its points are 0 to 9"),
            "{e}"
        );
        let e = Actions::parse("{\"frame\": 1, \"action\": \"release\", \"x\": 1}", "h", 10)
            .unwrap_err();
        assert!(e.to_string().contains("unknown field `x`"), "{e}");
    }
}
