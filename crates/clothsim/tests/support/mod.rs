//! A private tmux server driving a real binary in a real terminal, read back with
//! `capture-pane` and tmux's own view of the terminal's modes: the end-to-end tests' harness,
//! shared by clothsim's tests and the plug-in example's.
//!
//! Without tmux, [`Tmux::open`] prints a notice and gives `None` (the test passes), except under
//! CI (`CI=true`), where `.ci/run` installs tmux and its absence is a failure. Every wait polls
//! with a generous deadline, so a loaded two-core machine slows the tests down without failing
//! them.

#![allow(dead_code)] // NOTE: each test crate uses a part of the harness.

use std::process::{Command, Output};
use std::thread::sleep;
use std::time::{Duration, Instant};

pub mod hands;

/// Seconds to wait for the UI to come up (a debug binary on a busy machine).
pub const START: u64 = 60;
/// Seconds to wait for an answer to a key or a signal.
pub const ANSWER: u64 = 15;

/// What tmux reports of the terminal while the UI runs: alternate screen on, cursor hidden,
/// presses and drags reported, and not every motion of the pointer (mode 1003 would send a
/// report for each cell crossed).
pub const UI_MODES: &str = "1 0 1 0";
/// ... and what a shell expects: alternate screen off, cursor shown, no mouse tracking.
pub const SHELL_MODES: &str = "0 1 0 0";

/// A private tmux server (its own socket) with one pane running `sh`, killed when the test
/// ends however it ends.
pub struct Tmux {
    /// The server's socket name.
    pub socket: String,
    /// The shell's working folder, removed at the end.
    pub dir: tempfile::TempDir,
    /// The binary [`Tmux::clothsim`] starts.
    pub bin: String,
}

impl Tmux {
    /// A new server whose [`Tmux::clothsim`] starts `bin`, or `None` when tmux is not
    /// installed (a failure under CI).
    pub fn open(bin: &str, name: &str, width: u16, height: u16) -> Option<Self> {
        if !tmux_available() {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true");
            assert!(!ci, "tmux is required under CI (.ci/run installs it)");
            eprintln!("NOTICE: tmux is not installed; skipping the end-to-end test {name}");
            return None;
        }
        let t = Tmux {
            socket: format!("clothsim-e2e-{}-{name}", std::process::id()),
            dir: tempfile::tempdir().expect("a temporary folder"),
            bin: bin.to_owned(),
        };
        let (w, h) = (width.to_string(), height.to_string());
        let started = t.run(&[
            "-f",
            "/dev/null",
            "new-session",
            "-d",
            "-s",
            "e2e",
            "-x",
            &w,
            "-y",
            &h,
            "sh",
        ]);
        assert!(started.status.success(), "{started:?}");
        // A known shell, so its prompt and echo are predictable.
        t.keys(&["PS1='$ '; stty sane", "Enter"]);
        t.keys(&[&format!("cd '{}'", t.dir.path().display()), "Enter"]);
        Some(t)
    }

    pub fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .arg("-L")
            .arg(&self.socket)
            .args(args)
            .output()
            .expect("tmux runs")
    }

    pub fn screen(&self) -> String {
        let o = self.run(&["capture-pane", "-p", "-t", "e2e"]);
        String::from_utf8_lossy(&o.stdout).into_owned()
    }

    /// The terminal's modes as tmux sees them: `alternate_on cursor_flag mouse_button_flag
    /// mouse_all_flag` (1003: every motion).
    pub fn modes(&self) -> String {
        let o = self.run(&[
            "display",
            "-p",
            "-t",
            "e2e",
            "#{alternate_on} #{cursor_flag} #{mouse_button_flag} #{mouse_all_flag}",
        ]);
        String::from_utf8_lossy(&o.stdout).trim().to_owned()
    }

    pub fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", "e2e"];
        args.extend_from_slice(keys);
        assert!(self.run(&args).status.success());
    }

    /// Sends `text` as typed characters (no key names).
    pub fn literal(&self, text: &str) {
        assert!(
            self.run(&["send-keys", "-t", "e2e", "-l", text])
                .status
                .success()
        );
    }

    /// Waits until `ok` holds of the screen, or fails after `secs` with the screen shown.
    pub fn wait_for(&self, what: &str, secs: u64, ok: impl Fn(&str) -> bool) -> String {
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
            sleep(Duration::from_millis(50));
        }
    }

    /// Waits until the terminal's modes are `want`.
    pub fn wait_modes(&self, what: &str, want: &str) {
        let start = Instant::now();
        loop {
            let m = self.modes();
            if m == want {
                return;
            }
            assert!(
                start.elapsed() < Duration::from_secs(ANSWER),
                "timed out waiting for {what}: modes {m:?}, want {want:?}; the screen:\n{}",
                self.screen()
            );
            sleep(Duration::from_millis(50));
        }
    }

    /// Starts clothsim with `args` in the pane, its pid written to a file, and the exit
    /// status echoed when it ends; waits for the UI.
    pub fn clothsim(&self, args: &str) -> u32 {
        self.clothsim_with("", args)
    }

    /// As [`Self::clothsim`], with environment assignments `env` (`NAME=VALUE ...`).
    pub fn clothsim_with(&self, env: &str, args: &str) -> u32 {
        let bin = &self.bin;
        self.keys(&["clear", "Enter"]);
        self.keys(&[
            &format!("sh -c 'echo $$ > pid; exec env {env} \"{bin}\" {args}'; echo \"exit=$?\""),
            "Enter",
        ]);
        self.wait_for("the UI", START, |s| s.contains("parameters"));
        self.wait_modes("the UI's terminal modes", UI_MODES);
        self.pid()
    }

    pub fn pid(&self) -> u32 {
        let path = self.dir.path().join("pid");
        std::fs::read_to_string(&path)
            .ok()
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or_else(|| panic!("no pid in {}", path.display()))
    }

    /// Asserts the shell's terminal is back in canonical (cooked) mode with echo.
    pub fn assert_cooked(&self) {
        self.keys(&[
            r"stty -a | tr ' ;' '\n\n' | grep -x -- '-*icanon\|-*echo' | sed 's/^/mode:/'; echo done.",
            "Enter",
        ]);
        let s = self.wait_for("stty", ANSWER, |s| s.lines().any(|l| l.trim() == "done."));
        assert!(
            s.contains("mode:icanon") && s.contains("mode:echo"),
            "the terminal is back in canonical mode with echo:\n{s}"
        );
        assert!(!s.contains("mode:-"), "{s}");
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

pub fn tmux_available() -> bool {
    Command::new("tmux")
        .arg("-V")
        .output()
        .is_ok_and(|o| o.status.success())
}
