//! Style escapes (SGR, `ESC [ ... m`) written as few and as short as they can be.
//!
//! A [`Pen`] knows the style the terminal is writing with and, asked for another, writes one
//! escape that gets there: either the changes alone (a colour, an attribute turned on or
//! off) or a reset followed by the whole style, whichever is shorter. A run of cells of one
//! style costs one escape or none; an escape never has empty parameters.
//!
//! Colours are written at the depth chosen: the 16 basic colours as their own short codes
//! (`31`, `96`, `44`; crossterm would write `38;5;N` for them), 256-colour indices as `38;5;N`
//! and RGB as `38;2;R;G;B`. On a 16-colour terminal every colour becomes the nearest of the
//! 16 by the one conversion the renderer uses ([`ColorDepth::quantise`]). The escapes do not
//! depend on `NO_COLOR` or any other variable: what to colour was decided by the command
//! line and the environment before anything is drawn.

use cloth_render::{ColorDepth, Rgb, TermColor, xterm_rgb};
use ratatui::style::{Color, Modifier};

/// A cell's style: foreground, background and attributes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Foreground.
    pub fg: Color,
    /// Background.
    pub bg: Color,
    /// Attributes.
    pub modifier: Modifier,
}

impl Default for Style {
    fn default() -> Self {
        Self {
            fg: Color::Reset,
            bg: Color::Reset,
            modifier: Modifier::empty(),
        }
    }
}

/// Attributes with their on and off codes. Bold and dim share their off code (22).
const ATTRIBUTES: [(Modifier, u8, u8); 8] = [
    (Modifier::BOLD, 1, 22),
    (Modifier::DIM, 2, 22),
    (Modifier::ITALIC, 3, 23),
    (Modifier::UNDERLINED, 4, 24),
    (Modifier::SLOW_BLINK, 5, 25),
    (Modifier::REVERSED, 7, 27),
    (Modifier::HIDDEN, 8, 28),
    (Modifier::CROSSED_OUT, 9, 29),
];

/// The style the terminal writes with, and how to change it.
#[derive(Debug, Clone, Copy)]
pub struct Pen {
    /// The current style.
    pub style: Style,
    sixteen: bool,
}

impl Pen {
    /// A pen at the terminal's default style; `sixteen` writes every colour as one of the 16.
    pub fn new(sixteen: bool) -> Self {
        Self {
            style: Style::default(),
            sixteen,
        }
    }

    /// Writes to `out` the one escape that changes the style to `to` (nothing when it is the
    /// current one).
    pub fn set(&mut self, to: Style, out: &mut Vec<u8>) {
        if to == self.style {
            return;
        }
        let from = self.style;
        let mut changes = String::new();
        let removed = from.modifier - to.modifier;
        let mut added = to.modifier - from.modifier;
        if removed.intersects(Modifier::BOLD | Modifier::DIM) {
            // 22 turns both off: whichever of them stays is turned on again.
            added |= to.modifier & (Modifier::BOLD | Modifier::DIM);
        }
        let mut off_intensity = false;
        for (m, _, off) in ATTRIBUTES {
            if removed.contains(m) {
                if off == 22 {
                    if off_intensity {
                        continue;
                    }
                    off_intensity = true;
                }
                push_param(&mut changes, &off.to_string());
            }
        }
        for (m, on, _) in ATTRIBUTES {
            if added.contains(m) {
                push_param(&mut changes, &on.to_string());
            }
        }
        if to.fg != from.fg {
            push_param(&mut changes, &self.color(to.fg, false));
        }
        if to.bg != from.bg {
            push_param(&mut changes, &self.color(to.bg, true));
        }
        let mut reset = String::from("0");
        for (m, on, _) in ATTRIBUTES {
            if to.modifier.contains(m) {
                push_param(&mut reset, &on.to_string());
            }
        }
        if to.fg != Color::Reset {
            push_param(&mut reset, &self.color(to.fg, false));
        }
        if to.bg != Color::Reset {
            push_param(&mut reset, &self.color(to.bg, true));
        }
        let params = if reset.len() <= changes.len() {
            reset
        } else {
            changes
        };
        out.extend_from_slice(b"\x1b[");
        out.extend_from_slice(params.as_bytes());
        out.push(b'm');
        self.style = to;
    }

