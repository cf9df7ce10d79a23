//! What the terminal shows, and the bytes that bring it to what the UI wants.
//!
//! ratatui renders each frame into a buffer; [`Screen`] (the ratatui backend) writes nothing
//! when ratatui draws. The loop then hands the finished buffer to [`Screen::present`], which
//! compares it with what the terminal was last sent ([`Painter`]) and writes the cells that
//! differ: one style escape per run of equal style ([`super::sgr::Pen`]), short cursor moves,
//! and at most a byte budget when the link to the terminal is slow. What is left over is
//! written by the next present, so a frame cut short is finished rather than lost, and the
//! text (the header's PAUSED, a note, a dialog's line: where a key's answer shows) goes before
//! the pictures (the cloth panes and the plots), whose cells change all over while the cloth
//! moves.

use std::io::{self, Write};

use ratatui::backend::{Backend, ClearType, WindowSize};
use ratatui::buffer::{Buffer, Cell, CellDiffOption};
use ratatui::layout::{Position, Rect, Size};

use super::sgr::{Pen, Style};

/// The status query: the terminal answers `ESC [ row ; col R` once it has taken every byte
/// before it.
pub const STATUS_QUERY: &[u8] = b"\x1b[6n";

/// Two 24-bit colours this close (in every channel, out of 255) are written as one: 3 % of
/// the range, below what a shaded glyph shows, and the difference between a run of cells
/// that shares one escape and a run that needs one per cell.
pub const NEAR: u8 = 8;

/// A row counts as lightly changed (and goes first) when at most this share of it changed.
const LIGHT: usize = 4;

/// Cells of what the terminal shows, and the bytes that change them.
#[derive(Debug, Clone)]
pub struct Painter {
    /// What the terminal was sent.
    shown: Buffer,
    pen: Pen,
    /// Where the terminal's cursor is, when known.
    cursor: Option<(u16, u16)>,
    /// Where the last cut-short present stopped, so the next goes on from there.
    resume_row: u16,
}

/// What a present wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Painted {
    /// Bytes written.
    pub bytes: usize,
    /// Whether cells still differ (the budget ran out).
    pub unfinished: bool,
}

impl Painter {
    /// A painter for a blank screen of `area`; `sixteen` writes colours as the basic 16.
    pub fn new(area: Rect, sixteen: bool) -> Self {
        Self {
            shown: Buffer::empty(area),
            pen: Pen::new(sixteen),
            cursor: None,
            resume_row: 0,
        }
    }

    /// Forgets what the terminal shows: it has just been cleared to `area`.
    pub fn cleared(&mut self, area: Rect) {
        self.shown = Buffer::empty(area);
        self.pen.style = Style::default();
        self.cursor = None;
        self.resume_row = 0;
    }

