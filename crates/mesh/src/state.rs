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
}

impl From<&ClothMesh> for ClothState {
    fn from(mesh: &ClothMesh) -> Self {
        Self::new(mesh)
    }
}