    /// The SGR parameters of `color` as a foreground (or background) colour.
    fn color(&self, color: Color, background: bool) -> String {
        let basic = |k: u8| basic_code(k, background).to_string();
        let base = if background { 48 } else { 38 };
        let rgb = match color {
            Color::Reset => return if background { "49" } else { "39" }.to_owned(),
            Color::Black => return basic(0),
            Color::Red => return basic(1),
            Color::Green => return basic(2),
            Color::Yellow => return basic(3),
            Color::Blue => return basic(4),
            Color::Magenta => return basic(5),
            Color::Cyan => return basic(6),
            Color::Gray => return basic(7),
            Color::DarkGray => return basic(8),
            Color::LightRed => return basic(9),
            Color::LightGreen => return basic(10),
            Color::LightYellow => return basic(11),
            Color::LightBlue => return basic(12),
            Color::LightMagenta => return basic(13),
            Color::LightCyan => return basic(14),
            Color::White => return basic(15),
            Color::Indexed(i) if i < 16 => return basic(i),
            Color::Indexed(i) if !self.sixteen => return format!("{base};5;{i}"),
            Color::Indexed(i) => xterm_rgb(i),
            Color::Rgb(r, g, b) if !self.sixteen => return format!("{base};2;{r};{g};{b}"),
            Color::Rgb(r, g, b) => Rgb(r, g, b),
        };
        match ColorDepth::Ansi16.quantise(rgb) {
            TermColor::Basic(k) => basic(k),
            // NOTE: quantising to 16 colours gives a basic colour; keep the escape valid
            // should that ever change.
            TermColor::Indexed(_) | TermColor::Rgb(_) => {
                if background { "49" } else { "39" }.to_owned()
            }
        }
    }
}

fn push_param(params: &mut String, p: &str) {
    if !params.is_empty() {
        params.push(';');
    }
    params.push_str(p);
}

/// The SGR code of basic colour `k` (0..16).
fn basic_code(k: u8, background: bool) -> u8 {
    match (k < 8, background) {
        (true, false) => 30 + k,
        (true, true) => 40 + k,
        (false, false) => 90 + k - 8,
        (false, true) => 100 + k - 8,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(sixteen: bool, from: Style, to: Style) -> String {
        let mut pen = Pen::new(sixteen);
        pen.style = from;
        let mut out = Vec::new();
        pen.set(to, &mut out);
        assert_eq!(pen.style, to);
        String::from_utf8(out).unwrap()
    }

    fn fg(c: Color) -> Style {
        Style {
            fg: c,
            ..Style::default()
        }
    }

    #[test]
    fn basic_colours_take_their_short_codes_and_only_what_changed_is_written() {
        let s = Style::default();
        assert_eq!(change(false, s, fg(Color::Red)), "\x1b[31m");
        assert_eq!(change(false, s, fg(Color::Indexed(14))), "\x1b[96m");
        let on_blue = Style {
            bg: Color::Blue,
            ..fg(Color::Red)
        };
        // Only the foreground changes: the background is not written again.
        assert_eq!(
            change(
                false,
                on_blue,
                Style {
                    fg: Color::Green,
                    ..on_blue
                }
            ),
            "\x1b[32m"
        );
        assert_eq!(
            change(false, s, fg(Color::Rgb(1, 2, 3))),
            "\x1b[38;2;1;2;3m"
        );
        assert_eq!(change(false, s, fg(Color::Indexed(137))), "\x1b[38;5;137m");
    }

    #[test]
    fn the_same_style_writes_nothing_and_back_to_default_is_one_plain_reset() {
        let s = fg(Color::Rgb(200, 100, 0));
        assert_eq!(change(false, s, s), "");
        let bold = Style {
            modifier: Modifier::BOLD | Modifier::REVERSED,
            bg: Color::Indexed(17),
            ..s
        };
        assert_eq!(change(false, bold, Style::default()), "\x1b[0m");
    }

    #[test]
    fn turning_bold_off_keeps_dim() {
        let both = Style {
            modifier: Modifier::BOLD | Modifier::DIM,
            fg: Color::Rgb(10, 20, 30),
            ..Style::default()
        };
        let dim = Style {
            modifier: Modifier::DIM,
            ..both
        };
        assert_eq!(change(false, both, dim), "\x1b[22;2m");
    }

    #[test]
    fn on_sixteen_colours_every_colour_is_a_basic_code() {
        let s = Style::default();
        assert_eq!(change(true, s, fg(Color::Rgb(255, 0, 0))), "\x1b[91m");
        let out = change(true, s, fg(Color::Indexed(137)));
        assert!(!out.contains("38;5"), "{out:?}");
        let bg = Style {
            bg: Color::Rgb(0, 0, 0),
            ..s
        };
        assert_eq!(change(true, s, bg), "\x1b[40m");
    }

    #[test]
    fn no_escape_has_an_empty_parameter() {
        let styles = [
            Style::default(),
            fg(Color::Red),
            Style {
                bg: Color::Rgb(1, 1, 1),
                modifier: Modifier::BOLD,
                ..fg(Color::Reset)
            },
            Style {
                modifier: Modifier::REVERSED | Modifier::DIM,
                ..Style::default()
            },
        ];
        for a in styles {
            for b in styles {
                for sixteen in [false, true] {
                    let s = change(sixteen, a, b);
                    assert!(
                        !s.contains("[;") && !s.contains(";;") && !s.contains(";m"),
                        "{s:?}"
                    );
                }
            }
        }
    }
}
