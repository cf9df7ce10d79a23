//! The moving part of a cloth.

use crate::{ClothMesh, Vec3};

/// Positions and last positions of every point: the one source of truth of a simulation.
///
/// Solvers advance it; renderers and exporters read it. Kept as two contiguous arrays indexed
/// like the mesh, so a solver can stream through them and a swap of solver keeps the motion
/// (velocity is implied by `positions - last`).
#[derive(Debug, Clone, PartialEq)]
pub struct ClothState {
    /// Current positions, metres.
    pub positions: Vec<Vec3>,
    /// Positions one step ago, metres (Verlet's implicit velocity).
    pub last: Vec<Vec3>,
}

impl ClothState {
    /// The mesh at rest at its start positions.
    #[must_use]
    pub fn new(mesh: &ClothMesh) -> Self {
        Self {
            positions: mesh.start_positions().to_vec(),
            last: mesh.start_positions().to_vec(),
        }
    }

    /// Puts every point back at its start position with zero velocity (the course's R key).
    pub fn reset(&mut self, mesh: &ClothMesh) {
        self.positions.clear();
        self.positions.extend_from_slice(mesh.start_positions());
        self.last.clear();
        self.last.extend_from_slice(mesh.start_positions());
    }

    /// Index of the first point whose position or last position is not finite.
    #[must_use]
    pub fn first_non_finite(&self) -> Option<usize> {
        self.positions.iter().zip(&self.last).position(|(p, l)| {
            !(p.iter().all(|c| c.is_finite()) && l.iter().all(|c| c.is_finite()))
        })
    }

    /// Keeps the velocity across a change of step: `last` becomes the position `new_dt`
    /// seconds ago at the current velocity, where it was `old_dt` seconds ago.
    ///
    /// Velocity is implied by `(positions - last) / dt`, so a run whose step changes (another
    /// solver with other steps per frame, an edit of steps per frame or frames per second, a
    /// state written at another step) must rescale the displacement or the cloth speeds up or
    /// stops by the ratio of the steps. A ratio of exactly one leaves the state bit for bit.
    pub fn retime(&mut self, old_dt: f64, new_dt: f64) {
        let scale = new_dt / old_dt;
        // NOTE: `scale == 1` must not touch the bits: `p - (p - l)` need not round back to `l`.
        if scale == 1.0 || !scale.is_finite() {
            return;
        }
        for (l, p) in self.last.iter_mut().zip(&self.positions) {
            *l = p - (p - *l) * scale;
        }
    }
}

impl From<&ClothMesh> for ClothState {
    fn from(mesh: &ClothMesh) -> Self {
        Self::new(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClothMesh, GridSpec};

    #[test]
    fn retime_keeps_the_velocity_and_a_unit_ratio_keeps_the_bits() {
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let mut state = ClothState::new(&mesh);
        for (i, l) in state.last.iter_mut().enumerate() {
            *l -= Vec3::new(0.0, 1e-4 * (i % 7) as f64, 3e-5);
        }
        let velocity = |s: &ClothState, dt: f64| -> Vec<Vec3> {
            s.positions
                .iter()
                .zip(&s.last)
                .map(|(p, l)| (p - l) / dt)
                .collect()
        };
        let before = velocity(&state, 1.0 / 2700.0);
        let same = state.clone();
        state.retime(1.0 / 2700.0, 1.0 / 2700.0);
        assert_eq!(state, same);
        state.retime(1.0 / 2700.0, 1.0 / 90.0);
        for (a, b) in before.iter().zip(velocity(&state, 1.0 / 90.0)) {
            // One rounding of the scaled displacement, relative to a velocity of order 1e-2 m/s.
            assert!((a - b).norm() <= 1e-12, "{a} vs {b}");
        }
        assert_eq!(state.positions, same.positions);
    }
}
