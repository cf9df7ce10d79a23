//! The cloth's state as JSON: what `simulate` writes, and what `--from` reads back.
//!
//! ```json
//! {"num_width_points": 50, "num_height_points": 50, "frames": 90, "time": 1.0,
//!  "positions": [[x, y, z], ...], "last_positions": [[x, y, z], ...]}
//! ```
//!
//! `positions` and `last_positions` are the points in the scene's row-major order, metres;
//! `last_positions` are the positions one step of `dt` seconds earlier, so
//! `(positions - last_positions) / dt` is the velocity. A run started from the file keeps that
//! velocity whatever its own step: `last_positions` is rescaled to the run's step (a solver
//! at one step per frame continuing from Verlet at thirty). A file without `last_positions`
//! starts at rest, which [`StateFile::read`] says on stderr; one without `dt` is taken to have
//! the run's step.
//!
//! A state is read like a scene: regular files only (a FIFO is refused without waiting for a
//! writer, a device without reading it), at most [`max_state_bytes`] for the scene's cloth,
//! its parse checked against the memory available before it starts, and `frames` and `time`
//! within [`MAX_FRAMES`] and [`MAX_TIME`].

use std::path::Path;

use anyhow::{Context, bail};
use cloth_mesh::{ClothMesh, ClothState, Vec3};
use serde::{Deserialize, Serialize};

/// How far a pinned point of the state may be from the scene's pin, metres: pins never move,
/// so a state written by a run of this scene holds them exactly; the allowance only absorbs
/// the JSON round trip (which is exact for the shortest round-tripping decimals written here).
const PIN_TOLERANCE: f64 = 1e-9;

/// The most frames a state may have behind it: 10^12 frames are 350 years at 90 frames/s,
/// yet a run on from there (at most 10^7 frames a command, 10^4 steps a frame) counts its
/// frames and steps far below `u64`'s 1.8e19, and numbers the files of an OBJ sequence in
/// order, so no counter can wrap.
pub const MAX_FRAMES: u64 = 1_000_000_000_000;

/// The most simulated seconds a state may have behind it (3,170 years): below 10^11 s a
/// 64-bit float still resolves 1.6e-5 s, finer than the shortest frame (1e-4 s at the
/// scene's 10,000 frames/s), so the clock keeps counting frames.
pub const MAX_TIME: f64 = 1e11;

/// Bytes of text a state may take per point of the scene's cloth, and in all beside them.
///
/// NOTE: `simulate` writes at most 25 characters a coordinate, about 160 bytes a point for
/// both lists; 1 KiB a point leaves room for pretty-printing with deep indentation.
const BYTES_PER_POINT: u64 = 1024;
const BYTES_BESIDE: u64 = 64 * 1024;

/// The largest state file read for a cloth of `points` points, bytes.
pub fn max_state_bytes(points: usize) -> u64 {
    BYTES_BESIDE.saturating_add(BYTES_PER_POINT.saturating_mul(points as u64))
}

/// The JSON of a state.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateFile {
    /// Points along the cloth's width.
    pub num_width_points: usize,
    /// Points along the cloth's height.
    pub num_height_points: usize,
    /// Frames simulated since the scene's start.
    #[serde(default)]
    pub frames: u64,
    /// Simulated seconds since the scene's start.
    #[serde(default)]
    pub time: f64,
    /// Positions, metres.
    pub positions: Vec<[f64; 3]>,
    /// Positions one step earlier, metres (absent: the cloth is at rest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_positions: Option<Vec<[f64; 3]>>,
    /// The step between `last_positions` and `positions`, seconds (absent: the reading run's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Whether the divergence guard stopped the run that wrote it (the state is where it
    /// stopped); written only when true.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub diverged: bool,
}

impl StateFile {
    /// The file's form of `state` after `frames` frames (`time` seconds) of steps of `dt`
    /// seconds.
    pub fn new(mesh: &ClothMesh, state: &ClothState, frames: u64, time: f64, dt: f64) -> Self {
        let list = |v: &[Vec3]| v.iter().map(|p| [p.x, p.y, p.z]).collect();
        Self {
            num_width_points: mesh.nw(),
            num_height_points: mesh.nh(),
            frames,
            time,
            positions: list(&state.positions),
            last_positions: Some(list(&state.last)),
            dt: Some(dt),
            diverged: false,
        }
    }

