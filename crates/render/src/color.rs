//! Colour choice (`--color`), terminal colour depth and quantisation of [`Rgb`] to SGR codes.
//!
//! This is the one colour conversion of clothsim: the headless `render` command writes its
//! escapes with it, and the live UI turns the cloth's colours (and, on a 16-colour terminal,
//! every colour it writes) into terminal colours with it.

use std::fmt::{self, Write};
use std::str::FromStr;

use crate::{RenderError, Rgb};

/// What the user asked for with `--color`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorChoice {
    /// Colour when writing to a terminal that has it, unless the environment says otherwise
    /// (`NO_COLOR`, `CLICOLOR`, `CLICOLOR_FORCE`); depth from `COLORTERM` and `TERM`.
    #[default]
    Auto,
    /// Colour whatever the output and the environment; depth from `COLORTERM` and `TERM`.
    Always,
    /// Glyphs only.
    Never,
    /// The 16 standard ANSI colours.
    Ansi16,
    /// The xterm 256-colour palette.
    Ansi256,
    /// 24-bit colour.
    TrueColor,
}

/// How many colours the output may use, after [`ColorChoice::resolve`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorDepth {
    /// No colour: glyphs only.
    #[default]
    None,
    /// 16 colours.
    Ansi16,
    /// 256 colours.
    Ansi256,
    /// 24-bit colour.
    TrueColor,
}

/// The environment variables that decide colour, as read by the caller (this crate does no
/// I/O): `ColorEnv::read(|k| std::env::var(k).ok())`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ColorEnv {
    /// `NO_COLOR`: set and non-empty turns colour off (no-color.org).
    pub no_color: Option<String>,
    /// `CLICOLOR`: `0` turns colour off (bixense.com/clicolors).
    pub clicolor: Option<String>,
    /// `CLICOLOR_FORCE`: set, non-empty and not `0` turns colour on even off a terminal.
    pub clicolor_force: Option<String>,
    /// `COLORTERM`: `truecolor` or `24bit` means 24-bit colour.
    pub colorterm: Option<String>,
    /// `TERM`: `dumb` (or unset) has no colour, `*256color*` has 256, others 16.
    pub term: Option<String>,
}

impl ColorEnv {
    /// Reads the variables with `get` (a name to its value).
    pub fn read(get: impl Fn(&str) -> Option<String>) -> Self {
        Self {
            no_color: get("NO_COLOR"),
            clicolor: get("CLICOLOR"),
            clicolor_force: get("CLICOLOR_FORCE"),
            colorterm: get("COLORTERM"),
            term: get("TERM"),
        }
    }

    /// Whether `TERM` names a terminal without colour or cursor addressing (`dumb`, or none).
    pub fn dumb_terminal(&self) -> bool {
        self.term
            .as_deref()
            .is_none_or(|t| t.is_empty() || t == "dumb")
    }

    /// The most colours the terminal shows, from `COLORTERM` and `TERM`.
    pub fn depth(&self) -> ColorDepth {
        let truecolor = self.colorterm.as_deref().is_some_and(|v| {
            v.eq_ignore_ascii_case("truecolor") || v.eq_ignore_ascii_case("24bit")
        });
        if truecolor {
            ColorDepth::TrueColor
        } else if self.dumb_terminal() {
            ColorDepth::None
        } else if self.term.as_deref().is_some_and(|t| {
            t.contains("256color") || t.contains("truecolor") || t.contains("direct")
        }) {
            ColorDepth::Ansi256
        } else {
            ColorDepth::Ansi16
        }
    }
}

fn set(v: Option<&String>) -> bool {
    v.is_some_and(|v| !v.is_empty())
}

impl ColorChoice {
    /// The accepted spellings, for help and error messages.
    pub const NAMES: &'static str = "auto, always, never, 16, 256 or truecolor";

