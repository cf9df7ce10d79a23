//! Everything that can happen to the app, as data.

/// A mouse button.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Button {
    /// The left (first) button: grab, or turn the orbit off the cloth.
    Left,
    /// The middle button: pin or unpin.
    Middle,
    /// The right button: cut.
    Right,
}

/// One thing that happened: a key's meaning, a mouse gesture, a resize, time passing.
///
/// Keys become messages in one place (`input`); [`super::update()`] is the only code
/// that changes the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// Leave the app (asking first when there are unsaved edits; a second one confirms).
    Quit,
    /// Close the open box or prompt; nothing else.
    Escape,
    /// Stop the app for the shell (Ctrl-Z); `fg` brings it back.
    Suspend,
    /// Capture the mouse (orbit drag, wheel) or leave it to the terminal (text selection).
    ToggleMouse,
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
    /// Take back the last edit.
    Undo,
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
    /// Write the plots' numbers, one row per frame of the run so far, to a CSV file.
    WriteStats,
    /// Start recording the screen to a `.cast` file, or stop and keep it.
    ToggleRecording,
    /// A character typed into the prompt.
    Input(char),
    /// Delete the character before the prompt's cursor.
    Backspace,
    /// Delete the character at the prompt's cursor.
    Delete,
    /// Delete from the prompt's cursor back to the start of the line (Ctrl-U).
    KillToStart,
    /// Delete from the prompt's cursor to the end of the line (Ctrl-K).
    KillToEnd,
    /// Delete the word before the prompt's cursor (Ctrl-W).
    KillWord,
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
        /// Which button.
        button: Button,
        /// Whether Control was held.
        ctrl: bool,
    },
    /// The mouse moved with a button down.
    MouseDrag {
        /// Column.
        col: u16,
        /// Row.
        row: u16,
    },
    /// The button went up.
    MouseUp,
    /// Poke the cloth at the focused pane's centre (the hand without a mouse).
    Poke,
    /// Pin or unpin the point under the mouse (or at the focused pane's centre).
    Pin,
    /// Write the touches since the start or the last reset as an actions file.
    WriteActions,
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
    /// Wall-clock time passed; a simulation stepped inline owes this much (times the rate).
    /// The live app steps on a worker, which keeps its own clock; tests step inline.
    #[cfg(test)]
    Tick(std::time::Duration),
    /// Fresh measurements from the app loop.
    Measured(super::model::Stats),
}
