//! Changes of a cloth's topology by hand: pins set and lifted, springs cut.
//!
//! A [`ClothMesh`] stays immutable; each change makes a new mesh, so a solver that caches the
//! topology sees a different mesh and a run can go back to the scene's own.

use std::collections::HashSet;

use crate::{ClothMesh, Vec3};

/// How the stroke of a [`Knife`] is seen: what "crossing on screen" means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sight {
    /// Along a direction, as an orthographic view sees: the stroke sweeps a band along it.
    Along(Vec3),
    /// From a point, as a perspective camera's eye sees: the stroke sweeps a fan from it.
    From(Vec3),
}

/// A stroke that cuts every spring it crosses as seen from [`Sight`]: exactly the springs whose
/// drawn segment the stroke's drawn segment crosses in a view with that sight, whatever the
/// view's scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knife {
    /// Where the stroke starts, m (any point on the line of sight through it).
    pub from: Vec3,
    /// Where the stroke ends, m.
    pub to: Vec3,
    /// How it is seen.
    pub sight: Sight,
}

impl Knife {
    /// A 2-D picture of world points in which the knife's stroke and a spring cross exactly
    /// when they do on a screen with this sight: `None` when the sight is degenerate (a zero
    /// direction, or a stroke through the eye).
    fn picture(&self) -> Option<impl Fn(Vec3) -> Option<[f64; 2]>> {
        let (origin, forward, perspective) = match self.sight {
            Sight::Along(d) => (Vec3::zeros(), d, false),
            Sight::From(eye) => (eye, (self.from + self.to) / 2.0 - eye, true),
        };
        let forward = forward.try_normalize(1e-12)?;
        // Any two axes across the sight: the crossing test does not depend on which.
        let helper = if forward.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        let right = forward.cross(&helper).normalize();
        let up = right.cross(&forward);
        Some(move |p: Vec3| {
            let d = p - origin;
            let (u, v) = (d.dot(&right), d.dot(&up));
            if perspective {
                let z = d.dot(&forward);
                // NOTE: a point behind the eye is on no screen of it.
                (z > 1e-9).then(|| [u / z, v / z])
            } else {
                Some([u, v])
            }
        })
    }

    /// Whether the segment `p`–`q` crosses the stroke as seen (touching counts).
    #[must_use]
    pub fn crosses(&self, p: Vec3, q: Vec3) -> bool {
        let Some(picture) = self.picture() else {
            return false;
        };
        let (Some(a), Some(b), Some(c), Some(d)) =
            (picture(self.from), picture(self.to), picture(p), picture(q))
        else {
            return false;
        };
        segments_cross(a, b, c, d)
    }
}

/// Twice the signed area of `(a, b, c)`: which side of `a -> b` the point `c` lies on.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether the closed segments `a`–`b` and `c`–`d` meet (collinear overlaps count).
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (orient(a, b, c), orient(a, b, d));
    let (d3, d4) = (orient(c, d, a), orient(c, d, b));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return true;
    }
    let within = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    (d1 == 0.0 && within(a, b, c))
        || (d2 == 0.0 && within(a, b, d))
        || (d3 == 0.0 && within(c, d, a))
        || (d4 == 0.0 && within(c, d, b))
}

impl ClothMesh {
    /// This mesh with point `point` pinned (`true`) or free; the pin list of its spec follows,
    /// so a scene saved from it keeps the pin. `None` when the point is not on the grid.
    #[must_use]
    pub fn with_pin(&self, point: usize, pinned: bool) -> Option<Self> {
        if point >= self.len() {
            return None;
        }
        let mut out = self.clone();
        out.pinned[point] = pinned;
        let at = (point % self.nw(), point / self.nw());
        out.spec.pinned.retain(|&p| p != at);
        if pinned {
            out.spec.pinned.push(at);
        }
        Some(out)
    }