    /// Appends to `out` the bytes that make the terminal show `want`, stopping once `out` has
    /// grown by `budget` bytes (whole cells only). The style is back to the default at the end.
    ///
    /// Cells outside `pictures` (the text: the header, notes, the panel, the footer) are
    /// written first, top to bottom; then the pictures' cells, their lightly changed rows
    /// first, the rest from where the last cut-short present stopped, round the screen.
    pub fn paint(
        &mut self,
        want: &Buffer,
        budget: Option<usize>,
        pictures: &[Rect],
        out: &mut Vec<u8>,
    ) -> Painted {
        let start = out.len();
        if want.area != self.shown.area {
            out.extend_from_slice(b"\x1b[0m\x1b[2J");
            self.cleared(want.area);
        }
        let area = want.area;
        let in_picture = |x: u16, y: u16| {
            pictures
                .iter()
                .any(|r| r.contains(ratatui::layout::Position { x, y }))
        };
        // NOTE: a key's answer is text (PAUSED in the header, a note, a panel row) and is
        // often a whole row shifted (RUNNING is a letter longer than PAUSED); were it ranked
        // with the pictures' rows by how much changed, a moving cloth would keep it waiting
        // for its turn round the screen, seconds over a slow link.
        let mut text = Vec::new();
        let mut light = Vec::new();
        let mut heavy = Vec::new();
        for y in area.top()..area.bottom() {
            let (mut words, mut picture, mut width) = (0, 0, 0);
            for x in area.left()..area.right() {
                let p = in_picture(x, y);
                width += usize::from(p);
                if differs(&self.shown, want, x, y) {
                    if p {
                        picture += 1;
                    } else {
                        words += 1;
                    }
                }
            }
            if words > 0 {
                text.push((y, false));
            }
            if picture == 0 {
                continue;
            }
            if picture * LIGHT <= width {
                light.push((y, true));
            } else {
                heavy.push((y, true));
            }
        }
        let pivot = heavy
            .iter()
            .position(|&(y, _)| y >= self.resume_row)
            .unwrap_or(0);
        heavy.rotate_left(pivot);
        let limit = budget.map_or(usize::MAX, |b| start.saturating_add(b));
        let mut unfinished = false;
        'rows: for (y, pictured) in text.into_iter().chain(light).chain(heavy) {
            let mut x = area.left();
            while x < area.right() {
                if in_picture(x, y) != pictured || !differs(&self.shown, want, x, y) {
                    x += 1;
                    continue;
                }
                if out.len() >= limit {
                    unfinished = true;
                    if pictured {
                        self.resume_row = y;
                    }
                    break 'rows;
                }
                self.move_to(x, y, want, out);
                let mut cell = want[(x, y)].clone();
                // A foreground near the pen's is written in the pen's: one escape per run.
                if near(self.pen.style.fg, cell.fg)
                    && self.pen.style.bg == cell.bg
                    && self.pen.style.modifier == cell.modifier
                {
                    cell.fg = self.pen.style.fg;
                }
                self.pen.set(style_of(&cell), out);
                out.extend_from_slice(cell.symbol().as_bytes());
                let w = cell_width(&cell);
                for k in 0..w {
                    if let Some(c) = self.shown.cell_mut((x + k, y)) {
                        if k == 0 {
                            c.clone_from(&cell);
                        } else {
                            // Covered by the wide character.
                            c.reset();
                            c.set_symbol("");
                        }
                    }
                }
                x += w.max(1);
                self.cursor = if x >= area.right() {
                    // At the right edge the terminal's cursor waits to wrap: move explicitly.
                    None
                } else {
                    Some((x, y))
                };
            }
        }
        if !unfinished {
            self.resume_row = 0;
        }
        self.pen.set(Style::default(), out);
        Painted {
            bytes: out.len() - start,
            unfinished,
        }
    }

    /// Moves the cursor to `(x, y)` by the shortest of: nothing, printing the unchanged cells
    /// in between (when they are few, narrow and in the pen's style), a move right, or an
    /// absolute move.
    fn move_to(&mut self, x: u16, y: u16, want: &Buffer, out: &mut Vec<u8>) {
        if let Some((cx, cy)) = self.cursor
            && cy == y
            && cx <= x
        {
            if cx == x {
                return;
            }
            let gap = x - cx;
            let forward = if gap == 1 {
                3
            } else {
                3 + gap.to_string().len()
            };
            let reprint: Option<Vec<u8>> = (cx..x)
                .map(|gx| {
                    let c = &want[(gx, y)];
                    (style_of(c) == self.pen.style && c.symbol().len() == 1 && cell_width(c) == 1)
                        .then(|| c.symbol().as_bytes()[0])
                })
                .collect();
            match reprint {
                Some(bytes) if bytes.len() <= forward => {
                    out.extend_from_slice(&bytes);
                    // The reprinted cells are now what the terminal shows, changed or not.
                    for gx in cx..x {
                        if let Some(c) = self.shown.cell_mut((gx, y)) {
                            c.clone_from(&want[(gx, y)]);
                        }
                    }
                }
                _ if gap == 1 => out.extend_from_slice(b"\x1b[C"),
                _ => out.extend_from_slice(format!("\x1b[{gap}C").as_bytes()),
            }
            return;
        }
        out.extend_from_slice(format!("\x1b[{};{}H", y + 1, x + 1).as_bytes());
    }
}

/// The cell's style.
fn style_of(cell: &Cell) -> Style {
    Style {
        fg: cell.fg,
        bg: cell.bg,
        modifier: cell.modifier,
    }
}

/// Columns the cell's symbol takes.
fn cell_width(cell: &Cell) -> u16 {
    use unicode_width::UnicodeWidthStr;
    u16::try_from(cell.symbol().width()).unwrap_or(1)
}

