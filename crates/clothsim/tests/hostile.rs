//! The headless commands against hostile input and surroundings: special files as scenes,
//! result files of every kind, interruptions, slow runs, and values typed out of range.
#![cfg(unix)]

use std::io::Read as _;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_clothsim");

fn clothsim_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs")
}

fn clothsim(args: &[&str]) -> Output {
    clothsim_in(Path::new("."), args)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[cfg(target_os = "linux")]
/// Whether process `pid` has a file open in `dir` other than `result`: the temporary file of a
/// write in flight, which has no name in the folder on Linux (`O_TMPFILE`), so it is found
/// among the process's descriptors.
fn writing_into(pid: u32, dir: &Path, result: &str) -> bool {
    let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) else {
        return false;
    };
    fds.flatten().any(|fd| {
        std::fs::read_link(fd.path()).is_ok_and(|target| {
            target.parent() == Some(dir) && target.file_name() != Some(result.as_ref())
        })
    })
}

/// Runs `args` and fails the test if the program is still running after `limit` (it would
/// otherwise hang the suite).
fn within(limit: Duration, args: &[&str]) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("{args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn special_files_as_scenes_are_refused_at_once_with_their_kind_named() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("scene.json");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    // Generous limits for a loaded machine; a FIFO opened for reading would block forever and
    // /dev/zero would be read until memory ran out.
    let limit = Duration::from_secs(30);
    let fifo = fifo.to_string_lossy().into_owned();
    let d = dir.path().to_string_lossy().into_owned();
    for (scene, kind) in [
        (fifo.as_str(), "is a FIFO (named pipe), not a scene file"),
        ("/dev/zero", "is a character device, not a scene file"),
        (d.as_str(), "is a folder, not a scene file"),
    ] {
        let o = within(limit, &["simulate", scene, "--frames", "1"]);
        assert_eq!(o.status.code(), Some(1), "{scene}");
        let e = stderr(&o);
        assert_eq!(e, format!("clothsim: error: {scene} {kind}\n"));
    }
}

#[test]
fn a_file_named_like_a_bundled_scene_is_read_only_by_its_explicit_path_and_the_user_is_told() {
    let dir = tempfile::tempdir().unwrap();
    // A 4 x 4 cloth, unlike the bundled plane's 50 x 50.
    let small = cloth_scene::BUNDLED[3]
        .json
        .replace("\"num_width_points\": 50", "\"num_width_points\": 4")
        .replace("\"num_height_points\": 50", "\"num_height_points\": 4");
    std::fs::write(dir.path().join("plane"), &small).unwrap();
    let bare = clothsim_in(dir.path(), &["simulate", "plane", "--frames", "0"]);
    assert!(bare.status.success(), "{}", stderr(&bare));
    let v: serde_json::Value = serde_json::from_slice(&bare.stdout).unwrap();
    assert_eq!(v["num_width_points"], 50, "the bundled scene");
    assert_eq!(
        stderr(&bare),
        "clothsim: note: read the bundled scene plane; for the file of that name, write ./plane\n"
    );
    let explicit = clothsim_in(dir.path(), &["simulate", "./plane", "--frames", "0"]);
    let v: serde_json::Value = serde_json::from_slice(&explicit.stdout).unwrap();
    assert_eq!(v["num_width_points"], 4, "the file");
    assert!(stderr(&explicit).is_empty());
}

#[test]
fn out_to_a_folder_is_refused_once_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_string_lossy().into_owned();
    let o = clothsim(&["simulate", "pinned4", "--frames", "1", "--out", &d]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains("must end in .json or .obj"), "{e}");
    std::fs::create_dir(dir.path().join("state.json")).unwrap();
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--frames",
        "1",
        "--out",
        &format!("{d}/state.json"),
    ]);
    let e = stderr(&o);
    assert!(
        e.contains("state.json is a folder; give a file name"),
        "{e}"
    );
    assert_eq!(e.matches("folder").count(), 1, "said once: {e}");
    assert!(!e.contains("os error"), "{e}");
}

