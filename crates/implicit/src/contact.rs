//! Friction of the collision objects as a drag inside the implicit step: which points rest on
//! an object, the drag rate that stands for the course's friction, and the collisions that
//! finish the step (the crate's documentation, "Friction", says why).

use cloth_mesh::{ClothMesh, ClothState, Collider, REFERENCE_STEPS_PER_FRAME, StepParams, Vec3};

/// A free point this near a collision object's surface at the start of a step, metres, rests on
/// it: ten times the course's surface offset, inside which a point resting on a plane keeps,
/// and a few hundredths of the bundled scenes' springs.
pub const CONTACT_DISTANCE: f64 = 1e-3;

/// The highest friction whose drag rate is finite: friction 1 would hold a resting point
/// still, which a rate of `1e6 / h_ref` does to a micrometre in a metre's pull.
const MAX_FRICTION: f64 = 1.0 - 1e-6;

/// The drag rate, 1/s, that stands for the course's per-step friction `friction` of an object:
/// `f / ((1 - f) h_ref)`, whose backward-Euler step keeps `1 - f` of a displacement at the
/// course's step `h_ref` and slides a pulled point at the course's speed at any step (see the
/// module doc).
#[must_use]
pub fn friction_rate(friction: f64, params: &StepParams) -> f64 {
    let h_ref = 1.0 / (params.frames_per_sec * f64::from(REFERENCE_STEPS_PER_FRAME));
    let f = friction.clamp(0.0, MAX_FRICTION);
    f / ((1.0 - f) * h_ref)
}

/// Writes `colliders` into `out` with each friction retimed to the step of `params`: the share
/// of a displacement that one backward-Euler step of the friction's drag ([`friction_rate`])
/// takes, `1 - 1 / (1 + c_f h)`, which is the course's own friction at the course's step.
///
/// It is the friction the course's collisions apply to the step in which a point reaches an
/// object, and what an explicit integrator at another step than the course's applies at each
/// of its steps to keep the same friction.
pub fn retime_friction(colliders: &[Collider], params: &StepParams, out: &mut Vec<Collider>) {
    out.clear();
    out.extend_from_slice(colliders);
    let h = params.dt();
    for c in out.iter_mut() {
        let keep = 1.0 / (1.0 + friction_rate(c.friction(), params) * h);
        c.set_friction(1.0 - keep);
    }
}

/// How far `p` is from `collider`'s surface, metres, on the side `from` is on (a point inside
/// the sphere is at a negative distance), so that a point moving away has a growing distance.
fn distance(collider: &Collider, from: &Vec3, p: &Vec3) -> f64 {
    match collider {
        Collider::Sphere(s) => (p - s.origin).norm() - s.radius,
        Collider::Plane(pl) => {
            let side = if (from - pl.point).dot(&pl.normal) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            side * (p - pl.point).dot(&pl.normal)
        }
    }
}

/// Whether a free point of `state` lies within [`CONTACT_DISTANCE`] of a collision object's
/// surface.
pub(crate) fn touches(mesh: &ClothMesh, colliders: &[Collider], state: &ClothState) -> bool {
    state
        .positions
        .iter()
        .zip(mesh.pinned())
        .any(|(p, &pinned)| {
            !pinned
                && colliders
                    .iter()
                    .any(|c| distance(c, p, p) <= CONTACT_DISTANCE)
        })
}

/// The points resting on a collision object at the start of a step, with their friction's drag
/// rate, and the colliders that finish the step.
#[derive(Debug, Default)]
pub(crate) struct Contacts {
    /// Per point, the drag rate of the friction it rests on, 1/s (0 for a point that rests on
    /// nothing, and for pinned points).
    rate: Vec<f64>,
    /// The colliders without friction, for the resting points.
    sliding: Vec<Collider>,
    /// The colliders with the friction of one step's drag ([`retime_friction`]), for the other
    /// points.
    impact: Vec<Collider>,
    /// Whether a point whose prediction reaches an object also takes its drag when it starts
    /// the step away from it (the step in which it arrives), rather than only a point that
    /// starts the step on it.
    approach: bool,
}

