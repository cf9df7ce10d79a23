//! Progress of a long headless run, on stderr.
//!
//! On a terminal: a bar that advances with every simulation step (a big cloth can take minutes
//! per frame, so frames alone would look stuck), cleared at the end. When stderr is not a
//! terminal (a log file, CI): with `--progress`, one line every [`LINE_INTERVAL`] and one at the
//! end, so a slow run is never silent; without it, nothing, so scripts reading stderr see only
//! errors.

use std::io::{IsTerminal, Write as _};
use std::time::{Duration, Instant};

/// How often a progress line is written when stderr is not a terminal.
pub const LINE_INTERVAL: Duration = Duration::from_secs(10);

/// When to show progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum When {
    /// A bar when stderr is a terminal; nothing otherwise.
    #[default]
    Auto,
    /// A bar on a terminal, a line every 10 s otherwise.
    Always,
    /// Never.
    Never,
}

impl When {
    /// The names a command line takes, in order.
    pub const NAMES: [&'static str; 3] = ["auto", "always", "never"];
}

impl std::str::FromStr for When {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "always" => Ok(Self::Always),
            "never" => Ok(Self::Never),
            _ => Err(format!("{s:?} is not one of auto, always, never")),
        }
    }
}

/// Progress of `frames` frames of `steps_per_frame` steps each.
pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    lines: Option<Lines>,
    steps_per_frame: u64,
    done: u64,
}

impl Progress {
    /// Progress for a run named `label` (the scene), shown as `when` says. `stdout_on_terminal`
    /// keeps the bar off when the command's own output is on the same terminal.
    pub fn new(
        when: When,
        label: &str,
        frames: u64,
        steps_per_frame: u32,
        stdout_on_terminal: bool,
    ) -> Self {
        let steps_per_frame = u64::from(steps_per_frame.max(1));
        let total = frames.saturating_mul(steps_per_frame);
        let on_terminal = std::io::stderr().is_terminal();
        let (bar, lines) = match when {
            When::Never => (None, None),
            _ if on_terminal && !stdout_on_terminal => (Some(bar(total, frames)), None),
            When::Always if !on_terminal => (
                None,
                Some(Lines::new(label, frames, steps_per_frame, Instant::now())),
            ),
            _ => (None, None),
        };
        Self {
            bar,
            lines,
            steps_per_frame,
            done: 0,
        }
    }

    /// One simulation step done.
    pub fn step(&mut self) {
        self.done += 1;
        if let Some(bar) = &self.bar {
            bar.inc(1);
            if self.done.is_multiple_of(self.steps_per_frame) {
                bar.set_message(format!("{}", self.done / self.steps_per_frame));
            }
        }
        if let Some(lines) = &mut self.lines
            && let Some(line) = lines.due(self.done, Instant::now())
        {
            // A lost progress line changes nothing; the run goes on.
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }

    /// The run ended (finished or failed): clears the bar, or writes the last line.
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
        if let Some(lines) = self.lines {
            let _ = writeln!(
                std::io::stderr(),
                "{}",
                lines.last(self.done, Instant::now())
            );
        }
    }
}

fn bar(total: u64, frames: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(total);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{{bar:40}} frame {{msg}}/{frames} ({{eta}} left)"
    )) {
        bar.set_style(style);
    }
    bar.set_message("0");
    bar
}

/// Progress lines for a stderr that is not a terminal: one per [`LINE_INTERVAL`].
struct Lines {
    label: String,
    frames: u64,
    steps_per_frame: u64,
    start: Instant,
    next: Instant,
}

impl Lines {
    fn new(label: &str, frames: u64, steps_per_frame: u64, now: Instant) -> Self {
        Self {
            label: label.to_owned(),
            frames,
            steps_per_frame,
            start: now,
            next: now + LINE_INTERVAL,
        }
    }

    /// The line to write after `done` steps at `now`, when one is due.
    fn due(&mut self, done: u64, now: Instant) -> Option<String> {
        if now < self.next {
            return None;
        }
        self.next = now + LINE_INTERVAL;
        let total = self.frames.saturating_mul(self.steps_per_frame).max(1);
        let elapsed = now - self.start;
        let fraction = done as f64 / total as f64;
        let left = if done > 0 {
            format!(
                ", about {} left",
                duration(elapsed.as_secs_f64() * (1.0 - fraction) / fraction)
            )
        } else {
            String::new()
        };
        Some(format!(
            "{}: {}: frame {} of {} ({:.0} %), {} elapsed{left}",
            crate::headless::program_name(),
            self.label,
            (done / self.steps_per_frame).min(self.frames),
            self.frames,
            fraction * 100.0,
            duration(elapsed.as_secs_f64()),
        ))
    }

    /// The closing line after `done` steps at `now`.
    fn last(&self, done: u64, now: Instant) -> String {
        format!(
            "{}: {}: {} of {} frames simulated in {}",
            crate::headless::program_name(),
            self.label,
            done / self.steps_per_frame,
            self.frames,
            duration((now - self.start).as_secs_f64())
        )
    }
}

/// `s` seconds as `42 s`, `3 min 20 s` or `2 h 5 min`.
fn duration(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        _ => format!("{} h {} min", s / 3600, s % 3600 / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_due_every_interval_with_the_frame_and_what_is_left() {
        let t0 = Instant::now();
        let mut lines = Lines::new("sphere", 2, 30, t0);
        assert_eq!(lines.due(1, t0 + Duration::from_secs(1)), None);
        // 15 of 60 steps in 10 s: a quarter done, 30 s left.
        let line = lines.due(15, t0 + LINE_INTERVAL).unwrap();
        assert_eq!(
            line,
            "clothsim: sphere: frame 0 of 2 (25 %), 10 s elapsed, about 30 s left"
        );
        // Not again until another interval has passed.
        assert_eq!(
            lines.due(16, t0 + LINE_INTERVAL + Duration::from_secs(9)),
            None
        );
        let line = lines.due(45, t0 + LINE_INTERVAL * 12).unwrap();
        assert_eq!(
            line,
            "clothsim: sphere: frame 1 of 2 (75 %), 2 min 0 s elapsed, about 40 s left"
        );
        assert_eq!(
            lines.last(60, t0 + LINE_INTERVAL * 16),
            "clothsim: sphere: 2 of 2 frames simulated in 2 min 40 s"
        );
    }

    #[test]
    fn durations_read_at_a_glance() {
        assert_eq!(duration(0.4), "0 s");
        assert_eq!(duration(59.6), "1 min 0 s");
        assert_eq!(duration(194.0), "3 min 14 s");
        assert_eq!(duration(7500.0), "2 h 5 min");
    }
}