    /// Reads the state file at `path`, checks it against the scene's `mesh`, and returns it
    /// with the state for a run of steps of `dt` seconds.
    ///
    /// # Errors
    /// A message naming the file and what does not fit: unreadable, not a state, another
    /// grid, a wrong point count, a non-finite value, or a pinned point away from its pin.
    pub fn read(path: &Path, mesh: &ClothMesh, dt: f64) -> anyhow::Result<(Self, ClothState)> {
        let at = || format!("--from {}", path.display());
        let text = read_text(path, mesh).with_context(at)?;
        // A list would be read as the fields in order, and its errors would make no sense.
        if text.trim_start().starts_with('[') {
            bail!(
                "{}: not a clothsim state (the JSON that `clothsim simulate` writes): it is a \
                 list; a state is an object with the keys {KEYS}",
                at()
            );
        }
        let file: StateFile = serde_json::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: {}", at(), parse_error(&e)))?;
        drop(text);
        let state = file.to_state(mesh, dt).with_context(at)?;
        if file.last_positions.is_none() {
            use std::io::Write as _;
            // Nowhere else to say it; a lost warning does not change the run.
            let _ = writeln!(
                std::io::stderr(),
                "{}: warning: {}: the state has no last_positions, so the cloth starts \
                 at rest from its positions (the motion it had is not carried on)",
                crate::headless::program_name(),
                at()
            );
        }
        Ok((file, state))
    }

    /// The state for `mesh` and a step of `dt` seconds, checked.
    fn to_state(&self, mesh: &ClothMesh, dt: f64) -> anyhow::Result<ClothState> {
        if self.frames > MAX_FRAMES {
            bail!(
                "frames is {}, but it must be a whole number from 0 to {MAX_FRAMES} (10^12): \
                 a run on from it would count past what its outputs can number",
                self.frames
            );
        }
        if !(self.time.is_finite() && (0.0..=MAX_TIME).contains(&self.time)) {
            bail!(
                "time is {}, but it must be a number of seconds from 0 to 1e11",
                cloth_scene::show(self.time)
            );
        }
        if let Some(written) = self.dt
            && !(written.is_finite() && written > 0.0)
        {
            bail!("dt is {written}; it must be a number of seconds > 0");
        }
        if (self.num_width_points, self.num_height_points) != (mesh.nw(), mesh.nh()) {
            bail!(
                "the state is of a {} x {} cloth, but the scene's cloth is {} x {} \
                 (num_width_points x num_height_points); use a state written for this scene",
                self.num_width_points,
                self.num_height_points,
                mesh.nw(),
                mesh.nh()
            );
        }
        let points = |key: &str, list: &[[f64; 3]]| -> anyhow::Result<Vec<Vec3>> {
            if list.len() != mesh.len() {
                bail!(
                    "{key} has {} points, but a {} x {} cloth has {}",
                    list.len(),
                    mesh.nw(),
                    mesh.nh(),
                    mesh.len()
                );
            }
            if let Some(i) = list.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                bail!(
                    "{key}[{i}] is {}; every coordinate must be finite",
                    point(list[i])
                );
            }
            Ok(list.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect())
        };
        let positions = points("positions", &self.positions)?;
        let last = match &self.last_positions {
            Some(list) => points("last_positions", list)?,
            None => positions.clone(),
        };
        // Keep the velocity: the displacement over the written step becomes one over `dt`.
        let mut state = ClothState { positions, last };
        if let Some(written) = self.dt {
            state.retime(written, dt);
        }
        for (i, start) in mesh.start_positions().iter().enumerate() {
            if !mesh.pinned()[i] {
                continue;
            }
            for (key, list) in [
                ("positions", &state.positions),
                ("last_positions", &state.last),
            ] {
                if (list[i] - start).norm() > PIN_TOLERANCE {
                    bail!(
                        "{key}[{i}] (column {}, row {}) is {}, but the scene pins that point \
                         at {}: the state comes from another scene or pin set",
                        i % mesh.nw(),
                        i / mesh.nw(),
                        point([list[i].x, list[i].y, list[i].z]),
                        point([start.x, start.y, start.z])
                    );
                }
            }
        }
        Ok(state)
    }
}

/// `[x, y, z]` with each number as short as it reads back exactly.
fn point(p: [f64; 3]) -> String {
    let [x, y, z] = p.map(cloth_scene::show);
    format!("[{x}, {y}, {z}]")
}

