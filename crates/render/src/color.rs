//! Colour choice (`--color`), terminal colour depth and quantisation of [`Rgb`] to SGR codes.

use std::fmt::{self, Write};
use std::str::FromStr;

use crate::{RenderError, Rgb};

/// What the user asked for with `--color`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorChoice {
    /// Colour when writing to a terminal and `NO_COLOR` is unset or empty; depth from `COLORTERM`.
    #[default]
    Auto,
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

impl ColorChoice {
    /// The accepted spellings, for help and error messages.
    pub const NAMES: &'static str = "auto, never, 16, 256 or truecolor";

    /// Decides the colour depth from the environment, which the caller reads (this crate does
    /// no I/O): `is_tty` is whether the output is a terminal, `no_color_env` the value of
    /// `NO_COLOR`, `colorterm_env` that of `COLORTERM`.
    ///
    /// Explicit choices win (an explicit flag overrides `NO_COLOR`, as no-color.org asks);
    /// `Auto` gives no colour off a terminal or when `NO_COLOR` is set to anything non-empty,
    /// 24-bit when `COLORTERM` is `truecolor` or `24bit`, and 256 colours otherwise.
    #[must_use]
    pub fn resolve(
        self,
        is_tty: bool,
        no_color_env: Option<&str>,
        colorterm_env: Option<&str>,
    ) -> ColorDepth {
        match self {
            ColorChoice::Never => ColorDepth::None,
            ColorChoice::Ansi16 => ColorDepth::Ansi16,
            ColorChoice::Ansi256 => ColorDepth::Ansi256,
            ColorChoice::TrueColor => ColorDepth::TrueColor,
            ColorChoice::Auto => {
                if !is_tty || no_color_env.is_some_and(|v| !v.is_empty()) {
                    ColorDepth::None
                } else if colorterm_env.is_some_and(|v| {
                    v.eq_ignore_ascii_case("truecolor") || v.eq_ignore_ascii_case("24bit")
                }) {
                    ColorDepth::TrueColor
                } else {
                    ColorDepth::Ansi256
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

/// A colour as the terminal will be told it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SgrColor {
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
    pub(crate) fn quantise(self, c: Rgb) -> SgrColor {
        match self {
            // `None` never reaches here (writers skip colour); treat it as 24-bit.
            ColorDepth::None | ColorDepth::TrueColor => SgrColor::Rgb(c),
            ColorDepth::Ansi16 => {
                let best = (0..16u8)
                    .min_by_key(|&i| dist2(c, ANSI16[i as usize]))
                    .unwrap_or(7);
                SgrColor::Basic(best)
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
                    SgrColor::Indexed(232 + step)
                } else {
                    SgrColor::Indexed(cube_index as u8)
                }
            }
        }
    }
}

impl SgrColor {
    /// Writes the SGR escape that selects this colour as foreground or background.
    pub(crate) fn write_sgr(self, out: &mut impl Write, background: bool) -> fmt::Result {
        let base = if background { 48 } else { 38 };
        match self {
            SgrColor::Basic(i) => {
                let code = match (i < 8, background) {
                    (true, false) => 30 + i,
                    (true, true) => 40 + i,
                    (false, false) => 90 + i - 8,
                    (false, true) => 100 + i - 8,
                };
                write!(out, "\x1b[{code}m")
            }
            SgrColor::Indexed(i) => write!(out, "\x1b[{base};5;{i}m"),
            SgrColor::Rgb(Rgb(r, g, b)) => write!(out, "\x1b[{base};2;{r};{g};{b}m"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_follows_tty_no_color_and_colorterm_but_explicit_choices_win() {
        let auto = ColorChoice::Auto;
        assert_eq!(
            auto.resolve(false, None, Some("truecolor")),
            ColorDepth::None
        );
        assert_eq!(auto.resolve(true, Some("1"), None), ColorDepth::None);
        // NO_COLOR set but empty does not count (no-color.org).
        assert_eq!(auto.resolve(true, Some(""), None), ColorDepth::Ansi256);
        assert_eq!(
            auto.resolve(true, None, Some("24bit")),
            ColorDepth::TrueColor
        );
        assert_eq!(
            ColorChoice::Ansi16.resolve(false, Some("1"), None),
            ColorDepth::Ansi16
        );
        assert_eq!(
            ColorChoice::Never.resolve(true, None, None),
            ColorDepth::None
        );
        assert_eq!("256".parse::<ColorChoice>(), Ok(ColorChoice::Ansi256));
        assert!("rainbow".parse::<ColorChoice>().is_err());
    }

    #[test]
    fn quantisation_picks_the_palette_entry_itself_when_exact() {
        assert_eq!(
            ColorDepth::Ansi16.quantise(Rgb(255, 0, 0)),
            SgrColor::Basic(9)
        );
        // Cube entry (5, 0, 0) = 16 + 180 = 196; grey 8 + 10 * 11 = 118 is index 243.
        assert_eq!(
            ColorDepth::Ansi256.quantise(Rgb(255, 0, 0)),
            SgrColor::Indexed(196)
        );
        assert_eq!(
            ColorDepth::Ansi256.quantise(Rgb(118, 118, 118)),
            SgrColor::Indexed(243)
        );
        let mut s = String::new();
        SgrColor::Basic(9).write_sgr(&mut s, true).unwrap();
        assert_eq!(s, "\x1b[101m");
    }
}
