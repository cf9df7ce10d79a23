//! Bytes from the terminal to keys, mouse events and the answers to status queries.
//!
//! The UI reads the terminal itself rather than through crossterm's event reader, because
//! the answer to the status query that paces drawing (`ESC [ row ; col R`, see
//! [`super::link`]) arrives mixed with the keys, and crossterm's reader keeps such answers
//! to itself. The [`Decoder`] takes whatever each read returned and gives back
//! [`Input`]s in order; no key is lost to an answer, nor an answer to a key.
//!
//! A terminal sends a cursor key as several bytes (`ESC [ B` is ↓). Over a slow link `ESC`
//! may arrive alone and `[B` a few milliseconds later: an unfinished sequence is held for
//! [`WAIT`], and becomes the one key it was if the rest follows in time; otherwise the Esc
//! (and whatever followed) goes on as typed. Esc followed by an ordinary character in the
//! same read is Esc and that character (the UI binds nothing to Alt), so `Esc q` typed
//! quickly closes a box and quits.

use std::time::{Duration, Instant};

use ratatui::crossterm::event::{
    Event, KeyCode, KeyEvent, KeyEventKind, KeyEventState, KeyModifiers, MouseButton, MouseEvent,
    MouseEventKind,
};

/// How long an unfinished sequence waits for the rest.
///
/// NOTE: the bytes of one key leave the terminal together, so only the network splits them;
/// vim waits 100 ms by default (`ttimeoutlen`). 60 ms joins the splits of a jittery link yet
/// keeps Esc, which closes boxes, prompt.
pub const WAIT: Duration = Duration::from_millis(60);

/// Longest escape sequence held; a longer one is not a sequence.
const LONGEST: usize = 32;

/// What the terminal sent.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Input {
    /// A key, a mouse event.
    Event(Event),
    /// The answer to a status query (a cursor position report).
    Answer,
}

/// Bytes from the terminal, decoded as they come.
#[derive(Debug, Default)]
pub struct Decoder {
    /// Bytes of an unfinished sequence or character, and when they came.
    held: Vec<u8>,
    since: Option<Instant>,
}

/// One thing parsed from the front of the bytes.
enum Parsed {
    /// So many bytes make this (or nothing the UI uses).
    Done(usize, Option<Input>),
    /// The bytes may be the start of something longer.
    Partial,
}

impl Decoder {
    /// A decoder holding nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// When held bytes must go on as typed, if any are held.
    pub fn deadline(&self) -> Option<Instant> {
        self.since.map(|t| t + WAIT)
    }

    /// Takes the bytes of one read, made at `now`; returns what they (and any held before)
    /// mean, in order.
    pub fn push(&mut self, bytes: &[u8], now: Instant) -> Vec<Input> {
        let mut out = self.expire(now);
        if self.held.is_empty() {
            self.since = Some(now);
        }
        self.held.extend_from_slice(bytes);
        self.decode(false, &mut out);
        out
    }

    /// What held bytes mean once their wait is over at `now`.
    pub fn expire(&mut self, now: Instant) -> Vec<Input> {
        let mut out = Vec::new();
        if self.deadline().is_some_and(|d| now >= d) {
            self.decode(true, &mut out);
        }
        out
    }

    fn decode(&mut self, late: bool, out: &mut Vec<Input>) {
        let mut at = 0;
        while at < self.held.len() {
            match parse(&self.held[at..]) {
                Parsed::Done(n, input) => {
                    out.extend(input);
                    at += n;
                }
                Parsed::Partial if late => {
                    // The rest never came: the first byte goes on as typed.
                    out.extend(byte_key(self.held[at]).map(Input::Event));
                    at += 1;
                }
                Parsed::Partial => break,
            }
        }
        self.held.drain(..at);
        if self.held.is_empty() {
            self.since = None;
        }
    }
}

fn key(code: KeyCode, modifiers: KeyModifiers) -> Event {
    Event::Key(KeyEvent {
        code,
        modifiers,
        kind: KeyEventKind::Press,
        state: KeyEventState::NONE,
    })
}

