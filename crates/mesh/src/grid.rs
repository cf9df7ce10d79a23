//! The cloth grid: point masses, springs and triangles, built exactly as the course builds them.

use crate::{SplitMix64, Vec3};

/// The largest number of points a cloth may have (4 Mi), far above anything that runs
/// interactively; past it a typo such as `num_width_points: 50000` would exhaust memory.
pub const MAX_POINTS: usize = 1 << 22;

/// The widths, heights and thicknesses a cloth may have, in metres: from a nanometre to a
/// million kilometres, far beyond any cloth either way.
///
/// NOTE: the bound also keeps the solver's shortcuts exact. Its stretch check proves a spring
/// inside the limit from `len^2 <= max^2 (1 - 4 eps)` without a square root, which holds only
/// while `max^2` is a normal double (spring limits from about 1.5e-154 m to 1.3e154 m); with at
/// most [`MAX_POINTS`] points, spring lengths stay within 1e-16 m to 1e10 m here.
pub const EXTENT_RANGE: std::ops::RangeInclusive<f64> = 1e-9..=1e9;

/// How the cloth starts out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Orientation {
    /// In the xz-plane at y = 1 (the course's `orientation: 0`).
    #[default]
    Horizontal,
    /// In the xy-plane, row 0 at the bottom, each point jittered in z by up to 1 mm
    /// (the course's `orientation: 1`).
    Vertical,
}

/// Everything needed to build a [`ClothMesh`]; mirrors the course's `cloth` block minus the
/// live-editable physical parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSpec {
    /// Extent along the grid's x axis, metres.
    pub width: f64,
    /// Extent along the grid's second axis (z when horizontal, y when vertical), metres.
    pub height: f64,
    /// Points along x, at least 2.
    pub num_width_points: usize,
    /// Points along the second axis, at least 2.
    pub num_height_points: usize,
    /// Cloth thickness, metres: self-collision keeps points `2 * thickness` apart.
    pub thickness: f64,
    /// Start orientation.
    pub orientation: Orientation,
    /// Pinned points as `(column, row)`.
    pub pinned: Vec<(usize, usize)>,
    /// Seed of the vertical cloth's z-jitter, so runs are bit-identical.
    pub seed: u64,
}

impl Default for GridSpec {
    /// The course's standard cloth: 1 m x 1 m, 50 x 50 points, horizontal, nothing pinned.
    fn default() -> Self {
        Self {
            width: 1.0,
            height: 1.0,
            num_width_points: 50,
            num_height_points: 50,
            thickness: 0.0095,
            orientation: Orientation::Horizontal,
            pinned: Vec::new(),
            seed: 184,
        }
    }
}

/// Why a grid cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// Fewer than 2 points along an axis.
    #[error("{axis} is {value}, but a cloth needs at least 2 points along each axis")]
    TooFewPoints {
        /// `num_width_points` or `num_height_points`.
        axis: &'static str,
        /// The bad count.
        value: usize,
    },
    /// More than [`MAX_POINTS`] points in all.
    #[error("the grid has {points} points ({nw} x {nh}); at most {max} are allowed", max = MAX_POINTS)]
    TooManyPoints {
        /// Points along x.
        nw: usize,
        /// Points along the second axis.
        nh: usize,
        /// Their product (saturating).
        points: usize,
    },
    /// A size that is not a finite number in [`EXTENT_RANGE`].
    #[error("{field} is {value} m, but it must be a finite number from 1e-9 to 1e9 (metres)")]
    BadExtent {
        /// `width`, `height` or `thickness`.
        field: &'static str,
        /// The bad value.
        value: f64,
    },
    /// A pin that names a point outside the grid.
    #[error("pin [{x}, {y}] is outside the {nw} x {nh} grid (columns 0..={max_x}, rows 0..={max_y})", max_x = nw - 1, max_y = nh - 1)]
    PinOutOfRange {
        /// Column of the pin.
        x: usize,
        /// Row of the pin.
        y: usize,
        /// Points along x.
        nw: usize,
        /// Points along the second axis.
        nh: usize,
    },
}

