//! The cloth mesh of the CS184 "ClothSim" mass-spring model.
//!
//! A [`ClothMesh`] is the immutable topology of a cloth: its grid of point masses (start positions
//! and pins), its springs (index pairs with rest lengths, in the course's emission order) and its
//! triangles. The moving part, positions and last positions, is a [`ClothState`], the single
//! source of truth that solvers advance and renderers read.
//!
//! The cloth's world is data here too: the collision objects ([`Collider`]: the course's sphere
//! and plane, with the rule that puts a point back outside them) and the live parameters of a
//! run ([`StepParams`]). Scene files, renderers and every solver share these types, so none of
//! them needs another's crate.
//!
//! This crate does no I/O and knows nothing of solvers or rendering. All lengths are in metres.

mod collider;
mod cut;
mod grid;
mod normals;
mod params;
mod rng;
mod state;
mod wind;

pub use collider::{Collider, Plane, SURFACE_OFFSET, Sphere, apply_colliders};
pub use cut::{Knife, Sight};
pub use grid::{
    ClothMesh, EXTENT_RANGE, GridSpec, MAX_POINTS, MeshError, Orientation, Spring, SpringKind,
};
pub use normals::vertex_normals;
pub use params::{MAX_STRETCH, ParamError, REFERENCE_STEPS_PER_FRAME, StepParams};
pub use rng::SplitMix64;
pub use state::ClothState;
pub use wind::{AIR_DENSITY, Wind, apply_wind, wind_forces};

/// A 3-vector of `f64` in SI units (metres, metres per second, newtons...).
pub type Vec3 = nalgebra::Vector3<f64>;
