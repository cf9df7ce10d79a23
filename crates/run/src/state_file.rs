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
//! starts at rest; one without `dt` is taken to have the run's step.

use std::path::Path;

use anyhow::{Context, bail};
use cloth_mesh::{ClothMesh, ClothState, Vec3};
use serde::{Deserialize, Serialize};

/// How far a pinned point of the state may be from the scene's pin, metres: pins never move,
/// so a state written by a run of this scene holds them exactly; the allowance only absorbs
/// the JSON round trip (which is exact for the shortest round-tripping decimals written here).
const PIN_TOLERANCE: f64 = 1e-9;

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
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("--from {}: cannot read the state file", path.display()))?;
        let file: StateFile = serde_json::from_str(text.trim_start_matches('\u{feff}'))
            .with_context(|| {
                format!(
                    "--from {}: not a clothsim state (the JSON that `clothsim simulate` writes)",
                    path.display()
                )
            })?;
        let state = file
            .to_state(mesh, dt)
            .with_context(|| format!("--from {}", path.display()))?;
        Ok((file, state))
    }

    /// The state for `mesh` and a step of `dt` seconds, checked.
    fn to_state(&self, mesh: &ClothMesh, dt: f64) -> anyhow::Result<ClothState> {
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
                    "{key}[{i}] is {:?}; every coordinate must be finite",
                    list[i]
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
                        "{key}[{i}] (column {}, row {}) is {:?}, but the scene pins that point \
                         at {:?}: the state comes from another scene or pin set",
                        i % mesh.nw(),
                        i / mesh.nw(),
                        list[i].as_slice(),
                        start.as_slice()
                    );
                }
            }
        }
        Ok(state)
    }
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
