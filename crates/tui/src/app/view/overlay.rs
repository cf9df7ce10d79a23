//! Boxes drawn over the panes: help, picker, prompt, overwrite question, fault, too small.

use std::path::Path;

use ratatui::Frame;
use ratatui::layout::{Alignment, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Wrap};

use crate::app::keymap::{Group, KEYMAP, keys_label};
use crate::app::layout::{MIN_HEIGHT, MIN_WIDTH};
use crate::app::model::{App, Picker, Prompt, Purpose};
use crate::app::params::{Kind, fmt_number, row};
use crate::app::theme::Theme;

/// A box of `w` x `h` centred in `area` (clipped to it), cleared and bordered.
fn boxed(
    f: &mut Frame,
    area: Rect,
    w: u16,
    h: u16,
    title: &str,
    style: ratatui::style::Style,
) -> Rect {
    let w = w.min(area.width);
    let h = h.min(area.height);
    let r = Rect {
        x: area.x + (area.width - w) / 2,
        y: area.y + (area.height - h) / 2,
        width: w,
        height: h,
    };
    f.render_widget(Clear, r);
    let block = Block::bordered()
        .border_style(style)
        .title(Line::styled(format!(" {title} "), style));
    let inside = block.inner(r);
    f.render_widget(block, r);
    inside
}

/// The help, generated from [`KEYMAP`]: two columns when wide enough, else one that scrolls.
pub fn help(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    let key_w = KEYMAP
        .iter()
        .map(|b| keys_label(b).chars().count())
        .max()
        .unwrap_or(8);
    let group_lines = |g: Group| -> Vec<Line<'static>> {
        let mut v = vec![Line::styled(g.title().to_owned(), theme.warn)];
        for b in KEYMAP.iter().filter(|b| b.group == g) {
            v.push(Line::from(vec![
                Span::styled(format!("  {:<key_w$}  ", keys_label(b)), theme.key),
                Span::styled(b.help, theme.text),
            ]));
        }
        v.push(Line::raw(""));
        v
    };
    let all: Vec<Vec<Line>> = Group::ALL.iter().map(|&g| group_lines(g)).collect();
    let widest = KEYMAP
        .iter()
        .map(|b| b.help.chars().count())
        .max()
        .unwrap_or(40)
        + key_w
        + 4;
    let total: usize = all.iter().map(Vec::len).sum();
    let two = area.width as usize >= 2 * widest + 3;
    let (left, right): (Vec<Line>, Vec<Line>) = if two {
        // Split the groups where the left column holds about half the lines.
        let mut l = Vec::new();
        let mut r = Vec::new();
        for g in all {
            if l.len() + g.len() / 2 < total / 2 {
                l.extend(g);
            } else {
                r.extend(g);
            }
        }
        (l, r)
    } else {
        (all.into_iter().flatten().collect(), Vec::new())
    };
    let rows = left.len().max(right.len()) as u16 + 1;
    let w = if two {
        2 * widest as u16 + 3
    } else {
        widest as u16 + 2
    };
    let inside = boxed(
        f,
        area,
        w,
        rows + 2,
        "keys (Esc or ? closes, ↑↓ scroll)",
        theme.focus,
    );
    let scroll = app.help_scroll.min(rows.saturating_sub(inside.height));
    if two {
        let half = Rect {
            width: inside.width / 2,
            ..inside
        };
        f.render_widget(Paragraph::new(left).scroll((scroll, 0)), half);
        f.render_widget(
            Paragraph::new(right).scroll((scroll, 0)),
            Rect {
                x: inside.x + inside.width / 2 + 1,
                width: inside.width - inside.width / 2 - 1,
                ..inside
            },
        );
    } else {
        f.render_widget(Paragraph::new(left).scroll((scroll, 0)), inside);
    }
}

/// The scene picker: bundled scenes, the working folder's scene files, "type a path".
pub fn picker(f: &mut Frame, area: Rect, p: &Picker, theme: &Theme) {
    let scenes = cloth_scene::BUNDLED;
    let name_w = scenes
        .iter()
        .map(|s| s.name.len())
        .chain(p.files.iter().map(|n| n.chars().count().min(30)))
        .max()
        .unwrap_or(8);
    let style = |i: usize, normal| {
        if i == p.selected {
            theme.selected
        } else {
            normal
        }
    };
    let mut lines: Vec<Line> = scenes
        .iter()
        .enumerate()
        .map(|(i, s)| {
            Line::styled(
                format!(" {:<name_w$}  {}", s.name, s.description),
                style(i, theme.text),
            )
        })
        .collect();
    for (k, name) in p.files.iter().enumerate() {
        let i = scenes.len() + k;
        lines.push(Line::styled(
            format!(" {name:<name_w$}  scene file in this folder"),
            style(i, theme.text),
        ));
    }
    lines.push(Line::styled(
        " type a path...",
        style(p.len() - 1, theme.key),
    ));
    let w = lines.iter().map(Line::width).max().unwrap_or(40) as u16 + 3;
    let inside = boxed(
        f,
        area,
        w,
        lines.len() as u16 + 2,
        "open a scene (↑↓ choose, Enter opens, Esc cancels)",
        theme.focus,
    );
    let first = p
        .selected
        .saturating_sub(inside.height.saturating_sub(1) as usize);
    f.render_widget(Paragraph::new(lines).scroll((first as u16, 0)), inside);
}

