//! Styles, in colour or without (under `NO_COLOR`): without colour, emphasis is bold, reverse
//! and dim, so nothing depends on colour.

use ratatui::style::{Color, Modifier, Style};

/// The styles the view uses.
#[derive(Debug, Clone, Copy)]
pub struct Theme {
    /// Plain text.
    pub text: Style,
    /// Less important text.
    pub dim: Style,
    /// Pane and panel borders.
    pub border: Style,
    /// The focused pane's border.
    pub focus: Style,
    /// The selected parameter row.
    pub selected: Style,
    /// A value that differs from the scene's.
    pub edited: Style,
    /// Key names in the footer and help.
    pub key: Style,
    /// Informational notes.
    pub info: Style,
    /// Warnings.
    pub warn: Style,
    /// Errors and the fault box.
    pub error: Style,
    /// The running state in the status line.
    pub running: Style,
    /// The paused state.
    pub paused: Style,
    /// Kinetic-energy plot.
    pub plot_energy: Style,
    /// Stretch plot.
    pub plot_stretch: Style,
}

impl Theme {
    /// The theme with or without colour.
    pub fn new(color: bool) -> Self {
        let bold = Style::new().add_modifier(Modifier::BOLD);
        if color {
            Self {
                text: Style::new(),
                dim: Style::new().fg(Color::DarkGray),
                border: Style::new().fg(Color::DarkGray),
                focus: Style::new().fg(Color::Cyan),
                selected: Style::new().fg(Color::Black).bg(Color::Cyan),
                edited: Style::new().fg(Color::Yellow),
                key: Style::new().fg(Color::Cyan).add_modifier(Modifier::BOLD),
                info: Style::new(),
                warn: Style::new().fg(Color::Yellow).add_modifier(Modifier::BOLD),
                error: Style::new().fg(Color::Red).add_modifier(Modifier::BOLD),
                running: Style::new().fg(Color::Green).add_modifier(Modifier::BOLD),
                paused: Style::new().fg(Color::Yellow).add_modifier(Modifier::BOLD),
                plot_energy: Style::new().fg(Color::Magenta),
                plot_stretch: Style::new().fg(Color::Blue),
            }
        } else {
            Self {
                text: Style::new(),
                dim: Style::new().add_modifier(Modifier::DIM),
                border: Style::new(),
                focus: bold,
                selected: Style::new().add_modifier(Modifier::REVERSED),
                edited: bold,
                key: bold,
                info: Style::new(),
                warn: bold,
                error: bold,
                running: bold,
                paused: bold,
                plot_energy: Style::new(),
                plot_stretch: Style::new(),
            }
        }
    }
}
