//! The cloth mesh of the CS184 "ClothSim" mass-spring model.
//!
//! A [`ClothMesh`] is the immutable topology of a cloth: its grid of point masses (start positions
//! and pins), its springs (index pairs with rest lengths, in the course's emission order) and its
//! triangles. The moving part, positions and last positions, is a [`ClothState`], the single
//! source of truth that solvers advance and renderers read.
//!
//! This crate does no I/O and knows nothing of solvers or rendering. All lengths are in metres.

mod grid;
mod normals;
mod rng;
mod state;

pub use grid::{
    ClothMesh, EXTENT_RANGE, GridSpec, MAX_POINTS, MeshError, Orientation, Spring, SpringKind,
};
pub use normals::vertex_normals;
pub use rng::SplitMix64;
pub use state::ClothState;

/// A 3-vector of `f64` in SI units (metres, metres per second, newtons...).
pub type Vec3 = nalgebra::Vector3<f64>;
