//! End to end: the real `clothsim` binary in a real terminal (tmux), driven by keys and
//! signals and read back with `capture-pane` and tmux's own view of the terminal's modes, as a
//! user sees it.
//!
//! Needs tmux. Without it a test prints a notice and passes, except under CI (`CI=true`),
//! where `.ci/run` installs tmux and its absence is a failure. Every wait polls with a
//! generous deadline, so a loaded two-core machine slows the tests down without failing them.

mod support;

use std::process::Command;
use std::thread::sleep;
use std::time::{Duration, Instant};

use cloth_render::{FRONT_RAMP, PIN_GLYPH};
use support::{ANSWER, SHELL_MODES, START, Tmux, UI_MODES};

impl Tmux {
    /// A new server running `clothsim` (see [`Tmux::open`]).
    fn start(name: &str, width: u16, height: u16) -> Option<Self> {
        Self::open(env!("CARGO_BIN_EXE_clothsim"), name, width, height)
    }
}

fn kill(signal: &str, pid: u32) {
    let o = Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .output()
        .expect("kill runs");
    assert!(o.status.success(), "{o:?}");
}

#[test]
fn the_live_ui_draws_the_cloth_edits_a_parameter_and_restores_the_shell() {
    let Some(t) = Tmux::start("draws", 100, 30) else {
        return;
    };
    t.clothsim("tui pinned4 --paused");
    let s = t.wait_for("the paused UI", ANSWER, |s| s.contains("PAUSED"));
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
    let s = t.wait_for("the edited ks", ANSWER, |s| s.contains("5946 N/m"));
    assert!(s.contains("*ks"), "the edited row is marked:\n{s}");

    // One frame: simulated time moves by 1/90 s.
    t.keys(&["n"]);
    t.wait_for("one frame", ANSWER, |s| s.contains("t 0.011 s"));

    // Too small a terminal gets a clear message, and the layout comes back on resize.
    assert!(
        t.run(&["resize-window", "-t", "e2e", "-x", "50", "-y", "12"])
            .status
            .success()
    );
    t.wait_for("the too-small message", ANSWER, |s| {
        s.contains("terminal too small")
    });
    assert!(
        t.run(&["resize-window", "-t", "e2e", "-x", "100", "-y", "30"])
            .status
            .success()
    );
    t.wait_for("the layout again", ANSWER, |s| s.contains("parameters"));

    // Quit with an edit: it asks, a second q confirms; the shell comes back with its modes.
    t.keys(&["q"]);
    t.wait_for("the unsaved-edits question", ANSWER, |s| {
        s.contains("unsaved edits")
    });
    t.keys(&["q"]);
    let s = t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
    assert!(!s.contains("parameters"), "the UI is gone:\n{s}");
    t.wait_modes("the shell's modes", SHELL_MODES);
    t.assert_cooked();
}

/// Sends `signal` to a running UI and checks the terminal comes back.
fn a_signal_restores_the_terminal(signal: &str, code: i32) {
    let Some(t) = Tmux::start(&signal.to_lowercase(), 100, 30) else {
        return;
    };
    let pid = t.clothsim("tui pinned4");
    kill(signal, pid);
    t.wait_modes("the shell's modes", SHELL_MODES);
    if code != 2 {
        // The shell reports death by the signal: 128 + its number. (After a SIGINT it stops
        // the command list instead, as after a Ctrl-C, so nothing is echoed.)
        let want = format!("exit={}", 128 + code);
        t.wait_for("the shell after the signal", ANSWER, |s| s.contains(&want));
    }
    t.wait_for("the UI gone", ANSWER, |s| !s.contains("parameters"));
    t.assert_cooked();
}

#[test]
fn sigterm_restores_the_terminal() {
    a_signal_restores_the_terminal("TERM", 15);
}

#[test]
fn sighup_restores_the_terminal() {
    a_signal_restores_the_terminal("HUP", 1);
}

#[test]
fn sigint_and_sigquit_restore_the_terminal() {
    a_signal_restores_the_terminal("INT", 2);
    a_signal_restores_the_terminal("QUIT", 3);
}