    /// This mesh without the springs `knife` crosses with the cloth at `positions`, and without
    /// the triangles that lose an edge (every triangle edge is a structural or shearing spring,
    /// so the drawing shows the gap). `None` when it crosses no spring, or `positions` is not
    /// this mesh's.
    #[must_use]
    pub fn cut(&self, positions: &[Vec3], knife: &Knife) -> Option<Self> {
        if positions.len() != self.len() {
            return None;
        }
        let crossed = |a: u32, b: u32| knife.crosses(positions[a as usize], positions[b as usize]);
        let gone: HashSet<(u32, u32)> = self
            .springs
            .iter()
            .filter(|s| crossed(s.a, s.b))
            .map(|s| (s.a.min(s.b), s.a.max(s.b)))
            .collect();
        if gone.is_empty() {
            return None;
        }
        let mut out = self.clone();
        out.springs
            .retain(|s| !gone.contains(&(s.a.min(s.b), s.a.max(s.b))));
        out.triangles.retain(|t| {
            [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
                .iter()
                .all(|&(a, b)| !gone.contains(&(a.min(b), a.max(b))))
        });
        out.cut += gone.len();
        Some(out)
    }

    /// Whether every spring and triangle of the grid is there (nothing was cut).
    #[must_use]
    pub fn is_whole(&self) -> bool {
        self.cut == 0
    }

    /// How many springs were cut from the grid.
    #[must_use]
    pub fn springs_cut(&self) -> usize {
        self.cut
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GridSpec;

    fn standard() -> ClothMesh {
        ClothMesh::new(&GridSpec::default()).unwrap()
    }

    /// A stroke across the horizontal cloth along x = `x`, seen from above.
    fn across_at(x: f64) -> Knife {
        Knife {
            from: Vec3::new(x, 1.0, -0.5),
            to: Vec3::new(x, 1.0, 1.5),
            sight: Sight::Along(-Vec3::y()),
        }
    }

    #[test]
    fn a_stroke_across_the_cloth_cuts_every_spring_over_its_line_and_the_triangles_beside_it() {
        let mesh = standard();
        // Between columns 24 and 25 (spacing 1/49 m): springs joining a column <= 24 to one
        // >= 25 cross it: per row one structural, two shearing (per row pair), two bending.
        let x = 24.5 / 49.0;
        let cut = mesh.cut(mesh.start_positions(), &across_at(x)).unwrap();
        let nh = 50;
        let expected = nh + 2 * (nh - 1) + 2 * nh;
        assert_eq!(mesh.springs().len() - cut.springs().len(), expected);
        assert_eq!(cut.springs_cut(), expected);
        assert!(!cut.is_whole() && mesh.is_whole());
        // One column of cells loses both its triangles.
        assert_eq!(mesh.triangles().len() - cut.triangles().len(), 2 * (nh - 1));
        // No spring left joins the two halves.
        let nw = mesh.nw();
        let side = |i: u32| (i as usize % nw) <= 24;
        assert!(cut.springs().iter().all(|s| side(s.a) == side(s.b)));
    }

    #[test]
    fn a_stroke_off_the_cloth_or_along_its_line_of_sight_cuts_nothing() {
        let mesh = standard();
        assert!(mesh.cut(mesh.start_positions(), &across_at(2.0)).is_none());
        let point = Knife {
            from: Vec3::new(0.5, 2.0, 0.5),
            to: Vec3::new(0.5, 0.0, 0.5) + Vec3::new(0.0, 0.0, 1e-3),
            sight: Sight::Along(Vec3::zeros()),
        };
        assert!(mesh.cut(mesh.start_positions(), &point).is_none());
    }

    #[test]
    fn a_perspective_stroke_cuts_what_crosses_it_on_the_eyes_screen() {
        let mesh = standard();
        // An eye straight above column 24.5: the stroke drawn at half the height projects onto
        // the same line of the cloth as the orthographic stroke.
        let x = 24.5 / 49.0;
        let eye = Vec3::new(x, 3.0, 0.5);
        let knife = Knife {
            from: Vec3::new(x, 2.0, 0.5 - 1.0),
            to: Vec3::new(x, 2.0, 0.5 + 1.0),
            sight: Sight::From(eye),
        };
        let seen = mesh.cut(mesh.start_positions(), &knife).unwrap();
        let along = mesh.cut(mesh.start_positions(), &across_at(x)).unwrap();
        assert_eq!(seen, along);
        // A stroke behind the eye is on no screen of it.
        let behind = Knife {
            from: Vec3::new(x, 4.0, -1.0),
            to: Vec3::new(x, 4.0, 2.0),
            sight: Sight::From(eye),
        };
        assert!(mesh.cut(mesh.start_positions(), &behind).is_none());
    }

    #[test]
    fn pins_set_and_lifted_follow_the_spec() {
        let mesh = standard();
        let centre = mesh.index(25, 25);
        let pinned = mesh.with_pin(centre, true).unwrap();
        assert!(pinned.pinned()[centre]);
        assert!(pinned.spec().pinned.contains(&(25, 25)));
        assert_eq!(pinned.springs(), mesh.springs());
        let back = pinned.with_pin(centre, false).unwrap();
        assert_eq!(back, mesh);
        assert!(mesh.with_pin(mesh.len(), true).is_none());
    }
}
