//! Terminal events to messages: the one place that knows which key means what.
//!
//! Only key presses count (not repeats' releases), so terminals that report releases do not
//! act twice. The main screen goes through [`super::keymap::KEYMAP`]; overlays take their own
//! few keys (typing, moving, accepting, Esc) and swallow the rest.

use ratatui::crossterm::event::{
    Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
};

use super::keymap;
use super::message::Message;
use super::model::{App, Overlay};

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
    let ctrl_c = k.code == KeyCode::Char('c') && k.modifiers.contains(KeyModifiers::CONTROL);
    if ctrl_c {
        return Some(Message::Quit);
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
            // The fault box answers the recovery keys directly, so the advice it gives works.
            KeyCode::Esc | KeyCode::Enter => Some(Message::Escape),
            _ => keymap::lookup(k).filter(|m| {
                matches!(
                    m,
                    Message::Reset
                        | Message::Quit
                        | Message::RestoreAll
                        | Message::RestoreParam
                        | Message::SelectNext
                        | Message::SelectPrev
                        | Message::Nudge { .. }
                        | Message::EditValue
                )
            }),
        },
        Overlay::Picker(_) => match k.code {
            KeyCode::Esc => Some(Message::Escape),
            KeyCode::Up | KeyCode::Char('k') => Some(Message::Move(-1)),
            KeyCode::Down | KeyCode::Char('j') => Some(Message::Move(1)),
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
            KeyCode::Char(c) if !k.modifiers.contains(KeyModifiers::CONTROL) => {
                Some(Message::Input(c))
            }
            _ => None,
        },
        Overlay::ConfirmOverwrite(_) => match k.code {
            KeyCode::Char('y' | 'Y') => Some(Message::Answer(true)),
            KeyCode::Char('n' | 'N') | KeyCode::Esc => Some(Message::Answer(false)),
            _ => None,
        },
    }
}

fn mouse(m: MouseEvent) -> Option<Message> {
    let (col, row) = (m.column, m.row);
    match m.kind {
        MouseEventKind::Down(MouseButton::Left) => Some(Message::MouseDown { col, row }),
        MouseEventKind::Drag(MouseButton::Left) => Some(Message::MouseDrag { col, row }),
        MouseEventKind::Up(MouseButton::Left) => Some(Message::MouseUp),
        MouseEventKind::ScrollUp => Some(Message::Wheel { col, row, dir: -1 }),
        MouseEventKind::ScrollDown => Some(Message::Wheel { col, row, dir: 1 }),
        _ => None,
    }
}