/// The three spring types of the course's model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpringKind {
    /// To the left and upper neighbour; stiffness `ks`.
    Structural,
    /// To the two upper diagonal neighbours; stiffness `ks`.
    Shearing,
    /// Two points to the left and two up; stiffness `0.2 * ks`.
    Bending,
}

impl SpringKind {
    /// The factor applied to `ks` for this kind (1 or 0.2).
    #[must_use]
    pub fn stiffness_factor(self) -> f64 {
        match self {
            SpringKind::Structural | SpringKind::Shearing => 1.0,
            SpringKind::Bending => 0.2,
        }
    }
}

/// A spring between two points of the grid, by index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// Index of the point that emitted the spring (the later one in row-major order).
    pub a: u32,
    /// Index of the other end.
    pub b: u32,
    /// Rest length, metres: the distance at construction.
    pub rest: f64,
    /// Which type it is.
    pub kind: SpringKind,
}

/// The immutable topology of a cloth: start positions, pins, springs and triangles. A change by
/// hand (a pin, a cut) makes a new mesh: see [`ClothMesh::with_pin`] and [`ClothMesh::cut`].
///
/// Points are row-major with x fastest (`index = y * nw + x`), as in the course.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothMesh {
    pub(crate) spec: GridSpec,
    start: Vec<Vec3>,
    pub(crate) pinned: Vec<bool>,
    pub(crate) springs: Vec<Spring>,
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Springs cut by hand (see [`ClothMesh::cut`]); 0 for the grid as built.
    pub(crate) cut: usize,
}

impl ClothMesh {
    /// The course's `pinned4` cloth scaled to `n x n` points at the standard cloth's spacing
    /// (1/49 m, so the cloth is `(n - 1) / 49` m wide) and thickness, horizontal, pinned at its
    /// four corners: the cloth of benchmarks and of tests that need a cloth of any size.
    ///
    /// Keeping the spacing (rather than squeezing `n` points into 1 m) keeps every point's
    /// neighbourhood, stretch and self-contact the same as in the standard scene, so the cost per
    /// point measured on a big grid is the cost per point of the course's cloth. `n = 50` is
    /// exactly `pinned4`.
    ///
    /// # Errors
    /// A [`MeshError`] when `n < 2` or `n * n` exceeds [`MAX_POINTS`].
    pub fn pinned_grid(n: usize) -> Result<Self, MeshError> {
        let last = n.saturating_sub(1);
        let size = last as f64 / 49.0;
        Self::new(&GridSpec {
            width: size,
            height: size,
            num_width_points: n,
            num_height_points: n,
            thickness: 0.0095,
            orientation: Orientation::Horizontal,
            pinned: vec![(0, 0), (last, 0), (0, last), (last, last)],
            ..GridSpec::default()
        })
    }

    /// Builds the grid, springs and triangles described by `spec`.
    ///
    /// # Errors
    /// A [`MeshError`] when the spec is out of range (too few or too many points, a non-positive
    /// size, a pin outside the grid).
    pub fn new(spec: &GridSpec) -> Result<Self, MeshError> {
        let (nw, nh) = (spec.num_width_points, spec.num_height_points);
        for (axis, value) in [("num_width_points", nw), ("num_height_points", nh)] {
            if value < 2 {
                return Err(MeshError::TooFewPoints { axis, value });
            }
        }
        let points = nw.saturating_mul(nh);
        if points > MAX_POINTS {
            return Err(MeshError::TooManyPoints { nw, nh, points });
        }
        for (field, value) in [
            ("width", spec.width),
            ("height", spec.height),
            ("thickness", spec.thickness),
        ] {
            if !EXTENT_RANGE.contains(&value) {
                return Err(MeshError::BadExtent { field, value });
            }
        }
        let mut pinned = vec![false; points];
        for &(x, y) in &spec.pinned {
            if x >= nw || y >= nh {
                return Err(MeshError::PinOutOfRange { x, y, nw, nh });
            }
            pinned[y * nw + x] = true;
        }
        let start = start_positions(spec);
        let springs = build_springs(nw, nh, &start);
        let triangles = build_triangles(nw, nh);
        Ok(Self {
            spec: spec.clone(),
            start,
            pinned,
            springs,
            triangles,
            cut: 0,
        })
    }