fn parse(b: &[u8]) -> Parsed {
    match b[0] {
        0x1b => escape(b),
        c if c < 0x80 => Parsed::Done(1, byte_key(c).map(Input::Event)),
        lead => {
            let len = match lead {
                0xc0..=0xdf => 2,
                0xe0..=0xef => 3,
                0xf0..=0xf7 => 4,
                _ => return Parsed::Done(1, None),
            };
            if b.len() < len {
                return Parsed::Partial;
            }
            match std::str::from_utf8(&b[..len])
                .ok()
                .and_then(|s| s.chars().next())
            {
                Some(c) => Parsed::Done(len, Some(Input::Event(char_key(c)))),
                None => Parsed::Done(1, None),
            }
        }
    }
}

/// A typed character (capitals carry Shift, as crossterm reports them).
fn char_key(c: char) -> Event {
    let mods = if c.is_uppercase() {
        KeyModifiers::SHIFT
    } else {
        KeyModifiers::NONE
    };
    key(KeyCode::Char(c), mods)
}

/// The key of one byte below 0x80.
fn byte_key(c: u8) -> Option<Event> {
    let ctrl = KeyModifiers::CONTROL;
    Some(match c {
        0x1b => key(KeyCode::Esc, KeyModifiers::NONE),
        b'\r' | b'\n' => key(KeyCode::Enter, KeyModifiers::NONE),
        b'\t' => key(KeyCode::Tab, KeyModifiers::NONE),
        0x7f => key(KeyCode::Backspace, KeyModifiers::NONE),
        0 => key(KeyCode::Char(' '), ctrl),
        0x01..=0x1a => key(KeyCode::Char(char::from(b'a' + c - 1)), ctrl),
        0x1c..=0x1f => key(KeyCode::Char(char::from(b'4' + c - 0x1c)), ctrl),
        c if c >= 0x80 => return None,
        c => char_key(char::from(c)),
    })
}

fn escape(b: &[u8]) -> Parsed {
    let Some(&second) = b.get(1) else {
        return Parsed::Partial;
    };
    match second {
        b'[' => csi(b),
        b'O' => match b.get(2) {
            None => Parsed::Partial,
            Some(&c) => Parsed::Done(3, final_key(c, KeyModifiers::NONE).map(Input::Event)),
        },
        // Esc, then whatever follows, taken afresh.
        _ => Parsed::Done(1, byte_key(0x1b).map(Input::Event)),
    }
}

fn csi(b: &[u8]) -> Parsed {
    // X10 mouse: ESC [ M and three bytes.
    if b.get(2) == Some(&b'M') {
        if b.len() < 6 {
            return Parsed::Partial;
        }
        let (cb, cx, cy) = (b[3].wrapping_sub(32), b[4], b[5]);
        let ev = mouse(
            u16::from(cb),
            u16::from(cx.saturating_sub(32)),
            u16::from(cy.saturating_sub(32)),
            cb & 3 == 3,
        );
        return Parsed::Done(6, Some(Input::Event(ev)));
    }
    let mut i = 2;
    while let Some(&c) = b.get(i) {
        match c {
            0x20..=0x3f => i += 1,
            0x40..=0x7e => {
                let params = std::str::from_utf8(&b[2..i]).unwrap_or("");
                return Parsed::Done(i + 1, csi_input(params, c));
            }
            // Not a sequence: Esc as typed, the rest taken afresh.
            _ => return Parsed::Done(1, byte_key(0x1b).map(Input::Event)),
        }
        if i > LONGEST {
            return Parsed::Done(1, byte_key(0x1b).map(Input::Event));
        }
    }
    Parsed::Partial
}

fn csi_input(params: &str, last: u8) -> Option<Input> {
    if let Some(sgr) = params.strip_prefix('<') {
        let n: Vec<u16> = sgr.split(';').filter_map(|p| p.parse().ok()).collect();
        if n.len() != 3 || !matches!(last, b'M' | b'm') {
            return None;
        }
        return Some(Input::Event(mouse(n[0], n[1], n[2], last == b'm')));
    }
    let mut parts = params.split(';');
    let first = parts.next().filter(|p| !p.is_empty());
    let second = parts.next();
    if last == b'R' && first.is_some() && second.is_some() {
        return Some(Input::Answer);
    }
    let mods = modifiers(second);
    if last == b'~' {
        let code = match first.and_then(|p| p.parse::<u8>().ok())? {
            1 | 7 => KeyCode::Home,
            2 => KeyCode::Insert,
            3 => KeyCode::Delete,
            4 | 8 => KeyCode::End,
            5 => KeyCode::PageUp,
            6 => KeyCode::PageDown,
            n @ 11..=15 => KeyCode::F(n - 10),
            n @ 17..=21 => KeyCode::F(n - 11),
            n @ 23..=24 => KeyCode::F(n - 12),
            _ => return None,
        };
        return Some(Input::Event(key(code, mods)));
    }
    final_key(last, mods).map(Input::Event)
}

