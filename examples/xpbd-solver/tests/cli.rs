//! The `clothsim-xpbd` binary calls itself by its own name: in its help, `--version`, manual
//! pages and completion scripts, so that installing it beside `clothsim` replaces none of
//! clothsim's files and its own commands complete.

use std::process::{Command, Output};

fn xpbd(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_clothsim-xpbd"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// Standard output of a run that must succeed.
fn stdout(args: &[&str]) -> String {
    let o = xpbd(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).expect("UTF-8")
}

/// Whether `text` names `clothsim` anywhere other than as part of `clothsim-xpbd`.
fn names_clothsim_alone(text: &str) -> bool {
    text.replace("clothsim-xpbd", "").contains("clothsim")
}

#[test]
fn the_version_and_help_name_the_plug_in_binary() {
    let version = stdout(&["--version"]);
    assert!(
        version.starts_with(&format!("clothsim-xpbd {}", env!("CARGO_PKG_VERSION"))),
        "{version}"
    );
    assert!(version.contains("xpbd"), "its solver is listed: {version}");

    let help = stdout(&["--help"]);
    for needle in [
        "Usage: clothsim-xpbd",
        "`clothsim-xpbd solvers`",
        "clothsim-xpbd sphere --paused",
        "completions/clothsim-xpbd",
    ] {
        assert!(help.contains(needle), "{needle} in:\n{help}");
    }
    assert!(!names_clothsim_alone(&help), "{help}");
    for command in ["simulate", "render", "bench", "completions", "man"] {
        let help = stdout(&[command, "--help"]);
        assert!(
            help.contains(&format!("Usage: clothsim-xpbd {command}")),
            "{help}"
        );
        assert!(!names_clothsim_alone(&help), "{command}:\n{help}");
    }
}

#[test]
fn the_manual_pages_are_the_plug_in_binarys() {
    let page = stdout(&["man"]);
    assert!(page.contains(".TH clothsim-xpbd 1"), "{page}");
    let dir = std::env::temp_dir().join(format!("clothsim-xpbd-man-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the pages");
    let listed = stdout(&["man", "--dir", dir.to_str().expect("a UTF-8 path")]);
    let pages: Vec<String> = std::fs::read_dir(&dir)
        .expect("the folder lists")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .collect();
    std::fs::remove_dir_all(&dir).expect("the folder is removed");
    assert!(listed.is_empty(), "{listed}");
    for page in ["clothsim-xpbd.1", "clothsim-xpbd-simulate.1"] {
        assert!(pages.iter().any(|p| p == page), "{page} in {pages:?}");
    }
    assert!(
        pages.iter().all(|p| p.starts_with("clothsim-xpbd")),
        "{pages:?}"
    );
}

/// What bash completes for the command line `words` (the last one being completed), with the
/// script that `clothsim-xpbd completions bash` prints loaded.
fn bash_completes(script: &str, words: &[&str]) -> Vec<String> {
    let words_list = words.join(" ");
    let current = words.last().copied().unwrap_or_default();
    let previous = words
        .get(words.len().saturating_sub(2))
        .copied()
        .unwrap_or_default();
    // bash calls the function with the command's name, the word being completed and the one
    // before it, COMP_WORDS and COMP_CWORD set.
    let run = format!(
        "eval \"$1\"; COMP_WORDS=({words_list}); COMP_CWORD={}; \
         _clothsim__xpbd clothsim-xpbd '{current}' '{previous}'; \
         printf '%s\\n' \"${{COMPREPLY[@]}}\"",
        words.len() - 1
    );
    let o = Command::new("bash")
        .args(["-c", &run, "bash", script])
        .output()
        .expect("bash runs");
    assert!(
        o.status.success(),
        "{words:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(str::to_owned)
        .collect()
}

#[test]
fn bash_completes_the_plug_in_binary_and_its_commands() {
    let script = stdout(&["completions", "bash"]);
    assert!(
        script.contains("-o bashdefault -o default clothsim-xpbd\n"),
        "the script completes clothsim-xpbd:\n{script}"
    );
    assert!(
        !script.contains("default clothsim\n"),
        "it leaves clothsim's completion alone"
    );
    let commands = bash_completes(&script, &["clothsim-xpbd", "sim"]);
    assert_eq!(commands, ["simulate"]);
    // Past a command, its own options and the bundled scenes complete.
    let options = bash_completes(&script, &["clothsim-xpbd", "simulate", "--fra"]);
    assert_eq!(options, ["--frames"]);
    let scenes = bash_completes(&script, &["clothsim-xpbd", "simulate", "pinned"]);
    assert!(scenes.iter().any(|s| s == "pinned4"), "{scenes:?}");
    let solvers = bash_completes(&script, &["clothsim-xpbd", "simulate", "--solver", "xp"]);
    assert_eq!(solvers, ["xpbd"]);
}

#[test]
fn zsh_and_fish_complete_the_plug_in_binary() {
    let zsh = stdout(&["completions", "zsh"]);
    assert!(zsh.starts_with("#compdef clothsim-xpbd\n"), "{zsh}");
    let fish = stdout(&["completions", "fish"]);
    assert!(fish.contains("complete -c clothsim-xpbd "), "{fish}");
    assert!(!fish.contains("complete -c clothsim "), "{fish}");
}

#[test]
fn the_lines_a_run_writes_to_stderr_name_the_plug_in_binary() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let out = dir.path().join("state.json");
    let o = xpbd(&[
        "simulate",
        "pinned4",
        "--solver",
        "verlet",
        "--frames",
        "2",
        "--progress",
        "always",
        "--out",
        out.to_str().expect("a UTF-8 path"),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.starts_with("clothsim-xpbd: pinned4: 2 of 2 frames simulated"),
        "{stderr}"
    );
    assert!(!names_clothsim_alone(&stderr), "{stderr}");
}
