//! The one keymap: it dispatches keys, and generates the footer and the help overlay.

use std::f64::consts::PI;

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use super::message::Message;

/// A key with the modifiers that matter (Shift is ignored for characters: `H` is `H`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Key {
    /// The key.
    pub code: KeyCode,
    /// Required modifiers (only Control and Shift are compared; Shift only for non-characters).
    pub mods: KeyModifiers,
}

const fn key(code: KeyCode) -> Key {
    Key {
        code,
        mods: KeyModifiers::NONE,
    }
}

const fn ch(c: char) -> Key {
    key(KeyCode::Char(c))
}

const fn ctrl(c: char) -> Key {
    Key {
        code: KeyCode::Char(c),
        mods: KeyModifiers::CONTROL,
    }
}

const fn shift(code: KeyCode) -> Key {
    Key {
        code,
        mods: KeyModifiers::SHIFT,
    }
}

impl Key {
    /// Whether the event is this key.
    pub fn matches(&self, ev: &KeyEvent) -> bool {
        let relevant = KeyModifiers::CONTROL | KeyModifiers::SHIFT;
        let mut mods = ev.modifiers & relevant;
        if let KeyCode::Char(_) = ev.code {
            mods.remove(KeyModifiers::SHIFT);
        }
        if ev.code == KeyCode::BackTab {
            mods.remove(KeyModifiers::SHIFT);
        }
        self.code == ev.code && self.mods == mods
    }

    /// How the key is written in the footer and the help.
    pub fn label(&self) -> String {
        let base = match self.code {
            KeyCode::Char(' ') => "space".to_owned(),
            KeyCode::Char(c) => c.to_string(),
            KeyCode::Up => "↑".to_owned(),
            KeyCode::Down => "↓".to_owned(),
            KeyCode::Left => "←".to_owned(),
            KeyCode::Right => "→".to_owned(),
            KeyCode::Enter => "Enter".to_owned(),
            KeyCode::Esc => "Esc".to_owned(),
            KeyCode::Tab => "Tab".to_owned(),
            KeyCode::BackTab => "S-Tab".to_owned(),
            KeyCode::Backspace => "Bksp".to_owned(),
            KeyCode::F(n) => format!("F{n}"),
            other => format!("{other:?}"),
        };
        if self.mods.contains(KeyModifiers::CONTROL) {
            format!("C-{base}")
        } else if self.mods.contains(KeyModifiers::SHIFT) {
            format!("S-{base}")
        } else {
            base
        }
    }
}

/// Which part of the help a binding belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// Running the simulation.
    Simulation,
    /// The parameter panel.
    Parameters,
    /// Panes and cameras.
    Views,
    /// Touching the cloth: grab, pin, cut, poke.
    Hands,
    /// Scenes, help, quitting.
    General,
}

impl Group {
    /// Every group, in help order.
    pub const ALL: [Group; 5] = [
        Group::Simulation,
        Group::Hands,
        Group::Parameters,
        Group::Views,
        Group::General,
    ];

    /// Heading in the help.
    pub fn title(self) -> &'static str {
        match self {
            Group::Simulation => "Simulation",
            Group::Parameters => "Parameters",
            Group::Views => "Views",
            Group::Hands => "Touching the cloth",
            Group::General => "General",
        }
    }
}

/// One line of the keymap.
#[derive(Debug, Clone, Copy)]
pub struct Binding {
    /// The keys (any of them).
    pub keys: &'static [Key],
    /// What it does, for the help.
    pub help: &'static str,
    /// Keys and a short word for the footer; `None` keeps it out of the footer.
    pub footer: Option<(&'static str, &'static str)>,
    /// Help section.
    pub group: Group,
    /// What it sends.
    pub message: Message,
}

/// Orbit rotation per key press, radians (10 degrees).
const TURN: f64 = PI / 18.0;
/// Zoom factor per key press or wheel notch.
pub const ZOOM: f64 = 0.85;

