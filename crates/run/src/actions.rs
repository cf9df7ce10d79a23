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
//! {"frame": 70, "action": "pin", "point": 1275}
//! {"frame": 80, "action": "unpin", "point": 1275}
//! {"frame": 90, "action": "cut", "from": [0.5, 2, -1], "to": [0.5, 2, 2], "along": [0, -1, 0]}
//! ```
//!
//! An action at frame `k` is applied once `k` frames have been stepped, before the next one
//! (frame 0: before the first); with `"step": s` it is applied after `s` steps of that frame
//! (what the live UI records, since a hand acts between any two steps). Actions of one moment
//! apply in the order they are written. Positions are in metres, velocities in m/s, points by
//! index (`row * num_width_points + column`). A cut crosses the springs whose segments its
//! stroke `from`–`to` crosses as seen along the direction `along` (an orthographic view's) or
//! from the point `eye` (a perspective camera's): give one of the two.

use std::path::Path;

use anyhow::Context as _;
use cloth_mesh::{Knife, Sight, Vec3};
use serde::{Deserialize, Serialize};

use crate::{Command, Fault, Run, Timed, Touch};

/// The largest actions file read, bytes: far more than any hand can do in a run.
pub const MAX_BYTES: u64 = 16 * 1024 * 1024;

/// What one line does.
#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "action", rename_all = "lowercase", deny_unknown_fields)]
enum What {
    Grab {
        point: usize,
        to: [f64; 3],
    },
    Drag {
        to: [f64; 3],
    },
    // NOTE: a struct variant, so an unknown key beside it is refused as for the others.
    Release {},
    Poke {
        point: usize,
        velocity: [f64; 3],
    },
    Pin {
        point: usize,
    },
    Unpin {
        point: usize,
    },
    Cut {
        from: [f64; 3],
        to: [f64; 3],
        #[serde(default, skip_serializing_if = "Option::is_none")]
        along: Option<[f64; 3]>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        eye: Option<[f64; 3]>,
    },
}

impl What {
    /// The line of `touch`.
    fn of(touch: &Touch) -> Self {
        let a = |v: &Vec3| [v.x, v.y, v.z];
        match *touch {
            Touch::Grab { point, to } => What::Grab { point, to: a(&to) },
            Touch::Drag { to } => What::Drag { to: a(&to) },
            Touch::Release => What::Release {},
            Touch::Poke { point, velocity } => What::Poke {
                point,
                velocity: a(&velocity),
            },
            Touch::Pin {
                point,
                pinned: true,
            } => What::Pin { point },
            Touch::Pin {
                point,
                pinned: false,
            } => What::Unpin { point },
            Touch::Cut(k) => {
                let (along, eye) = match k.sight {
                    Sight::Along(d) => (Some(a(&d)), None),
                    Sight::From(e) => (None, Some(a(&e))),
                };
                What::Cut {
                    from: a(&k.from),
                    to: a(&k.to),
                    along,
                    eye,
                }
            }
        }
    }
}

/// A line's `frame`, `step` (0 when absent) and action.
fn when_and_what(v: serde_json::Value) -> Result<(u64, u32, What), serde_json::Error> {
    use serde::de::Error as _;
    let serde_json::Value::Object(mut map) = v else {
        return Err(serde_json::Error::custom("not a JSON object"));
    };
    let frame = map
        .remove("frame")
        .ok_or_else(|| serde_json::Error::missing_field("frame"))?;
    let frame = u64::deserialize(frame)?;
    let step = match map.remove("step") {
        Some(s) => u32::deserialize(s)?,
        None => 0,
    };
    let what = What::deserialize(serde_json::Value::Object(map))?;
    Ok((frame, step, what))
}

/// The line that replays `timed` (see the module's documentation), without its newline.
#[must_use]
pub fn line(timed: &Timed) -> String {
    #[derive(Serialize)]
    struct Out {
        frame: u64,
        #[serde(skip_serializing_if = "Option::is_none")]
        step: Option<u32>,
        #[serde(flatten)]
        what: What,
    }
    let out = Out {
        frame: timed.frame,
        step: (timed.step > 0).then_some(timed.step),
        what: What::of(&timed.touch),
    };
    serde_json::to_string(&out).unwrap_or_default()
}