    /// The spec the mesh was built from.
    #[must_use]
    pub fn spec(&self) -> &GridSpec {
        &self.spec
    }

    /// Points along x.
    #[must_use]
    pub fn nw(&self) -> usize {
        self.spec.num_width_points
    }

    /// Points along the second axis.
    #[must_use]
    pub fn nh(&self) -> usize {
        self.spec.num_height_points
    }

    /// Number of points, `nw * nh`.
    #[must_use]
    pub fn len(&self) -> usize {
        self.start.len()
    }

    /// Always false: a mesh has at least 2 x 2 points.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.start.is_empty()
    }

    /// Index of the point at column `x`, row `y`.
    #[must_use]
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.nw() + x
    }

    /// Cloth thickness, metres.
    #[must_use]
    pub fn thickness(&self) -> f64 {
        self.spec.thickness
    }

    /// Start positions, metres.
    #[must_use]
    pub fn start_positions(&self) -> &[Vec3] {
        &self.start
    }

    /// Whether each point is pinned.
    #[must_use]
    pub fn pinned(&self) -> &[bool] {
        &self.pinned
    }

    /// The springs, in the course's emission order (y outer, x inner; per point structural left,
    /// structural up, shearing up-left, shearing up-right, bending left, bending up).
    #[must_use]
    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }

    /// Two triangles per grid cell, `(A, C, B)` and `(B, C, D)` with `A = (x, y)`,
    /// `B = (x + 1, y)`, `C = (x, y + 1)`, `D = (x + 1, y + 1)`.
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Mass of each point, kg: the cloth's area times `density` (kg/m^2) shared equally.
    #[must_use]
    pub fn point_mass(&self, density: f64) -> f64 {
        self.spec.width * self.spec.height * density / self.len() as f64
    }
}

fn start_positions(spec: &GridSpec) -> Vec<Vec3> {
    let (nw, nh) = (spec.num_width_points, spec.num_height_points);
    let dw = spec.width / (nw - 1) as f64;
    let dh = spec.height / (nh - 1) as f64;
    let mut rng = SplitMix64::new(spec.seed);
    let mut out = Vec::with_capacity(nw * nh);
    for y in 0..nh {
        for x in 0..nw {
            let (u, v) = (x as f64 * dw, y as f64 * dh);
            out.push(match spec.orientation {
                Orientation::Horizontal => Vec3::new(u, 1.0, v),
                Orientation::Vertical => Vec3::new(u, v, rng.uniform(-0.001, 0.001)),
            });
        }
    }
    out
}

fn build_springs(nw: usize, nh: usize, start: &[Vec3]) -> Vec<Spring> {
    let structural = 2 * nw * nh - nw - nh;
    let shearing = 2 * (nw - 1) * (nh - 1);
    // Two apart along a row, and along a column.
    let bending = nw.saturating_sub(2) * nh + nw * nh.saturating_sub(2);
    let mut springs = Vec::with_capacity(structural + shearing + bending);
    // NOTE: the order is the course's; the stretch limit is a sequential sweep, so reordering
    // would change results in the last bits.
    let neighbours: [(isize, isize, SpringKind); 6] = [
        (-1, 0, SpringKind::Structural),
        (0, -1, SpringKind::Structural),
        (-1, -1, SpringKind::Shearing),
        (1, -1, SpringKind::Shearing),
        (-2, 0, SpringKind::Bending),
        (0, -2, SpringKind::Bending),
    ];
    for y in 0..nh {
        for x in 0..nw {
            let a = y * nw + x;
            for &(dx, dy, kind) in &neighbours {
                let (bx, by) = (x as isize + dx, y as isize + dy);
                if bx < 0 || by < 0 || bx >= nw as isize {
                    continue;
                }
                let b = by as usize * nw + bx as usize;
                springs.push(Spring {
                    a: a as u32,
                    b: b as u32,
                    rest: (start[a] - start[b]).norm(),
                    kind,
                });
            }
        }
    }
    springs
}

