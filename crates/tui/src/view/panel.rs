//! The parameter panel, drawn from the rows of [`row`].

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph, Wrap};

use crate::model::App;
use crate::params::{Kind, row, row_count};
use crate::theme::Theme;

/// Width of the label column.
const LABEL: usize = 15;

/// Every parameter with value and unit; the selected one highlighted, edited ones marked `*`,
/// absent ones (no sphere...) dimmed, ks marked `!` past the explicit stability limit.
pub fn params(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    let block = Block::bordered()
        .border_style(theme.border)
        .title(Line::styled(" parameters ", theme.text))
        .title_bottom(Line::styled(" * edited  ! unstable ", theme.dim).right_aligned());
    let inside = block.inner(area);
    f.render_widget(block, area);
    let count = row_count(&app.sim);
    let rows = count as u16;
    let (list_h, help_h) = if inside.height >= rows + 2 {
        (rows, inside.height - rows)
    } else {
        (inside.height, 0)
    };
    // Scroll so the selected row stays visible.
    let first = app
        .selected
        .saturating_sub(list_h.saturating_sub(1) as usize);
    let scene = app.sim.scene_settings();
    let unstable = app.sim.stability_warning().is_some();
    let value_w = (inside.width as usize).saturating_sub(LABEL + 2 + 7).max(4);
    let mut lines = Vec::with_capacity(list_h as usize);
    for i in (0..count).skip(first).take(list_h as usize) {
        let p = row(&app.sim, i);
        // Compare mode: the varied key's row shows its values (each variant keeps its own).
        let varied = app.compare.as_ref().and_then(|c| {
            c.axes
                .iter()
                .find(|(k, _)| k.rsplit('.').next() == Some(p.label))
                .map(|(_, v)| v.replace(' ', ""))
        });
        let (value, unit, edited) = if let Some(values) = varied {
            // NOTE: cut values end in an ellipsis, so `1,5000,20000,1` is never read as a
            // last value of 1 (the table's title gives them all).
            let values: String = if values.chars().count() > value_w {
                values
                    .chars()
                    .take(value_w.saturating_sub(1))
                    .chain(['…'])
                    .collect()
            } else {
                values
            };
            (
                values,
                if p.kind == Kind::Solver { "" } else { p.unit },
                false,
            )
        } else if p.kind == Kind::Solver {
            (
                app.sim.entry().name().to_owned(),
                "",
                app.sim.entry().name() != app.sim.scene_solver(),
            )
        } else {
            let v = (p.get)(&app.sim.settings);
            (p.format(v), p.unit, v != (p.get)(&scene))
        };
        let flag = if p.label == "ks" && unstable {
            "!"
        } else if edited {
            "*"
        } else {
            " "
        };
        let text = format!("{flag}{:<LABEL$} {value:>value_w$} {unit:<6}", p.label);
        let style = if i == app.selected {
            theme.selected
        } else if flag == "!" {
            theme.warn
        } else if edited {
            theme.edited
        } else if (p.get)(&app.sim.settings).is_none() && p.kind != Kind::Solver {
            theme.dim
        } else {
            theme.text
        };
        lines.push(Line::styled(text, style));
    }
    f.render_widget(
        Paragraph::new(lines),
        Rect {
            height: list_h,
            ..inside
        },
    );
    if help_h > 0 {
        let help = Rect {
            y: inside.y + list_h + 1,
            height: help_h - 1,
            ..inside
        };
        let text = row(&app.sim, app.selected).help;
        f.render_widget(
            Paragraph::new(Span::styled(text, theme.dim)).wrap(Wrap { trim: true }),
            help,
        );
    }
}