/// The touches of a file, by frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Actions {
    /// `(frame, step, line number, touch)`, in the file's order.
    items: Vec<(u64, u32, usize, Touch)>,
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
            let parsed = serde_json::from_str::<serde_json::Value>(line)
                .map_err(anyhow::Error::from)
                .and_then(|v| when_and_what(v).map_err(anyhow::Error::from))
                .map_err(|e| {
                    anyhow::anyhow!(
                        "{origin}:{n}: {e}; an action is an object with \"frame\" (and \"step\") \
                     and \"action\": grab with point and to, drag with to, release, poke \
                     with point and velocity, pin or unpin with point, cut with from, to and \
                     along or eye"
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
            let (frame, step, what) = parsed;
            let touch = match what {
                What::Grab { point, to } => Touch::Grab {
                    point: point_ok(point)?,
                    to: vec("to", to)?,
                },
                What::Drag { to } => Touch::Drag { to: vec("to", to)? },
                What::Release {} => Touch::Release,
                What::Poke { point, velocity } => Touch::Poke {
                    point: point_ok(point)?,
                    velocity: vec("velocity", velocity)?,
                },
                What::Pin { point } => Touch::Pin {
                    point: point_ok(point)?,
                    pinned: true,
                },
                What::Unpin { point } => Touch::Pin {
                    point: point_ok(point)?,
                    pinned: false,
                },
                What::Cut {
                    from,
                    to,
                    along,
                    eye,
                } => {
                    let sight = match (along, eye) {
                        (Some(d), None) => {
                            let d = vec("along", d)?;
                            anyhow::ensure!(
                                d.norm() > 0.0,
                                "{origin}:{n}: along must be a direction, not [0, 0, 0]"
                            );
                            Sight::Along(d)
                        }
                        (None, Some(e)) => Sight::From(vec("eye", e)?),
                        _ => anyhow::bail!(
                            "{origin}:{n}: a cut is seen along a direction or from an eye: \
                             give exactly one of \"along\" and \"eye\""
                        ),
                    };
                    Touch::Cut(Knife {
                        from: vec("from", from)?,
                        to: vec("to", to)?,
                        sight,
                    })
                }
            };
            items.push((frame, step, n, touch));
        }
        // NOTE: stable, so the actions of one frame keep the file's order.
        items.sort_by_key(|&(frame, step, _, _)| (frame, step));
        Ok(Self {
            items,
            origin: origin.to_owned(),
        })
    }

    /// Applies to `run` every action due at its present moment (`run.frames` frames and
    /// [`Run::step_in_frame`] steps into the next; those of earlier moments too, when the run
    /// starts later, as from a state).
    ///
    /// # Errors
    /// An action the run refuses (a drag with no point held), naming its line.
    pub fn apply_due(&mut self, run: &mut Run) -> anyhow::Result<()> {
        let now = (run.frames, run.step_in_frame());
        let due = self
            .items
            .iter()
            .take_while(|&&(frame, step, _, _)| (frame, step) <= now)
            .count();
        for (_, _, n, touch) in self.items.drain(..due) {
            run.apply(Command::Touch(touch))
                .map_err(|e| anyhow::anyhow!("{}:{n}: {e}", self.origin))?;
        }
        Ok(())
    }

    /// Steps `run` one frame with the actions due before each step applied, calling
    /// `each_step` after every step (as [`Run::step_frame_with`]).
    ///
    /// # Errors
    /// An action the run refuses (the outer error), or the frame's fault (the inner one).
    pub fn step_frame(
        &mut self,
        run: &mut Run,
        each_step: &mut dyn FnMut(),
    ) -> anyhow::Result<Result<(), Box<Fault>>> {
        for _ in 0..run.settings.params.steps_per_frame {
            self.apply_due(run)?;
            if let Err(f) = run.step() {
                return Ok(Err(f));
            }
            each_step();
        }
        Ok(Ok(()))
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
        assert_eq!(a.items[1].3, Touch::Release);
        let e = Actions::parse("{\"frame\": 1, \"action\": \"tear\"}", "h", 10).unwrap_err();
        assert!(
            e.to_string().starts_with("h:1: unknown variant `tear`"),
            "{e}"
        );
        let e = Actions::parse(
            "{\"frame\": 1, \"action\": \"cut\", \"from\": [0,0,0], \"to\": [1,0,0]}",
            "h",
            10,
        )
        .unwrap_err();
        assert!(e.to_string().contains("exactly one of"), "{e}");
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