fn build_triangles(nw: usize, nh: usize) -> Vec<[u32; 3]> {
    let mut tris = Vec::with_capacity(2 * (nw - 1) * (nh - 1));
    for y in 0..nh - 1 {
        for x in 0..nw - 1 {
            let a = (y * nw + x) as u32;
            let b = a + 1;
            let c = a + nw as u32;
            let d = c + 1;
            tris.push([a, c, b]);
            tris.push([b, c, d]);
        }
    }
    tris
}

#[cfg(test)]
mod tests {
    use super::*;

    fn standard() -> ClothMesh {
        ClothMesh::new(&GridSpec::default()).unwrap()
    }

    fn count(mesh: &ClothMesh, kind: SpringKind) -> usize {
        mesh.springs().iter().filter(|s| s.kind == kind).count()
    }

    #[test]
    fn pinned_grid_of_50_is_the_courses_pinned4() {
        let mesh = ClothMesh::pinned_grid(50).unwrap();
        assert_eq!(mesh.spec().width, 1.0);
        assert_eq!(mesh.springs().len(), 14_502);
        assert_eq!(mesh.pinned().iter().filter(|&&p| p).count(), 4);
        // The big cloth of the speed figures: 256 x 256 has 390,658 springs.
        assert_eq!(
            ClothMesh::pinned_grid(256).unwrap().springs().len(),
            390_658
        );
        assert!(matches!(
            ClothMesh::pinned_grid(1),
            Err(MeshError::TooFewPoints { .. })
        ));
        assert!(matches!(
            ClothMesh::pinned_grid(1 << 12),
            Err(MeshError::TooManyPoints { .. })
        ));
    }

    #[test]
    fn standard_cloth_has_the_courses_spring_counts() {
        let mesh = standard();
        let (nw, nh) = (50, 50);
        let structural = 2 * nw * nh - nw - nh;
        assert_eq!(count(&mesh, SpringKind::Structural), structural);
        assert_eq!(count(&mesh, SpringKind::Shearing), 2 * (nw - 1) * (nh - 1));
        assert_eq!(count(&mesh, SpringKind::Bending), structural - nw - nh);
        assert_eq!(mesh.springs().len(), 14_502);
    }

    #[test]
    fn the_arrays_hold_no_room_beyond_the_cloth() {
        // What the memory check counts is the arrays' lengths: a spring array that outgrew a
        // short reservation would hold up to twice that.
        for (nw, nh) in [(2, 2), (2, 7), (50, 50), (31, 3), (120, 80)] {
            let mut spec = standard().spec().clone();
            spec.num_width_points = nw;
            spec.num_height_points = nh;
            spec.pinned = vec![(0, 0)];
            let mesh = ClothMesh::new(&spec).unwrap();
            assert_eq!(mesh.springs.capacity(), mesh.springs.len(), "{nw} x {nh}");
            assert_eq!(
                mesh.triangles.capacity(),
                mesh.triangles.len(),
                "{nw} x {nh}"
            );
            assert_eq!(mesh.start.capacity(), mesh.start.len(), "{nw} x {nh}");
        }
    }

    #[test]
    fn rest_lengths_are_grid_distances() {
        // Spacing is 1/49 m; rest lengths follow from the offsets, to rounding error only.
        let mesh = standard();
        let d = 1.0 / 49.0;
        for s in mesh.springs() {
            let expected = match s.kind {
                SpringKind::Structural => d,
                SpringKind::Shearing => d * 2f64.sqrt(),
                SpringKind::Bending => 2.0 * d,
            };
            assert!((s.rest - expected).abs() < 1e-12, "{s:?}");
        }
    }

    #[test]
    fn mass_per_point_is_area_times_density_over_count() {
        // 1 m^2 * 150 kg/m^2 / 2500 points = 0.06 kg.
        assert!((standard().point_mass(150.0) - 0.06).abs() < 1e-15);
    }