#[test]
fn ctrl_z_suspends_and_fg_resumes_in_raw_mode_and_redraws() {
    let Some(t) = Tmux::start("suspend", 100, 30) else {
        return;
    };
    // Job control needs the program run by the interactive shell itself.
    let bin = env!("CARGO_BIN_EXE_clothsim");
    t.keys(&[&format!("\"{bin}\" tui pinned4 --paused"), "Enter"]);
    t.wait_for("the UI", START, |s| s.contains("PAUSED"));
    t.wait_modes("the UI's modes", UI_MODES);

    t.keys(&["C-z"]);
    t.wait_modes("the shell's modes after Ctrl-Z", SHELL_MODES);
    t.assert_cooked();
    t.keys(&["clear; fg", "Enter"]);
    t.wait_modes("the UI's modes after fg", UI_MODES);
    // Redrawn, and in raw mode: a single key acts without Enter and is not echoed.
    t.wait_for("the redrawn UI", ANSWER, |s| s.contains("parameters"));
    t.keys(&["n"]);
    t.wait_for("one frame after fg", ANSWER, |s| s.contains("t 0.011 s"));

    // The same from another shell's kill -TSTP: the pane's shell runs clothsim as its only
    // child.
    let shell = t.run(&["display", "-p", "-t", "e2e", "#{pane_pid}"]);
    let shell = String::from_utf8_lossy(&shell.stdout).trim().to_owned();
    let child = Command::new("pgrep")
        .args(["-P", &shell])
        .output()
        .expect("pgrep runs");
    let pid: u32 = String::from_utf8_lossy(&child.stdout)
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("one child of the shell: {child:?}"));
    kill("TSTP", pid);
    t.wait_modes("the shell's modes after SIGTSTP", SHELL_MODES);
    t.keys(&["clear; fg", "Enter"]);
    t.wait_modes("the UI's modes after fg", UI_MODES);
    t.keys(&["n"]);
    t.wait_for("another frame", ANSWER, |s| s.contains("t 0.022 s"));
    t.keys(&["q"]);
    t.wait_modes("the shell's modes after q", SHELL_MODES);
}

#[test]
fn esc_never_quits_and_a_split_escape_sequence_is_one_key() {
    let Some(t) = Tmux::start("esc", 120, 40) else {
        return;
    };
    t.clothsim("tui pinned4 --paused");
    t.keys(&["Escape"]);
    // Accept a prompt, then Esc: still running.
    t.keys(&["Enter"]);
    t.wait_for("the value prompt", ANSWER, |s| s.contains("set a value"));
    t.literal("6000");
    t.keys(&["Enter"]);
    t.wait_for("ks = 6000", ANSWER, |s| s.contains("6000 N/m"));
    t.keys(&["Escape"]);
    sleep(Duration::from_millis(300));
    assert_eq!(t.modes(), UI_MODES, "Esc did not quit:\n{}", t.screen());

    // ↓ as a slow link delivers it: ESC, then `[B` 10 ms later. It selects density (whose
    // help line the panel shows) and types nothing.
    t.keys(&["Escape"]);
    sleep(Duration::from_millis(10));
    t.literal("[B");
    t.wait_for("density selected", ANSWER, |s| {
        s.contains("surface density")
    });
    assert_eq!(t.modes(), UI_MODES);

    t.keys(&["q"]);
    t.wait_for("the question", ANSWER, |s| s.contains("unsaved edits"));
    t.keys(&["Escape"]);
    sleep(Duration::from_millis(300));
    assert_eq!(t.modes(), UI_MODES, "Esc keeps editing");
    t.keys(&["q"]);
    t.keys(&["q"]);
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
}

#[test]
fn q_is_answered_within_half_a_second_on_a_1024_by_1024_cloth() {
    let Some(t) = Tmux::start("big", 120, 40) else {
        return;
    };
    t.clothsim("tui pinned4 --set cloth.num_width_points=1024 --set cloth.num_height_points=1024");
    // Let it run: the steps of a million points are on their own thread.
    t.wait_for("the running cloth", START, |s| s.contains("RUNNING"));
    sleep(Duration::from_secs(2));
    let asked = Instant::now();
    t.keys(&["q"]);
    t.wait_modes("the shell's modes", SHELL_MODES);
    let took = asked.elapsed();
    // NOTE: the modes are polled every 50 ms and tmux answers within a few; half a second
    // is the bound on answering a key, with the poll's slack inside it.
    assert!(
        took < Duration::from_millis(500),
        "q took {took:?} on a 1024 x 1024 cloth"
    );
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
}