    /// Decides the colour depth: `is_tty` is whether the output is a terminal.
    ///
    /// Explicit depths win (a flag overrides `NO_COLOR`, as no-color.org asks); `Always`
    /// colours at the terminal's depth (16 at least). `Auto` follows the common convention
    /// in anstream's order: `NO_COLOR` set turns colour off; else `CLICOLOR_FORCE` set (not
    /// `0`) turns it on; else `CLICOLOR=0` turns it off; else colour when the output is a
    /// terminal whose `TERM` has colour. The depth is 24-bit when `COLORTERM` says so, 256
    /// colours when `TERM` says so, else the 16 every colour terminal has.
    #[must_use]
    pub fn resolve(self, is_tty: bool, env: &ColorEnv) -> ColorDepth {
        let depth = || match env.depth() {
            ColorDepth::None => ColorDepth::Ansi16,
            d => d,
        };
        match self {
            ColorChoice::Never => ColorDepth::None,
            ColorChoice::Ansi16 => ColorDepth::Ansi16,
            ColorChoice::Ansi256 => ColorDepth::Ansi256,
            ColorChoice::TrueColor => ColorDepth::TrueColor,
            ColorChoice::Always => depth(),
            ColorChoice::Auto => {
                if set(env.no_color.as_ref()) {
                    ColorDepth::None
                } else if set(env.clicolor_force.as_ref())
                    && env.clicolor_force.as_deref() != Some("0")
                {
                    depth()
                } else if env.clicolor.as_deref() == Some("0") || !is_tty {
                    ColorDepth::None
                } else {
                    env.depth()
                }
            }
        }
    }
}

impl FromStr for ColorChoice {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "always" => Ok(Self::Always),
            "never" | "none" | "off" => Ok(Self::Never),
            "16" | "ansi16" => Ok(Self::Ansi16),
            "256" | "ansi256" => Ok(Self::Ansi256),
            "truecolor" | "24bit" => Ok(Self::TrueColor),
            _ => Err(RenderError::Unknown {
                what: "colour choice",
                value: s.to_owned(),
                allowed: Self::NAMES,
            }),
        }
    }
}

impl fmt::Display for ColorChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Auto => "auto",
            Self::Always => "always",
            Self::Never => "never",
            Self::Ansi16 => "16",
            Self::Ansi256 => "256",
            Self::TrueColor => "truecolor",
        })
    }
}

/// The xterm defaults of the 16 ANSI colours, in SGR order (30..=37, then 90..=97).
const ANSI16: [Rgb; 16] = [
    Rgb(0, 0, 0),
    Rgb(205, 0, 0),
    Rgb(0, 205, 0),
    Rgb(205, 205, 0),
    Rgb(0, 0, 238),
    Rgb(205, 0, 205),
    Rgb(0, 205, 205),
    Rgb(229, 229, 229),
    Rgb(127, 127, 127),
    Rgb(255, 0, 0),
    Rgb(0, 255, 0),
    Rgb(255, 255, 0),
    Rgb(92, 92, 255),
    Rgb(255, 0, 255),
    Rgb(0, 255, 255),
    Rgb(255, 255, 255),
];

/// The six channel levels of the xterm 256-colour cube.
const CUBE: [u8; 6] = [0, 95, 135, 175, 215, 255];

/// The colour of xterm's palette entry `index`: the 16 basic colours, the 6 x 6 x 6 cube,
/// then the grey ramp.
pub fn xterm_rgb(index: u8) -> Rgb {
    match index {
        0..16 => ANSI16[index as usize],
        16..232 => {
            let i = index - 16;
            Rgb(
                CUBE[(i / 36) as usize],
                CUBE[(i / 6 % 6) as usize],
                CUBE[(i % 6) as usize],
            )
        }
        _ => {
            let g = 8 + 10 * (index - 232);
            Rgb(g, g, g)
        }
    }
}

/// A colour as the terminal will be told it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TermColor {
    /// Index 0..16 into the ANSI colours.
    Basic(u8),
    /// Index into the 256-colour palette.
    Indexed(u8),
    /// 24-bit.
    Rgb(Rgb),
}