/// The text of the state file at `path` for `mesh`'s scene, with the checks in the module doc.
fn read_text(path: &Path, mesh: &ClothMesh) -> anyhow::Result<String> {
    use std::io::Read as _;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // NOTE: a FIFO opened non-blocking returns at once instead of waiting for a writer;
        // it is then refused by its kind.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let kind = |m: &std::fs::Metadata| {
        cloth_scene::special_kind(m).map_or(Ok(()), |kind| {
            Err(anyhow::anyhow!(
                "it is {kind}, not a state file (the JSON that `clothsim simulate` writes)"
            ))
        })
    };
    // Checked before opening, so a device is never opened (a tape, a terminal).
    kind(&std::fs::metadata(path).context("cannot read the state file")?)?;
    let file = options.open(path).context("cannot read the state file")?;
    let meta = file.metadata().context("cannot read the state file")?;
    kind(&meta)?;
    let cap = max_state_bytes(mesh.len());
    let too_large = |size: u64| {
        anyhow::anyhow!(
            "it is {size} bytes, more than any state of this {} x {} cloth takes (states of it \
             are read up to {cap} bytes)",
            mesh.nw(),
            mesh.nh()
        )
    };
    if meta.len() > cap {
        return Err(too_large(meta.len()));
    }
    // The text, and the two lists of points the parse builds (twice over while they grow).
    let need = meta
        .len()
        .saturating_add(4 * crate::memory::state_bytes(mesh));
    if let Some(available) = crate::memory::available_memory()
        && need > available
    {
        bail!(
            "reading it needs about {}, more than the {} of memory available",
            crate::memory::human_bytes(need),
            crate::memory::human_bytes(available)
        );
    }
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(cap + 1)
        .read_to_end(&mut bytes)
        .context("cannot read the state file")?;
    if bytes.len() as u64 > cap {
        return Err(too_large(bytes.len() as u64));
    }
    cloth_scene::utf8_text(bytes).map_err(|reason| anyhow::anyhow!("{reason}"))
}

/// A state's keys, for messages.
const KEYS: &str = "num_width_points, num_height_points, frames, time, positions, \
                    last_positions and dt";

