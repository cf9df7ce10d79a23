//! The hand end to end: SGR mouse reports sent to the pane grab a point of pinned4, drag it
//! and let it go, as a terminal sends them for a user's mouse.

use super::{ANSWER, Tmux};

/// An SGR (mode 1006) mouse report: button code `cb` (0 left, +32 while moving) at 0-based
/// cell `(col, row)`, pressed (`M`) or released (`m`).
fn sgr(cb: u16, col: usize, row: usize, end: char) -> String {
    format!("\x1b[<{cb};{};{}{end}", col + 1, row + 1)
}

/// The inside of the pane titled `title` (`2 top`): its columns and rows, 0-based, ends
/// excluded.
fn pane(screen: &str, title: &str) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let lines: Vec<Vec<char>> = screen.lines().map(|l| l.chars().collect()).collect();
    let head = format!("┌ {title} ");
    let (r0, c0) = lines
        .iter()
        .enumerate()
        .find_map(|(r, l)| {
            let s: String = l.iter().collect();
            let byte = s.find(&head)?;
            Some((r, s[..byte].chars().count()))
        })
        .unwrap_or_else(|| panic!("no pane {title}:\n{screen}"));
    let c1 = (c0 + 1..lines[r0].len())
        .find(|&c| lines[r0][c] == '┐')
        .expect("the pane's top right corner");
    let r1 = (r0 + 1..lines.len())
        .find(|&r| lines[r].get(c0) == Some(&'└'))
        .expect("the pane's bottom left corner");
    (c0 + 1..c1, r0 + 1..r1)
}

/// Where the held point's mark is on the screen, 0-based.
fn mark(screen: &str) -> Option<(usize, usize)> {
    screen.lines().enumerate().find_map(|(r, l)| {
        l.chars()
            .position(|c| c == cloth_render::HAND_GLYPH)
            .map(|c| (c, r))
    })
}

/// The kinetic energy the plot's title shows, J.
fn kinetic(screen: &str) -> f64 {
    let at = screen.find("kinetic energy ").expect("the energy plot");
    screen[at + "kinetic energy ".len()..]
        .split_whitespace()
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("a number after \"kinetic energy\":\n{screen}"))
}

/// Starts the UI with `args` (pinned4, paused) in a 100 x 30 terminal; presses the left
/// button over the middle of the top view, drags six cells right and three up and steps one
/// frame: the point taken is at the hand (its mark within a cell of the cursor, where the
/// cloth was not) and the cloth moves. Then lets go and runs: the cloth swings on.
pub fn a_point_is_grabbed_dragged_and_let_go(t: &Tmux, args: &str) {
    t.clothsim(args);
    let s = t.wait_for("the paused UI", ANSWER, |s| s.contains("PAUSED"));
    let (cols, rows) = pane(&s, "2 top");
    let (col, row) = (
        usize::midpoint(cols.start, cols.end),
        usize::midpoint(rows.start, rows.end),
    );
    t.literal(&sgr(0, col, row, 'M'));
    // The mark shows once the stepping thread has taken the point.
    t.wait_for("the point taken and marked", ANSWER, |s| {
        s.contains("holding point (") && mark(s).is_some()
    });
    let (to_col, to_row) = (col + 6, row - 3);
    t.literal(&sgr(32, to_col, to_row, 'M'));
    t.keys(&["n"]);
    let s = t.wait_for("the point at the hand after one frame", ANSWER, |s| {
        mark(s).is_some_and(|(c, r)| c.abs_diff(to_col) <= 1 && r.abs_diff(to_row) <= 1)
    });
    assert!(kinetic(&s) > 0.0, "the hand moved the cloth:\n{s}");
    t.literal(&sgr(0, to_col, to_row, 'm'));
    t.wait_for("the point let go", ANSWER, |s| s.contains("let go"));
    t.keys(&["space"]);
    let first = kinetic(&t.wait_for("running", ANSWER, |s| s.contains("RUNNING")));
    let s = t.wait_for("the cloth swinging", ANSWER, |s| {
        s.contains("RUNNING") && kinetic(s) != first
    });
    assert!(mark(&s).is_none(), "nothing is held:\n{s}");
    t.keys(&["q"]);
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
}
