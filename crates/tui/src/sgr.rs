//! Colour escapes for a 16-colour terminal.
//!
//! crossterm writes every colour as a 256-colour (`38;5;N`) or 24-bit (`38;2;R;G;B`) escape,
//! even the 16 basic ones. A terminal of 16 colours does not understand those, so on one the
//! UI writes through [`Sgr16`], which rewrites each colour of each SGR escape (`ESC [ ... m`)
//! to the nearest of the 16 (`30`-`37`, `90`-`97`, and `40`-`47`, `100`-`107` for
//! backgrounds), by the one conversion the renderer uses ([`ColorDepth::quantise`]).
//! Everything else passes through byte for byte.

use std::io::{self, Write};

use cloth_render::{ColorDepth, TermColor, xterm_rgb};

/// Longest escape held while waiting for its end; longer ones pass through as they are.
const MAX_ESCAPE: usize = 64;

/// A writer that rewrites colour escapes to 16 colours when `on`.
pub struct Sgr16<W: Write> {
    inner: W,
    on: bool,
    /// An escape begun in an earlier write.
    held: Vec<u8>,
    out: Vec<u8>,
}

impl<W: Write> Sgr16<W> {
    /// Wraps `inner`; `on` turns the rewriting on.
    pub fn new(inner: W, on: bool) -> Self {
        Self {
            inner,
            on,
            held: Vec::new(),
            out: Vec::new(),
        }
    }

    fn rewrite(&mut self, buf: &[u8]) {
        for &b in buf {
            if self.held.is_empty() {
                if b == 0x1b {
                    self.held.push(b);
                } else {
                    self.out.push(b);
                }
                continue;
            }
            self.held.push(b);
            let len = self.held.len();
            if len == 2 {
                if b != b'[' {
                    self.out.append(&mut self.held);
                }
                continue;
            }
            if (0x40..=0x7e).contains(&b) {
                if b == b'm' {
                    let params = String::from_utf8_lossy(&self.held[2..len - 1]).into_owned();
                    self.out.extend_from_slice(b"\x1b[");
                    self.out.extend_from_slice(sixteen(&params).as_bytes());
                    self.out.push(b'm');
                    self.held.clear();
                } else {
                    self.out.append(&mut self.held);
                }
            } else if len >= MAX_ESCAPE {
                self.out.append(&mut self.held);
            }
        }
    }
}

/// The SGR parameters `params` with every colour made one of the 16.
fn sixteen(params: &str) -> String {
    let p: Vec<&str> = params.split(';').collect();
    let mut out: Vec<String> = Vec::with_capacity(p.len());
    let mut i = 0;
    while i < p.len() {
        let background = match p[i] {
            "38" => Some(false),
            "48" => Some(true),
            _ => None,
        };
        let color = background.and_then(|bg| match p.get(i + 1).copied() {
            Some("5") => {
                let n = p.get(i + 2)?.parse::<u8>().ok()?;
                Some((bg, xterm_rgb(n), 3))
            }
            Some("2") => {
                let c = |k: usize| p.get(i + k)?.parse::<u8>().ok();
                Some((bg, cloth_render::Rgb(c(2)?, c(3)?, c(4)?), 5))
            }
            _ => None,
        });
        if let Some((bg, rgb, used)) = color {
            let code = match ColorDepth::Ansi16.quantise(rgb) {
                TermColor::Basic(k) => basic_code(k, bg),
                // NOTE: quantising to 16 colours gives a basic colour; keep the escape valid
                // should that ever change.
                TermColor::Indexed(_) | TermColor::Rgb(_) => {
                    if bg {
                        49
                    } else {
                        39
                    }
                }
            };
            out.push(code.to_string());
            i += used;
        } else {
            out.push(p[i].to_owned());
            i += 1;
        }
    }
    out.join(";")
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

impl<W: Write> Write for Sgr16<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if !self.on {
            return self.inner.write(buf);
        }
        self.rewrite(buf);
        let out = std::mem::take(&mut self.out);
        let result = self.inner.write_all(&out);
        self.out = out;
        self.out.clear();
        result.map(|()| buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        if !self.held.is_empty() {
            // An escape cut off at a flush: pass it on rather than hold it back.
            let held = std::mem::take(&mut self.held);
            self.inner.write_all(&held)?;
        }
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn through(chunks: &[&[u8]]) -> String {
        let mut w = Sgr16::new(Vec::new(), true);
        for c in chunks {
            w.write_all(c).unwrap();
        }
        w.flush().unwrap();
        String::from_utf8(w.inner).unwrap()
    }

    #[test]
    fn indexed_and_rgb_colours_become_basic_codes() {
        // crossterm's Cyan is index 14; its background Black is index 0.
        assert_eq!(through(&[b"\x1b[38;5;14;48;5;0mx"]), "\x1b[96;40mx");
        // A 256-colour brown (index 137 = rgb 175, 135, 95) is one of the 16 too.
        let s = through(&[b"\x1b[38;5;137m"]);
        assert!(!s.contains("38;5"), "{s:?}");
        assert_eq!(through(&[b"\x1b[38;2;255;0;0m"]), "\x1b[91m");
    }

    #[test]
    fn other_escapes_and_text_pass_untouched_even_split_across_writes() {
        assert_eq!(
            through(&[b"a\x1b[1;", b"38;5;", b"9mb\x1b[2J\x1b[10;5H"]),
            "a\x1b[1;91mb\x1b[2J\x1b[10;5H"
        );
        assert_eq!(
            through(&[b"\x1b[0m\x1b[39m\x1b[?25l"]),
            "\x1b[0m\x1b[39m\x1b[?25l"
        );
    }

    #[test]
    fn off_it_changes_nothing() {
        let mut w = Sgr16::new(Vec::new(), false);
        w.write_all(b"\x1b[38;5;137m").unwrap();
        assert_eq!(w.inner, b"\x1b[38;5;137m");
    }
}