/// Every key of the main screen, in footer and help order.
pub const KEYMAP: &[Binding] = &[
    Binding {
        keys: &[ch('?')],
        help: "show or hide this help",
        footer: Some(("?", "help")),
        group: Group::General,
        message: Message::ToggleHelp,
    },
    Binding {
        keys: &[ch('q'), ctrl('c')],
        help: "quit (asks first when there are unsaved edits)",
        footer: Some(("q", "quit")),
        group: Group::General,
        message: Message::Quit,
    },
    Binding {
        keys: &[key(KeyCode::Esc)],
        help: "close the box or prompt that is open",
        footer: None,
        group: Group::General,
        message: Message::Escape,
    },
    Binding {
        keys: &[ctrl('z')],
        help: "suspend to the shell (fg brings it back)",
        footer: None,
        group: Group::General,
        message: Message::Suspend,
    },
    Binding {
        keys: &[ch(' '), ch('p')],
        help: "pause / resume",
        footer: Some(("space", "pause")),
        group: Group::Simulation,
        message: Message::TogglePause,
    },
    Binding {
        keys: &[ch('n')],
        help: "advance exactly one frame (pauses)",
        footer: Some(("n", "step")),
        group: Group::Simulation,
        message: Message::StepFrame,
    },
    Binding {
        keys: &[ch('r')],
        help: "reset the cloth, keep the parameters",
        footer: Some(("r", "reset")),
        group: Group::Simulation,
        message: Message::Reset,
    },
    Binding {
        keys: &[ch('+'), ch('=')],
        help: "simulated time faster (x2)",
        footer: None,
        group: Group::Simulation,
        message: Message::Faster,
    },
    Binding {
        keys: &[ch('-')],
        help: "simulated time slower (/2)",
        footer: Some(("+/-", "speed")),
        group: Group::Simulation,
        message: Message::Slower,
    },
    Binding {
        keys: &[ch('t')],
        help: "poke the cloth at the focused pane's centre",
        footer: Some(("t", "poke")),
        group: Group::Hands,
        message: Message::Poke,
    },
    Binding {
        keys: &[ch('P')],
        help: "pin / unpin the point under the mouse",
        footer: Some(("P", "pin")),
        group: Group::Hands,
        message: Message::Pin,
    },
    Binding {
        keys: &[ch('A')],
        help: "write the touches since r as an actions file",
        footer: None,
        group: Group::Hands,
        message: Message::WriteActions,
    },
    Binding {
        keys: &[key(KeyCode::Up), ch('k')],
        help: "select the parameter above",
        footer: None,
        group: Group::Parameters,
        message: Message::SelectPrev,
    },
    Binding {
        keys: &[key(KeyCode::Down), ch('j')],
        help: "select the parameter below",
        footer: Some(("↑↓", "select")),
        group: Group::Parameters,
        message: Message::SelectNext,
    },
    Binding {
        keys: &[key(KeyCode::Left), ch('h')],
        help: "decrease (ks, density: /2^(1/4); flip toggle)",
        footer: None,
        group: Group::Parameters,
        message: Message::Nudge {
            dir: -1,
            coarse: false,
        },
    },
    Binding {
        keys: &[key(KeyCode::Right), ch('l')],
        help: "increase the parameter",
        footer: Some(("←→", "adjust")),
        group: Group::Parameters,
        message: Message::Nudge {
            dir: 1,
            coarse: false,
        },
    },
    Binding {
        keys: &[shift(KeyCode::Left), ch('H')],
        help: "decrease coarsely (ks, density: halve)",
        footer: None,
        group: Group::Parameters,
        message: Message::Nudge {
            dir: -1,
            coarse: true,
        },
    },
    Binding {
        keys: &[shift(KeyCode::Right), ch('L')],
        help: "increase coarsely (ks, density: double)",
        footer: None,
        group: Group::Parameters,
        message: Message::Nudge {
            dir: 1,
            coarse: true,
        },
    },
    Binding {
        keys: &[key(KeyCode::Enter)],
        help: "type an exact value",
        footer: Some(("Enter", "edit")),
        group: Group::Parameters,
        message: Message::EditValue,
    },
    Binding {
        keys: &[ch('u')],
        help: "undo the last edit (again: the one before)",
        footer: Some(("u", "undo")),
        group: Group::Parameters,
        message: Message::Undo,
    },
    Binding {
        keys: &[ch('U')],
        help: "restore every parameter to the scene's value",
        footer: None,
        group: Group::Parameters,
        message: Message::RestoreAll,
    },
    Binding {
        keys: &[ch('v')],
        help: "layout: one, two or four panes",
        footer: Some(("v", "layout")),
        group: Group::Views,
        message: Message::CycleLayout,
    },
    Binding {
        keys: &[ch('f')],
        help: "maximise the focused pane / back",
        footer: Some(("f", "max")),
        group: Group::Views,
        message: Message::ToggleMaximise,
    },
    Binding {
        keys: &[key(KeyCode::Tab)],
        help: "focus the next pane",
        footer: None,
        group: Group::Views,
        message: Message::FocusNext,
    },
    Binding {
        keys: &[key(KeyCode::BackTab)],
        help: "focus the previous pane",
        footer: None,
        group: Group::Views,
        message: Message::FocusPrev,
    },
    Binding {
        keys: &[ch('c')],
        help: "next view in the focused pane (side, top...)",
        footer: Some(("c", "view")),
        group: Group::Views,
        message: Message::CycleView,
    },
    Binding {
        keys: &[ch('m')],
        help: "glyph mode: ascii, half blocks, braille",
        footer: None,
        group: Group::Views,
        message: Message::CycleMode,
    },
    Binding {
        keys: &[ch('C')],
        help: "colour on / off",
        footer: None,
        group: Group::Views,
        message: Message::ToggleColor,
    },
    Binding {
        keys: &[ch('M')],
        help: "mouse capture on / off (off: select text)",
        footer: None,
        group: Group::Views,
        message: Message::ToggleMouse,
    },
    Binding {
        keys: &[ch('a')],
        help: "orbit: turn left (or drag with the mouse)",
        footer: None,
        group: Group::Views,
        message: Message::Orbit {
            yaw: -TURN,
            pitch: 0.0,
        },
    },
    Binding {
        keys: &[ch('d')],
        help: "orbit: turn right",
        footer: None,
        group: Group::Views,
        message: Message::Orbit {
            yaw: TURN,
            pitch: 0.0,
        },
    },
    Binding {
        keys: &[ch('w')],
        help: "orbit: look from higher",
        footer: None,
        group: Group::Views,
        message: Message::Orbit {
            yaw: 0.0,
            pitch: TURN,
        },
    },
    Binding {
        keys: &[ch('s')],
        help: "orbit: look from lower",
        footer: None,
        group: Group::Views,
        message: Message::Orbit {
            yaw: 0.0,
            pitch: -TURN,
        },
    },
    Binding {
        keys: &[ch('z')],
        help: "orbit: zoom in (or the mouse wheel)",
        footer: None,
        group: Group::Views,
        message: Message::Zoom(ZOOM),
    },
    Binding {
        keys: &[ch('x')],
        help: "orbit: zoom out",
        footer: None,
        group: Group::Views,
        message: Message::Zoom(1.0 / ZOOM),
    },
    Binding {
        keys: &[ch('0')],
        help: "orbit: back to the start camera",
        footer: None,
        group: Group::Views,
        message: Message::ResetCamera,
    },
    Binding {
        keys: &[ch('o')],
        help: "open another scene (bundled or a file)",
        footer: Some(("o", "open")),
        group: Group::General,
        message: Message::OpenPicker,
    },
    Binding {
        keys: &[ch('S')],
        help: "save the scene with its edits as JSON",
        footer: Some(("S", "save")),
        group: Group::General,
        message: Message::Save,
    },
    Binding {
        keys: &[ch('e')],
        help: "write the plots' numbers per frame to CSV",
        footer: None,
        group: Group::General,
        message: Message::WriteStats,
    },
    Binding {
        keys: &[ch('R')],
        help: "record the screen to a .cast file / stop",
        footer: None,
        group: Group::General,
        message: Message::ToggleRecording,
    },
];