#[cfg(target_os = "linux")]
#[test]
fn interrupting_a_write_leaves_no_temporary_file_and_the_result_old_or_whole() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("state.obj");
    std::fs::write(&out, "precious").unwrap();
    // A 600 x 600 cloth's OBJ is tens of megabytes: its write takes long enough to be caught
    // while the temporary file exists.
    let mut child = Command::new(BIN)
        .args([
            "simulate",
            "pinned4",
            "--frames",
            "0",
            "--set",
            "cloth.num_width_points=600",
            "--set",
            "cloth.num_height_points=600",
            "--out",
        ])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    let folder = dir.path().canonicalize().unwrap();
    let mut caught = false;
    while Instant::now() < deadline && child.try_wait().unwrap().is_none() {
        if writing_into(child.id(), &folder, "state.obj") {
            // As a shell's Ctrl-C would.
            let sent = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(sent.success());
            caught = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let status = child.wait().unwrap();
    assert!(caught, "the temporary file was never seen");
    if status.success() {
        // The write finished before the signal was handled: the whole new result is there.
        assert!(std::fs::read_to_string(&out).unwrap().ends_with('\n'));
    } else {
        assert_eq!(status.signal(), Some(2), "ended by SIGINT");
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(
            text == "precious" || text.starts_with("# clothsim"),
            "old or whole"
        );
    }
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["state.obj"]);
}

#[test]
fn progress_lines_come_to_a_log_only_when_asked_for() {
    let o = clothsim(&["simulate", "pinned4", "--frames", "2", "--progress"]);
    assert!(o.status.success());
    let e = stderr(&o);
    // A run this short has no periodic line, only the closing one.
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(
        e.starts_with("clothsim: pinned4: 2 of 2 frames simulated in "),
        "{e}"
    );
    let quiet = clothsim(&["simulate", "pinned4", "--frames", "2"]);
    assert!(stderr(&quiet).is_empty(), "{}", stderr(&quiet));
}

#[test]
fn render_streams_its_first_frame_before_the_run_ends() {
    // 2000 frames of the 50 x 50 cloth take many seconds; the first printed frame must come
    // long before that, so the reader sees it while the rest is simulated.
    let mut child = Command::new(BIN)
        .args([
            "render", "pinned4", "--frames", "2000", "--every", "1", "--size", "30x12",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut first = vec![0u8; 31 * 12];
    stdout.read_exact(&mut first).unwrap();
    // The run goes on after the first frame: it has not ended yet.
    assert!(child.try_wait().unwrap().is_none(), "still simulating");
    drop(stdout);
    // With the reader gone, the run ends quietly at its next frame.
    let status = child.wait().unwrap();
    assert!(status.success());
}

#[test]
fn values_out_of_range_are_reported_as_typed() {
    let o = clothsim(&["render", "pinned4", "--size", "99999999999999999999x40"]);
    let e = stderr(&o);
    assert!(
        e.contains("frame size 99999999999999999999x40 is too large"),
        "{e}"
    );
    assert!(!e.contains("18446744073709551615"), "{e}");
    let o = clothsim(&["simulate", "pinned4", "--set", "cloth.ks=1e309"]);
    let e = stderr(&o);
    assert!(
        e.contains("--set cloth.ks=1e309: 1e309 is out of range"),
        "{e}"
    );
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--set",
        "cloth.density=1e-300",
        "--frames",
        "3",
    ]);
    let e = stderr(&o);
    assert!(e.contains("diverged"), "{e}");
    assert!(e.contains("cloth.density is 1e-300 kg/m^2"), "{e}");
    assert!(
        !e.contains("reset"),
        "no UI-only advice in a headless command: {e}"
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_signal_during_a_streamed_cache_leaves_no_temporary_file_and_keeps_the_old_one() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("drape.pc2");
    std::fs::write(&out, "precious").unwrap();
    // The cache's temporary file is open for the whole run, which is far longer than the wait.
    let mut child = Command::new(BIN)
        .args(["simulate", "pinned4", "--frames", "1000000", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    let folder = dir.path().canonicalize().unwrap();
    let mut caught = false;
    while Instant::now() < deadline && child.try_wait().unwrap().is_none() {
        if writing_into(child.id(), &folder, "drape.pc2") {
            let sent = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(sent.success());
            caught = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    if !caught {
        let _ = child.kill();
    }
    let status = child.wait().unwrap();
    assert!(caught, "the temporary file was never seen");
    assert_eq!(status.signal(), Some(15), "ended by SIGTERM");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "precious");
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["drape.pc2"], "no temporary file, no mesh");
}
