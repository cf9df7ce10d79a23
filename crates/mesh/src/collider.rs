//! Collision objects: the course's sphere and plane, with friction.

use crate::Vec3;

/// How far above a plane a colliding point is put back, metres (the course's `SURFACE_OFFSET`).
pub const SURFACE_OFFSET: f64 = 1e-4;

/// A solid sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Centre, metres.
    pub origin: Vec3,
    /// Radius, metres (> 0).
    pub radius: f64,
    /// Friction in [0, 1]: 0 slides freely, 1 sticks.
    pub friction: f64,
}

/// An infinite plane that points may not cross.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point on the plane, metres.
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Friction in [0, 1].
    pub friction: f64,
}

/// A collision object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Collider {
    /// A sphere.
    Sphere(Sphere),
    /// A plane.
    Plane(Plane),
}

impl Collider {
    /// The object's friction in [0, 1].
    #[must_use]
    pub fn friction(&self) -> f64 {
        match self {
            Collider::Sphere(s) => s.friction,
            Collider::Plane(p) => p.friction,
        }
    }

    /// Sets the friction (clamped to [0, 1]).
    pub fn set_friction(&mut self, friction: f64) {
        let f = friction.clamp(0.0, 1.0);
        match self {
            Collider::Sphere(s) => s.friction = f,
            Collider::Plane(p) => p.friction = f,
        }
    }

    /// Resolves a collision of a point that moved from `last` to `p` this step, returning its
    /// corrected position, or `None` when it does not collide. `last` is left unchanged by the
    /// caller, so friction also removes the matching share of velocity.
    #[must_use]
    pub fn resolve(&self, last: Vec3, p: Vec3) -> Option<Vec3> {
        match self {
            Collider::Sphere(s) => {
                let d = p - s.origin;
                let dist = d.norm();
                // NOTE: a point exactly at the centre has no direction out; leave it rather than
                // divide by zero (the course would produce NaN).
                if dist > s.radius || dist == 0.0 {
                    return None;
                }
                let target = s.origin + d * (s.radius / dist);
                Some(last + (target - last) * (1.0 - s.friction))
            }
            Collider::Plane(pl) => {
                let now = (p - pl.point).dot(&pl.normal);
                let before = (last - pl.point).dot(&pl.normal);
                // NOTE: a point starting exactly on the plane counts as coming from the normal's
                // side, so the selfCollision scene's bottom row, which starts on the floor, stays.
                let side_before = if before >= 0.0 { 1.0 } else { -1.0 };
                let side_now = if now >= 0.0 { 1.0 } else { -1.0 };
                if side_before == side_now {
                    return None;
                }
                let target = p - pl.normal * now + pl.normal * (SURFACE_OFFSET * side_before);
                Some(last + (target - last) * (1.0 - pl.friction))
            }
        }
    }
}

/// Applies every collider, in order, to every unpinned point (step 4 of the course's step).
pub fn apply_colliders(
    colliders: &[Collider],
    pinned: &[bool],
    positions: &mut [Vec3],
    last: &[Vec3],
) {
    if colliders.is_empty() {
        return;
    }
    for ((p, &l), &pin) in positions.iter_mut().zip(last).zip(pinned) {
        if pin {
            continue;
        }
        for c in colliders {
            if let Some(q) = c.resolve(l, *p) {
                *p = q;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floor(friction: f64) -> Collider {
        Collider::Plane(Plane {
            point: Vec3::zeros(),
            normal: Vec3::y(),
            friction,
        })
    }

    #[test]
    fn a_non_finite_point_stays_non_finite() {
        // The Verlet solver's finiteness check leans on this: no collision makes a NaN or an
        // infinite position finite again, whatever the friction.
        let last = Vec3::new(0.0, 0.01, 0.0);
        for friction in [0.0, 0.5, 1.0] {
            let ball = Collider::Sphere(Sphere {
                origin: Vec3::zeros(),
                radius: 0.1,
                friction,
            });
            for collider in [floor(friction), ball] {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    for axis in 0..3 {
                        let mut p = Vec3::new(0.01, -0.02, 0.0);
                        p[axis] = bad;
                        if let Some(q) = collider.resolve(last, p) {
                            assert!(!q.iter().all(|c| c.is_finite()), "{collider:?} {p:?} {q:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_point_crossing_the_plane_lands_just_above_it() {
        let q = floor(0.0)
            .resolve(Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.1, -0.02, 0.0))
            .unwrap();
        assert!((q - Vec3::new(0.1, SURFACE_OFFSET, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn friction_keeps_a_share_of_the_motion_from_last() {
        // Full friction: the point stays where it was last step.
        let last = Vec3::new(0.0, 0.01, 0.0);
        let q = floor(1.0)
            .resolve(last, Vec3::new(0.1, -0.02, 0.0))
            .unwrap();
        assert_eq!(q, last);
    }

    #[test]
    fn a_point_starting_on_the_plane_does_not_fall_through() {
        let c = floor(0.5);
        let q = c
            .resolve(Vec3::zeros(), Vec3::new(0.0, -1e-6, 0.0))
            .unwrap();
        assert!(q.y > 0.0);
        assert!(
            c.resolve(Vec3::zeros(), Vec3::new(0.0, 1e-6, 0.0))
                .is_none()
        );
    }

    #[test]
    fn a_point_inside_the_sphere_goes_to_its_surface() {
        let s = Collider::Sphere(Sphere {
            origin: Vec3::zeros(),
            radius: 1.0,
            friction: 0.0,
        });
        let q = s
            .resolve(Vec3::new(0.0, 1.5, 0.0), Vec3::new(0.0, 0.5, 0.0))
            .unwrap();
        assert!((q.norm() - 1.0).abs() < 1e-15);
        assert!(s.resolve(Vec3::zeros(), Vec3::new(0.0, 1.5, 0.0)).is_none());
    }
}