/// The status line's time in seconds, as shown (`0.022` of `t 0.022 s`).
fn status_time(screen: &str) -> Option<String> {
    let mut words = screen.lines().next()?.split_whitespace();
    words.find(|w| *w == "t")?;
    words.next().map(str::to_owned)
}

#[test]
fn compare_answers_keys_at_once_while_big_variants_step() {
    let Some(t) = Tmux::start("cmpbig", 160, 48) else {
        return;
    };
    t.clothsim(
        "compare pinned4 --set cloth.num_width_points=256 --set cloth.num_height_points=256 \
         --vary cloth.ks=1000,5000,20000",
    );
    t.wait_for("the variants under way", START, |s| {
        s.contains("RUNNING") && status_time(s).is_some_and(|t| t != "0.000")
    });
    let asked = Instant::now();
    t.keys(&["Space"]);
    t.wait_for("the pause", ANSWER, |s| s.contains("PAUSED"));
    let took = asked.elapsed();
    // NOTE: the screen is polled every 50 ms; half a second holds a key's tenth with the
    // poll's and tmux's slack, while a frame of the three variants of 65,536 points each
    // takes longer in a debug build.
    assert!(
        took < Duration::from_millis(500),
        "space took {took:?} with three 256 x 256 variants"
    );
    // A reset is shown at once too, every variant back at the start on the one clock, though
    // the frame in progress is still being stepped.
    t.keys(&["r"]);
    t.wait_for("the reset", ANSWER, |s| {
        status_time(s).as_deref() == Some("0.000") && s.contains("reset")
    });
    t.keys(&["q"]);
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
}

#[test]
fn the_stretch_limit_off_experiment_is_not_stopped() {
    let Some(t) = Tmux::start("stretch", 120, 40) else {
        return;
    };
    t.clothsim("tui pinned4 --paused");
    // Up from the first row wraps to the last (the four wind rows, the default solver's
    // option rows, threads and order), then the solver row: one more is the stretch limit.
    t.keys(&["k", "k", "k", "k", "k", "k", "k", "k", "Right"]);
    t.wait_for("the stretch limit off", ANSWER, |s| {
        s.contains("stretch limit = off")
    });
    t.keys(&["Space"]);
    // The old guard stopped this run at t = 0.456 s; let it run well past that, however
    // slowly the machine runs it.
    let s = t.wait_for("t past 1.5 s", START, |s| {
        s.contains("simulation stopped")
            || s.split_whitespace()
                .skip_while(|w| *w != "t")
                .nth(1)
                .and_then(|v| v.parse::<f64>().ok())
                .is_some_and(|v| v > 1.5)
    });
    assert!(
        !s.contains("simulation stopped"),
        "the run was stopped:\n{s}"
    );
    assert!(s.contains("RUNNING"), "{s}");
    t.keys(&["q", "q"]);
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
}

