//! Escape sequences split across reads, put back together.
//!
//! A terminal sends a cursor key as several bytes (`ESC [ B` is ↓). When they arrive in one
//! read, crossterm parses them as one key; over a slow link `ESC` may arrive alone and `[B` a
//! few milliseconds later, and crossterm then reports Esc, `[` and `B`. The [`Joiner`] holds a
//! lone Esc for [`WAIT`]: if the rest of a sequence follows in time, it becomes the one key it
//! was; otherwise the Esc (and whatever followed) goes on as typed.

use std::time::{Duration, Instant};

use ratatui::crossterm::event::{
    Event, KeyCode, KeyEvent, KeyEventKind, KeyEventState, KeyModifiers,
};

/// How long a lone Esc waits for the rest of a sequence.
///
/// NOTE: the bytes of one key leave the terminal together, so only the network splits them;
/// vim waits 100 ms by default (`ttimeoutlen`). 60 ms joins the splits of a jittery link yet
/// keeps Esc, which closes boxes, prompt.
pub const WAIT: Duration = Duration::from_millis(60);

/// Puts split escape sequences back together.
#[derive(Debug, Default)]
pub struct Joiner {
    /// The characters after a held Esc, and when the Esc came.
    pending: Option<(Instant, String)>,
}

/// What a complete or partial sequence after Esc is.
enum Parse {
    /// A whole sequence: this key (or an unknown one, swallowed).
    Key(Option<KeyEvent>),
    /// The start of one: wait for more.
    Partial,
    /// Not a sequence: Esc was Esc.
    Not,
}

