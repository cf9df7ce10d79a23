//! What a run leaves behind: animations, the per-frame table, recordings, read back as the
//! programs that use them read them.

use std::path::Path;
use std::process::{Command, Output};

fn clothsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_clothsim"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn run_ok(args: &[&str]) -> Output {
    let o = clothsim(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    o
}

/// The positions `simulate` writes as JSON after `frames` frames of `scene`.
fn json_positions(scene: &str, frames: u64) -> Vec<[f64; 3]> {
    let o = run_ok(&["simulate", scene, "--frames", &frames.to_string()]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    serde_json::from_value(v["positions"].clone()).unwrap()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn i32_le(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn f32_le(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// The `points` positions of sample `sample` of a point cache whose samples start at `data`.
fn sample(b: &[u8], data: usize, points: usize, sample: usize, big: bool) -> Vec<[f32; 3]> {
    let start = data + sample * points * 12;
    (0..points)
        .map(|i| {
            let at = start + i * 12;
            std::array::from_fn(|k| {
                let bytes: [u8; 4] = b[at + 4 * k..at + 4 * k + 4].try_into().unwrap();
                if big {
                    f32::from_be_bytes(bytes)
                } else {
                    f32::from_le_bytes(bytes)
                }
            })
        })
        .collect()
}

/// The cache holds each coordinate as the f32 nearest the simulation's f64, so it equals the
/// JSON state's coordinates rounded to f32, bit for bit.
fn rounded(positions: &[[f64; 3]]) -> Vec<[f32; 3]> {
    positions.iter().map(|p| p.map(|c| c as f32)).collect()
}

#[test]
fn a_pc2_cache_reads_back_with_its_header_frame_count_and_frames() {
    let dir = tempfile::tempdir().unwrap();
    let pc2 = dir.path().join("drape.pc2");
    run_ok(&[
        "simulate",
        "pinned4",
        "--frames",
        "6",
        "--every",
        "3",
        "--out",
        pc2.to_str().unwrap(),
    ]);
    let b = std::fs::read(&pc2).unwrap();
    assert_eq!(&b[..12], b"POINTCACHE2\0");
    assert_eq!(i32_le(&b, 12), 1, "version");
    assert_eq!(i32_le(&b, 16), 2500, "points of the 50 x 50 cloth");
    assert_eq!(f32_le(&b, 20), 0.0, "start frame");
    assert_eq!(f32_le(&b, 24), 3.0, "frames between samples");
    assert_eq!(i32_le(&b, 28), 3, "frames 0, 3 and 6");
    assert_eq!(b.len(), 32 + 3 * 2500 * 12);
    assert_eq!(
        sample(&b, 32, 2500, 1, false),
        rounded(&json_positions("pinned4", 3))
    );
    assert_eq!(
        sample(&b, 32, 2500, 2, false),
        rounded(&json_positions("pinned4", 6))
    );
    // The mesh to attach it to: the first sample's positions, with texture coordinates.
    assert_eq!(names(dir.path()), ["drape.obj", "drape.pc2"]);
    let obj = std::fs::read_to_string(dir.path().join("drape.obj")).unwrap();
    let first: Vec<[f32; 3]> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [c[0] as f32, c[1] as f32, c[2] as f32]
        })
        .collect();
    assert_eq!(first, sample(&b, 32, 2500, 0, false));
    assert_eq!(obj.lines().filter(|l| l.starts_with("vt ")).count(), 2500);
}

#[test]
fn an_mdd_cache_is_big_endian_with_a_time_per_sample() {
    let dir = tempfile::tempdir().unwrap();
    let mdd = dir.path().join("drape.mdd");
    run_ok(&[
        "simulate",
        "pinned4",
        "--frames",
        "4",
        "--every",
        "2",
        "--out",
        mdd.to_str().unwrap(),
    ]);
    let b = std::fs::read(&mdd).unwrap();
    let i32_be = |at: usize| i32::from_be_bytes(b[at..at + 4].try_into().unwrap());
    let f32_be = |at: usize| f32::from_be_bytes(b[at..at + 4].try_into().unwrap());
    assert_eq!((i32_be(0), i32_be(4)), (3, 2500), "samples, points");
    let times: Vec<f32> = (0..3).map(|i| f32_be(8 + 4 * i)).collect();
    assert_eq!(times, [0.0, (2.0f64 / 90.0) as f32, (4.0f64 / 90.0) as f32]);
    let data = 8 + 3 * 4;
    assert_eq!(b.len(), data + 3 * 2500 * 12);
    assert_eq!(
        sample(&b, data, 2500, 2, true),
        rounded(&json_positions("pinned4", 4))
    );
}

#[test]
fn an_obj_sequence_writes_one_numbered_file_per_sample() {
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("f_%03d.obj");
    run_ok(&[
        "simulate",
        "pinned4",
        "--frames",
        "2",
        "--out",
        pattern.to_str().unwrap(),
    ]);
    assert_eq!(names(dir.path()), ["f_000.obj", "f_001.obj", "f_002.obj"]);
    let text = std::fs::read_to_string(dir.path().join("f_002.obj")).unwrap();
    let v: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect();
    // OBJ coordinates are the shortest decimals that round-trip, as the JSON's are.
    assert_eq!(v, json_positions("pinned4", 2));
    assert_eq!(text.lines().filter(|l| l.starts_with("vt ")).count(), 2500);
    assert_eq!(text.lines().filter(|l| l.starts_with("vn ")).count(), 2500);
    assert!(
        text.contains("\nf 1/1/1 51/51/51 2/2/2\n"),
        "first triangle, 1-based"
    );
}

#[test]
fn the_stats_table_has_a_row_per_frame_and_repeats_but_for_the_wall_time() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    for p in [&a, &b] {
        run_ok(&[
            "simulate",
            "pinned4",
            "--frames",
            "5",
            "--stats",
            p.to_str().unwrap(),
            "--out",
            dir.path().join("state.json").to_str().unwrap(),
        ]);
    }
    let read = |p: &Path| std::fs::read_to_string(p).unwrap();
    let (ta, tb) = (read(&a), read(&b));
    let lines: Vec<&str> = ta.lines().collect();
    assert_eq!(
        lines[0],
        "frame,time_s,kinetic_energy_j,max_stretch,lowest_y_m,centre_y_m,steps,wall_s"
    );
    assert_eq!(lines.len(), 6, "a header and frames 1 to 5");
    let without_wall = |t: &str| -> Vec<String> {
        t.lines()
            .map(|l| l.rsplit_once(',').unwrap().0.to_owned())
            .collect()
    };
    assert_eq!(without_wall(&ta), without_wall(&tb), "deterministic");
    let cols: Vec<&str> = lines[5].split(',').collect();
    assert_eq!(cols[0], "5");
    assert_eq!(cols[1].parse::<f64>().unwrap(), 5.0 / 90.0);
    assert_eq!(cols[6], "30", "pinned4's steps per frame");
    assert!(cols[7].parse::<f64>().unwrap() > 0.0, "wall time measured");
    // The lowest height is the minimum over the state written at the end.
    let state: serde_json::Value =
        serde_json::from_str(&read(&dir.path().join("state.json"))).unwrap();
    let lowest = state["positions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p[1].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert_eq!(cols[4].parse::<f64>().unwrap(), lowest);
    // A cloth released at rest and pulled by gravity gains energy over the first frames.
    let energy = |l: &str| l.split(',').nth(2).unwrap().parse::<f64>().unwrap();
    assert!(energy(lines[5]) > energy(lines[1]), "{ta}");

    let json = dir.path().join("s.json");
    run_ok(&[
        "simulate",
        "pinned4",
        "--frames",
        "3",
        "--stats",
        json.to_str().unwrap(),
    ]);
    let v: serde_json::Value = serde_json::from_str(&read(&json)).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 3);
    assert_eq!(v[2]["frame"], 3);
}

#[test]
fn render_writes_an_asciinema_recording_of_the_plain_frames() {
    let args = [
        "render", "pinned4", "--frames", "4", "--every", "2", "--size", "20x8",
    ];
    let plain = run_ok(&args);
    let plain = String::from_utf8(plain.stdout).unwrap();
    let plain: Vec<&str> = plain.split("\x0c\n").collect();
    let mut cast_args = args.to_vec();
    cast_args.extend(["--format", "cast", "--color", "never"]);
    let cast = run_ok(&cast_args);
    let cast = String::from_utf8(cast.stdout).unwrap();
    let mut lines = cast.lines();
    let head: serde_json::Value = serde_json::from_str(lines.next().unwrap()).unwrap();
    assert_eq!(head["version"], 2);
    assert_eq!(
        (head["width"].as_u64(), head["height"].as_u64()),
        (Some(20), Some(8))
    );
    let events: Vec<(f64, String, String)> =
        lines.map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(events.len(), 2, "frames 2 and 4");
    assert_eq!(events[0].0, 2.0 / 90.0, "at the simulated time");
    assert_eq!(events[1].0, 4.0 / 90.0);
    for (i, (_, kind, data)) in events.iter().enumerate() {
        assert_eq!(kind, "o");
        let body = data
            .trim_start_matches("\x1b[2J")
            .trim_start_matches("\x1b[H");
        assert_eq!(body.replace("\r\n", "\n") + "\n", plain[i], "frame {i}");
    }
    assert!(
        events[0].2.starts_with("\x1b[2J\x1b[H"),
        "the first clears the screen"
    );
}

#[test]
fn bad_export_arguments_are_one_clear_message_each() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    std::fs::write(&file, "x").unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["--out".into(), d("x.txt")],
            "must end in .json or .obj",
        ),
        (vec!["--out".into(), d("f_%04.obj")], "one %d or %0Nd"),
        (vec!["--out".into(), d("f_%d.ply")], "written as OBJ files"),
        (vec!["--out".into(), d("%d/f.obj")], "in the file's name"),
        (vec!["--out".into(), d("no-such/x.pc2")], "cannot be used"),
        (
            vec!["--out".into(), d("no-such/f_%d.obj")],
            "cannot be used",
        ),
        (
            vec!["--out".into(), d("plain-file/x.mdd")],
            "is not a folder",
        ),
        (
            vec!["--stats".into(), d("s.txt")],
            "must end in .csv or .json",
        ),
        (vec!["--stats".into(), d("no-such/s.csv")], "cannot be used"),
        (
            vec!["--every".into(), "2".into(), "--out".into(), d("s.json")],
            "--every applies to an animation",
        ),
    ];
    for (extra, expected) in cases {
        let mut args = vec!["simulate", "pinned4", "--frames", "2"];
        args.extend(extra.iter().map(String::as_str));
        let o = clothsim(&args);
        assert!(!o.status.success(), "{args:?}");
        let e = stderr(&o);
        assert!(e.contains(expected), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{e}");
    }
    assert_eq!(names(dir.path()), ["plain-file"], "nothing left behind");
}