#[test]
fn a_scene_and_ui_flags_at_the_top_level_open_the_ui() {
    let Some(t) = Tmux::start("top", 100, 30) else {
        return;
    };
    let bin = env!("CARGO_BIN_EXE_clothsim");
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

#[test]
fn a_dumb_terminal_is_refused_with_a_pointer_to_render() {
    let Some(t) = Tmux::start("dumb", 100, 30) else {
        return;
    };
    let bin = env!("CARGO_BIN_EXE_clothsim");
    t.keys(&[
        &format!("TERM=dumb \"{bin}\" tui; echo \"exit=$?\""),
        "Enter",
    ]);
    let s = t.wait_for("the refusal", START, |s| s.contains("exit=1"));
    assert!(s.contains("clothsim render"), "{s}");
    assert_eq!(
        t.modes(),
        SHELL_MODES,
        "no alternate screen, no mouse:\n{s}"
    );
}

#[test]
fn r_records_the_screen_to_a_cast_file_named_in_the_status_line() {
    let Some(t) = Tmux::start("record", 100, 30) else {
        return;
    };
    t.clothsim("tui pinned4 --paused");
    t.keys(&["R"]);
    t.wait_for("the recording", ANSWER, |s| s.contains("REC pinned4.cast"));
    t.keys(&["n"]);
    t.wait_for("a frame", ANSWER, |s| s.contains("t 0.011 s"));
    t.keys(&["R"]);
    t.wait_for("the kept recording", ANSWER, |s| {
        s.contains("recording saved to")
    });
    t.keys(&["q"]);
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
    let text = std::fs::read_to_string(t.dir.path().join("pinned4.cast")).unwrap();
    let mut lines = text.lines();
    let head: serde_json::Value = serde_json::from_str(lines.next().unwrap()).unwrap();
    assert_eq!(head["version"], 2);
    assert_eq!(
        (head["width"].as_u64(), head["height"].as_u64()),
        (Some(100), Some(30))
    );
    let events: Vec<(f64, String, String)> =
        lines.map(|l| serde_json::from_str(l).unwrap()).collect();
    assert!(events.len() >= 2, "the screen before and after the frame");
    assert!(
        events.windows(2).all(|w| w[0].0 <= w[1].0),
        "times in order"
    );
    assert!(events[0].2.contains("REC pinned4.cast"));
    // Events hold what changed: played back in the terminal, as `asciinema play` would,
    // they leave the stepped frame on screen.
    let played: String = events.iter().map(|e| e.2.as_str()).collect();
    std::fs::write(t.dir.path().join("played"), played).unwrap();
    t.keys(&["clear; cat played; sleep 5", "Enter"]);
    t.wait_for("the recording played back", ANSWER, |s| {
        s.contains("t 0.011 s") && s.contains("REC pinned4.cast")
    });
}

#[test]
fn an_explicit_colour_flag_beats_no_color() {
    let Some(t) = Tmux::start("nocolor", 100, 30) else {
        return;
    };
    t.clothsim_with("NO_COLOR=1", "tui pinned4 --paused --color 256");
    // The pane's cells with their colours as escapes: the cloth's glyphs are coloured.
    let o = t.run(&["capture-pane", "-p", "-e", "-t", "e2e"]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("38;5;"),
        "no 256-colour foreground on screen:\n{s}"
    );
    t.keys(&["q"]);
    t.wait_for("the shell", ANSWER, |s| s.contains("exit=0"));
}

#[test]
fn simulate_without_out_on_a_terminal_prints_a_summary_and_piped_prints_the_json() {
    let Some(t) = Tmux::start("summary", 120, 30) else {
        return;
    };
    let bin = env!("CARGO_BIN_EXE_clothsim");
    t.keys(&[
        &format!("\"{bin}\" simulate pinned4 --frames 10; echo \"exit=$?\""),
        "Enter",
    ]);
    let s = t.wait_for("the summary", START, |s| {
        s.lines().any(|l| l.starts_with("exit="))
    });
    assert!(s.contains("exit=0"), "{s}");
    assert!(s.contains("pinned4: 10 frames"), "{s}");
    assert!(s.contains("--out state.json"), "{s}");
    assert!(!s.contains("positions"), "no JSON on the terminal:\n{s}");
    t.keys(&["clear", "Enter"]);
    t.keys(&[
        &format!("\"{bin}\" simulate pinned4 --frames 10 | head -c 40; echo; echo \"done=$?\""),
        "Enter",
    ]);
    let s = t.wait_for("the JSON", START, |s| {
        s.lines().any(|l| l.starts_with("done="))
    });
    assert!(s.contains("{\"num_width_points\""), "{s}");
}

#[test]
fn the_mouse_grabs_drags_and_lets_go_a_point_of_pinned4() {
    let Some(t) = Tmux::start("hand-verlet", 100, 30) else {
        return;
    };
    support::hands::a_point_is_grabbed_dragged_and_let_go(&t, "tui pinned4 --paused");
}

#[test]
fn the_mouse_grabs_drags_and_lets_go_a_point_under_fast_implicit() {
    let Some(t) = Tmux::start("hand-fast-implicit", 100, 30) else {
        return;
    };
    support::hands::a_point_is_grabbed_dragged_and_let_go(
        &t,
        "tui pinned4 --paused --solver fast-implicit",
    );
}
