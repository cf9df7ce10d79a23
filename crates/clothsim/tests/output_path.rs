//! Every command's output path under a reader that went away, a full disk and a closed
//! standard output: a reader that went away is a normal end (exit 0, nothing on stderr), the
//! others are one clear error and a non-zero exit, and nothing panics.
#![cfg(unix)]

use std::fs::File;
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_clothsim");

/// Every command that writes to standard output, with small, quick arguments; each writes
/// more than a pipe holds or at least a line.
fn commands() -> Vec<Vec<&'static str>> {
    vec![
        vec!["scenes"],
        vec!["simulate", "pinned4", "--frames", "1"],
        vec![
            "render", "pinned4", "--frames", "4", "--every", "1", "--size", "40x20",
        ],
        vec!["bench", "--grid", "6", "--frames", "1"],
        vec!["bench", "--grid", "6", "--frames", "1", "--json"],
        vec![
            "bench",
            "--grid",
            "6",
            "--frames",
            "1",
            "--interleave",
            "--solver",
            "verlet",
            "--order",
            "faithful",
            "--order",
            "colored",
        ],
        vec!["--help"],
        vec!["simulate", "--help"],
        vec!["--version"],
    ]
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `args` with standard output going to `out`.
fn run_with(args: &[&str], out: Stdio) -> Output {
    Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(Stdio::piped())
        .output()
        .expect("the binary runs")
}

#[test]
fn a_reader_that_went_away_ends_every_command_quietly_with_exit_0() {
    for args in commands() {
        // The pipe's reading end is closed before the program starts, so its first write
        // meets a pipe with no reader, deterministically (no race with a reader quitting).
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let o = run_with(&args, Stdio::from(writer));
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).is_empty(), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn a_full_disk_is_one_clear_error_and_a_non_zero_exit_for_every_command() {
    for args in commands() {
        let full = File::options().write(true).open("/dev/full").unwrap();
        let o = run_with(&args, Stdio::from(full));
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(
            e.starts_with("clothsim: error: ")
                && e.contains("cannot write to standard output: No space left on device"),
            "{args:?}: {e}"
        );
        assert_eq!(e.lines().count(), 1, "one message: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
}

#[test]
fn a_closed_standard_output_is_an_error_not_output_lost_in_silence() {
    for args in commands() {
        // `exec ... >&-` starts the program with descriptor 1 closed, as a shell user would.
        let o = Command::new("sh")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" >&-")
            .arg(BIN)
            .args(&args)
            .stdin(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .expect("sh runs");
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(e.contains("standard output is closed"), "{args:?}: {e}");
    }
}

#[test]
fn a_closed_standard_output_does_not_matter_when_the_result_goes_to_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("state.json");
    let o = Command::new("sh")
        .arg("-c")
        .arg("exec \"$0\" \"$@\" >&-")
        .arg(BIN)
        .args(["simulate", "pinned4", "--frames", "1", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&out).unwrap().contains("positions"));
}

#[test]
fn output_to_dev_null_is_a_success() {
    // /dev/null opened by the shell for writing is a place the user chose, unlike a closed
    // descriptor.
    let null = File::options().write(true).open("/dev/null").unwrap();
    let o = run_with(&["scenes"], Stdio::from(null));
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_usage_error_still_goes_to_stderr_with_exit_2() {
    let o = run_with(&["simulate", "--frames", "x", "pinned4"], Stdio::piped());
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("invalid value 'x'"), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
}

/// Where standard output goes in a generated case.
#[derive(Debug, Clone, Copy)]
enum Sink {
    ReaderGone,
    Full,
    Closed,
}

fn run_into(args: &[String], sink: Sink) -> Output {
    match sink {
        Sink::ReaderGone => {
            let (reader, writer) = std::io::pipe().unwrap();
            drop(reader);
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            run_with(&args, Stdio::from(writer))
        }
        Sink::Full => {
            let full = File::options().write(true).open("/dev/full").unwrap();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            run_with(&args, Stdio::from(full))
        }
        Sink::Closed => Command::new("sh")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" >&-")
            .arg(BIN)
            .args(args)
            .stdin(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .unwrap(),
    }
}

/// A headless command with generated, valid arguments.
fn command() -> impl proptest::strategy::Strategy<Value = Vec<String>> {
    use proptest::prelude::*;
    let scene = proptest::sample::select(
        cloth_scene::BUNDLED
            .iter()
            .map(|b| b.name)
            .collect::<Vec<_>>(),
    );
    prop_oneof![
        Just(vec!["scenes".to_owned()]),
        (scene.clone(), 0u64..3).prop_map(|(s, f)| {
            vec![
                "simulate".into(),
                s.into(),
                "--frames".into(),
                f.to_string(),
            ]
        }),
        (
            scene,
            0u64..3,
            proptest::sample::select(vec!["side", "top", "all", "orbit"]),
            proptest::sample::select(vec!["plain", "ansi"]),
            proptest::sample::select(vec!["ascii", "half", "braille"]),
        )
            .prop_map(|(s, f, view, format, mode)| {
                vec![
                    "render".into(),
                    s.into(),
                    "--frames".into(),
                    f.to_string(),
                    "--every".into(),
                    "1".into(),
                    "--view".into(),
                    view.into(),
                    "--format".into(),
                    format.into(),
                    "--mode".into(),
                    mode.into(),
                    "--size".into(),
                    "24x10".into(),
                ]
            }),
        (2usize..8, any::<bool>()).prop_map(|(n, json)| {
            let mut v: Vec<String> = vec![
                "bench".into(),
                "--grid".into(),
                n.to_string(),
                "--frames".into(),
                "1".into(),
            ];
            if json {
                v.push("--json".into());
            }
            v
        }),
    ]
}

proptest::proptest! {
    // Each case starts a process: few cases, each a different command and sink.
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 24, ..Default::default() })]

    #[test]
    fn generated_commands_end_quietly_for_a_gone_reader_and_with_one_error_otherwise(
        args in command(),
        sink in proptest::prop_oneof![
            proptest::strategy::Just(Sink::ReaderGone),
            proptest::strategy::Just(Sink::Full),
            proptest::strategy::Just(Sink::Closed),
        ],
    ) {
        let o = run_into(&args, sink);
        let e = stderr(&o);
        proptest::prop_assert!(!e.contains("panicked"), "{args:?}: {e}");
        match sink {
            Sink::ReaderGone => {
                proptest::prop_assert_eq!(o.status.code(), Some(0), "{:?}: {}", args, e);
                proptest::prop_assert!(e.is_empty(), "{args:?}: {e}");
            }
            Sink::Full | Sink::Closed => {
                proptest::prop_assert_eq!(o.status.code(), Some(1), "{:?}: {}", args, e);
                proptest::prop_assert_eq!(e.lines().count(), 1, "{:?}: {}", args, e);
            }
        }
    }
}