fn dist2(a: Rgb, b: Rgb) -> u32 {
    let d = |x: u8, y: u8| (i32::from(x) - i32::from(y)).unsigned_abs().pow(2);
    d(a.0, b.0) + d(a.1, b.1) + d(a.2, b.2)
}

impl ColorDepth {
    /// The nearest colour this depth can show (in RGB distance).
    pub fn quantise(self, c: Rgb) -> TermColor {
        match self {
            // `None` never reaches here (writers skip colour); treat it as 24-bit.
            ColorDepth::None | ColorDepth::TrueColor => TermColor::Rgb(c),
            ColorDepth::Ansi16 => {
                let best = (0..16u8)
                    .min_by_key(|&i| dist2(c, ANSI16[i as usize]))
                    .unwrap_or(7);
                TermColor::Basic(best)
            }
            ColorDepth::Ansi256 => {
                let level = |v: u8| {
                    (0..6)
                        .min_by_key(|&i| (i32::from(CUBE[i]) - i32::from(v)).unsigned_abs())
                        .unwrap_or(0)
                };
                let (r, g, b) = (level(c.0), level(c.1), level(c.2));
                let cube = Rgb(CUBE[r], CUBE[g], CUBE[b]);
                let cube_index = 16 + 36 * r + 6 * g + b;
                // Grey ramp 232..=255 is 8, 18, ..., 238.
                let mean = (u32::from(c.0) + u32::from(c.1) + u32::from(c.2)) / 3;
                let step = (mean.saturating_sub(3) / 10).min(23) as u8;
                let grey = 8 + 10 * step;
                if dist2(c, Rgb(grey, grey, grey)) < dist2(c, cube) {
                    TermColor::Indexed(232 + step)
                } else {
                    TermColor::Indexed(cube_index as u8)
                }
            }
        }
    }
}

