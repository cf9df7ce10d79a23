//! The status line, the message line and the key footer.

use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Wrap};

use crate::keymap::KEYMAP;
use crate::model::{App, Level};
use crate::theme::Theme;

/// `clothsim  pinned4  verlet  RUNNING 1x  t 1.234 s  rtf 1.00  2700 steps/s  30 fps`; in
/// compare mode the time and the rates are the group's (`3 variants rtf 1.00`).
pub fn title(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    let sim = &app.sim;
    let (stopped, time) = match &app.compare {
        Some(c) => {
            let all = sim.fault.is_some() && c.members.iter().all(|m| m.sim.fault.is_some());
            (all, c.clock(sim).1)
        }
        None => (sim.fault.is_some(), sim.time),
    };
    let group = app
        .compare
        .as_ref()
        .map_or_else(String::new, |c| format!("{} variants ", c.len()));
    let (state, style) = if stopped {
        ("STOPPED", theme.error)
    } else if app.running {
        ("RUNNING", theme.running)
    } else {
        ("PAUSED", theme.paused)
    };
    let rate = app.rate();
    let rate = if rate >= 1.0 {
        format!("{rate}x")
    } else {
        format!("1/{}x", (1.0 / rate).round())
    };
    let s = &app.stats;
    // (priority, span): when the line is too wide, the lowest priorities go first.
    let mut fields = vec![
        (2, Span::styled(" clothsim ", theme.key)),
        (
            8,
            Span::styled(format!(" {} ", sim.scene.origin), theme.text),
        ),
        (
            4,
            Span::styled(format!(" {} ", sim.entry().name()), theme.dim),
        ),
        (10, Span::styled(format!(" {state}"), style)),
        (10, Span::styled(format!(" {rate} "), theme.text)),
        (9, Span::styled(format!(" t {time:.3} s "), theme.text)),
    ];
    if let Some(r) = &app.recording {
        let name = r
            .path()
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        fields.push((10, Span::styled(format!(" REC {name} "), theme.error)));
    }
    // NOTE: rates are shown only for a running cloth once measured, so pausing does not
    // leave the last second's figures standing as if current.
    let r = &s.rates;
    if app.running && r.measured {
        if r.lagging {
            fields.push((
                9,
                Span::styled(
                    format!(" {group}slower than real time: {:.2}x ", r.realtime_factor),
                    theme.warn,
                ),
            ));
        } else {
            fields.push((
                7,
                Span::styled(format!(" {group}rtf {:.2} ", r.realtime_factor), theme.text),
            ));
        }
        fields.push((
            5,
            Span::styled(format!(" {:.0} steps/s ", r.steps_per_sec), theme.dim),
        ));
    }
    if s.link.limited {
        let why = if s.link.by_cap {
            "held to --max-rate"
        } else {
            "limited by the terminal"
        };
        fields.push((
            9,
            Span::styled(
                format!(
                    " drawing {why}: {:.0} fps, {:.1} KB/s ",
                    s.draws_per_sec,
                    s.link.bytes_per_sec / 1024.0
                ),
                theme.warn,
            ),
        ));
    } else if s.draws_per_sec > 0.0 {
        fields.push((
            6,
            Span::styled(format!(" {:.0} fps ", s.draws_per_sec), theme.dim),
        ));
    }
    if s.draw_ms > 0.0 {
        fields.push((
            1,
            Span::styled(format!(" draw {:.1} ms ", s.draw_ms), theme.dim),
        ));
    }
    let width = |f: &[(i32, Span)]| f.iter().map(|(_, s)| s.width()).sum::<usize>();
    while fields.len() > 2 && width(&fields) > area.width as usize {
        if let Some(k) = (0..fields.len()).min_by_key(|&k| fields[k].0) {
            fields.remove(k);
        }
    }
    let spans: Vec<Span> = fields.into_iter().map(|(_, s)| s).collect();
    f.render_widget(Paragraph::new(Line::from(spans)), area);
}

/// The latest note, styled by level, as one line (see [`note_lines`]).
pub fn note(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    let Some(n) = &app.note else {
        return;
    };
    let (mark, style) = match n.level {
        Level::Info => ("", theme.info),
        Level::Warn => ("! ", theme.warn),
        Level::Error => ("error: ", theme.error),
    };
    f.render_widget(
        Paragraph::new(Line::styled(format!(" {mark}{}", n.text), style)).wrap(Wrap { trim: true }),
        area,
    );
}

/// Rows the note needs at `width` columns when wrapped (at least one).
pub fn note_lines(app: &App, width: u16) -> u16 {
    let Some(n) = &app.note else {
        return 1;
    };
    let mark = match n.level {
        Level::Info => "",
        Level::Warn => "! ",
        Level::Error => "error: ",
    };
    // NOTE: the mark is counted as the words it is (spaces alone would be dropped between
    // words), and the line's leading space as a column less: counted short, the last words
    // of a note that only just fits would be cut.
    let text = format!("{mark}{}", n.text);
    (crate::layout::wrapped_rows(&text, usize::from(width).saturating_sub(1)) as u16).max(1)
}

/// The footer, from the keymap: as many bindings as fit.
pub fn footer(f: &mut Frame, area: Rect, theme: &Theme) {
    let mut spans = vec![Span::raw(" ")];
    let mut width = 1;
    for (keys, word) in KEYMAP.iter().filter_map(|b| b.footer) {
        let w = keys.chars().count() + word.len() + 3;
        if width + w > area.width as usize {
            break;
        }
        width += w;
        spans.push(Span::styled(keys, theme.key));
        spans.push(Span::styled(format!(" {word}  "), theme.dim));
    }
    f.render_widget(Paragraph::new(Line::from(spans)), area);
}
