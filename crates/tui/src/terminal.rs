//! The terminal in use: raw mode, the alternate screen, a hidden cursor and mouse capture,
//! entered and left as one, however the program ends.
//!
//! [`TerminalGuard::leave`] puts the terminal back and is safe to call twice; the guard leaves on
//! drop, and a panic hook leaves before the panic message is printed. Signals are the loop's
//! business ([`super::runner`]): it leaves, then ends or stops the process.

use std::io::{self, Write};

use ratatui::Terminal;
use ratatui::crossterm::cursor::{Hide, Show};
use ratatui::crossterm::execute;
use ratatui::crossterm::terminal::{
    EnterAlternateScreen, LeaveAlternateScreen, disable_raw_mode, enable_raw_mode,
};

use super::screen::Screen;

/// The terminal the UI draws on.
pub type Term = Terminal<Screen<io::Stdout>>;

/// Mouse reports of presses, releases and drags (1000, 1002), in SGR form (1006); not every
/// motion (1003), which would send a report for each cell the pointer crosses.
const MOUSE_ON: &[u8] = b"\x1b[?1000h\x1b[?1002h\x1b[?1006h";

/// Every mouse mode off, including those other programs may have left on.
const MOUSE_OFF: &[u8] = b"\x1b[?1006l\x1b[?1015l\x1b[?1003l\x1b[?1002l\x1b[?1000l";

/// An entered terminal.
pub struct TerminalGuard {
    /// The ratatui terminal.
    pub terminal: Term,
    mouse: bool,
    entered: bool,
}

/// Puts the terminal back as the shell expects it; every step is tried whatever fails (on
/// a closed terminal they all do).
pub fn restore_terminal() {
    let mut out = io::stdout();
    let _ = out.write_all(MOUSE_OFF);
    let _ = out.write_all(b"\x1b[0m");
    let _ = execute!(out, LeaveAlternateScreen, Show);
    let _ = disable_raw_mode();
    let _ = out.flush();
}

/// Installs a panic hook that restores the terminal before the panic message prints.
pub fn restore_on_panic() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        restore_terminal();
        previous(info);
    }));
}

fn enter(mouse: bool) -> io::Result<()> {
    enable_raw_mode()?;
    let mut out = io::stdout();
    execute!(out, EnterAlternateScreen, Hide)?;
    if mouse {
        out.write_all(MOUSE_ON)?;
        out.flush()?;
    }
    Ok(())
}

impl TerminalGuard {
    /// Enters the terminal: raw mode, alternate screen, hidden cursor, mouse when `mouse`;
    /// `sixteen` rewrites colours for a 16-colour terminal.
    ///
    /// # Errors
    /// When the terminal refuses; it is left as it was.
    pub fn enter(mouse: bool, sixteen: bool) -> io::Result<Self> {
        if let Err(e) = enter(mouse) {
            restore_terminal();
            return Err(e);
        }
        let backend = Screen::new(io::stdout(), sixteen);
        match Terminal::new(backend) {
            Ok(terminal) => Ok(Self {
                terminal,
                mouse,
                entered: true,
            }),
            Err(e) => {
                restore_terminal();
                Err(e)
            }
        }
    }

    /// Puts the shell's screen back (the alternate screen left, the cursor shown, the mouse
    /// freed) but stays in raw mode, so that what the terminal still sends is read, not echoed.
    pub fn leave_screen(&mut self) {
        if self.entered {
            let mut out = io::stdout();
            let _ = out.write_all(MOUSE_OFF);
            let _ = out.write_all(b"\x1b[0m");
            let _ = execute!(out, LeaveAlternateScreen, Show);
            let _ = out.flush();
        }
    }

    /// Leaves the terminal as the shell expects it (idempotent).
    pub fn leave(&mut self) {
        if self.entered {
            self.entered = false;
            restore_terminal();
        }
    }

    /// Enters again after [`Self::leave`] (on resume) and redraws everything on the next draw.
    ///
    /// # Errors
    /// When the terminal refuses.
    pub fn resume(&mut self) -> io::Result<()> {
        enter(self.mouse)?;
        self.entered = true;
        // A resize to the current size clears the screen and forgets what was drawn.
        let size = self.terminal.size()?;
        self.terminal
            .resize(ratatui::layout::Rect::new(0, 0, size.width, size.height))
    }

    /// Captures the mouse or frees it.
    ///
    /// # Errors
    /// When the terminal cannot be written.
    pub fn set_mouse(&mut self, on: bool) -> io::Result<()> {
        if on != self.mouse {
            self.mouse = on;
            let mut out = io::stdout();
            out.write_all(if on { MOUSE_ON } else { MOUSE_OFF })?;
            out.flush()?;
        }
        Ok(())
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        self.leave();
    }
}