impl TermColor {
    /// Writes the SGR escape that selects this colour as foreground or background.
    ///
    /// # Errors
    /// When `out` refuses the text.
    pub fn write_sgr(self, out: &mut impl Write, background: bool) -> fmt::Result {
        let base = if background { 48 } else { 38 };
        match self {
            TermColor::Basic(i) => {
                let code = match (i < 8, background) {
                    (true, false) => 30 + i,
                    (true, true) => 40 + i,
                    (false, false) => 90 + i - 8,
                    (false, true) => 100 + i - 8,
                };
                write!(out, "\x1b[{code}m")
            }
            TermColor::Indexed(i) => write!(out, "\x1b[{base};5;{i}m"),
            TermColor::Rgb(Rgb(r, g, b)) => write!(out, "\x1b[{base};2;{r};{g};{b}m"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(pairs: &[(&str, &str)]) -> ColorEnv {
        ColorEnv::read(|k| {
            pairs
                .iter()
                .find(|(name, _)| *name == k)
                .map(|(_, v)| (*v).to_owned())
        })
    }

    #[test]
    fn auto_follows_tty_no_color_and_colorterm_but_explicit_choices_win() {
        let auto = ColorChoice::Auto;
        let xterm256 = ("TERM", "xterm-256color");
        assert_eq!(
            auto.resolve(false, &env(&[xterm256, ("COLORTERM", "truecolor")])),
            ColorDepth::None
        );
        assert_eq!(
            auto.resolve(true, &env(&[xterm256, ("NO_COLOR", "1")])),
            ColorDepth::None
        );
        // NO_COLOR set but empty does not count (no-color.org).
        assert_eq!(
            auto.resolve(true, &env(&[xterm256, ("NO_COLOR", "")])),
            ColorDepth::Ansi256
        );
        assert_eq!(
            auto.resolve(true, &env(&[xterm256, ("COLORTERM", "24bit")])),
            ColorDepth::TrueColor
        );
        assert_eq!(
            ColorChoice::Ansi16.resolve(false, &env(&[("NO_COLOR", "1")])),
            ColorDepth::Ansi16
        );
        assert_eq!(
            ColorChoice::Never.resolve(true, &env(&[xterm256])),
            ColorDepth::None
        );
        assert_eq!("256".parse::<ColorChoice>(), Ok(ColorChoice::Ansi256));
        assert_eq!("always".parse::<ColorChoice>(), Ok(ColorChoice::Always));
        assert!("rainbow".parse::<ColorChoice>().is_err());
    }

    #[test]
    fn term_decides_the_depth_and_dumb_terminals_get_none() {
        let auto = ColorChoice::Auto;
        assert_eq!(
            auto.resolve(true, &env(&[("TERM", "xterm")])),
            ColorDepth::Ansi16
        );
        assert_eq!(
            auto.resolve(true, &env(&[("TERM", "dumb")])),
            ColorDepth::None
        );
        assert_eq!(auto.resolve(true, &env(&[])), ColorDepth::None);
        assert!(env(&[("TERM", "dumb")]).dumb_terminal());
    }

    #[test]
    fn clicolor_and_clicolor_force_follow_the_common_convention() {
        let auto = ColorChoice::Auto;
        let xterm = ("TERM", "xterm");
        assert_eq!(
            auto.resolve(true, &env(&[xterm, ("CLICOLOR", "0")])),
            ColorDepth::None
        );
        assert_eq!(
            auto.resolve(true, &env(&[xterm, ("CLICOLOR", "1")])),
            ColorDepth::Ansi16
        );
        // Forced: colour off a terminal too, and over CLICOLOR=0; but NO_COLOR wins.
        assert_eq!(
            auto.resolve(
                false,
                &env(&[xterm, ("CLICOLOR_FORCE", "1"), ("CLICOLOR", "0")])
            ),
            ColorDepth::Ansi16
        );
        assert_eq!(
            auto.resolve(false, &env(&[xterm, ("CLICOLOR_FORCE", "0")])),
            ColorDepth::None
        );
        assert_eq!(
            auto.resolve(
                true,
                &env(&[xterm, ("CLICOLOR_FORCE", "1"), ("NO_COLOR", "1")])
            ),
            ColorDepth::None
        );
        // Always colours even a pipe under NO_COLOR, at the terminal's depth.
        assert_eq!(
            ColorChoice::Always.resolve(
                false,
                &env(&[("NO_COLOR", "1"), ("COLORTERM", "truecolor")])
            ),
            ColorDepth::TrueColor
        );
    }

    #[test]
    fn the_xterm_palette_reads_back_through_quantisation() {
        for i in 16..=255u8 {
            let q = ColorDepth::Ansi256.quantise(xterm_rgb(i));
            assert_eq!(
                xterm_rgb(match q {
                    TermColor::Indexed(k) => k,
                    other => panic!("{other:?}"),
                }),
                xterm_rgb(i),
                "index {i}"
            );
        }
        assert_eq!(xterm_rgb(196), Rgb(255, 0, 0));
        assert_eq!(xterm_rgb(232), Rgb(8, 8, 8));
    }

    #[test]
    fn quantisation_picks_the_palette_entry_itself_when_exact() {
        assert_eq!(
            ColorDepth::Ansi16.quantise(Rgb(255, 0, 0)),
            TermColor::Basic(9)
        );
        // Cube entry (5, 0, 0) = 16 + 180 = 196; grey 8 + 10 * 11 = 118 is index 243.
        assert_eq!(
            ColorDepth::Ansi256.quantise(Rgb(255, 0, 0)),
            TermColor::Indexed(196)
        );
        assert_eq!(
            ColorDepth::Ansi256.quantise(Rgb(118, 118, 118)),
            TermColor::Indexed(243)
        );
        let mut s = String::new();
        TermColor::Basic(9).write_sgr(&mut s, true).unwrap();
        assert_eq!(s, "\x1b[101m");
    }
}
