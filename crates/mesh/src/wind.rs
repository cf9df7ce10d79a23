//! Wind: air moving past the cloth, felt by each triangle as the aerodynamic drag of the
//! relative velocity's normal component (docs/model.md states the model and its source).
//!
//! The drag on a triangle of area `A` and unit normal `n`, whose points move on average at `u`
//! through air moving at `w`, is
//!
//! ```text
//! F = 1/2 rho C_d A (v . n) |v . n| n,    v = w - u
//! ```
//!
//! (the drag equation with the flow's component across the surface; a flat sheet feels no drag
//! from air sliding along it), shared equally by the triangle's three points. It is applied
//! once per step, before the solver's step, as a change of each free point's velocity
//! `F / m dt`: through the previous positions, which every solver reads its velocity from, so
//! every solver of the registry feels the same wind without knowing of it. Drag can only carry
//! the cloth towards the air's velocity along the normal, so it brings no energy of its own
//! beyond the work the moving air does.

use crate::{ClothMesh, ClothState, Vec3};

/// Density of air at sea level and 15 C (the International Standard Atmosphere), kg/m^3.
pub const AIR_DENSITY: f64 = 1.225;

/// The wind of a run: the air's velocity, the cloth's drag coefficient and an optional gust.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind {
    /// The air's mean velocity, m/s (default zero: no wind, and nothing is applied, so a run
    /// is the course's to the bit).
    pub velocity: Vec3,
    /// The cloth's drag coefficient across the flow, dimensionless (default 1.2, a flat plate
    /// broadside to the flow).
    pub drag: f64,
    /// The gust's amplitude as a fraction of the mean velocity (default 0: steady). The air
    /// moves at `velocity * (1 + gust * sin(2 pi t / gust_period))`.
    pub gust: f64,
    /// The gust's period, s (default 2).
    pub gust_period: f64,
}

impl Default for Wind {
    fn default() -> Self {
        Self {
            velocity: Vec3::zeros(),
            drag: 1.2,
            gust: 0.0,
            gust_period: 2.0,
        }
    }
}

impl Wind {
    /// Whether there is any wind to apply (a zero velocity or drag applies nothing).
    #[must_use]
    pub fn blows(&self) -> bool {
        self.drag != 0.0 && self.velocity != Vec3::zeros()
    }

    /// The air's velocity at simulated time `time`, m/s.
    #[must_use]
    pub fn at(&self, time: f64) -> Vec3 {
        if self.gust == 0.0 {
            return self.velocity;
        }
        let phase = std::f64::consts::TAU * time / self.gust_period;
        self.velocity * (1.0 + self.gust * phase.sin())
    }
}

/// The wind's force on every point of `mesh` in `state` at simulated time `time`, N, with the
/// velocities of the last step (`dt` long); added to `forces`.
pub fn wind_forces(
    mesh: &ClothMesh,
    state: &ClothState,
    wind: &Wind,
    time: f64,
    dt: f64,
    forces: &mut [Vec3],
) {
    let air = wind.at(time);
    let k = 0.5 * AIR_DENSITY * wind.drag;
    let velocity = |i: usize| (state.positions[i] - state.last[i]) / dt;
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| i as usize);
        let (pa, pb, pc) = (state.positions[a], state.positions[b], state.positions[c]);
        let cross = (pb - pa).cross(&(pc - pa));
        let twice_area = cross.norm();
        if twice_area == 0.0 {
            continue;
        }
        let n = cross / twice_area;
        let u = (velocity(a) + velocity(b) + velocity(c)) / 3.0;
        let across = (air - u).dot(&n);
        let f = n * (k * 0.5 * twice_area * across * across.abs() / 3.0);
        for i in [a, b, c] {
            forces[i] += f;
        }
    }
}

