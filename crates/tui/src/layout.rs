//! Where everything goes on the screen: one pure function of the model and the terminal size,
//! used by the view to draw and by the update to hit-test the mouse.

use ratatui::layout::{Constraint, Direction, Layout as Split, Rect};

use super::model::App;
use super::params::{row, row_count};

/// The smallest terminal the layout fits, columns.
pub const MIN_WIDTH: u16 = 60;
/// The smallest terminal the layout fits, rows.
pub const MIN_HEIGHT: u16 = 16;

/// Fewest rows a compare pane is drawn in (its border and three rows of cloth).
const MIN_PANE: u16 = 5;

/// The screen's regions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Regions {
    /// Status line at the top.
    pub title: Rect,
    /// The cloth panes, with their slot numbers.
    pub panes: Vec<(usize, Rect)>,
    /// The parameter panel.
    pub params: Rect,
    /// The two plots (kinetic energy, stretch); empty when there is no room.
    pub plots: [Rect; 2],
    /// The message line.
    pub note: Rect,
    /// The key footer.
    pub footer: Rect,
    /// Compare mode: one pane per variant, in the study's order (empty otherwise; `panes` is
    /// then empty).
    pub variants: Vec<Rect>,
    /// Compare mode: the table of the variants' figures under their panes.
    pub table: Rect,
}

impl Regions {
    /// The insides of the panes, the variants' panes and the plots: the pictures, which
    /// change all over while the cloth moves (the rest is text).
    pub fn pictures(&self) -> Vec<Rect> {
        self.panes
            .iter()
            .map(|&(_, r)| r)
            .chain(self.variants.iter().copied())
            .chain(self.plots)
            .map(inner)
            .filter(|r| !r.is_empty())
            .collect()
    }
}

/// The regions for `area`, or `None` when it is smaller than [`MIN_WIDTH`] x [`MIN_HEIGHT`].
pub fn regions(app: &App, area: Rect) -> Option<Regions> {
    if area.width < MIN_WIDTH || area.height < MIN_HEIGHT {
        return None;
    }
    // A long message wraps onto up to three lines rather than being cut.
    let note_h = super::view::note_lines(app, area.width).min(3);
    let rows = Split::vertical([
        Constraint::Length(1),
        Constraint::Min(1),
        Constraint::Length(note_h),
        Constraint::Length(1),
    ])
    .split(area);
    let (title, body, note, footer) = (rows[0], rows[1], rows[2], rows[3]);

    let panel_w = if area.width >= 110 { 40 } else { 32 };
    let cols = Split::horizontal([Constraint::Min(1), Constraint::Length(panel_w)]).split(body);
    let (mut views, right) = (cols[0], cols[1]);

    // Rows, border and the selected parameter's help when there is room: a blank line, then
    // as many lines as the longest help takes wrapped, so none is cut (the active solver's
    // option rows included).
    let count = row_count(&app.sim);
    let wanted = count as u16 + 2;
    let help_rows = (0..count)
        .map(|i| {
            wrapped_rows(
                row(&app.sim, i).help,
                usize::from(panel_w.saturating_sub(2)),
            )
        })
        .max()
        .unwrap_or(1) as u16;
    let with_help = wanted + 1 + help_rows;
    let params_h = if right.height >= with_help + 8 {
        with_help
    } else {
        wanted.min(right.height)
    };
    let mut plots = [Rect::default(); 2];
    let params;
    if right.height >= params_h + 8 {
        let r = Split::vertical([Constraint::Length(params_h), Constraint::Min(8)]).split(right);
        params = r[0];
        let p = Split::vertical([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)]).split(r[1]);
        plots = [p[0], p[1]];
    } else {
        params = right;
        if views.height >= 5 + 8 {
            let r = Split::vertical([Constraint::Min(8), Constraint::Length(5)]).split(views);
            views = r[0];
            let p =
                Split::horizontal([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)]).split(r[1]);
            plots = [p[0], p[1]];
        }
    }

    if let Some(c) = &app.compare {
        let n = c.len();
        let columns = c.columns.clamp(1, n);
        let rows = n.div_ceil(columns);
        // The figures first: the table takes the rows it needs, and the panes go when what
        // is left gives each fewer than MIN_PANE rows.
        let table_h = super::view::compare_table_height(app, views.width).min(views.height);
        let mut r = Split::vertical([Constraint::Min(0), Constraint::Length(table_h)]).split(views);
        let mut variants = Vec::with_capacity(n);
        if r[0].height / rows as u16 >= MIN_PANE {
            let row_rects =
                Split::vertical(vec![Constraint::Ratio(1, rows as u32); rows]).split(r[0]);
            for row_rect in row_rects.iter() {
                let cells = Split::horizontal(vec![Constraint::Ratio(1, columns as u32); columns])
                    .split(*row_rect);
                variants.extend(cells.iter().copied());
            }
            variants.truncate(n);
        } else {
            r = Split::vertical([Constraint::Min(0), Constraint::Length(views.height)])
                .split(views);
        }
        return Some(Regions {
            title,
            panes: Vec::new(),
            params,
            plots,
            note,
            footer,
            variants,
            table: r[1],
        });
    }
    let slots = app.visible_slots();
    let rects: Vec<Rect> = match slots.len() {
        1 => vec![views],
        2 => Split::horizontal([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)])
            .split(views)
            .to_vec(),
        _ => {
            let halves =
                Split::vertical([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)]).split(views);
            let mut out = Vec::with_capacity(4);
            for h in halves.iter() {
                out.extend(
                    Split::default()
                        .direction(Direction::Horizontal)
                        .constraints([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)])
                        .split(*h)
                        .iter()
                        .copied(),
                );
            }
            out
        }
    };
    Some(Regions {
        title,
        panes: slots.into_iter().zip(rects).collect(),
        params,
        plots,
        note,
        footer,
        variants: Vec::new(),
        table: Rect::default(),
    })
}

/// Rows `text` takes when word-wrapped at `width` columns (greedy, as ratatui wraps; a word
/// longer than a line is broken).
pub fn wrapped_rows(text: &str, width: usize) -> usize {
    if width == 0 {
        return 0;
    }
    let mut rows = 1;
    let mut used = 0;
    for word in text.split_whitespace() {
        let w = word.chars().count();
        let need = if used == 0 { w } else { used + 1 + w };
        if need <= width {
            used = need;
        } else if w <= width {
            rows += 1;
            used = w;
        } else {
            // Broken across lines.
            let start = if used == 0 { 0 } else { used + 1 };
            let total = start + w;
            if used > 0 && start >= width {
                rows += 1;
                rows += (w - 1) / width;
                used = (w - 1) % width + 1;
            } else {
                rows += (total - 1) / width;
                used = (total - 1) % width + 1;
            }
        }
    }
    rows
}

/// The inside of a bordered pane (where the cloth is drawn).
pub fn inner(r: Rect) -> Rect {
    Rect {
        x: r.x.saturating_add(1),
        y: r.y.saturating_add(1),
        width: r.width.saturating_sub(2),
        height: r.height.saturating_sub(2),
    }
}
