//! Boxes drawn over the panes: help, picker, prompt, overwrite question, fault, too small.

use std::path::Path;

use ratatui::Frame;
use ratatui::layout::{Alignment, Rect};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Wrap};

use crate::keymap::{Group, KEYMAP, MOUSE, keys_label};
use crate::layout::{MIN_HEIGHT, MIN_WIDTH};
use crate::model::{App, Picker, Prompt, Purpose, Then};
use crate::params::{Kind, fmt_number, is_option_row, row, row_count};
use crate::theme::Theme;

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

/// The help's text laid out for `area`: its columns, whether there are two, the box's width
/// and the rows.
struct HelpText {
    left: Vec<Line<'static>>,
    right: Vec<Line<'static>>,
    two: bool,
    w: u16,
    rows: u16,
    left_w: u16,
}

/// Columns between the two columns of keys.
const GAP: usize = 4;

fn help_text(area: Rect, theme: &Theme) -> HelpText {
    let key_w = KEYMAP
        .iter()
        .map(|b| keys_label(b).chars().count())
        .chain(MOUSE.iter().map(|(k, _)| k.chars().count()))
        .max()
        .unwrap_or(8);
    let row = |keys: &str, help: &'static str| {
        Line::from(vec![
            Span::styled(format!("  {keys:<key_w$}  "), theme.key),
            Span::styled(help, theme.text),
        ])
    };
    let group_lines = |g: Group| -> Vec<Line<'static>> {
        let mut v = vec![Line::styled(g.title().to_owned(), theme.warn)];
        if g == Group::Hands {
            v.extend(MOUSE.iter().map(|&(k, help)| row(k, help)));
        }
        for b in KEYMAP.iter().filter(|b| b.group == g) {
            v.push(row(&keys_label(b), b.help));
        }
        v
    };
    let all: Vec<Vec<Line>> = Group::ALL.iter().map(|&g| group_lines(g)).collect();
    let width = |lines: &[Line]| lines.iter().map(Line::width).max().unwrap_or(0);
    // Groups one after the other, a blank line between them.
    let join = |groups: &[Vec<Line<'static>>]| -> Vec<Line<'static>> {
        let mut out = Vec::new();
        for (i, g) in groups.iter().enumerate() {
            if i > 0 {
                out.push(Line::raw(""));
            }
            out.extend(g.iter().cloned());
        }
        out
    };
    // Split the groups where the two columns come closest to equal.
    let total: usize = all.iter().map(Vec::len).sum();
    let mut split = 1;
    let mut best = usize::MAX;
    for k in 1..all.len() {
        let left: usize = all[..k].iter().map(Vec::len).sum();
        let diff = left.abs_diff(total - left);
        if diff < best {
            best = diff;
            split = k;
        }
    }
    let (left, right) = (join(&all[..split]), join(&all[split..]));
    let two_w = width(&left) + GAP + width(&right) + 2;
    let two = usize::from(area.width) >= two_w;
    let (left, right) = if two {
        (left, right)
    } else {
        (join(&all), Vec::new())
    };
    let rows = left.len().max(right.len()) as u16;
    let w = if two {
        two_w as u16
    } else {
        width(&left) as u16 + 2
    };
    HelpText {
        left_w: width(&left) as u16,
        left,
        right,
        two,
        w,
        rows,
    }
}

/// How far the help scrolls in `area` before its last row is at the bottom.
pub fn help_scroll_max(area: Rect) -> u16 {
    let t = help_text(area, &Theme::new(false));
    let inside = (t.rows + 2).min(area.height).saturating_sub(2);
    t.rows.saturating_sub(inside)
}