fn key(code: KeyCode, modifiers: KeyModifiers) -> KeyEvent {
    KeyEvent {
        code,
        modifiers,
        kind: KeyEventKind::Press,
        state: KeyEventState::NONE,
    }
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

fn parse(s: &str) -> Parse {
    let mut chars = s.chars();
    match chars.next() {
        None => Parse::Partial,
        Some('O') => match chars.next() {
            None => Parse::Partial,
            Some(c) => Parse::Key(final_key(c, KeyModifiers::NONE)),
        },
        Some('[') => {
            let body: String = chars.collect();
            let Some(last) = body.chars().last() else {
                return Parse::Partial;
            };
            let params = &body[..body.len() - last.len_utf8()];
            if !params.chars().all(|c| ('\x30'..='\x3f').contains(&c)) {
                return Parse::Not;
            }
            if ('\x30'..='\x3f').contains(&last) {
                // Still in the parameters.
                return if body.len() > 16 {
                    Parse::Not
                } else {
                    Parse::Partial
                };
            }
            if !('\x40'..='\x7e').contains(&last) {
                return Parse::Not;
            }
            let mut parts = params.split(';');
            let first = parts.next().filter(|p| !p.is_empty());
            let mods = modifiers(parts.next());
            if last == '~' {
                let code = match first.and_then(|p| p.parse::<u8>().ok()) {
                    Some(1 | 7) => Some(KeyCode::Home),
                    Some(2) => Some(KeyCode::Insert),
                    Some(3) => Some(KeyCode::Delete),
                    Some(4 | 8) => Some(KeyCode::End),
                    Some(5) => Some(KeyCode::PageUp),
                    Some(6) => Some(KeyCode::PageDown),
                    Some(n @ 11..=15) => Some(KeyCode::F(n - 10)),
                    Some(n @ 17..=21) => Some(KeyCode::F(n - 11)),
                    Some(n @ 23..=24) => Some(KeyCode::F(n - 12)),
                    _ => None,
                };
                return Parse::Key(code.map(|c| key(c, mods)));
            }
            Parse::Key(final_key(last, mods))
        }
        Some(_) => Parse::Not,
    }
}

/// The key of a sequence's final character (`A` is ↑...).
fn final_key(c: char, mods: KeyModifiers) -> Option<KeyEvent> {
    let code = match c {
        'A' => KeyCode::Up,
        'B' => KeyCode::Down,
        'C' => KeyCode::Right,
        'D' => KeyCode::Left,
        'H' => KeyCode::Home,
        'F' => KeyCode::End,
        'Z' => return Some(key(KeyCode::BackTab, KeyModifiers::SHIFT)),
        'P' => KeyCode::F(1),
        'Q' => KeyCode::F(2),
        'R' => KeyCode::F(3),
        'S' => KeyCode::F(4),
        _ => return None,
    };
    Some(key(code, mods))
}

fn is_lone_esc(ev: &Event) -> bool {
    matches!(ev, Event::Key(k) if k.code == KeyCode::Esc
        && k.modifiers == KeyModifiers::NONE
        && k.kind == KeyEventKind::Press)
}

/// A plain character typed (Shift allowed: crossterm marks capitals with it).
fn typed(ev: &Event) -> Option<char> {
    match ev {
        Event::Key(k)
            if k.kind == KeyEventKind::Press && (k.modifiers - KeyModifiers::SHIFT).is_empty() =>
        {
            match k.code {
                KeyCode::Char(c) => Some(c),
                _ => None,
            }
        }
        _ => None,
    }
}

impl Joiner {
    /// A joiner holding nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// When the held Esc must go on by itself, if one is held.
    pub fn deadline(&self) -> Option<Instant> {
        self.pending.as_ref().map(|(t, _)| *t + WAIT)
    }

    /// Takes an event read at `now`; returns the events to act on, in order.
    pub fn push(&mut self, ev: Event, now: Instant) -> Vec<Event> {
        let mut out = self.expire(now);
        let Some((since, mut text)) = self.pending.take() else {
            if is_lone_esc(&ev) {
                self.pending = Some((now, String::new()));
            } else {
                out.push(ev);
            }
            return out;
        };
        if let Some(c) = typed(&ev) {
            text.push(c);
            match parse(&text) {
                Parse::Key(k) => {
                    out.extend(k.map(Event::Key));
                    return out;
                }
                Parse::Partial => {
                    self.pending = Some((since, text));
                    return out;
                }
                Parse::Not => {
                    text.pop();
                    out.extend(flush(&text));
                    // The character that broke the sequence is taken afresh.
                    out.push(ev);
                    return out;
                }
            }
        }
        out.extend(flush(&text));
        out.extend(self.push(ev, now));
        out
    }

    /// The held Esc (and what followed it) once its wait is over at `now`.
    pub fn expire(&mut self, now: Instant) -> Vec<Event> {
        match &self.pending {
            Some((since, _)) if now.duration_since(*since) >= WAIT => self
                .pending
                .take()
                .map_or_else(Vec::new, |(_, text)| flush(&text)),
            _ => Vec::new(),
        }
    }
}

/// Esc and the characters after it, as typed.
fn flush(text: &str) -> Vec<Event> {
    std::iter::once(key(KeyCode::Esc, KeyModifiers::NONE))
        .chain(
            text.chars()
                .map(|c| key(KeyCode::Char(c), KeyModifiers::NONE)),
        )
        .map(Event::Key)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(code: KeyCode) -> Event {
        Event::Key(KeyEvent::new(code, KeyModifiers::NONE))
    }

    fn c(ch: char) -> Event {
        let mods = if ch.is_ascii_uppercase() {
            KeyModifiers::SHIFT
        } else {
            KeyModifiers::NONE
        };
        Event::Key(KeyEvent::new(KeyCode::Char(ch), mods))
    }

    fn codes(events: &[Event]) -> Vec<KeyCode> {
        events
            .iter()
            .filter_map(|e| match e {
                Event::Key(k) => Some(k.code),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn an_arrow_split_after_esc_is_one_key() {
        let t0 = Instant::now();
        let mut j = Joiner::new();
        assert!(j.push(k(KeyCode::Esc), t0).is_empty());
        let ms = |n| t0 + Duration::from_millis(n);
        assert!(j.push(c('['), ms(10)).is_empty());
        let out = j.push(c('B'), ms(11));
        assert_eq!(codes(&out), vec![KeyCode::Down]);
        assert_eq!(j.deadline(), None);
    }

    #[test]
    fn a_lone_esc_goes_on_after_the_wait_and_not_before() {
        let t0 = Instant::now();
        let mut j = Joiner::new();
        assert!(j.push(k(KeyCode::Esc), t0).is_empty());
        assert!(j.expire(t0 + WAIT / 2).is_empty());
        assert_eq!(codes(&j.expire(t0 + WAIT)), vec![KeyCode::Esc]);
    }

    #[test]
    fn esc_then_an_ordinary_key_is_esc_then_that_key() {
        let t0 = Instant::now();
        let mut j = Joiner::new();
        j.push(k(KeyCode::Esc), t0);
        let out = j.push(c('q'), t0 + Duration::from_millis(5));
        assert_eq!(codes(&out), vec![KeyCode::Esc, KeyCode::Char('q')]);
        // A second Esc is held in its turn.
        j.push(k(KeyCode::Esc), t0);
        let out = j.push(k(KeyCode::Esc), t0 + Duration::from_millis(5));
        assert_eq!(codes(&out), vec![KeyCode::Esc]);
        assert!(j.deadline().is_some());
    }

    #[test]
    fn a_sequence_completed_too_late_is_typed_as_it_came() {
        let t0 = Instant::now();
        let mut j = Joiner::new();
        j.push(k(KeyCode::Esc), t0);
        let out = j.push(c('['), t0 + WAIT + Duration::from_millis(1));
        assert_eq!(codes(&out), vec![KeyCode::Esc, KeyCode::Char('[')]);
    }

    #[test]
    fn parameters_and_modifiers_are_read() {
        let t0 = Instant::now();
        let mut j = Joiner::new();
        j.push(k(KeyCode::Esc), t0);
        let mut out = Vec::new();
        for ch in "[1;2C".chars() {
            out.extend(j.push(c(ch), t0));
        }
        assert_eq!(out.len(), 1);
        let Event::Key(key) = &out[0] else {
            panic!("a key")
        };
        assert_eq!(
            (key.code, key.modifiers),
            (KeyCode::Right, KeyModifiers::SHIFT)
        );
        j.push(k(KeyCode::Esc), t0);
        let out: Vec<Event> = "[5~".chars().flat_map(|ch| j.push(c(ch), t0)).collect();
        assert_eq!(codes(&out), vec![KeyCode::PageUp]);
        j.push(k(KeyCode::Esc), t0);
        let out: Vec<Event> = "OA".chars().flat_map(|ch| j.push(c(ch), t0)).collect();
        assert_eq!(codes(&out), vec![KeyCode::Up]);
    }
}
