//! The pure view: `view(&App, &mut Frame)` draws the model and reads nothing else (no clock,
//! no terminal), so a snapshot of the same model is the same screen.

mod compare;
mod overlay;
mod panel;
mod plots;
mod status;

pub use status::note_lines;

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph};

use super::layout::{self, inner};
use super::model::{App, Overlay};
use super::panes::AsciiView;
use super::theme::Theme;

/// Draws the whole screen.
pub fn view(app: &App, f: &mut Frame) {
    let area = f.area();
    let theme = Theme::new(app.color || app.color_allowed);
    let Some(r) = layout::regions(app, area) else {
        overlay::too_small(f, area, &theme);
        return;
    };
    status::title(app, f, r.title, &theme);
    for &(slot, rect) in &r.panes {
        pane(app, f, slot, rect, &theme);
    }
    if app.compare.is_some() {
        compare::panes(app, f, &r.variants, &theme);
        compare::table(app, f, r.table, &theme);
    }
    panel::params(app, f, r.params, &theme);
    plots::plots(app, f, r.plots, &theme);
    status::note(app, f, r.note, &theme);
    status::footer(f, r.footer, &theme);
    // Boxes are centred between the status line and the message line.
    let body = Rect {
        y: r.title.y + 1,
        height: r.note.y.saturating_sub(r.title.y + 1),
        ..area
    };
    match &app.overlay {
        Overlay::None => {}
        Overlay::Help => overlay::help(app, f, body, &theme),
        Overlay::Picker(p) => overlay::picker(f, body, p, &theme),
        Overlay::Prompt(p) => overlay::prompt(app, f, body, p, &theme),
        Overlay::ConfirmOverwrite(path) => overlay::confirm(f, body, path, &theme),
        Overlay::ConfirmDiscard(then) => overlay::discard(app, f, body, *then, &theme),
        Overlay::ConfirmBig(points) => overlay::big(app, f, body, *points, &theme),
        Overlay::Fault => overlay::fault(app, f, body, &theme),
    }
}

#[cfg(test)]
pub use compare::sig;

/// Rows compare mode's table needs at `width` columns.
pub fn compare_table_height(app: &App, width: u16) -> u16 {
    compare::table_height(app, width)
}

/// How far the help overlay scrolls on the app's screen before its last row shows.
pub fn help_scroll_max(app: &App) -> u16 {
    let area = Rect::new(0, 0, app.screen.0, app.screen.1);
    let Some(r) = layout::regions(app, area) else {
        return 0;
    };
    let body = Rect {
        y: r.title.y + 1,
        height: r.note.y.saturating_sub(r.title.y + 1),
        ..area
    };
    overlay::help_scroll_max(body)
}

fn pane(app: &App, f: &mut Frame, slot: usize, rect: Rect, theme: &Theme) {
    let view = app.views[slot];
    let focused = slot == app.focus && app.visible_slots().len() > 1;
    let mut title = vec![Span::styled(
        format!(" {} {} ", slot + 1, view.name()),
        if focused { theme.focus } else { theme.text },
    )];
    if app.maximised {
        title.push(Span::styled("(max) ", theme.dim));
    }
    let mut block = Block::bordered()
        .border_style(if focused { theme.focus } else { theme.border })
        .title(Line::from(title));
    if let Some((up, right)) = view.axis_labels() {
        block = block
            .title_bottom(Line::styled(format!(" {right}→ {up}↑ "), theme.dim).right_aligned());
    }
    f.render_widget(block, rect);
    let inside = inner(rect);
    match &app.frames[slot] {
        Some(frame)
            if frame.width() == inside.width as usize
                && frame.height() == inside.height as usize =>
        {
            let depth = if app.color {
                app.depth
            } else {
                cloth_render::ColorDepth::None
            };
            f.render_widget(AsciiView::new(frame, depth), inside);
        }
        Some(_) | None => {
            if inside.width < cloth_render::MIN_WIDTH as u16
                || inside.height < cloth_render::MIN_HEIGHT as u16
            {
                f.render_widget(Paragraph::new("too small").style(theme.dim), inside);
            }
        }
    }
}