/// Applies one step (`dt` long, at simulated time `time`) of `wind` to `state`: each free
/// point's velocity changes by its force over its mass times `dt`, through its previous
/// position. Pinned points do not move. Does nothing when the wind does not blow.
pub fn apply_wind(
    mesh: &ClothMesh,
    state: &mut ClothState,
    wind: &Wind,
    point_mass: f64,
    time: f64,
    dt: f64,
) {
    if !wind.blows() {
        return;
    }
    let mut forces = vec![Vec3::zeros(); mesh.len()];
    wind_forces(mesh, state, wind, time, dt, &mut forces);
    let scale = dt * dt / point_mass;
    for ((last, f), pinned) in state.last.iter_mut().zip(&forces).zip(mesh.pinned()) {
        if !pinned {
            *last -= f * scale;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat, horizontal cloth at rest.
    fn flat() -> (ClothMesh, ClothState) {
        let mesh = ClothMesh::pinned_grid(8).unwrap();
        let state = ClothState::new(&mesh);
        (mesh, state)
    }

    fn total(mesh: &ClothMesh, state: &ClothState, wind: &Wind) -> Vec3 {
        let mut f = vec![Vec3::zeros(); mesh.len()];
        wind_forces(mesh, state, wind, 0.0, 1e-3, &mut f);
        f.iter().sum()
    }

    #[test]
    fn air_across_a_flat_cloth_at_rest_pushes_it_with_the_drag_equation() {
        let (mesh, state) = flat();
        let n = state.positions[mesh.index(0, 0)] - state.positions[mesh.index(1, 0)];
        let m = state.positions[mesh.index(0, 0)] - state.positions[mesh.index(0, 1)];
        let normal = n.cross(&m).normalize();
        let wind = Wind {
            velocity: normal * 3.0,
            ..Wind::default()
        };
        let f = total(&mesh, &state, &wind);
        let area: f64 = mesh
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| state.positions[i as usize]);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum();
        let expected = 0.5 * AIR_DENSITY * 1.2 * area * 9.0;
        assert!(
            (f.norm() - expected).abs() <= 1e-12 * expected,
            "{} N against {expected} N",
            f.norm()
        );
        assert!(f.normalize().dot(&normal) > 1.0 - 1e-12, "along the wind");
    }

    #[test]
    fn air_along_a_flat_cloth_or_moving_with_it_exerts_nothing() {
        let (mesh, mut state) = flat();
        let a = state.positions[mesh.index(0, 0)];
        let along = (state.positions[mesh.index(1, 0)] - a).normalize() * 5.0;
        let wind = Wind {
            velocity: along,
            ..Wind::default()
        };
        assert!(total(&mesh, &state, &wind).norm() < 1e-12);
        // The cloth moving with the air, across its plane: no relative velocity.
        let normal = (state.positions[mesh.index(1, 0)] - a)
            .cross(&(state.positions[mesh.index(0, 1)] - a))
            .normalize();
        let dt = 1e-3;
        for (p, l) in state.positions.clone().iter().zip(state.last.iter_mut()) {
            *l = p - normal * 4.0 * dt;
        }
        let wind = Wind {
            velocity: normal * 4.0,
            ..Wind::default()
        };
        let mut f = vec![Vec3::zeros(); mesh.len()];
        wind_forces(&mesh, &state, &wind, 0.0, dt, &mut f);
        assert!(f.iter().all(|f| f.norm() < 1e-9), "{:?}", f[0]);
    }

    #[test]
    fn no_wind_leaves_the_state_untouched_and_pins_never_move() {
        let (mesh, mut state) = flat();
        let before = state.clone();
        apply_wind(&mesh, &mut state, &Wind::default(), 0.06, 0.0, 1e-3);
        assert_eq!(state, before, "no wind: the same bits");
        let a = state.positions[0];
        let normal = (state.positions[mesh.index(1, 0)] - a)
            .cross(&(state.positions[mesh.index(0, 1)] - a))
            .normalize();
        let wind = Wind {
            velocity: normal * 10.0,
            ..Wind::default()
        };
        apply_wind(&mesh, &mut state, &wind, 0.06, 0.0, 1e-3);
        for (i, pinned) in mesh.pinned().iter().enumerate() {
            let moved = state.last[i] != before.last[i];
            assert_eq!(moved, !pinned, "point {i}");
        }
    }

    #[test]
    fn a_gust_swings_the_air_about_its_mean_over_its_period() {
        let wind = Wind {
            velocity: Vec3::new(2.0, 0.0, 0.0),
            gust: 0.5,
            gust_period: 4.0,
            ..Wind::default()
        };
        assert!(
            (wind.at(1.0).x - 3.0).abs() < 1e-12,
            "peak a quarter period in"
        );
        assert!((wind.at(3.0).x - 1.0).abs() < 1e-12, "trough");
        assert!((wind.at(4.0).x - 2.0).abs() < 1e-12, "mean after a period");
    }
}