/// The help, generated from [`KEYMAP`]: two columns when wide enough, else one that scrolls;
/// the box fits its text, so it sits centred.
pub fn help(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    let HelpText {
        left,
        right,
        two,
        w,
        rows,
        left_w,
    } = help_text(area, theme);
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
        let lw = left_w;
        f.render_widget(
            Paragraph::new(left).scroll((scroll, 0)),
            Rect {
                width: lw.min(inside.width),
                ..inside
            },
        );
        let x = inside.x + (lw + GAP as u16).min(inside.width);
        f.render_widget(
            Paragraph::new(right).scroll((scroll, 0)),
            Rect {
                x,
                width: inside.right().saturating_sub(x),
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
        let what = if p.states.get(k).copied().unwrap_or(false) {
            "a cloth's state, not a scene: start a scene from it with --from"
        } else {
            "scene file in this folder"
        };
        lines.push(Line::styled(
            format!(" {name:<name_w$}  {what}"),
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
    let mut text: Vec<Span> = Vec::new();
    let chars: Vec<char> = p.text.chars().collect();
    let before: String = chars[..p.cursor.min(chars.len())].iter().collect();
    let at: String = chars.get(p.cursor).map_or(" ".to_owned(), char::to_string);
    let after: String = chars.iter().skip(p.cursor + 1).collect();
    text.push(Span::styled("> ", theme.key));
    if p.selected {
        // The pre-filled value, all selected: typing replaces it.
        text.push(Span::styled(p.text.clone(), theme.selected));
        text.push(Span::styled(" ", theme.text));
    } else {
        text.push(Span::styled(before, theme.text));
        text.push(Span::styled(at, theme.selected));
        text.push(Span::styled(after, theme.text));
    }
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
    let hint = if p.selected {
        "type to replace, ←→ to edit; Enter accepts, Esc cancels"
    } else {
        "Enter accepts, Esc cancels; C-u clears, C-w deletes a word"
    };
    lines.push(Line::styled(hint, theme.dim));
    // The box is as wide as its longest line (the screen allowing) and as tall as its lines
    // wrapped, so no line is cut.
    let w = (lines.iter().map(Line::width).max().unwrap_or(0).max(50) + 4)
        .min(usize::from(area.width)) as u16;
    let h = rows_of(&lines, w);
    let inside = boxed(f, area, w, h + 2, title, theme.focus);
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

/// Lines in a box of `w` columns (two of them border), wrapped: how many rows they take.
fn rows_of(lines: &[Line], w: u16) -> u16 {
    let text_w = usize::from(w.saturating_sub(2)).max(1);
    lines
        .iter()
        .map(|l| {
            let s: String = l.spans.iter().map(|s| s.content.as_ref()).collect();
            crate::layout::wrapped_rows(&s, text_w).max(1)
        })
        .sum::<usize>() as u16
}

/// "Discard the unsaved edits?" before quitting or opening another scene.
pub fn discard(app: &App, f: &mut Frame, area: Rect, then: Then, theme: &Theme) {
    let key = |k: &'static str| Span::styled(k, theme.key);
    let txt = |t: &'static str| Span::styled(t, theme.text);
    let (what, again) = match then {
        Then::Quit => ("quit", "q"),
        Then::Open => ("open another scene", "o"),
    };
    // NOTE: option rows are the active solver's; after a solver switch the solver row says
    // it, and the saved options (another solver's) are not compared.
    let same_solver = app.sim.entry().name() == app.saved.1;
    let edited: Vec<&str> = (0..row_count(&app.sim))
        .map(|i| (i, row(&app.sim, i)))
        .filter(|(i, p)| match p.kind {
            Kind::Solver => !same_solver,
            _ if is_option_row(&app.sim, *i) && !same_solver => false,
            _ => (p.get)(&app.sim.settings) != (p.get)(&app.saved.0),
        })
        .map(|(_, p)| p.label)
        .collect();
    let lines = vec![
        Line::styled(
            format!(
                "{} has unsaved edits ({}).",
                app.sim.scene.origin,
                edited.join(", ")
            ),
            theme.text,
        ),
        Line::raw(""),
        Line::from(vec![
            key(again),
            txt(", "),
            key("y"),
            Span::styled(format!("    {what} and discard them"), theme.text),
        ]),
        Line::from(vec![key("S"), txt("       save them first")]),
        Line::from(vec![key("Esc"), txt(", "), key("n"), txt("  keep editing")]),
    ];
    let w = area.width.saturating_sub(4).min(72);
    let inside = boxed(
        f,
        area,
        w,
        rows_of(&lines, w) + 2,
        "unsaved edits",
        theme.warn,
    );
    f.render_widget(Paragraph::new(lines).wrap(Wrap { trim: false }), inside);
}

/// "This cloth is big: open it?"
pub fn big(app: &App, f: &mut Frame, area: Rect, points: usize, theme: &Theme) {
    let name = app
        .big
        .as_ref()
        .map_or_else(String::new, |s| s.origin.clone());
    // The estimate the memory check uses: the solver's, the cloth's states and the drawing.
    let need = app
        .big
        .as_ref()
        .and_then(|s| crate::update::scene_need(app, s))
        .map_or_else(
            || "an unknown amount of memory".to_owned(),
            |(_, n)| format!("about {}", cloth_run::memory::human_bytes(n.total())),
        );
    let lines = vec![
        Line::styled(
            format!(
                "{name} has {points} points (more than {}). It will likely run slower than \
                 real time and needs {need}; the keys still answer at once.",
                crate::update::BIG_CLOTH
            ),
            theme.text,
        ),
        Line::raw(""),
        Line::from(vec![
            Span::styled("y", theme.key),
            Span::styled(" open it   ", theme.text),
            Span::styled("n", theme.key),
            Span::styled(" or ", theme.text),
            Span::styled("Esc", theme.key),
            Span::styled(" keep the current scene", theme.text),
        ]),
    ];
    let w = area.width.saturating_sub(4).min(72);
    let inside = boxed(
        f,
        area,
        w,
        rows_of(&lines, w) + 2,
        "a big cloth",
        theme.warn,
    );
    f.render_widget(Paragraph::new(lines).wrap(Wrap { trim: false }), inside);
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
        Line::styled(format!("What to change: {}.", fault.advice), theme.warn),
        Line::raw(""),
        Line::styled(
            "The simulation is paused; the last good frame is shown.",
            theme.text,
        ),
        Line::from(vec![
            key("  r      "),
            txt("reset the cloth to its start (your parameters are kept)"),
        ]),
        Line::from(vec![
            key("  ↑↓ ←→  "),
            txt("select and change a parameter here; Enter types a value"),
        ]),
        Line::from(vec![
            key("  u U    "),
            txt("undo the last edit / restore the scene's values"),
        ]),
    ];
    if fault.resumable {
        lines.push(Line::from(vec![
            key("  space  "),
            txt("go on anyway (this test stays off until r)"),
        ]));
    }
    lines.push(Line::from(vec![
        key("  Esc    "),
        txt("close this message (stays paused)"),
    ]));
    let w = area.width.saturating_sub(4).min(90);
    let rows = rows_of(&lines, w);
    let inside = boxed(f, area, w, rows + 2, "simulation stopped", theme.error);
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
