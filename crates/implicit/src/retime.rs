//! Keeping the velocity when the step size changes, and the course's per-step friction at
//! another step.

use cloth_mesh::{ClothState, Collider, REFERENCE_STEPS_PER_FRAME, StepParams};

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

/// Writes `colliders` into `out` with each friction retimed to the step of `params`.
///
/// The course's friction `f` removes that share of a colliding point's displacement at every
/// step of its reference step count ([`REFERENCE_STEPS_PER_FRAME`]), so a point that stays in
/// contact keeps `(1 - f)` of its velocity per reference step: over a step `h` that is
/// `(1 - f)^(h / h_ref)`, the friction `1 - (1 - f)^(h / h_ref)` applied once. Without this an
/// implicit solver at one step per frame would apply the course's friction once where Verlet
/// applies it thirty times, and a cloth that Verlet holds on a sphere slides off it. The same
/// reading of a per-step constant as a rate turns the course's damping into
/// [`StepParams::drag_rate`].
pub fn retime_friction(colliders: &[Collider], params: &StepParams, out: &mut Vec<Collider>) {
    out.clear();
    out.extend_from_slice(colliders);
    let h_ref = 1.0 / (params.frames_per_sec * f64::from(REFERENCE_STEPS_PER_FRAME));
    let ratio = params.dt() / h_ref;
    for c in out.iter_mut() {
        let keep = (1.0 - c.friction()).powf(ratio);
        c.set_friction(1.0 - keep);
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

    #[test]
    fn friction_applied_once_per_frame_keeps_what_thirty_steps_keep() {
        let sphere = Collider::Sphere(cloth_mesh::Sphere {
            origin: Vec3::zeros(),
            radius: 0.5,
            friction: 0.3,
        });
        let mut out = Vec::new();
        let at = |steps_per_frame| StepParams {
            steps_per_frame,
            ..StepParams::default()
        };
        retime_friction(&[sphere], &at(30), &mut out);
        // At the course's own step the friction is its own, up to the rounding of the two
        // ways the step is computed (an ulp of the exponent).
        assert!((out[0].friction() - 0.3).abs() < 1e-15);
        retime_friction(&[sphere], &at(1), &mut out);
        // One step keeps what thirty of the course's keep: 0.7^30; a few ulps of rounding.
        assert!((1.0 - out[0].friction() - 0.7_f64.powi(30)).abs() < 1e-15);
    }
}