/// xterm's modifier parameter (`1 + shift + 2 alt + 4 ctrl`) to crossterm's.
fn modifiers(param: Option<&str>) -> KeyModifiers {
    let m = param
        .and_then(|p| p.parse::<u8>().ok())
        .unwrap_or(1)
        .saturating_sub(1);
    let mut out = KeyModifiers::NONE;
    if m & 1 != 0 {
        out |= KeyModifiers::SHIFT;
    }
    if m & 2 != 0 {
        out |= KeyModifiers::ALT;
    }
    if m & 4 != 0 {
        out |= KeyModifiers::CONTROL;
    }
    out
}

/// The key of a sequence's final character (`A` is ↑...).
fn final_key(c: u8, mods: KeyModifiers) -> Option<Event> {
    let code = match c {
        b'A' => KeyCode::Up,
        b'B' => KeyCode::Down,
        b'C' => KeyCode::Right,
        b'D' => KeyCode::Left,
        b'H' => KeyCode::Home,
        b'F' => KeyCode::End,
        b'Z' => return Some(key(KeyCode::BackTab, KeyModifiers::SHIFT)),
        b'P' => KeyCode::F(1),
        b'Q' => KeyCode::F(2),
        b'R' => KeyCode::F(3),
        b'S' => KeyCode::F(4),
        _ => return None,
    };
    Some(key(code, mods))
}