impl Contacts {
    /// Contacts whose drag also acts on a point in the step in which its prediction reaches
    /// an object ([`Contacts::approach`]).
    pub(crate) fn approaching() -> Self {
        Self {
            approach: true,
            ..Self::default()
        }
    }

    /// Finds the free points of `state` that rest on one of `colliders` (see the module doc):
    /// within [`CONTACT_DISTANCE`] of its surface, and their prediction `y` too. A point
    /// resting on several takes the largest rate.
    pub(crate) fn find(
        &mut self,
        mesh: &ClothMesh,
        colliders: &[Collider],
        params: &StepParams,
        state: &ClothState,
        y: &[Vec3],
    ) {
        self.rate.clear();
        self.rate.resize(mesh.len(), 0.0);
        retime_friction(colliders, params, &mut self.impact);
        self.sliding.clear();
        for c in colliders {
            let rate = friction_rate(c.friction(), params);
            let mut sliding = *c;
            sliding.set_friction(0.0);
            self.sliding.push(sliding);
            if rate == 0.0 {
                continue;
            }
            for (((r, x0), y), &pinned) in self
                .rate
                .iter_mut()
                .zip(&state.positions)
                .zip(y)
                .zip(mesh.pinned())
            {
                if pinned {
                    continue;
                }
                if distance(c, x0, y) <= CONTACT_DISTANCE
                    && (self.approach || distance(c, x0, x0) <= CONTACT_DISTANCE)
                {
                    *r = r.max(rate);
                }
            }
        }
    }

    /// Per point, the drag rate of the friction it rests on, 1/s.
    pub(crate) fn rates(&self) -> &[f64] {
        &self.rate
    }

    /// Pushes the points of `positions` (moved from `last` this step) out of the collision
    /// objects: the resting ones without friction (the step had their drag), the others with
    /// one step's drag applied to their displacement.
    pub(crate) fn resolve(&self, pinned: &[bool], positions: &mut [Vec3], last: &[Vec3]) {
        for (((p, &l), &pin), &rate) in positions.iter_mut().zip(last).zip(pinned).zip(&self.rate) {
            if pin {
                continue;
            }
            let colliders = if rate > 0.0 {
                &self.sliding
            } else {
                &self.impact
            };
            for c in colliders {
                if let Some(q) = c.resolve(l, *p) {
                    *p = q;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_step_of_the_friction_drag_keeps_the_course_share_at_the_course_step() {
        let at = |steps_per_frame| StepParams {
            steps_per_frame,
            ..StepParams::default()
        };
        let mut out = Vec::new();
        for f in [0.1, 0.3, 0.5, 0.9] {
            let sphere = Collider::Sphere(cloth_mesh::Sphere {
                origin: Vec3::zeros(),
                radius: 0.5,
                friction: f,
            });
            // At the course's step the friction is its own, up to the rounding of the rate
            // and the step (a few ulps).
            retime_friction(&[sphere], &at(REFERENCE_STEPS_PER_FRAME), &mut out);
            assert!(
                (out[0].friction() - f).abs() < 1e-14,
                "f {f}: {}",
                out[0].friction()
            );
            // One step a frame keeps what a thirty times longer step of the drag keeps.
            retime_friction(&[sphere], &at(1), &mut out);
            let keep = 1.0 / (1.0 + 30.0 * f / (1.0 - f));
            assert!((1.0 - out[0].friction() - keep).abs() < 1e-14, "f {f}");
        }
        // Full friction holds a point: finite, and a step keeps at most a millionth.
        let p = at(1);
        let rate = friction_rate(1.0, &p);
        assert!(rate.is_finite() && 1.0 / (1.0 + rate * p.dt()) < 1e-6);
        assert_eq!(friction_rate(0.0, &p), 0.0);
    }
}