/// What the JSON parser said, in a state file's words: no Rust type names.
fn parse_error(e: &serde_json::Error) -> String {
    const NOT_A_STATE: &str = "not a clothsim state (the JSON that `clothsim simulate` writes)";
    let message = e.to_string();
    let message = message.split(" at line ").next().unwrap_or(&message);
    let at = format!("line {}, column {}", e.line(), e.column());
    if e.is_syntax() || e.is_eof() {
        return format!("{NOT_A_STATE}: invalid JSON at {at}: {message}");
    }
    let plain = message
        .replace(
            "expected struct StateFile with 8 elements",
            &format!("expected an object with the keys {KEYS}"),
        )
        .replace(
            "expected struct StateFile",
            &format!("expected an object with the keys {KEYS}"),
        )
        .replace("expected usize", "expected a whole number >= 0")
        .replace("expected u64", "expected a whole number >= 0")
        .replace("expected f64", "expected a number")
        .replace("expected an array of length 3", "expected [x, y, z]");
    format!("{NOT_A_STATE}: {plain} ({at})")
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::GridSpec;

    fn mesh(n: usize) -> ClothMesh {
        ClothMesh::new(&GridSpec {
            num_width_points: n,
            num_height_points: n,
            pinned: vec![(0, 0)],
            ..GridSpec::default()
        })
        .unwrap()
    }

    #[test]
    fn a_written_state_reads_back_bit_for_bit_with_its_velocity() {
        let m = mesh(3);
        let mut state = ClothState::new(&m);
        for (i, (p, l)) in state.positions.iter_mut().zip(&mut state.last).enumerate() {
            if i > 0 {
                *l += Vec3::new(0.1, -0.2 / 3.0, 1e-17);
                *p += Vec3::new(0.3, -1.0 / 7.0, 2e-9);
            }
        }
        let dt = 1.0 / 2700.0;
        let json = serde_json::to_string(&StateFile::new(&m, &state, 7, 7.0 / 90.0, dt)).unwrap();
        let back: StateFile = serde_json::from_str(&json).unwrap();
        assert_eq!(back.frames, 7);
        assert_eq!(back.to_state(&m, dt).unwrap(), state);
    }

    #[test]
    fn a_run_with_another_step_keeps_the_written_velocity() {
        let m = mesh(2);
        let mut state = ClothState::new(&m);
        state.last[3] += Vec3::new(0.0, 1e-3, 0.0);
        let (written, read) = (1.0 / 2700.0, 1.0 / 90.0);
        let file = StateFile::new(&m, &state, 0, 0.0, written);
        let s = file.to_state(&m, read).unwrap();
        let v = |st: &ClothState, dt: f64| (st.positions[3] - st.last[3]) / dt;
        // Rounding of a 1 m coordinate (1e-16 m) against a 3e-2 m displacement: 1e-14
        // relative at most, far below any wrong scale (a factor 30 here).
        assert!((v(&s, read) - v(&state, written)).norm() < 1e-12 * v(&state, written).norm());
    }

    #[test]
    fn a_state_of_another_grid_or_pin_set_is_refused_with_the_reason() {
        let state = StateFile::new(&mesh(3), &ClothState::new(&mesh(3)), 0, 0.0, 0.01);
        let e = state.to_state(&mesh(4), 0.01).unwrap_err().to_string();
        assert!(e.contains("3 x 3") && e.contains("4 x 4"), "{e}");
        let mut moved = state;
        moved.positions[0][1] += 0.5;
        let e = moved.to_state(&mesh(3), 0.01).unwrap_err().to_string();
        assert!(e.contains("positions[0]") && e.contains("pins"), "{e}");
        moved.positions[0][1] = f64::NAN;
        let e = moved.to_state(&mesh(3), 0.01).unwrap_err().to_string();
        assert!(e.contains("finite"), "{e}");
    }

    fn written(dir: &Path, name: &str, text: &[u8]) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn state_json(m: &ClothMesh, frames: u64, time: f64) -> serde_json::Value {
        serde_json::to_value(StateFile::new(m, &ClothState::new(m), frames, time, 0.01)).unwrap()
    }

    #[test]
    fn frames_and_time_that_would_wrap_or_mean_nothing_are_refused() {
        let m = mesh(2);
        let dir = tempfile::tempdir().unwrap();
        let read = |v: &serde_json::Value| {
            let p = written(dir.path(), "s.json", v.to_string().as_bytes());
            StateFile::read(&p, &m, 0.01).map(|(f, _)| (f.frames, f.time))
        };
        assert_eq!(
            read(&state_json(&m, MAX_FRAMES, MAX_TIME)).unwrap(),
            (MAX_FRAMES, MAX_TIME)
        );
        for (frames, time, what) in [
            (
                u64::MAX - 5,
                1.0,
                "frames is 18446744073709551610, but it must be",
            ),
            (MAX_FRAMES + 1, 1.0, "frames is 1000000000001"),
            (0, -1.0, "time is -1, but it must be"),
            (0, MAX_TIME * 1.0002, "time is 100020000000"),
        ] {
            let e = format!("{:#}", read(&state_json(&m, frames, time)).unwrap_err());
            assert!(e.starts_with("--from ") && e.contains(what), "{e}");
        }
    }

    #[cfg(unix)]
    #[test]
    fn special_files_oversized_and_utf16_states_are_refused_like_scenes() {
        let m = mesh(2);
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo.json");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        // Opened for reading, a FIFO without a writer would block forever.
        let e = format!("{:#}", StateFile::read(&fifo, &m, 0.01).unwrap_err());
        assert!(
            e.contains("it is a FIFO (named pipe), not a state file"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            StateFile::read(Path::new("/dev/zero"), &m, 0.01).unwrap_err()
        );
        assert!(e.contains("it is a character device"), "{e}");
        // One byte over the cap for this cloth: refused by its size, before it is read.
        let big = dir.path().join("big.json");
        std::fs::File::create(&big)
            .unwrap()
            .set_len(max_state_bytes(4) + 1)
            .unwrap();
        let e = format!("{:#}", StateFile::read(&big, &m, 0.01).unwrap_err());
        assert!(
            e.contains("69633 bytes, more than any state of this 2 x 2 cloth"),
            "{e}"
        );
        let p = written(dir.path(), "u16.json", b"\xFF\xFE{\0}\0");
        let e = format!("{:#}", StateFile::read(&p, &m, 0.01).unwrap_err());
        assert!(
            e.contains("UTF-16") && e.contains("save it as UTF-8"),
            "{e}"
        );
    }

    #[test]
    fn json_that_is_no_state_is_told_without_rust_type_names() {
        let m = mesh(2);
        let dir = tempfile::tempdir().unwrap();
        for (text, what) in [
            (
                "[1, 2, 3, 4, 5, 6, 7, 8]",
                "it is a list; a state is an object with the keys",
            ),
            (" []", "it is a list"),
            ("7", "expected an object with the keys"),
            ("{\"num_width_points\": -2}", "expected a whole number >= 0"),
            ("{", "invalid JSON at line 1"),
        ] {
            let p = written(dir.path(), "s.json", text.as_bytes());
            let e = format!("{:#}", StateFile::read(&p, &m, 0.01).unwrap_err());
            assert!(e.contains(what), "{text}: {e}");
            assert!(
                !e.contains("struct") && !e.contains("StateFile") && !e.contains("usize"),
                "{e}"
            );
        }
    }

    #[test]
    fn a_state_without_last_positions_starts_at_rest() {
        let m = mesh(2);
        let mut file = StateFile::new(&m, &ClothState::new(&m), 0, 0.0, 0.01);
        file.positions[3][1] -= 0.25;
        file.last_positions = None;
        let s = file.to_state(&m, 0.02).unwrap();
        assert_eq!(s.positions, s.last);
    }
}
