//! The completion scripts in the shells themselves: what a user's Tab offers after each
//! command, in zsh (through `capture.zsh`, an interactive zsh on a pseudo-terminal) and bash
//! (its completion function called as bash calls it).

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_clothsim");

/// Every command, with the long flags its `--help` lists.
fn commands() -> Vec<(String, BTreeSet<String>)> {
    let names = [
        "tui",
        "compare",
        "simulate",
        "render",
        "scenes",
        "solvers",
        "bench",
        "check",
        "completions",
        "man",
    ];
    names
        .iter()
        .map(|&name| {
            let o = Command::new(BIN)
                .args([name, "--help"])
                .output()
                .expect("the binary runs");
            assert!(o.status.success(), "{name} --help");
            let help = String::from_utf8(o.stdout).expect("UTF-8");
            let flags = help
                .lines()
                .filter_map(|l| {
                    let l = l.trim_start();
                    let l = l
                        .strip_prefix("-")
                        .filter(|r| r.len() > 2 && r.as_bytes()[1] == b',')
                        .map_or(l, |r| r[2..].trim_start());
                    l.starts_with("--").then(|| {
                        l.split([' ', '=', '<', '.'])
                            .next()
                            .unwrap_or_default()
                            .to_owned()
                    })
                })
                .collect();
            (name.to_owned(), flags)
        })
        .collect()
}

/// Whether `shell` runs here; under CI it must.
fn available(shell: &str) -> bool {
    let ok = Command::new(shell)
        .args(["-c", "true"])
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "{shell} is required under CI (.ci/run installs it)"
        );
        eprintln!("NOTICE: {shell} is not installed; skipping its completion test");
    }
    ok
}

/// A folder to complete in: a scene file and a file that is none.
fn workdir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(dir.path().join("my-scene.json"), "{}").expect("a file");
    std::fs::write(dir.path().join("notes.txt"), "").expect("a file");
    dir
}

/// What zsh offers on Tab after `line`, with the script in `functions` and `dir` as the
/// working folder.
fn zsh_offers(functions: &Path, dir: &Path, line: &str) -> BTreeSet<String> {
    let capture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/capture.zsh");
    let o = Command::new("timeout")
        .arg("30")
        .args(["zsh", "-f"])
        .arg(&capture)
        .arg(functions)
        .arg(line)
        .current_dir(dir)
        .output()
        .expect("zsh runs");
    let out = String::from_utf8_lossy(&o.stdout);
    out.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(str::to_owned)
        .collect()
}

/// What bash's completion function offers for `words` (the last being completed).
fn bash_offers(script: &Path, dir: &Path, words: &[&str]) -> BTreeSet<String> {
    let quoted: Vec<String> = words.iter().map(|w| format!("'{w}'")).collect();
    let cword = words.len() - 1;
    let (cur, prev) = (words[cword], words[cword - 1]);
    let run = format!(
        "source '{}'; COMP_WORDS=({}); COMP_CWORD={cword}; COMP_LINE='{}'; \
         COMP_POINT=${{#COMP_LINE}}; _clothsim clothsim '{cur}' '{prev}'; \
         printf '%s\\n' \"${{COMPREPLY[@]}}\"",
        script.display(),
        quoted.join(" "),
        words.join(" "),
    );
    let o = Command::new("bash")
        .args(["-c", &run])
        .current_dir(dir)
        .output()
        .expect("bash runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter(|l| !l.is_empty())
        .map(str::to_owned)
        .collect()
}

fn scenes() -> BTreeSet<String> {
    cloth_scene::BUNDLED
        .iter()
        .map(|s| s.name.to_owned())
        .collect()
}

#[test]
fn zsh_offers_each_command_its_own_flags_and_scenes_where_a_scene_goes() {
    if !available("zsh") {
        return;
    }
    let functions = tempfile::tempdir().expect("a temporary folder");
    let o = Command::new(BIN)
        .args(["completions", "zsh"])
        .output()
        .expect("the binary runs");
    assert!(o.status.success());
    std::fs::write(functions.path().join("_clothsim"), o.stdout).expect("the script written");
    let dir = workdir();
    let offers = |line: &str| zsh_offers(functions.path(), dir.path(), line);

    for (name, flags) in commands() {
        let got: BTreeSet<String> = offers(&format!("clothsim {name} --"))
            .into_iter()
            .filter(|c| c.starts_with("--"))
            .collect();
        assert_eq!(got, flags, "clothsim {name} --<Tab>");
    }
    let render = offers("clothsim render -");
    assert!(
        render.contains("--frames") && render.contains("-h"),
        "{render:?}"
    );
    assert!(
        !render.contains("--fps"),
        "not the live UI's flags: {render:?}"
    );

    // A scene's place: the bundled names and scene files, never the commands.
    for line in ["clothsim simulate ", "clothsim render ", "clothsim tui "] {
        let got = offers(line);
        assert!(got.is_superset(&scenes()), "{line}<Tab>: {got:?}");
        assert!(got.contains("my-scene.json"), "{line}<Tab>: {got:?}");
        assert!(
            !got.contains("notes.txt") && !got.contains("render"),
            "{line}<Tab>: {got:?}"
        );
    }
    // The first word: a command or a scene.
    let first = offers("clothsim ");
    assert!(first.is_superset(&scenes()), "{first:?}");
    for command in ["tui", "simulate", "render", "compare", "completions"] {
        assert!(first.contains(command), "{command} in {first:?}");
    }
    // After a scene at the top level, the live UI's flags.
    let ui = offers("clothsim pinned4 --");
    assert!(ui.contains("--paused") && ui.contains("--fps"), "{ui:?}");
    assert!(!ui.contains("--frames"), "{ui:?}");
    // Option values.
    let views = offers("clothsim render --view ");
    for view in ["side", "top", "bottom", "front", "orbit", "all"] {
        assert!(views.contains(view), "{view} in {views:?}");
    }
}

#[test]
fn bash_offers_each_command_its_own_flags_and_scenes_where_a_scene_goes() {
    if !available("bash") {
        return;
    }
    let dir = workdir();
    let o = Command::new(BIN)
        .args(["completions", "bash"])
        .output()
        .expect("the binary runs");
    assert!(o.status.success());
    let script = dir.path().join("clothsim.bash");
    std::fs::write(&script, o.stdout).expect("the script written");
    for (name, flags) in commands() {
        let got: BTreeSet<String> = bash_offers(&script, dir.path(), &["clothsim", &name, "--"])
            .into_iter()
            .filter(|c| c.starts_with("--"))
            .collect();
        assert_eq!(got, flags, "clothsim {name} --<Tab>");
    }
    for command in ["simulate", "render", "tui"] {
        let got = bash_offers(&script, dir.path(), &["clothsim", command, ""]);
        assert!(
            got.is_superset(&scenes()),
            "clothsim {command} <Tab>: {got:?}"
        );
        assert!(!got.contains("render"), "clothsim {command} <Tab>: {got:?}");
    }
    let first = bash_offers(&script, dir.path(), &["clothsim", ""]);
    assert!(
        first.is_superset(&scenes()) && first.contains("simulate"),
        "{first:?}"
    );
}
