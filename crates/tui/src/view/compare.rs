//! Compare mode's panes (one per variant, titled with its values, greyed with its reason when
//! it stopped) and the table of their figures.

use cloth_render::ColorDepth;
use ratatui::Frame;
use ratatui::layout::{Constraint, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Cell, Row, Table};

use super::super::layout::inner;
use super::super::model::App;
use super::super::panes::AsciiView;
use super::super::theme::Theme;
use cloth_run::Run;

/// Each variant's title, simulation and pane, in the study's order.
fn variants(app: &App) -> Vec<(&str, &Run, Option<&cloth_render::AsciiFrame>)> {
    let Some(c) = &app.compare else {
        return Vec::new();
    };
    std::iter::once((c.title.as_str(), &app.sim, c.frame.as_ref()))
        .chain(
            c.members
                .iter()
                .map(|m| (m.title.as_str(), &m.sim, m.frame.as_ref())),
        )
        .collect()
}

/// Draws the variants' panes into `rects`.
pub fn panes(app: &App, f: &mut Frame, rects: &[Rect], theme: &Theme) {
    let view = app.views[app.focus];
    for ((title, sim, frame), rect) in variants(app).into_iter().zip(rects) {
        let stopped = sim.fault.is_some();
        let mut spans = vec![Span::styled(
            format!(" {title} "),
            if stopped { theme.dim } else { theme.focus },
        )];
        // NOTE: the variants step in lockstep, so the group's time (the status line's) is
        // every pane's; a stopped one gives the time it stopped at.
        spans.push(Span::styled(format!("{} ", view.name()), theme.dim));
        if let Some(fault) = &sim.fault {
            spans.push(Span::styled(
                format!("stopped at {:.2} s: {} ", fault.time, fault.what),
                theme.error,
            ));
        }
        let block = Block::bordered()
            .border_style(if stopped { theme.dim } else { theme.border })
            .title(Line::from(spans));
        f.render_widget(block, *rect);
        let inside = inner(*rect);
        if let Some(frame) = frame
            && frame.width() == inside.width as usize
            && frame.height() == inside.height as usize
        {
            // A stopped variant is drawn in glyphs only, dimmed: it no longer moves.
            let depth = if app.color && !stopped {
                app.depth
            } else {
                ColorDepth::None
            };
            f.render_widget(AsciiView::new(frame, depth), inside);
            if stopped {
                f.buffer_mut().set_style(inside, theme.dim);
            }
        }
    }
}

/// Draws the table: per variant the centre's and the lowest point's heights, the largest
/// stretch, the kinetic energy and whether it stopped.
pub fn table(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    if area.height < 3 {
        return;
    }
    let header = Row::new(
        [
            "variant",
            "centre height",
            "lowest height",
            "max stretch",
            "kinetic energy",
            "diverged",
        ]
        .map(|h| Cell::from(h).style(theme.dim)),
    );
    let rows = variants(app).into_iter().map(|(title, sim, _)| {
        let mesh = &sim.scene.mesh;
        let state = &sim.state;
        let centre = state
            .positions
            .get(mesh.index(mesh.nw() / 2, mesh.nh() / 2))
            .map_or(f64::NAN, |p| p.y);
        let lowest = state
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        // NOTE: the UI's copy of a worker's state has its positions only, so velocities come
        // from the last frame's sample (taken where the state is whole), not from the copy.
        let (kinetic, stretch) = sim
            .history
            .back()
            .map_or((f64::NAN, f64::NAN), |s| (s.kinetic, s.stretch));
        let style = if sim.fault.is_some() {
            theme.dim
        } else {
            theme.text
        };
        Row::new([
            Cell::from(title.to_owned()),
            Cell::from(format!("{centre:>10.4} m")),
            Cell::from(format!("{lowest:>10.4} m")),
            Cell::from(format!("{stretch:>8.4}")),
            Cell::from(format!("{kinetic:>11.3e} J")),
            Cell::from(match &sim.fault {
                Some(fault) => format!("yes: {}", fault.what),
                None => "no".to_owned(),
            }),
        ])
        .style(style)
    });
    let axes = app
        .compare
        .as_ref()
        .map(|c| {
            c.axes
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>()
                .join("  x  ")
        })
        .unwrap_or_default();
    let widths = [
        Constraint::Length(22),
        Constraint::Length(14),
        Constraint::Length(14),
        Constraint::Length(11),
        Constraint::Length(15),
        Constraint::Min(8),
    ];
    let table = Table::new(rows, widths).header(header).block(
        Block::bordered()
            .border_style(theme.border)
            .title(Line::styled(format!(" compare: {axes} "), theme.text)),
    );
    f.render_widget(table, area);
}