/// Whether the cell at `(x, y)` must be written: it differs from what was sent and is not a
/// cell covered by a wide character (nor one ratatui was told to leave alone).
fn differs(shown: &Buffer, want: &Buffer, x: u16, y: u16) -> bool {
    let w = &want[(x, y)];
    if w.diff_option == CellDiffOption::Skip {
        return false;
    }
    if x > want.area.left() && cell_width(&want[(x - 1, y)]) > 1 {
        return false;
    }
    let s = &shown[(x, y)];
    s.symbol() != w.symbol() || !near(s.fg, w.fg) || s.bg != w.bg || s.modifier != w.modifier
}

/// Whether `a` may stand for `b`: the same colour, or 24-bit colours within [`NEAR`].
pub fn near(a: ratatui::style::Color, b: ratatui::style::Color) -> bool {
    use ratatui::style::Color::Rgb;
    match (a, b) {
        (Rgb(r1, g1, b1), Rgb(r2, g2, b2)) => {
            r1.abs_diff(r2) <= NEAR && g1.abs_diff(g2) <= NEAR && b1.abs_diff(b2) <= NEAR
        }
        _ => a == b,
    }
}

/// The ratatui backend on the terminal's output: ratatui's draw writes nothing (the loop
/// presents the finished buffer); the rest (clearing, the cursor, the size) goes to the
/// terminal at once.
pub struct Screen<W: Write> {
    out: W,
    painter: Painter,
    /// A size to report instead of asking the terminal (tests).
    fixed: Option<Size>,
}

impl<W: Write> Screen<W> {
    /// A screen writing to `out`; `sixteen` writes colours as the basic 16.
    pub fn new(out: W, sixteen: bool) -> Self {
        Self {
            out,
            painter: Painter::new(Rect::default(), sixteen),
            fixed: None,
        }
    }

    /// A screen of a fixed size that never asks the terminal (for tests).
    #[cfg(test)]
    pub fn fixed(out: W, sixteen: bool, width: u16, height: u16) -> Self {
        Self {
            fixed: Some(Size::new(width, height)),
            ..Self::new(out, sixteen)
        }
    }

    /// The writer.
    #[cfg(test)]
    pub fn writer(&self) -> &W {
        &self.out
    }

    /// Writes to the terminal what changes it to `want` (at most `budget` bytes of cells, the
    /// text before the `pictures`), inside a synchronized update, then the status query when
    /// `query`; all in one write.
    ///
    /// # Errors
    /// When the terminal cannot be written.
    pub fn present(
        &mut self,
        want: &Buffer,
        budget: Option<usize>,
        pictures: &[Rect],
        query: bool,
    ) -> io::Result<Painted> {
        let mut bytes = Vec::new();
        bytes.extend_from_slice(b"\x1b[?2026h");
        let painted = self.painter.paint(want, budget, pictures, &mut bytes);
        if painted.bytes == 0 {
            bytes.clear();
        } else {
            bytes.extend_from_slice(b"\x1b[?2026l");
        }
        if query && !bytes.is_empty() {
            bytes.extend_from_slice(STATUS_QUERY);
        }
        if !bytes.is_empty() {
            self.out.write_all(&bytes)?;
            self.out.flush()?;
        }
        Ok(Painted {
            bytes: bytes.len(),
            unfinished: painted.unfinished,
        })
    }

    /// Writes `bytes` to the terminal at once.
    ///
    /// # Errors
    /// When the terminal cannot be written.
    pub fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.out.write_all(bytes)?;
        self.out.flush()
    }

    fn area(&self) -> io::Result<Rect> {
        let s = self.size()?;
        Ok(Rect::new(0, 0, s.width, s.height))
    }
}

impl<W: Write> Backend for Screen<W> {
    type Error = io::Error;

