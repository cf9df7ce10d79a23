//! Everything that can happen to the app, as data.

use std::time::Duration;

/// One thing that happened: a key's meaning, a mouse gesture, a resize, time passing.
///
/// Keys become messages in one place ([`super::input`]); [`super::update()`] is the only code
/// that changes the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// Leave the app.
    Quit,
    /// Close the open overlay or prompt; quit when nothing is open.
    Escape,
    /// Show or hide the key help.
    ToggleHelp,
    /// Pause or resume the simulation.
    TogglePause,
    /// Advance exactly one frame (pauses first).
    StepFrame,
    /// Back to the start positions, keeping the live parameters.
    Reset,
    /// Double the simulated-time rate.
    Faster,
    /// Halve the simulated-time rate.
    Slower,
    /// Select the parameter above.
    SelectPrev,
    /// Select the parameter below.
    SelectNext,
    /// Nudge the selected parameter up (+1) or down (-1), finely or coarsely.
    Nudge {
        /// +1 or -1.
        dir: i32,
        /// Coarse steps.
        coarse: bool,
    },
    /// Type an exact value for the selected parameter.
    EditValue,
    /// Put the selected parameter back to the scene's value.
    RestoreParam,
    /// Put every parameter back to the scene's values.
    RestoreAll,
    /// Cycle single / two / four panes.
    CycleLayout,
    /// Maximise the focused pane, or restore the layout.
    ToggleMaximise,
    /// Focus the next pane.
    FocusNext,
    /// Focus the previous pane.
    FocusPrev,
    /// Show the next view (side, top, ...) in the focused pane.
    CycleView,
    /// Cycle the glyph mode (ascii, half blocks, braille).
    CycleMode,
    /// Colour on or off.
    ToggleColor,
    /// Turn the orbit camera, radians.
    Orbit {
        /// Yaw change.
        yaw: f64,
        /// Pitch change.
        pitch: f64,
    },
    /// Scale the orbit camera's distance (< 1 zooms in).
    Zoom(f64),
    /// The orbit camera back to its start.
    ResetCamera,
    /// Open the scene picker.
    OpenPicker,
    /// Save the scene with its live parameters.
    Save,
    /// A character typed into the prompt.
    Input(char),
    /// Delete the character before the prompt's cursor.
    Backspace,
    /// Delete the character at the prompt's cursor.
    Delete,
    /// Move the prompt's cursor or the picker's selection left / up (-1) or right / down (+1).
    Move(i32),
    /// The prompt's cursor to the start.
    Home,
    /// The prompt's cursor to the end.
    End,
    /// Accept the prompt or the picked entry.
    Submit,
    /// Answer to a yes/no question.
    Answer(bool),
    /// A mouse button went down at a cell.
    MouseDown {
        /// Column.
        col: u16,
        /// Row.
        row: u16,
    },
    /// The mouse moved with the button down.
    MouseDrag {
        /// Column.
        col: u16,
        /// Row.
        row: u16,
    },
    /// The button went up.
    MouseUp,
    /// The wheel turned over a cell (+1 = towards the user = zoom out).
    Wheel {
        /// Column.
        col: u16,
        /// Row.
        row: u16,
        /// +1 or -1.
        dir: i32,
    },
    /// The terminal now has this size.
    Resize {
        /// Columns.
        width: u16,
        /// Rows.
        height: u16,
    },
    /// Wall-clock time passed; a running simulation owes this much (times the rate).
    Tick(Duration),
    /// Fresh measurements from the app loop.
    Measured(super::model::Stats),
}