#[test]
fn a_diverged_run_keeps_no_animation_but_keeps_the_table_of_its_good_frames() {
    let dir = tempfile::tempdir().unwrap();
    let pc2 = dir.path().join("x.pc2");
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--frames",
        "30",
        "--set",
        "cloth.ks=1e9",
        "--out",
        pc2.to_str().unwrap(),
        "--stats",
        dir.path().join("s.csv").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("diverged"), "{}", stderr(&o));
    assert_eq!(
        names(dir.path()),
        ["s.csv"],
        "no cache, no mesh, no temporary file; the table of the frames before"
    );
    // ks 1e9 is 4500 times Verlet's stability limit: the spring energy explodes within the
    // first frame, which the energy test stops, so the table holds the header alone.
    let table = std::fs::read_to_string(dir.path().join("s.csv")).unwrap();
    assert_eq!(table.lines().count(), 1, "the header alone:\n{table}");
    assert!(stderr(&o).contains("at frame 1 of 30"), "{}", stderr(&o));
}

#[cfg(unix)]
#[test]
fn a_folder_that_allows_no_new_file_is_refused_before_the_run() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    // The superuser may create files in a read-only folder: then the cache is written.
    let can_create = std::fs::File::create(ro.join("probe")).is_ok();
    let _ = std::fs::remove_file(ro.join("probe"));
    let pc2 = ro.join("x.pc2");
    let o = clothsim(&[
        "simulate",
        "pinned4",
        "--frames",
        "1",
        "--out",
        pc2.to_str().unwrap(),
    ]);
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    if can_create {
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(names(&ro), ["x.obj", "x.pc2"]);
    } else {
        assert!(!o.status.success());
        let e = stderr(&o);
        assert!(e.contains("x.pc2: cannot create a file in"), "{e}");
        assert!(names(&ro).is_empty());
    }
}
