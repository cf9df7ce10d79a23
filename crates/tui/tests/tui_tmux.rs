//! End to end: the real `clothsim` binary in a real terminal (tmux), driven by keys and read
//! back with `capture-pane`, as a user sees it.
//!
//! Needs tmux. Without it the test prints a notice and passes, except under CI (`CI=true`),
//! where `.ci/run` installs tmux and its absence is a failure.

use std::process::{Command, Output};
use std::thread::sleep;
use std::time::{Duration, Instant};

use cloth_render::{FRONT_RAMP, PIN_GLYPH};

/// A private tmux server (its own socket), killed when the test ends however it ends.
struct Tmux {
    socket: String,
}

impl Tmux {
    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .arg("-L")
            .arg(&self.socket)
            .args(args)
            .output()
            .expect("tmux runs")
    }

    fn screen(&self) -> String {
        let o = self.run(&["capture-pane", "-p", "-t", "e2e"]);
        String::from_utf8_lossy(&o.stdout).into_owned()
    }

    fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", "e2e"];
        args.extend_from_slice(keys);
        assert!(self.run(&args).status.success());
    }

    /// Waits until the screen satisfies `ok`, or fails after `secs` with the screen shown.
    fn wait_for(&self, what: &str, secs: u64, ok: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let s = self.screen();
            if ok(&s) {
                return s;
            }
            assert!(
                start.elapsed() < Duration::from_secs(secs),
                "timed out waiting for {what}; the screen:\n{s}"
            );
            sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

fn tmux_available() -> bool {
    Command::new("tmux")
        .arg("-V")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn the_live_ui_draws_the_cloth_edits_a_parameter_and_restores_the_shell() {
    if !tmux_available() {
        let ci = std::env::var("CI").is_ok_and(|v| v == "true");
        assert!(!ci, "tmux is required under CI (.ci/run installs it)");
        eprintln!("NOTICE: tmux is not installed; skipping the end-to-end TUI test");
        return;
    }
    let t = Tmux {
        socket: format!("clothsim-e2e-{}", std::process::id()),
    };
    let started = t.run(&[
        "new-session",
        "-d",
        "-s",
        "e2e",
        "-x",
        "100",
        "-y",
        "30",
        "sh",
    ]);
    assert!(started.status.success(), "{started:?}");
    // A known shell, so its prompt and echo are predictable.
    t.keys(&["PS1='$ '; stty sane", "Enter"]);
    let bin = env!("CARGO_BIN_EXE_clothsim");
    t.keys(&[
        &format!("{bin} tui pinned4 --paused; echo \"exit=$?\""),
        "Enter",
    ]);

    let s = t.wait_for("the UI", 30, |s| {
        s.contains("parameters") && s.contains("PAUSED")
    });
    // The cloth is drawn: the top view shows the four pins and a shaded sheet between them.
    let pins = s.matches(PIN_GLYPH).count();
    let shaded = s.chars().filter(|c| FRONT_RAMP.contains(c)).count();
    assert!(pins >= 4, "the four pins are drawn:\n{s}");
    assert!(
        shaded >= 200,
        "the sheet is drawn ({shaded} shaded cells):\n{s}"
    );
    assert!(s.contains("5000 N/m"), "ks shows the scene's value:\n{s}");

    // Right arrow on the selected first row (ks) raises it by 2^(1/4): 5946 N/m.
    t.keys(&["Right"]);
    let s = t.wait_for("the edited ks", 10, |s| s.contains("5946 N/m"));
    assert!(s.contains("*ks"), "the edited row is marked:\n{s}");

    // One frame: simulated time moves by 1/90 s.
    t.keys(&["n"]);
    t.wait_for("one frame", 10, |s| s.contains("t 0.011 s"));

    // Too small a terminal gets a clear message, and the layout comes back on resize.
    assert!(
        t.run(&["resize-window", "-t", "e2e", "-x", "50", "-y", "12"])
            .status
            .success()
    );
    t.wait_for("the too-small message", 10, |s| {
        s.contains("terminal too small")
    });
    assert!(
        t.run(&["resize-window", "-t", "e2e", "-x", "100", "-y", "30"])
            .status
            .success()
    );
    t.wait_for("the layout again", 10, |s| s.contains("parameters"));

    // Quit: the shell comes back, out of the alternate screen, with its terminal modes.
    t.keys(&["q"]);
    let s = t.wait_for("the shell", 10, |s| s.contains("exit=0"));
    assert!(!s.contains("parameters"), "the UI is gone:\n{s}");
    t.keys(&["stty -a | grep -o -- '-*icanon' ; echo done", "Enter"]);
    let s = t.wait_for("stty", 10, |s| s.lines().any(|l| l.trim() == "done"));
    assert!(
        s.lines().any(|l| l.trim() == "icanon"),
        "the terminal is back in canonical (cooked) mode:\n{s}"
    );

    // With no arguments: pinned4, running; Esc with nothing open quits.
    t.keys(&["clear", "Enter"]);
    t.keys(&[&format!("{bin}; echo \"bare=$?\""), "Enter"]);
    t.wait_for("the default scene running", 30, |s| {
        s.contains("pinned4") && s.contains("RUNNING")
    });
    t.keys(&["Escape"]);
    t.wait_for("the shell again", 10, |s| s.contains("bare=0"));
}

#[test]
fn a_scene_and_ui_flags_at_the_top_level_open_the_ui() {
    if !tmux_available() {
        let ci = std::env::var("CI").is_ok_and(|v| v == "true");
        assert!(!ci, "tmux is required under CI (.ci/run installs it)");
        eprintln!("NOTICE: tmux is not installed; skipping the end-to-end TUI test");
        return;
    }
    let t = Tmux {
        socket: format!("clothsim-e2e-top-{}", std::process::id()),
    };
    let bin = env!("CARGO_BIN_EXE_clothsim");
    let started = t.run(&[
        "new-session",
        "-d",
        "-s",
        "e2e",
        "-x",
        "100",
        "-y",
        "30",
        "sh",
    ]);
    assert!(started.status.success(), "{started:?}");
    t.keys(&["PS1='$ '; stty sane", "Enter"]);
    t.keys(&[
        &format!("{bin} pinned2 --paused; echo \"exit=$?\""),
        "Enter",
    ]);
    let s = t.wait_for("the UI on pinned2, paused", 30, |s| {
        s.contains("pinned2") && s.contains("PAUSED") && s.contains("parameters")
    });
    assert!(s.contains("t 0.000 s"), "paused from the start:\n{s}");
    t.keys(&["q"]);
    t.wait_for("the shell", 10, |s| s.contains("exit=0"));
}

#[test]
fn without_a_terminal_it_points_to_render() {
    let o = Command::new(env!("CARGO_BIN_EXE_clothsim"))
        .arg("tui")
        .output()
        .expect("the binary runs");
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("clothsim render"), "{e}");
}