/// A mouse report: button code `cb` (xterm's: low bits the button, 32 motion, 64 wheel,
/// 4/8/16 shift/alt/ctrl) at 1-based `(x, y)`.
fn mouse(cb: u16, x: u16, y: u16, release: bool) -> Event {
    let button = match cb & 3 {
        0 => MouseButton::Left,
        1 => MouseButton::Middle,
        _ => MouseButton::Right,
    };
    let kind = if cb & 64 != 0 {
        match cb & 3 {
            0 => MouseEventKind::ScrollUp,
            1 => MouseEventKind::ScrollDown,
            2 => MouseEventKind::ScrollLeft,
            _ => MouseEventKind::ScrollRight,
        }
    } else if release || (cb & 3 == 3 && cb & 32 == 0) {
        MouseEventKind::Up(button)
    } else if cb & 32 != 0 {
        if cb & 3 == 3 {
            MouseEventKind::Moved
        } else {
            MouseEventKind::Drag(button)
        }
    } else {
        MouseEventKind::Down(button)
    };
    let mut modifiers = KeyModifiers::NONE;
    if cb & 4 != 0 {
        modifiers |= KeyModifiers::SHIFT;
    }
    if cb & 8 != 0 {
        modifiers |= KeyModifiers::ALT;
    }
    if cb & 16 != 0 {
        modifiers |= KeyModifiers::CONTROL;
    }
    Event::Mouse(MouseEvent {
        kind,
        column: x.saturating_sub(1),
        row: y.saturating_sub(1),
        modifiers,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codes(inputs: &[Input]) -> Vec<KeyCode> {
        inputs
            .iter()
            .filter_map(|e| match e {
                Input::Event(Event::Key(k)) => Some(k.code),
                _ => None,
            })
            .collect()
    }

    fn all(bytes: &[u8]) -> Vec<Input> {
        let t0 = Instant::now();
        let mut d = Decoder::new();
        let mut out = d.push(bytes, t0);
        out.extend(d.expire(t0 + WAIT));
        out
    }

    #[test]
    fn an_answer_among_keys_is_taken_out_and_every_key_kept() {
        let out = all(b"a\x1b[12;40Rq \x1b[1;1R\x1b[B");
        assert_eq!(
            out.iter().filter(|i| **i == Input::Answer).count(),
            2,
            "{out:?}"
        );
        assert_eq!(
            codes(&out),
            vec![
                KeyCode::Char('a'),
                KeyCode::Char('q'),
                KeyCode::Char(' '),
                KeyCode::Down
            ]
        );
    }

    #[test]
    fn an_answer_split_across_reads_is_still_an_answer() {
        let t0 = Instant::now();
        let mut d = Decoder::new();
        let ms = |n| t0 + Duration::from_millis(n);
        assert!(d.push(b"\x1b", t0).is_empty());
        assert!(d.push(b"[3", ms(5)).is_empty());
        assert_eq!(d.push(b"0;1R", ms(9)), vec![Input::Answer]);
        assert_eq!(d.deadline(), None);
    }

    #[test]
    fn esc_and_q_in_one_read_are_both_kept() {
        assert_eq!(
            codes(&all(b"\x1bq")),
            vec![KeyCode::Esc, KeyCode::Char('q')]
        );
        assert_eq!(codes(&all(b"\x1b\x1b")), vec![KeyCode::Esc, KeyCode::Esc]);
    }

    #[test]
    fn an_arrow_split_after_esc_is_one_key() {
        let t0 = Instant::now();
        let mut d = Decoder::new();
        assert!(d.push(b"\x1b", t0).is_empty());
        assert!(d.push(b"[", t0 + Duration::from_millis(10)).is_empty());
        let out = d.push(b"B", t0 + Duration::from_millis(11));
        assert_eq!(codes(&out), vec![KeyCode::Down]);
        assert_eq!(d.deadline(), None);
    }

    #[test]
    fn a_lone_esc_goes_on_after_the_wait_and_not_before() {
        let t0 = Instant::now();
        let mut d = Decoder::new();
        assert!(d.push(b"\x1b", t0).is_empty());
        assert!(d.expire(t0 + WAIT / 2).is_empty());
        assert_eq!(codes(&d.expire(t0 + WAIT)), vec![KeyCode::Esc]);
    }

    #[test]
    fn a_sequence_completed_too_late_is_typed_as_it_came() {
        let t0 = Instant::now();
        let mut d = Decoder::new();
        d.push(b"\x1b", t0);
        let out = d.push(b"[", t0 + WAIT + Duration::from_millis(1));
        // The Esc went on alone; `[` now waits as the start of nothing (it is a character).
        assert_eq!(codes(&out), vec![KeyCode::Esc, KeyCode::Char('[')]);
    }

    #[test]
    fn keys_with_parameters_modifiers_and_control_are_read() {
        let out = all(b"\x1b[1;2C\x1b[5~\x1bOA\x03\r\x7fX\xc3\xa9");
        let keys: Vec<(KeyCode, KeyModifiers)> = out
            .iter()
            .filter_map(|e| match e {
                Input::Event(Event::Key(k)) => Some((k.code, k.modifiers)),
                _ => None,
            })
            .collect();
        assert_eq!(
            keys,
            vec![
                (KeyCode::Right, KeyModifiers::SHIFT),
                (KeyCode::PageUp, KeyModifiers::NONE),
                (KeyCode::Up, KeyModifiers::NONE),
                (KeyCode::Char('c'), KeyModifiers::CONTROL),
                (KeyCode::Enter, KeyModifiers::NONE),
                (KeyCode::Backspace, KeyModifiers::NONE),
                (KeyCode::Char('X'), KeyModifiers::SHIFT),
                (KeyCode::Char('é'), KeyModifiers::NONE),
            ]
        );
    }

    #[test]
    fn sgr_mouse_reports_become_mouse_events() {
        let out = all(b"\x1b[<0;10;5M\x1b[<32;11;5M\x1b[<0;11;5m\x1b[<65;3;4M");
        let kinds: Vec<(MouseEventKind, u16, u16)> = out
            .iter()
            .filter_map(|e| match e {
                Input::Event(Event::Mouse(m)) => Some((m.kind, m.column, m.row)),
                _ => None,
            })
            .collect();
        assert_eq!(
            kinds,
            vec![
                (MouseEventKind::Down(MouseButton::Left), 9, 4),
                (MouseEventKind::Drag(MouseButton::Left), 10, 4),
                (MouseEventKind::Up(MouseButton::Left), 10, 4),
                (MouseEventKind::ScrollDown, 2, 3),
            ]
        );
    }
}
