//! Live plots of kinetic energy and the largest spring stretch.
//!
//! Each column is [`BUCKET`] seconds of simulated time (the largest sample in it), so the plots
//! scroll a few times a second instead of every frame: a settled cloth then leaves the screen,
//! and the bytes sent, unchanged. Energy is drawn on a log scale spanning [`DECADES`] below its
//! peak since the start or the last reset: a settling cloth loses energy exponentially, which
//! reads as a steady ramp down (a linear scale would show the first swing and then nothing).

use std::collections::VecDeque;

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::Line;
use ratatui::widgets::{Block, Sparkline};

use crate::model::App;
use crate::theme::Theme;
use cloth_run::Sample;
use cloth_solver::MAX_STRETCH;

/// Simulated seconds per plot column.
pub const BUCKET: f64 = 0.25;

/// Bar heights are integers; this many levels span the plot.
const LEVELS: f64 = 1000.0;

/// Decades of kinetic energy below the peak that the energy plot spans; less shows as nothing.
pub const DECADES: f64 = 8.0;

/// Bar height of energy `k` on the log scale below `peak`.
fn log_level(k: f64, peak: f64) -> u64 {
    if !(peak > 0.0 && k > 0.0) {
        return 0;
    }
    let t = ((k / peak).log10() + DECADES) / DECADES;
    (t.clamp(0.0, 1.0) * LEVELS).round() as u64
}

/// The largest `value` in each of the last `width` buckets, oldest first.
fn columns(h: &VecDeque<Sample>, width: usize, value: impl Fn(&Sample) -> f64) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(width);
    let mut current: Option<i64> = None;
    for s in h.iter().rev() {
        let b = (s.time / BUCKET).floor() as i64;
        if current == Some(b) {
            if let Some(last) = out.last_mut() {
                *last = last.max(value(s));
            }
        } else {
            if out.len() == width {
                break;
            }
            out.push(value(s));
            current = Some(b);
        }
    }
    out.reverse();
    out
}

fn plot(
    f: &mut Frame,
    area: Rect,
    title: String,
    data: Vec<u64>,
    theme: &Theme,
    style: ratatui::style::Style,
) {
    f.render_widget(
        Sparkline::default()
            .block(
                Block::bordered()
                    .border_style(theme.border)
                    .title(Line::styled(title, theme.text)),
            )
            .data(data)
            .max(LEVELS as u64)
            .style(style),
        area,
    );
}

/// The two plots, when the layout has room for them.
pub fn plots(app: &App, f: &mut Frame, areas: [Rect; 2], theme: &Theme) {
    let [energy, stretch] = areas;
    let sim = &app.sim;
    let h = &sim.history;
    let last = h.back().copied();
    if energy.height >= 3 {
        let width = energy.width.saturating_sub(2) as usize;
        let peak = sim.peak_kinetic;
        let data = columns(h, width, |s| s.kinetic)
            .into_iter()
            .map(|k| log_level(k, peak))
            .collect();
        let now = last.map_or(0.0, |s| s.kinetic);
        let title = if width >= 30 {
            format!(" kinetic energy {} J (log) ", sci(now))
        } else {
            format!(" KE {} J (log) ", sci(now))
        };
        plot(f, energy, title, data, theme, theme.plot_energy);
    }
    if stretch.height >= 3 {
        let width = stretch.width.saturating_sub(2) as usize;
        let shown = columns(h, width, |s| s.stretch);
        // NOTE: the plot spans rest length (1) to twice the limit's excess (1.2), or higher
        // when exceeded, so a cloth hanging at the limit fills half the height and the limit
        // itself is a dashed line, not the plot's ceiling.
        let top = shown
            .iter()
            .copied()
            .fold(1.0 + 2.0 * (MAX_STRETCH - 1.0), f64::max);
        let data = shown
            .iter()
            .map(|&s| ((s - 1.0).max(0.0) / (top - 1.0) * LEVELS).round() as u64)
            .collect();
        let now = last.map_or(1.0, |s| s.stretch);
        let title = if width >= 30 {
            format!(" max stretch {now:.3} (limit {MAX_STRETCH} ┄) ")
        } else {
            format!(" stretch {now:.3} ")
        };
        plot(f, stretch, title, data, theme, theme.plot_stretch);
        limit_line(f, stretch, (MAX_STRETCH - 1.0) / (top - 1.0), theme);
    }
}

/// A dashed line across the plot's empty cells at `fraction` of its height.
fn limit_line(f: &mut Frame, area: Rect, fraction: f64, theme: &Theme) {
    let inner = crate::layout::inner(area);
    if inner.height == 0 {
        return;
    }
    let from_bottom = ((fraction * f64::from(inner.height)).floor() as u16).min(inner.height - 1);
    let y = inner.bottom() - 1 - from_bottom;
    let buf = f.buffer_mut();
    for x in inner.left()..inner.right() {
        if let Some(cell) = buf.cell_mut((x, y))
            && cell.symbol() == " "
        {
            cell.set_symbol("┄");
            cell.set_style(theme.dim);
        }
    }
}

/// A number in short scientific notation (`1.23e-3`).
fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".to_owned()
    } else if (0.01..1000.0).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_hold_the_largest_sample_of_each_bucket_newest_last() {
        let h: VecDeque<Sample> = (0..10)
            .map(|i| Sample {
                time: f64::from(i) * 0.1,
                kinetic: f64::from(i),
                stretch: 1.0,
            })
            .collect();
        // Buckets of 0.25 s: [0, 0.1, 0.2], [0.3, 0.4], [0.5, 0.6, 0.7], [0.8, 0.9].
        assert_eq!(columns(&h, 10, |s| s.kinetic), vec![2.0, 4.0, 7.0, 9.0]);
        assert_eq!(columns(&h, 2, |s| s.kinetic), vec![7.0, 9.0]);
    }

    #[test]
    fn energy_levels_are_logarithmic_below_the_peak() {
        assert_eq!(log_level(5.0, 5.0), 1000);
        // Half the decades down is half the height.
        assert_eq!(log_level(5.0e-4, 5.0), 500);
        assert_eq!(log_level(5.0e-9, 5.0), 0);
        assert_eq!(log_level(0.0, 5.0), 0);
        assert_eq!(log_level(1.0, 0.0), 0);
    }
}
