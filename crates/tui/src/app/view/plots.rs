//! Live plots of kinetic energy and the largest spring stretch, one sample per simulated frame.

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::Line;
use ratatui::widgets::{Block, Sparkline};

use crate::app::model::App;
use crate::app::theme::Theme;
use cloth_solver::MAX_STRETCH;

/// Bar heights are integers; this many levels span the plot.
const LEVELS: f64 = 1000.0;

/// The two plots, when the layout has room for them.
pub fn plots(app: &App, f: &mut Frame, areas: [Rect; 2], theme: &Theme) {
    let [energy, stretch] = areas;
    let h = &app.sim.history;
    let last = h.back().copied();
    if energy.height >= 3 {
        let width = energy.width.saturating_sub(2) as usize;
        let shown: Vec<f64> = h
            .iter()
            .rev()
            .take(width)
            .rev()
            .map(|s| s.kinetic)
            .collect();
        let top = shown.iter().copied().fold(0.0, f64::max);
        let data: Vec<u64> = shown
            .iter()
            .map(|&k| {
                if top > 0.0 {
                    (k / top * LEVELS).round() as u64
                } else {
                    0
                }
            })
            .collect();
        let title = format!(
            " kinetic energy {} J ",
            sci(last.map_or(0.0, |s| s.kinetic))
        );
        f.render_widget(
            Sparkline::default()
                .block(
                    Block::bordered()
                        .border_style(theme.border)
                        .title(Line::styled(title, theme.text)),
                )
                .data(data)
                .max(LEVELS as u64)
                .style(theme.plot_energy),
            energy,
        );
    }
    if stretch.height >= 3 {
        let width = stretch.width.saturating_sub(2) as usize;
        let shown: Vec<f64> = h
            .iter()
            .rev()
            .take(width)
            .rev()
            .map(|s| s.stretch)
            .collect();
        // NOTE: the plot spans rest length (1) to the 10 % limit, or higher if exceeded, so a
        // cloth hanging at the limit reads as a full bar.
        let top = shown.iter().copied().fold(MAX_STRETCH, f64::max);
        let data: Vec<u64> = shown
            .iter()
            .map(|&s| ((s - 1.0).max(0.0) / (top - 1.0) * LEVELS).round() as u64)
            .collect();
        let title = format!(
            " max stretch {:.3} (limit {MAX_STRETCH}) ",
            last.map_or(1.0, |s| s.stretch)
        );
        f.render_widget(
            Sparkline::default()
                .block(
                    Block::bordered()
                        .border_style(theme.border)
                        .title(Line::styled(title, theme.text)),
                )
                .data(data)
                .max(LEVELS as u64)
                .style(theme.plot_stretch),
            stretch,
        );
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
