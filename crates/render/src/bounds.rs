//! World-space boxes used to fit orthographic views and to size the floor patch.

use cloth_mesh::Collider;
use cloth_mesh::Vec3;

use crate::RenderError;

/// How far a drawn floor patch reaches past what stands on it, as a fraction of its size.
const FLOOR_MARGIN: f64 = 0.15;

/// An axis-aligned box in world space, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Bounds {
    /// The box around `points`, or `None` when there are none.
    ///
    /// # Errors
    /// [`RenderError::NonFinite`] with the index of the first non-finite point.
    pub fn of_points(points: &[Vec3]) -> Result<Option<Self>, RenderError> {
        let mut out: Option<Self> = None;
        for (index, p) in points.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(RenderError::NonFinite { index });
            }
            out = Some(match out {
                None => Self { min: *p, max: *p },
                Some(b) => b.including(*p),
            });
        }
        Ok(out)
    }

    /// The box around the cloth's points and every sphere (what stands on a floor).
    ///
    /// # Errors
    /// [`RenderError::NonFinite`] when a point is not finite; `BadOption` for an empty cloth.
    pub fn of_solids(positions: &[Vec3], colliders: &[Collider]) -> Result<Self, RenderError> {
        let mut b = Self::of_points(positions)?.ok_or_else(|| RenderError::BadOption {
            name: "positions",
            value: "0 points".to_owned(),
            allowed: "at least one point",
        })?;
        for c in colliders {
            if let Collider::Sphere(s) = c {
                let r = Vec3::repeat(s.radius);
                b = b.union(&Self {
                    min: s.origin - r,
                    max: s.origin + r,
                });
            }
        }
        Ok(b)
    }

    /// The box around everything a view shows: the cloth's points, each sphere, and the floor
    /// patch each plane is drawn as (see [`Bounds::floor_patch`]). Take the union of this over an
    /// animation's frames for a fixed extent that does not jump.
    ///
    /// # Errors
    /// As [`Bounds::of_solids`].
    pub fn of_scene(positions: &[Vec3], colliders: &[Collider]) -> Result<Self, RenderError> {
        let solid = Self::of_solids(positions, colliders)?;
        Ok(solid.with_floors(&solid, colliders))
    }

    /// This box grown to hold the floor patch of every plane in `colliders`, each patch sized
    /// to lie under `over`.
    #[must_use]
    pub fn with_floors(&self, over: &Self, colliders: &[Collider]) -> Self {
        let mut b = *self;
        for c in colliders {
            if let Collider::Plane(p) = c {
                for corner in Self::floor_patch(over, p.point, p.normal) {
                    b = b.including(corner);
                }
            }
        }
        b
    }

    /// The smallest box holding both.
    #[must_use]
    pub fn union(&self, other: &Self) -> Self {
        Self {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }

    /// This box grown to hold `p`.
    #[must_use]
    pub fn including(&self, p: Vec3) -> Self {
        Self {
            min: self.min.inf(&p),
            max: self.max.sup(&p),
        }
    }

    /// The eight corners.
    #[must_use]
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// Length of the diagonal, metres.
    #[must_use]
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).norm()
    }

    /// The finite rectangle an infinite plane is drawn as: the shadow of `over` cast along the
    /// plane's normal, grown by 15 % on each side, as four corners in order around it.
    #[must_use]
    pub fn floor_patch(over: &Self, point: Vec3, normal: Vec3) -> [Vec3; 4] {
        let (u, v) = plane_basis(normal);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in over.corners() {
            let d = c - point;
            let (a, b) = (d.dot(&u), d.dot(&v));
            lo = [lo[0].min(a), lo[1].min(b)];
            hi = [hi[0].max(a), hi[1].max(b)];
        }
        let grow = |l: f64, h: f64| {
            // NOTE: a cloth seen exactly edge-on along the normal has zero extent; keep a patch.
            let m = ((h - l) * FLOOR_MARGIN).max(0.05);
            (l - m, h + m)
        };
        let (a0, a1) = grow(lo[0], hi[0]);
        let (b0, b1) = grow(lo[1], hi[1]);
        [
            point + u * a0 + v * b0,
            point + u * a1 + v * b0,
            point + u * a1 + v * b1,
            point + u * a0 + v * b1,
        ]
    }
}

/// Two unit vectors spanning the plane with unit `normal`, chosen deterministically.
pub(crate) fn plane_basis(normal: Vec3) -> (Vec3, Vec3) {
    // Pick the world axis least aligned with the normal so the cross product is well conditioned.
    let helper = if normal.x.abs() <= normal.y.abs() && normal.x.abs() <= normal.z.abs() {
        Vec3::x()
    } else if normal.y.abs() <= normal.z.abs() {
        Vec3::y()
    } else {
        Vec3::z()
    };
    let u = normal.cross(&helper).normalize();
    let v = normal.cross(&u);
    (u, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{Plane, Sphere};

    #[test]
    fn scene_bounds_hold_cloth_sphere_and_a_floor_patch_under_them() {
        let cloth = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 1.0)];
        let colliders = [
            Collider::Sphere(Sphere {
                origin: Vec3::new(0.5, 0.2, 0.5),
                radius: 0.2,
                friction: 0.3,
            }),
            Collider::Plane(Plane {
                point: Vec3::zeros(),
                normal: Vec3::y(),
                friction: 0.5,
            }),
        ];
        let b = Bounds::of_scene(&cloth, &colliders).unwrap();
        // The floor lies at y = 0; the patch reaches 15 % of the 1 m extent past the cloth.
        assert!((b.min.y - 0.0).abs() < 1e-12);
        assert!((b.max.y - 1.0).abs() < 1e-12);
        assert!((b.min.x + 0.15).abs() < 1e-12 && (b.max.z - 1.15).abs() < 1e-12);
        assert_eq!(
            Bounds::of_scene(&[Vec3::new(f64::NAN, 0.0, 0.0)], &[]),
            Err(RenderError::NonFinite { index: 0 })
        );
    }
}
