//! Keeping the velocity when the step size changes.

use cloth_mesh::ClothState;

/// Rescales the implied velocity `(positions - last) / dt` of `state` from a step of `old_dt`
/// seconds to one of `new_dt`, so the cloth keeps its velocity when the step changes (a solver
/// swap that also changes `steps_per_frame`, or a live edit of it).
///
/// Every solver reads the velocity as `(positions - last) / params.dt()`; without this call a
/// change of step reinterprets the same displacement over the new step, as the course's own
/// simulator does when its steps per frame are edited. Non-positive or non-finite steps leave
/// the state unchanged.
pub fn retime_velocity(state: &mut ClothState, old_dt: f64, new_dt: f64) {
    if !(old_dt.is_finite() && new_dt.is_finite() && old_dt > 0.0 && new_dt > 0.0) {
        return;
    }
    let scale = new_dt / old_dt;
    for (p, l) in state.positions.iter().zip(state.last.iter_mut()) {
        *l = p - (p - *l) * scale;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::Vec3;

    #[test]
    fn velocity_survives_a_change_of_step() {
        let mut s = ClothState {
            positions: vec![Vec3::new(0.0, 1.0, 0.0)],
            last: vec![Vec3::new(0.0, 1.001, 0.0)],
        };
        let v_before = (s.positions[0] - s.last[0]) / (1.0 / 2700.0);
        retime_velocity(&mut s, 1.0 / 2700.0, 1.0 / 90.0);
        let v_after = (s.positions[0] - s.last[0]) / (1.0 / 90.0);
        // Rounding `last` (about 1 m) costs ~1e-16 m against the new 3.3e-5 m displacement, a
        // few 1e-12 relative; 1e-9 is far above that and far below any wrong scale factor.
        assert!((v_after - v_before).norm() < 1e-9 * v_before.norm());
    }
}