    fn draw<'a, I>(&mut self, _content: I) -> io::Result<()>
    where
        I: Iterator<Item = (u16, u16, &'a Cell)>,
    {
        Ok(())
    }

    fn hide_cursor(&mut self) -> io::Result<()> {
        self.send(b"\x1b[?25l")
    }

    fn show_cursor(&mut self) -> io::Result<()> {
        self.send(b"\x1b[?25h")
    }

    fn get_cursor_position(&mut self) -> io::Result<Position> {
        // NOTE: the answer to a cursor query arrives with the keys, on the input thread; the
        // UI never needs to ask, so ratatui is told the top left.
        Ok(Position::ORIGIN)
    }

    fn set_cursor_position<P: Into<Position>>(&mut self, position: P) -> io::Result<()> {
        let p = position.into();
        self.painter.cursor = Some((p.x, p.y));
        self.send(format!("\x1b[{};{}H", p.y + 1, p.x + 1).as_bytes())
    }

    fn clear(&mut self) -> io::Result<()> {
        self.send(b"\x1b[0m\x1b[2J")?;
        let area = self.area()?;
        self.painter.cleared(area);
        Ok(())
    }

    fn clear_region(&mut self, _clear_type: ClearType) -> io::Result<()> {
        // A full-screen UI clears only all of it; clearing all keeps what is known right.
        self.clear()
    }

    fn size(&self) -> io::Result<Size> {
        if let Some(s) = self.fixed {
            return Ok(s);
        }
        let (width, height) = ratatui::crossterm::terminal::size()?;
        Ok(Size { width, height })
    }

    fn window_size(&mut self) -> io::Result<WindowSize> {
        let columns_rows = self.size()?;
        let pixels =
            ratatui::crossterm::terminal::window_size().map_or(Size::default(), |w| Size {
                width: w.width,
                height: w.height,
            });
        Ok(WindowSize {
            columns_rows,
            pixels,
        })
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    fn append_lines(&mut self, _n: u16) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use ratatui::Terminal;
    use ratatui::style::{Color, Modifier, Style as RStyle};

    /// A small terminal: the text of each cell and the cursor; colours are not kept.
    pub(crate) struct Model {
        cells: Vec<Vec<String>>,
        x: usize,
        y: usize,
        /// Status queries seen.
        pub queries: usize,
    }

    impl Model {
        pub(crate) fn new(width: u16, height: u16) -> Self {
            Self {
                cells: vec![vec![" ".to_owned(); usize::from(width)]; usize::from(height)],
                x: 0,
                y: 0,
                queries: 0,
            }
        }

        pub(crate) fn replay(bytes: &[u8], width: u16, height: u16) -> Self {
            let mut m = Self::new(width, height);
            m.feed(bytes);
            m
        }

        pub(crate) fn rows(&self) -> Vec<String> {
            self.cells.iter().map(|r| r.concat()).collect()
        }

        pub(crate) fn feed(&mut self, bytes: &[u8]) {
            let text = std::str::from_utf8(bytes).expect("whole UTF-8 characters");
            let mut chars = text.chars().peekable();
            while let Some(c) = chars.next() {
                match c {
                    '\x1b' => {
                        assert_eq!(chars.next(), Some('['), "only CSI sequences are written");
                        let mut params = String::new();
                        let fin = loop {
                            let c = chars.next().expect("a whole sequence");
                            if ('\x40'..='\x7e').contains(&c) {
                                break c;
                            }
                            params.push(c);
                        };
                        let n: Vec<usize> = params
                            .trim_start_matches('?')
                            .split(';')
                            .map(|p| p.parse().unwrap_or(0))
                            .collect();
                        match fin {
                            'H' => {
                                self.y = n[0].max(1) - 1;
                                self.x = n.get(1).copied().unwrap_or(1).max(1) - 1;
                            }
                            'C' => self.x += n[0].max(1),
                            'J' => {
                                for row in &mut self.cells {
                                    row.fill(" ".to_owned());
                                }
                            }
                            'n' => self.queries += 1,
                            'm' => assert!(
                                !params.starts_with(';')
                                    && !params.ends_with(';')
                                    && !params.contains(";;"),
                                "an empty SGR parameter: {params:?}"
                            ),
                            _ => {}
                        }
                    }
                    '\r' => self.x = 0,
                    '\n' => self.y += 1,
                    c => {
                        if let Some(cell) =
                            self.cells.get_mut(self.y).and_then(|r| r.get_mut(self.x))
                        {
                            *cell = c.to_string();
                        }
                        self.x += 1;
                    }
                }
            }
        }
    }

    fn text_of(b: &Buffer) -> Vec<String> {
        (b.area.top()..b.area.bottom())
            .map(|y| {
                (b.area.left()..b.area.right())
                    .map(|x| b[(x, y)].symbol().to_owned())
                    .collect()
            })
            .collect()
    }

    /// A screenful of shifting text and colours: frame `k` of a made-up animation.
    fn frame(k: u16, w: u16, h: u16) -> Buffer {
        let mut b = Buffer::empty(Rect::new(0, 0, w, h));
        b.set_string(
            0,
            0,
            format!("clothsim RUNNING t {k}"),
            RStyle::default().bold(),
        );
        for y in 2..h - 1 {
            for x in 0..w {
                let v = (x + 2 * y + k) % 11;
                if v < 6 {
                    let glyph = ["#", "%", "*", "+", "=", "-"][usize::from(v)];
                    let c = RStyle::default().fg(Color::Rgb((v * 40) as u8, 100, 200));
                    b.set_string(x, y, glyph, c);
                }
            }
        }
        b.set_string(
            0,
            h - 1,
            "space pause  q quit",
            RStyle::default().fg(Color::Cyan),
        );
        b
    }

    #[test]
    fn painting_leaves_the_terminal_showing_each_frame() {
        let (w, h) = (40, 12);
        let mut p = Painter::new(Rect::new(0, 0, w, h), false);
        let mut m = Model::new(w, h);
        for k in 0..20 {
            let b = frame(k, w, h);
            let mut out = Vec::new();
            let painted = p.paint(&b, None, &[], &mut out);
            assert!(!painted.unfinished);
            m.feed(&out);
            assert_eq!(m.rows(), text_of(&b), "frame {k}");
        }
    }

    #[test]
    fn a_budget_cuts_a_frame_and_the_next_paints_finish_it_light_rows_first() {
        let (w, h) = (40, 12);
        let mut p = Painter::new(Rect::new(0, 0, w, h), false);
        let mut m = Model::new(w, h);
        let mut out = Vec::new();
        p.paint(&frame(0, w, h), None, &[], &mut out);
        m.feed(&out);
        let b = frame(5, w, h);
        let mut rounds = 0;
        loop {
            let mut out = Vec::new();
            let painted = p.paint(&b, Some(120), &[], &mut out);
            // A cell's bytes may pass the budget, never by more than one cell and the reset.
            assert!(out.len() <= 120 + 40, "{}", out.len());
            m.feed(&out);
            if rounds == 0 {
                // The header changed little: it is written first.
                assert_eq!(m.rows()[0], text_of(&b)[0]);
            }
            rounds += 1;
            if !painted.unfinished {
                break;
            }
            assert!(rounds < 100, "the frame never finishes");
        }
        assert!(rounds > 3, "{rounds}");
        assert_eq!(m.rows(), text_of(&b));
    }

    /// Frame `k` with `header` (padded to the width) on its top row.
    fn with_header(k: u16, w: u16, h: u16, header: &str) -> Buffer {
        let mut b = frame(k, w, h);
        let line = format!("{header:<width$}", width = usize::from(w));
        b.set_string(0, 0, line, RStyle::default().bold());
        b
    }

    #[test]
    fn text_goes_before_the_pictures_however_much_of_its_row_changed() {
        // A header shifted by a letter (PAUSED to RUNNING) changes its whole row, as much as
        // a moving cloth changes each of its rows.
        let (w, h) = (60, 16);
        let picture = Rect::new(0, 2, w, h - 3);
        let mut p = Painter::new(Rect::new(0, 0, w, h), false);
        let mut m = Model::new(w, h);
        let paused = " clothsim  pinned4  verlet  PAUSED 1x  t 3.556 s  draw 2.4 ms";
        let running = " clothsim  pinned4  verlet  RUNNING 1x  t 3.556 s  draw 2.4 ms";
        let mut out = Vec::new();
        p.paint(&with_header(0, w, h, paused), None, &[picture], &mut out);
        m.feed(&out);
        // The cloth moves and the link is slow: a frame is cut part way down the picture.
        let mut out = Vec::new();
        let cut = p.paint(
            &with_header(3, w, h, paused),
            Some(300),
            &[picture],
            &mut out,
        );
        assert!(cut.unfinished && p.resume_row > 0, "{}", p.resume_row);
        m.feed(&out);
        // Space: the next frame's budget goes to the header before any of the cloth.
        let b = with_header(6, w, h, running);
        let mut out = Vec::new();
        let painted = p.paint(&b, Some(300), &[picture], &mut out);
        m.feed(&out);
        assert!(
            painted.unfinished,
            "the budget is less than the cloth's change"
        );
        assert_eq!(m.rows()[0], text_of(&b)[0], "the header is written whole");
        assert_eq!(
            m.rows()[h as usize - 1],
            text_of(&b)[h as usize - 1],
            "so is the footer"
        );
    }

    #[test]
    fn wide_characters_and_a_resize_are_painted_right() {
        let mut p = Painter::new(Rect::new(0, 0, 6, 2), false);
        let mut b = Buffer::empty(Rect::new(0, 0, 8, 2));
        b.set_string(0, 0, "a界b", RStyle::default());
        let mut out = Vec::new();
        p.paint(&b, None, &[], &mut out);
        let m = Model::replay(&out, 8, 2);
        // The model gives every character one cell; the terminal gives 界 two.
        assert!(String::from_utf8(out.clone()).unwrap().contains("a界"));
        assert_eq!(m.rows()[0].chars().next(), Some('a'));
        assert!(
            out.starts_with(b"\x1b[0m\x1b[2J"),
            "a new size clears first"
        );
    }

    /// A writer whose bytes can be read while a backend owns it.
    #[derive(Clone, Default)]
    struct Shared(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            self.0.borrow_mut().extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    /// The bytes of `frames` drawn at 100 x 30 by ratatui's crossterm backend (as the UI
    /// drew before, in a synchronized update) and by [`Screen::present`].
    fn bytes_both_ways(frames: &[Buffer]) -> (usize, usize) {
        use ratatui::backend::CrosstermBackend;
        use ratatui::{TerminalOptions, Viewport};
        let area = frames[0].area;
        let fixed = || TerminalOptions {
            viewport: Viewport::Fixed(area),
        };
        let sink = Shared::default();
        let mut old = Terminal::with_options(CrosstermBackend::new(sink.clone()), fixed()).unwrap();
        let mut new = Terminal::with_options(
            Screen::fixed(Vec::new(), false, area.width, area.height),
            fixed(),
        )
        .unwrap();
        let mut sync = 0;
        for f in frames {
            old.draw(|fr| fr.buffer_mut().merge(f)).unwrap();
            sync += b"\x1b[?2026h\x1b[?2026l".len();
            let drawn = new
                .draw(|fr| fr.buffer_mut().merge(f))
                .unwrap()
                .buffer
                .clone();
            new.backend_mut().present(&drawn, None, &[], true).unwrap();
        }
        (sink.0.borrow().len() + sync, new.backend().writer().len())
    }

    #[test]
    fn a_truecolour_fall_at_100_by_30_takes_at_most_half_the_bytes_it_took() {
        let mut app = crate::tests::coloured_app("pinned4", cloth_render::ColorChoice::TrueColor);
        let mut frames = Vec::new();
        // Two seconds of the fall, a frame drawn per simulated frame.
        for _ in 0..60 {
            crate::tests::step_frame(&mut app);
            frames.push(crate::tests::buffer_of(&mut app, 100, 30));
        }
        let (old, new) = bytes_both_ways(&frames);
        eprintln!("{new} bytes now, {old} before");
        assert!(new * 2 <= old, "{new} bytes now, {old} before");
        // The screen the bytes leave is the app's: the same glyphs, every colour within
        // NEAR of the one the renderer chose.
        let mut p = Painter::new(frames[0].area, false);
        let mut m = Model::new(100, 30);
        for f in &frames {
            let mut out = Vec::new();
            p.paint(f, None, &[], &mut out);
            m.feed(&out);
            assert_eq!(m.rows(), text_of(f));
            for (shown, want) in p.shown.content.iter().zip(&f.content) {
                assert!(near(shown.fg, want.fg), "{:?} for {:?}", shown.fg, want.fg);
                assert_eq!((shown.bg, shown.modifier), (want.bg, want.modifier));
            }
        }
    }

    #[test]
    fn sixteen_colour_screens_get_only_basic_colour_codes() {
        let mut b = Buffer::empty(Rect::new(0, 0, 4, 1));
        b.set_string(0, 0, "ab", RStyle::default().fg(Color::Rgb(250, 10, 10)));
        b.set_string(
            2,
            0,
            "cd",
            RStyle::default()
                .bg(Color::Indexed(137))
                .add_modifier(Modifier::BOLD),
        );
        let mut out = Vec::new();
        Painter::new(b.area, true).paint(&b, None, &[], &mut out);
        let s = String::from_utf8(out).unwrap();
        assert!(!s.contains("38;") && !s.contains("48;"), "{s:?}");
        assert!(s.contains("91m"), "{s:?}");
    }
}
