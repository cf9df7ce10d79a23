//! The cloth's total energy and its parts, J: one measure for the conformance kit's energy
//! figures and the divergence guard's judgement of a run.

use cloth_mesh::{ClothMesh, ClothState, StepParams};

use crate::kinetic_energy;

/// Kinetic energy from the step velocity `(positions - last) / dt`, J: what every solver hands
/// the next step (and the next solver) as the cloth's motion.
#[must_use]
pub fn kinetic(mesh: &ClothMesh, state: &ClothState, params: &StepParams) -> f64 {
    kinetic_energy(state, mesh.point_mass(params.density), params.dt())
}

/// Energy stored in the springs, J: `k (l - rest)^2 / 2` for every spring whose kind is
/// enabled, with the stiffness the model gives it (`ks`, or `0.2 ks` for bending).
#[must_use]
pub fn spring(mesh: &ClothMesh, state: &ClothState, params: &StepParams) -> f64 {
    mesh.springs()
        .iter()
        .map(|s| {
            let k = params.stiffness(s.kind);
            if k == 0.0 {
                return 0.0;
            }
            let l = (state.positions[s.a as usize] - state.positions[s.b as usize]).norm();
            0.5 * k * (l - s.rest) * (l - s.rest)
        })
        .sum()
}

/// Potential energy of the scene's gravity, J, from the origin: `-m g . x` summed over points.
#[must_use]
pub fn gravity(mesh: &ClothMesh, state: &ClothState, params: &StepParams) -> f64 {
    let m = mesh.point_mass(params.density);
    -m * state
        .positions
        .iter()
        .map(|x| params.gravity.dot(x))
        .sum::<f64>()
}

/// Total energy `H = kinetic + spring + gravity`, J.
#[must_use]
pub fn total(mesh: &ClothMesh, state: &ClothState, params: &StepParams) -> f64 {
    kinetic(mesh, state, params) + spring(mesh, state, params) + gravity(mesh, state, params)
}

/// The scene's energy scale `E = M |g| L`, J: the cloth's mass, gravity's magnitude and the
/// cloth's longest side, the order of the energy a fall of the cloth's own size releases.
#[must_use]
pub fn scale(mesh: &ClothMesh, params: &StepParams) -> f64 {
    let spec = mesh.spec();
    let mass = mesh.point_mass(params.density) * mesh.len() as f64;
    mass * params.gravity.norm() * spec.width.max(spec.height)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{GridSpec, Vec3};

    #[test]
    fn a_cloth_at_rest_has_only_gravitys_energy_and_a_lift_adds_m_g_h() {
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let params = StepParams::default();
        let mut state = ClothState::new(&mesh);
        assert_eq!(kinetic(&mesh, &state, &params), 0.0);
        assert!(spring(&mesh, &state, &params).abs() < 1e-20);
        let h0 = total(&mesh, &state, &params);
        // 150 kg at y = 1 under 9.8 m/s^2.
        assert!((h0 - 150.0 * 9.8).abs() < 1e-9, "{h0}");
        assert!((scale(&mesh, &params) - 150.0 * 9.8).abs() < 1e-9);
        for (p, l) in state.positions.iter_mut().zip(&mut state.last) {
            *p += Vec3::new(0.0, 0.5, 0.0);
            *l += Vec3::new(0.0, 0.5, 0.0);
        }
        let h1 = total(&mesh, &state, &params);
        assert!((h1 - h0 - 150.0 * 9.8 * 0.5).abs() < 1e-9);
    }

    #[test]
    fn a_stretched_spring_stores_half_k_x_squared_and_a_disabled_one_nothing() {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 2,
            num_height_points: 2,
            pinned: vec![],
            ..GridSpec::default()
        })
        .unwrap();
        let mut state = ClothState::new(&mesh);
        // On the 1 m grid, moving point 1 by 1 cm along x stretches its structural spring to
        // point 0 by 1 cm and the one to point 3 (1 m along z) to sqrt(1 + 1e-4) m.
        state.positions[1].x += 0.01;
        let structural_only = StepParams {
            shearing: false,
            bending: false,
            ..StepParams::default()
        };
        let e = spring(&mesh, &state, &structural_only);
        let side = (1.0_f64 + 1e-4).sqrt() - 1.0;
        let expected = 0.5 * 5000.0 * (1e-4 + side * side);
        assert!((e - expected).abs() < 1e-12, "{e} vs {expected}");
        let none = StepParams {
            structural: false,
            shearing: false,
            bending: false,
            ..StepParams::default()
        };
        assert_eq!(spring(&mesh, &state, &none), 0.0);
    }
}
