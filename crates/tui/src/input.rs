//! Terminal events to messages: the one place that knows which key means what.
//!
//! Only key presses count (not repeats' releases), so terminals that report releases do not
//! act twice. The main screen goes through [`super::keymap::KEYMAP`]; overlays take their own
//! few keys (typing, moving, accepting, Esc) and swallow the rest.

use ratatui::crossterm::event::{
    Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
};

use super::keymap;
use super::message::{Button, Message};
use super::model::{App, Overlay, Then};

/// The message for a terminal event, if it means anything now.
pub fn message(app: &App, event: &Event) -> Option<Message> {
    match event {
        Event::Key(k) if k.kind != KeyEventKind::Release => key(app, k),
        Event::Mouse(m) if app.overlay == Overlay::None => mouse(*m),
        Event::Resize(width, height) => Some(Message::Resize {
            width: *width,
            height: *height,
        }),
        _ => None,
    }
}

fn key(app: &App, k: &KeyEvent) -> Option<Message> {
    let ctrl = k.modifiers.contains(KeyModifiers::CONTROL);
    match k.code {
        // Ctrl-C quits from anywhere (asking first about unsaved edits; a second confirms).
        KeyCode::Char('c') if ctrl => return Some(Message::Quit),
        KeyCode::Char('z') if ctrl => return Some(Message::Suspend),
        _ => {}
    }
    match &app.overlay {
        Overlay::None => keymap::lookup(k),
        Overlay::Help => match k.code {
            KeyCode::Esc | KeyCode::Char('?' | 'q') | KeyCode::Enter => Some(Message::ToggleHelp),
            KeyCode::Up | KeyCode::Char('k') => Some(Message::Move(-1)),
            KeyCode::Down | KeyCode::Char('j') => Some(Message::Move(1)),
            KeyCode::PageUp => Some(Message::Move(-10)),
            KeyCode::PageDown | KeyCode::Char(' ') => Some(Message::Move(10)),
            _ => None,
        },
        Overlay::Fault => match k.code {
            // The fault box answers the recovery keys directly, so the advice it gives works;
            // other keys (digits typed for a value, say) are swallowed, not sent on.
            KeyCode::Esc => Some(Message::Escape),
            _ => keymap::lookup(k).filter(|m| {
                matches!(
                    m,
                    Message::Reset
                        | Message::Quit
                        | Message::TogglePause
                        | Message::RestoreAll
                        | Message::Undo
                        | Message::SelectNext
                        | Message::SelectPrev
                        | Message::Nudge { .. }
                        | Message::EditValue
                        | Message::ToggleHelp
                )
            }),
        },
        Overlay::Picker(_) => match k.code {
            KeyCode::Esc => Some(Message::Escape),
            KeyCode::Up | KeyCode::Char('k') => Some(Message::Move(-1)),
            KeyCode::Down | KeyCode::Char('j') => Some(Message::Move(1)),
            KeyCode::PageUp | KeyCode::Home => Some(Message::Move(-100)),
            KeyCode::PageDown | KeyCode::End => Some(Message::Move(100)),
            KeyCode::Enter => Some(Message::Submit),
            _ => None,
        },
        Overlay::Prompt(_) => match k.code {
            KeyCode::Esc => Some(Message::Escape),
            KeyCode::Enter => Some(Message::Submit),
            KeyCode::Backspace => Some(Message::Backspace),
            KeyCode::Delete => Some(Message::Delete),
            KeyCode::Left => Some(Message::Move(-1)),
            KeyCode::Right => Some(Message::Move(1)),
            KeyCode::Home => Some(Message::Home),
            KeyCode::End => Some(Message::End),
            KeyCode::Char('a') if ctrl => Some(Message::Home),
            KeyCode::Char('e') if ctrl => Some(Message::End),
            KeyCode::Char('u') if ctrl => Some(Message::KillToStart),
            KeyCode::Char('k') if ctrl => Some(Message::KillToEnd),
            KeyCode::Char('w') if ctrl => Some(Message::KillWord),
            KeyCode::Char('h') if ctrl => Some(Message::Backspace),
            KeyCode::Char('b') if ctrl => Some(Message::Move(-1)),
            KeyCode::Char('f') if ctrl => Some(Message::Move(1)),
            KeyCode::Char(c) if !ctrl => Some(Message::Input(c)),
            _ => None,
        },
        Overlay::ConfirmOverwrite(_) | Overlay::ConfirmBig(_) => match k.code {
            KeyCode::Char('y' | 'Y') => Some(Message::Answer(true)),
            KeyCode::Char('n' | 'N') | KeyCode::Esc => Some(Message::Answer(false)),
            _ => None,
        },
        Overlay::ConfirmDiscard(then) => match k.code {
            KeyCode::Char('y' | 'Y') | KeyCode::Enter => Some(Message::Answer(true)),
            // The key that asked, pressed again, confirms.
            KeyCode::Char('q') if *then == Then::Quit => Some(Message::Quit),
            KeyCode::Char('o') if *then == Then::Open => Some(Message::OpenPicker),
            KeyCode::Char('S') => Some(Message::Save),
            KeyCode::Char('n' | 'N') | KeyCode::Esc => Some(Message::Answer(false)),
            _ => None,
        },
    }
}

fn mouse(m: MouseEvent) -> Option<Message> {
    let (col, row) = (m.column, m.row);
    let button = |b: MouseButton| match b {
        MouseButton::Left => Button::Left,
        MouseButton::Middle => Button::Middle,
        MouseButton::Right => Button::Right,
    };
    match m.kind {
        MouseEventKind::Down(b) => Some(Message::MouseDown {
            col,
            row,
            button: button(b),
            ctrl: m.modifiers.contains(KeyModifiers::CONTROL),
        }),
        MouseEventKind::Drag(_) => Some(Message::MouseDrag { col, row }),
        MouseEventKind::Up(_) => Some(Message::MouseUp),
        MouseEventKind::ScrollUp => Some(Message::Wheel { col, row, dir: -1 }),
        MouseEventKind::ScrollDown => Some(Message::Wheel { col, row, dir: 1 }),
        _ => None,
    }
}