    #[test]
    fn springs_come_in_the_courses_order() {
        let mesh = standard();
        let s = mesh.springs();
        // Point (1, 0) emits only its structural spring to (0, 0); point (2, 0) adds bending.
        assert_eq!((s[0].a, s[0].b, s[0].kind), (1, 0, SpringKind::Structural));
        assert_eq!((s[1].a, s[1].b, s[1].kind), (2, 1, SpringKind::Structural));
        assert_eq!((s[2].a, s[2].b, s[2].kind), (2, 0, SpringKind::Bending));
        // Point (1, 1) = index 51: left, up, up-left, up-right.
        let first_51 = s.iter().position(|s| s.a == 51).unwrap();
        let kinds: Vec<_> = s[first_51..first_51 + 4]
            .iter()
            .map(|s| (s.b, s.kind))
            .collect();
        assert_eq!(
            kinds,
            vec![
                (50, SpringKind::Structural),
                (1, SpringKind::Structural),
                (0, SpringKind::Shearing),
                (2, SpringKind::Shearing),
            ]
        );
    }

    #[test]
    fn grid_spans_the_extent_in_the_right_plane() {
        let mesh = standard();
        let p = mesh.start_positions();
        assert_eq!(p[0], Vec3::new(0.0, 1.0, 0.0));
        assert!((p[2499] - Vec3::new(1.0, 1.0, 1.0)).norm() < 1e-12);
        let vertical = ClothMesh::new(&GridSpec {
            orientation: Orientation::Vertical,
            ..GridSpec::default()
        })
        .unwrap();
        let v = vertical.start_positions();
        assert!((v[2499].xy() - nalgebra::Vector2::new(1.0, 1.0)).norm() < 1e-12);
        assert!(v.iter().all(|p| p.z.abs() <= 0.001));
        assert!(
            v.iter().any(|p| p.z != 0.0),
            "vertical cloth is jittered in z"
        );
    }

    #[test]
    fn bad_specs_are_rejected() {
        let bad = |spec: GridSpec| ClothMesh::new(&spec).unwrap_err();
        assert!(matches!(
            bad(GridSpec {
                num_width_points: 1,
                ..GridSpec::default()
            }),
            MeshError::TooFewPoints {
                axis: "num_width_points",
                value: 1
            }
        ));
        assert!(matches!(
            bad(GridSpec {
                num_width_points: 5000,
                num_height_points: 5000,
                ..GridSpec::default()
            }),
            MeshError::TooManyPoints { .. }
        ));
        assert!(matches!(
            bad(GridSpec {
                thickness: f64::NAN,
                ..GridSpec::default()
            }),
            MeshError::BadExtent {
                field: "thickness",
                ..
            }
        ));
        // Past either end of the range, and just inside it.
        for width in [0.0, -1.0, 1e-10, 2e9, f64::INFINITY] {
            let e = bad(GridSpec {
                width,
                ..GridSpec::default()
            });
            assert!(
                matches!(e, MeshError::BadExtent { field: "width", .. }),
                "{width}"
            );
        }
        assert_eq!(
            bad(GridSpec {
                height: 1e-12,
                ..GridSpec::default()
            })
            .to_string(),
            "height is 0.000000000001 m, but it must be a finite number from 1e-9 to 1e9 (metres)"
        );
        for size in [1e-9, 1e9] {
            let spec = GridSpec {
                width: size,
                height: size,
                thickness: size,
                ..GridSpec::default()
            };
            assert!(ClothMesh::new(&spec).is_ok(), "{size}");
        }
        let e = bad(GridSpec {
            pinned: vec![(50, 0)],
            ..GridSpec::default()
        });
        assert_eq!(
            e.to_string(),
            "pin [50, 0] is outside the 50 x 50 grid (columns 0..=49, rows 0..=49)"
        );
    }

    #[test]
    fn triangles_cover_every_cell_twice() {
        let mesh = standard();
        assert_eq!(mesh.triangles().len(), 2 * 49 * 49);
        assert_eq!(mesh.triangles()[0], [0, 50, 1]);
        assert_eq!(mesh.triangles()[1], [1, 50, 51]);
    }
}