/// A text prompt with its question, the text (cursor shown reversed) and any refusal.
pub fn prompt(app: &App, f: &mut Frame, area: Rect, p: &Prompt, theme: &Theme) {
    let (title, question) = match p.purpose {
        Purpose::Value(at) => {
            let param = row(&app.sim, at);
            let range = match param.kind {
                Kind::Number { min, max, .. } => format!(
                    "{}: a value from {} to {} {}",
                    param.label,
                    fmt_number(min),
                    fmt_number(max),
                    param.unit
                ),
                _ => param.label.to_owned(),
            };
            ("set a value", range)
        }
        Purpose::SavePath => (
            "save scene",
            format!(
                "save {} with its edited parameters as (in {}):",
                app.sim.scene.origin,
                app.cwd.display()
            ),
        ),
        Purpose::OpenPath => ("open a scene file", "path of a scene JSON file:".to_owned()),
    };
    let w = (question
        .chars()
        .count()
        .max(p.text.chars().count() + 2)
        .max(50)
        + 4) as u16;
    let h = if p.error.is_some() { 7 } else { 5 };
    let inside = boxed(f, area, w, h + 2, title, theme.focus);
    let mut text: Vec<Span> = Vec::new();
    let chars: Vec<char> = p.text.chars().collect();
    let before: String = chars[..p.cursor.min(chars.len())].iter().collect();
    let at: String = chars.get(p.cursor).map_or(" ".to_owned(), char::to_string);
    let after: String = chars.iter().skip(p.cursor + 1).collect();
    text.push(Span::styled("> ", theme.key));
    text.push(Span::styled(before, theme.text));
    text.push(Span::styled(at, theme.selected));
    text.push(Span::styled(after, theme.text));
    let mut lines = vec![
        Line::styled(question, theme.text),
        Line::raw(""),
        Line::from(text),
        Line::raw(""),
    ];
    if let Some(e) = &p.error {
        lines.push(Line::styled(e.clone(), theme.error));
        lines.push(Line::raw(""));
    }
    lines.push(Line::styled("Enter accepts, Esc cancels", theme.dim));
    f.render_widget(Paragraph::new(lines).wrap(Wrap { trim: false }), inside);
}

/// "This file exists: overwrite it?"
pub fn confirm(f: &mut Frame, area: Rect, path: &Path, theme: &Theme) {
    let text = format!("{} already exists.", path.display());
    let w = (text.chars().count().max(40) + 4) as u16;
    let inside = boxed(f, area, w, 6, "overwrite?", theme.warn);
    f.render_widget(
        Paragraph::new(vec![
            Line::styled(text, theme.text),
            Line::raw(""),
            Line::from(vec![
                Span::styled("y", theme.key),
                Span::styled(" overwrite it   ", theme.text),
                Span::styled("n", theme.key),
                Span::styled(" choose another name", theme.text),
            ]),
        ]),
        inside,
    );
}

/// What stopped the simulation and how to recover.
pub fn fault(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    let Some(fault) = &app.sim.fault else {
        return;
    };
    let key = |k: &'static str| Span::styled(k, theme.key);
    let txt = |t: &'static str| Span::styled(t, theme.text);
    let mut lines = vec![
        Line::styled(
            format!("At t = {:.3} s: {}.", fault.time, fault.what),
            theme.error,
        ),
        Line::raw(""),
        Line::styled(
            "The simulation is paused; the last good frame is shown. To recover:",
            theme.text,
        ),
        Line::from(vec![
            key("  r  "),
            txt("reset the cloth to its start (your parameters are kept)"),
        ]),
        Line::from(vec![
            key("  ←  "),
            txt("lower ks, or raise steps/frame or density, then r"),
        ]),
        Line::from(vec![
            key("  U  "),
            txt("restore every parameter to the scene's values, then r"),
        ]),
        Line::from(vec![
            key("  Esc"),
            txt(" close this message (stays paused)"),
        ]),
    ];
    if let Some(w) = app.sim.stability_warning() {
        lines.insert(2, Line::styled(format!("Likely cause: {w}."), theme.warn));
    }
    let w = area.width.saturating_sub(4).min(90);
    let text_w = usize::from(w.saturating_sub(2)).max(1);
    let rows: usize = lines
        .iter()
        .map(|l| l.width().max(1).div_ceil(text_w))
        .sum();
    let inside = boxed(
        f,
        area,
        w,
        rows as u16 + 2,
        "simulation stopped",
        theme.error,
    );
    f.render_widget(Paragraph::new(lines).wrap(Wrap { trim: false }), inside);
}

/// The whole screen, when it is too small for the layout.
pub fn too_small(f: &mut Frame, area: Rect, theme: &Theme) {
    let lines = vec![
        Line::styled(
            format!("terminal too small: {} x {}", area.width, area.height),
            theme.warn,
        ),
        Line::styled(
            format!("clothsim needs at least {MIN_WIDTH} x {MIN_HEIGHT}."),
            theme.text,
        ),
        Line::styled("Enlarge the window, or press q to quit.", theme.text),
    ];
    let h = 5.min(area.height);
    let r = Rect {
        y: area.y + (area.height - h) / 2,
        height: h,
        ..area
    };
    f.render_widget(
        Paragraph::new(lines)
            .alignment(Alignment::Center)
            .wrap(Wrap { trim: true }),
        r,
    );
}
