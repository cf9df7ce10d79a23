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

/// A figure in 4 significant digits: fixed between 0.01 and 10 000, else with its exponent
/// (`2.280e-6`), so narrowing the table never cuts the exponent off; `-` when not measured.
pub fn sig(x: f64) -> String {
    if !x.is_finite() {
        return "-".to_owned();
    }
    if x == 0.0 {
        return "0".to_owned();
    }
    let a = x.abs();
    if (0.01..10_000.0).contains(&a) {
        let magnitude = a.log10().floor() as i32;
        let decimals = (3 - magnitude).max(0) as usize;
        let s = format!("{x:.decimals$}");
        // Rounding can reach the next power of ten (9.996 -> 10.00): one decimal fewer.
        let rounded: f64 = s.parse().unwrap_or(x);
        if rounded.abs() >= 10f64.powi(magnitude + 1) && decimals > 0 {
            return format!("{x:.prec$}", prec = decimals - 1);
        }
        return s;
    }
    format!("{x:.3e}")
}

/// Column headers of the table (units in the header, so the cells hold only digits).
const HEADERS: [&str; 5] = ["centre m", "lowest m", "stretch", "kinetic J", "stopped"];

/// The table's text at `width` columns inside its border: the rows' cells and the legend
/// lines that name the variants when their names do not fit (then the rows say A, B, ...).
struct TableText {
    rows: Vec<[String; 6]>,
    widths: [u16; 6],
    legend: Vec<String>,
}

fn table_text(app: &App, width: u16) -> TableText {
    let mut rows: Vec<[String; 6]> = variants(app)
        .into_iter()
        .map(|(title, sim, _)| {
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
            // NOTE: the UI's copy of a worker's state has its positions only, so velocities
            // come from the last frame's sample (taken where the state is whole), not the copy.
            let (kinetic, stretch) = sim
                .history
                .back()
                .map_or((f64::NAN, f64::NAN), |s| (s.kinetic, s.stretch));
            [
                title.to_owned(),
                sig(centre),
                sig(lowest),
                sig(stretch),
                sig(kinetic),
                match &sim.fault {
                    Some(fault) => format!("yes: {}", fault.what),
                    None => "no".to_owned(),
                },
            ]
        })
        .collect();
    let mut widths = [0u16; 6];
    for (k, h) in HEADERS.iter().enumerate() {
        let longest = rows
            .iter()
            .map(|r| r[k + 1].chars().count())
            .max()
            .unwrap_or(0);
        widths[k + 1] = h.len().max(longest) as u16;
    }
    // The numbers come first; "stopped" keeps its header's width, the reason is cut.
    widths[5] = HEADERS[4].len() as u16;
    let spacing = 6;
    let fixed: u16 = widths[1..].iter().sum::<u16>() + spacing;
    let room = width.saturating_sub(fixed);
    let longest_title = rows.iter().map(|r| r[0].chars().count()).max().unwrap_or(0) as u16;
    let mut legend = Vec::new();
    if longest_title.max(7) <= room {
        widths[0] = longest_title.max(7);
        widths[5] += room - widths[0];
    } else {
        // Letters in the rows, the names in a legend below.
        let mut line = String::new();
        for (i, r) in rows.iter_mut().enumerate() {
            let letter = char::from(b'A' + (i % 26) as u8).to_string();
            let entry = format!("{letter} {}", r[0]);
            if !line.is_empty()
                && line.chars().count() + 2 + entry.chars().count() > usize::from(width)
            {
                legend.push(std::mem::take(&mut line));
            }
            if !line.is_empty() {
                line.push_str("  ");
            }
            line.push_str(&entry);
            r[0] = letter;
        }
        if !line.is_empty() {
            legend.push(line);
        }
        widths[0] = room.clamp(1, 7);
        widths[5] += room - widths[0];
    }
    TableText {
        rows,
        widths,
        legend,
    }
}

/// Rows the table needs at `width` columns (border, header, a row per variant, the legend).
pub fn table_height(app: &App, width: u16) -> u16 {
    let t = table_text(app, width.saturating_sub(2));
    (t.rows.len() + t.legend.len() + 3) as u16
}

/// Draws the table: per variant the centre's and the lowest point's heights, the largest
/// stretch, the kinetic energy and whether it stopped; figures in 4 significant digits with
/// their exponents, variant names in a legend when they do not fit.
pub fn table(app: &App, f: &mut Frame, area: Rect, theme: &Theme) {
    if area.height < 3 {
        return;
    }
    let inside = inner(area);
    let t = table_text(app, inside.width);
    let header = Row::new(
        std::iter::once("variant")
            .chain(HEADERS)
            .map(|h| Cell::from(h).style(theme.dim)),
    );
    let stopped: Vec<bool> = variants(app)
        .iter()
        .map(|(_, sim, _)| sim.fault.is_some())
        .collect();
    let rows = t.rows.iter().zip(&stopped).map(|(r, &stop)| {
        let right = |s: &str, w: u16| format!("{s:>w$}", w = usize::from(w));
        Row::new([
            Cell::from(r[0].clone()),
            Cell::from(right(&r[1], t.widths[1])),
            Cell::from(right(&r[2], t.widths[2])),
            Cell::from(right(&r[3], t.widths[3])),
            Cell::from(right(&r[4], t.widths[4])),
            Cell::from(r[5].clone()),
        ])
        .style(if stop { theme.dim } else { theme.text })
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
    let widths = t.widths.map(Constraint::Length);
    let table = Table::new(rows, widths)
        .header(header)
        .column_spacing(1)
        .block(
            Block::bordered()
                .border_style(theme.border)
                .title(Line::styled(format!(" compare: {axes} "), theme.text)),
        );
    f.render_widget(table, area);
    let used = (t.rows.len() + 1) as u16;
    for (i, line) in t.legend.iter().enumerate() {
        let y = inside.y + used + i as u16;
        if y < inside.bottom() {
            f.buffer_mut()
                .set_stringn(inside.x, y, line, usize::from(inside.width), theme.dim);
        }
    }
}