/// What the mouse does (with the mouse captured), for the help's "Touching the cloth".
pub const MOUSE: &[(&str, &str)] = &[
    ("drag", "carry a point of the cloth (off it: orbit)"),
    ("C-click", "pin / unpin the point (or the middle button)"),
    ("R-drag", "cut the springs the stroke crosses (right)"),
];

/// The message bound to `ev` on the main screen.
pub fn lookup(ev: &KeyEvent) -> Option<Message> {
    KEYMAP
        .iter()
        .find(|b| b.keys.iter().any(|k| k.matches(ev)))
        .map(|b| b.message)
}

/// The keys of a binding, joined for display (`space/p`).
pub fn keys_label(b: &Binding) -> String {
    b.keys.iter().map(Key::label).collect::<Vec<_>>().join("/")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn help_lines_are_short_enough_for_two_columns_at_120_columns() {
        // Two columns of "  KEYS     help" with a gap of 4 and a border fit 120 columns when
        // no help is longer than 46 characters (key labels take 7).
        for b in KEYMAP {
            assert!(b.help.chars().count() <= 46, "{:?} is too long", b.help);
            assert!(keys_label(b).chars().count() <= 7, "{:?}", keys_label(b));
        }
        for (keys, help) in MOUSE {
            assert!(help.chars().count() <= 46, "{help:?} is too long");
            assert!(keys.chars().count() <= 7, "{keys:?}");
        }
    }

    #[test]
    fn no_key_is_bound_twice() {
        let all: Vec<Key> = KEYMAP.iter().flat_map(|b| b.keys.iter().copied()).collect();
        for (i, a) in all.iter().enumerate() {
            assert!(!all[i + 1..].contains(a), "{} is bound twice", a.label());
        }
    }

    #[test]
    fn shift_is_ignored_for_characters_but_not_arrows() {
        let shifted_h = KeyEvent::new(KeyCode::Char('H'), KeyModifiers::SHIFT);
        assert_eq!(
            lookup(&shifted_h),
            Some(Message::Nudge {
                dir: -1,
                coarse: true
            })
        );
        let shift_left = KeyEvent::new(KeyCode::Left, KeyModifiers::SHIFT);
        assert_eq!(
            lookup(&shift_left),
            Some(Message::Nudge {
                dir: -1,
                coarse: true
            })
        );
        let left = KeyEvent::new(KeyCode::Left, KeyModifiers::NONE);
        assert_eq!(
            lookup(&left),
            Some(Message::Nudge {
                dir: -1,
                coarse: false
            })
        );
        let ctrl_q = KeyEvent::new(KeyCode::Char('q'), KeyModifiers::CONTROL);
        assert_eq!(lookup(&ctrl_q), None);
    }
}
