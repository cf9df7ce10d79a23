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

/// `args` in `dir` through `sh -c SCRIPT`, where the script ends by running the binary with
/// the arguments (`exec "$0" "$@"`): for limits set with `ulimit` and signals ignored with
/// `trap` before the program starts.
fn through_shell(dir: &Path, script: &str, args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn names_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn every_output_target_is_proved_writable_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let limit = Duration::from_secs(30);
    // 248 bytes: the temporary name adds 8, past the 255-byte limit. A long run would end in
    // "File name too long" after all its work; it is refused first, in a moment.
    let long = dir.path().join(format!("{}.json", "a".repeat(243)));
    let long = long.to_str().unwrap();
    // 238 bytes: the name a diverged run's state is kept under (`NAME.diverged.json`) is 247.
    let fits = dir.path().join(format!("{}.json", "b".repeat(233)));
    let fits = fits.to_str().unwrap();
    let sequence = dir.path().join(format!("{}_%d.obj", "c".repeat(236)));
    let sequence = sequence.to_str().unwrap();
    let pc2 = dir.path().join(format!("{}.pc2", "d".repeat(244)));
    let pc2 = pc2.to_str().unwrap();
    let stats = dir.path().join(format!("{}.csv", "e".repeat(244)));
    let stats = stats.to_str().unwrap();
    for args in [
        vec!["simulate", "pinned4", "--frames", "10000000", "--out", long],
        vec!["simulate", "pinned4", "--frames", "10000000", "--out", pc2],
        vec![
            "simulate", "pinned4", "--frames", "10000000", "--stats", stats,
        ],
        // Frame 0's name fits (242 bytes); frame 10 000 000's (249) does not.
        vec![
            "simulate", "pinned4", "--frames", "10000000", "--out", sequence,
        ],
        // The variants' names are longer than the name given.
        vec![
            "simulate",
            "pinned4",
            "--frames",
            "10000000",
            "--out",
            fits,
            "--vary",
            "cloth.ks=1000,2000",
        ],
    ] {
        let o = within(limit, &args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(
            e.contains("too long") && e.contains("at most 247 bytes"),
            "{args:?}: {e}"
        );
    }
    // A name that fits, and a diverged run's longer name (`NAME.diverged.json`) is checked too.
    let o = within(
        limit,
        &["simulate", "pinned4", "--frames", "1", "--out", fits],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let almost = dir.path().join(format!("{}.json", "f".repeat(234)));
    let o = within(
        limit,
        &[
            "simulate",
            "pinned4",
            "--frames",
            "10000000",
            "--out",
            almost.to_str().unwrap(),
        ],
    );
    let e = stderr(&o);
    assert!(
        e.contains(".diverged.json") && e.contains("too long"),
        "{e}"
    );
    assert_eq!(
        names_in(dir.path()).len(),
        1,
        "nothing but the result left behind"
    );
}

#[cfg(target_os = "linux")]
#[test]
fn out_to_a_fifo_is_refused_at_once_for_every_format() {
    let dir = tempfile::tempdir().unwrap();
    for (name, flag) in [
        ("state.json", "--out"),
        ("state.obj", "--out"),
        ("anim.pc2", "--out"),
        ("anim.mdd", "--out"),
        ("stats.csv", "--stats"),
    ] {
        let fifo = dir.path().join(name);
        assert!(
            Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );

        // Without a reader, a FIFO opened for writing blocks forever.
        let o = within(
            Duration::from_secs(30),
            &[
                "simulate",
                "pinned4",
                "--frames",
                "1",
                flag,
                fifo.to_str().unwrap(),
            ],
        );
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {e}");
        assert!(e.contains("is a FIFO (named pipe)"), "{name}: {e}");
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_folder_that_takes_no_new_file_is_refused_before_the_run_for_a_plain_user() {
    use std::os::unix::fs::PermissionsExt;
    // The superuser may create files anywhere: the case needs a dropped uid.
    let root = Command::new("id").arg("-u").output().unwrap();
    let has_setpriv = Command::new("setpriv").arg("--help").output().is_ok();
    if String::from_utf8_lossy(&root.stdout).trim() != "0" || !has_setpriv {
        eprintln!("skipped: needs root and setpriv to run the binary as another user");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // The temporary folder itself is private; a world-readable folder inside it is not
    // writable by the plain user.
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = dir.path().join("state.json");
    let o = Command::new("setpriv")
        .args(["--reuid=65534", "--regid=65534", "--clear-groups", BIN])
        .args(["simulate", "pinned4", "--frames", "10000000", "--out"])
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("cannot create a file in the folder") && e.contains("Permission denied"),
        "{e}"
    );
    assert!(names_in(dir.path()).is_empty());
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_keeps_the_old_contents_of_every_name_of_a_hard_linked_result() {
    // RLIMIT_FSIZE (`ulimit -f`) makes a write past the limit fail with EFBIG, as a full disk
    // fails with ENOSPC: the program meets a real write error part way through the file.
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one.json");
    let two = dir.path().join("two.json");
    std::fs::write(&one, "old contents").unwrap();
    std::fs::hard_link(&one, &two).unwrap();
    for (out, extra) in [
        ("one.json", None),
        ("anim.pc2", None),
        ("one.json", Some("--vary")),
    ] {
        let mut args = vec!["simulate", "pinned4", "--frames", "3", "--out", out];
        if extra.is_some() {
            args.extend(["--vary", "cloth.ks=1000,2000"]);
            std::fs::hard_link(&one, dir.path().join("one.ks=1000.json")).unwrap();
        }
        if out == "anim.pc2" {
            std::fs::hard_link(&one, dir.path().join("anim.pc2")).unwrap();
        }
        // 64 blocks (32 KiB in sh's 512-byte blocks, 64 KiB in bash's): far below the state's
        // 300 KB.
        let o = through_shell(
            dir.path(),
            "ulimit -f 64; trap '' XFSZ; exec \"$0\" \"$@\"",
            &args,
        );
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(e.contains("File too large"), "{args:?}: {e}");
        for name in names_in(dir.path()) {
            assert_eq!(
                std::fs::read_to_string(dir.path().join(&name)).unwrap(),
                "old contents",
                "{args:?}: {name}"
            );
        }
    }
    assert_eq!(
        names_in(dir.path()),
        ["anim.pc2", "one.json", "one.ks=1000.json", "two.json"],
        "no temporary file, no half-written file"
    );
}

#[test]
fn energy_made_from_nothing_is_a_failure_at_any_run_length_with_its_cause_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.json");
    let out = out.to_str().unwrap();
    for (scene, set) in [
        // The cloth starts inside a sphere of 4e9 m: the first step throws every point to its
        // surface. Five frames: far shorter than the runaway test's window.
        ("sphere", "sphere.radius=4294967296"),
        // Self-collision with a thickness of 1e9 m pushes every point away from every other.
        ("selfCollision", "cloth.thickness=1e9"),
    ] {
        let o = clothsim(&[
            "simulate", scene, "--frames", "5", "--set", set, "--out", out,
        ]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{set}: {e}");
        assert!(
            e.contains("diverged at frame 1 of 5")
                && e.contains("total energy (kinetic + spring + gravity) rose by")
                && e.contains("mostly as kinetic energy")
                && e.contains("cloth.thickness and the colliders"),
            "{set}: {e}"
        );
        assert!(!std::path::Path::new(out).exists(), "{set}: no result");
    }
}

#[test]
fn a_run_that_outruns_the_stretch_limit_says_so_on_stderr() {
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--frames",
        "30",
        "--set",
        "simulation.gravity=[0,-1e6,0]",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains(
            "warning: pinned4: the stretch limit is on, yet the cloth ends with a spring at"
        ) && e.contains("simulation.gravity of 1.0e6 m/s^2"),
        "{e}"
    );
    // render says it too, after its frames.
    let o = clothsim(&[
        "render",
        "pinned4",
        "--frames",
        "30",
        "--every",
        "30",
        "--set",
        "simulation.gravity=[0,-1e6,0]",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("warning: pinned4: the stretch limit is on"),
        "{e}"
    );
    // The course's cloth under the limit: no warning.
    let o = clothsim(&["simulate", "pinned4", "--frames", "30"]);
    assert!(o.status.success());
    assert_eq!(stderr(&o), "");
}

#[cfg(target_os = "linux")]
#[test]
fn from_is_read_like_a_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("state.json");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let fifo = fifo.to_str().unwrap();
    let limit = Duration::from_secs(30);
    for args in [
        vec!["simulate", "pinned4", "--frames", "1", "--from", fifo],
        vec!["render", "pinned4", "--frames", "1", "--from", fifo],
        vec![
            "simulate",
            "pinned4",
            "--frames",
            "1",
            "--from",
            "/dev/zero",
        ],
    ] {
        // A FIFO opened for reading waits for a writer forever; /dev/zero never ends.
        let o = within(limit, &args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(e.contains("not a state file"), "{args:?}: {e}");
    }
    // A state whose frame count would wrap the OBJ sequence's numbers onto frame 0.
    let good = dir.path().join("good.json");
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--frames",
        "2",
        "--out",
        good.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut state: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&good).unwrap()).unwrap();
    let bad = dir.path().join("bad.json");
    let bad = bad.to_str().unwrap();
    let seq = dir.path().join("seq");
    std::fs::create_dir(&seq).unwrap();
    let pattern = seq.join("f_%d.obj");
    state["frames"] = serde_json::json!(18_446_744_073_709_551_610_u64);
    std::fs::write(bad, state.to_string()).unwrap();
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--frames",
        "10",
        "--from",
        bad,
        "--out",
        pattern.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(
        e.contains("frames is 18446744073709551610, but it must be"),
        "{e}"
    );
    assert!(names_in(&seq).is_empty(), "nothing written");
    state["frames"] = serde_json::json!(2);
    state["time"] = serde_json::json!(-5.0);
    std::fs::write(bad, state.to_string()).unwrap();
    let e = stderr(&clothsim(&["simulate", "pinned4", "--from", bad]));
    assert!(e.contains("time is -5, but it must be"), "{e}");
    // Without last_positions: accepted, with a warning that the motion is not carried on.
    state["time"] = serde_json::json!(2.0 / 90.0);
    state.as_object_mut().unwrap().remove("last_positions");
    std::fs::write(bad, state.to_string()).unwrap();
    let o = clothsim(&["simulate", "pinned4", "--frames", "1", "--from", bad]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("warning") && e.contains("starts at rest"), "{e}");
    // UTF-16 is named as such, as for scenes.
    let mut utf16 = vec![0xFF, 0xFE];
    utf16.extend(state.to_string().encode_utf16().flat_map(u16::to_le_bytes));
    std::fs::write(bad, utf16).unwrap();
    let e = stderr(&clothsim(&["simulate", "pinned4", "--from", bad]));
    assert!(
        e.contains("UTF-16") && !e.contains("stream did not contain"),
        "{e}"
    );
    // A list is no state; no Rust type name is shown.
    std::fs::write(bad, "[1, 2, 3, 4, 5, 6, 7, 8]").unwrap();
    let e = stderr(&clothsim(&["simulate", "pinned4", "--from", bad]));
    assert!(
        e.contains("it is a list") && !e.contains("StateFile"),
        "{e}"
    );
}

#[cfg(target_os = "linux")]
#[test]
fn the_memory_check_counts_the_address_space_limit_whatever_max_memory_says() {
    let dir = tempfile::tempdir().unwrap();
    // Verlet on 2048 x 2048 needs about 2.4 GiB; `ulimit -v 2000000` allows 1.9 GiB in all.
    let grid = [
        "simulate",
        "pinned4",
        "--frames",
        "1",
        "--set",
        "cloth.num_width_points=2048",
        "--set",
        "cloth.num_height_points=2048",
    ];
    for extra in [&[][..], &["--max-memory", "8G"][..]] {
        let args: Vec<&str> = grid.iter().chain(extra).copied().collect();
        let o = through_shell(dir.path(), "ulimit -v 2000000; exec \"$0\" \"$@\"", &args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {e}");
        assert!(
            e.contains("the verlet solver on this 2048 x 2048 cloth needs about 2.4 GiB")
                && e.contains("the address-space limit (ulimit -v)"),
            "{extra:?}: {e}"
        );
    }
}
