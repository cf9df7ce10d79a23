//! Self-collision through a spatial hash (step 3 of the course's step).
//!
//! [`SpatialHash`] groups the points by the course's boxes and pushes apart the points of a box
//! closer than `2 * thickness`, making the course's corrections bit for bit. Its parts, one
//! concept a file:
//!
//! - `keys`: a point's box as one integer;
//! - `table`: box keys to cell numbers;
//! - `layout`: the points grouped box by box, in index order, kept or moved between rebuilds;
//! - `memory`: what is remembered of a box, so a box provably still clear is skipped;
//! - `resolution`: the corrections, box by box, on threads when the solver has them.

use cloth_mesh::{ClothMesh, Vec3};

mod keys;
mod layout;
mod memory;
mod resolution;
mod table;

use layout::Run;
use memory::Memory;
use table::Table;

/// A spatial hash of the cloth's points in boxes of `3 * width / nw` by `3 * height / nh` by the
/// larger of the two, exactly the course's boxes, so the same pairs of points interact.
///
/// The course keys a `std::unordered_map` by a float hash of the box. We key by the box's integer
/// coordinates and group points with a counting sort:
///
/// 1. each box gets a cell number, in order of first appearance, from an open-addressing table
///    (linear probing, at most half full). Cells are kept from one rebuild to the next, so a
///    point whose key has not changed (nearly every point: a step moves a point a small fraction
///    of a box) keeps its cell without a lookup, as does a point whose key is that of the point
///    before it or of the one a row up;
/// 2. when the last layout is known and only a few points changed box (a moving cloth: about one
///    point in two hundred a step), those points are moved in it: the boxes between them slide
///    as blocks (see `SpatialHash::relayout`);
/// 3. otherwise a count per cell, a prefix sum and one placement pass lay the points out box by
///    box.
///
/// With threads, the points are cut into one contiguous run per thread. Each run computes its
/// keys and finds their cells (the table is only read), and in a full layout counts into its
/// own counters; the few points whose box has no cell yet get one afterwards, in index order,
/// on one thread. The prefix sum gives each run its own places in each box, after those of the
/// runs before it, so each box lists its points in index order whatever the thread count: the
/// order in which the correction sums are taken, part of the faithful result. A relayout
/// gives the same layout, on one thread (it is a copy of the indices).
///
/// The resolution skips a box found clear at an earlier pass whose points have all moved, since
/// then, within a provably safe distance of the move of its first point (a box carried along by
/// the cloth keeps being skipped): such a box is still clear, so skipping it changes nothing
/// (see `Repulsion::allowance`). On a settling cloth
/// that is nearly every box; a box whose anchors keep being outrun waits longer and longer
/// before it takes new ones, so a moving cloth does not pay for them.
///
/// Every pass is linear in the number of points or cells (at most about twice the boxes in use:
/// the table is cleared when the cloth has left more boxes behind), but for the relayout's sort
/// of its moves (at most one point in `RELAYOUT_SHARE`); once the arrays have grown, nothing
/// is allocated.
#[derive(Debug, Default, Clone)]
pub struct SpatialHash {
    /// Box key of each point, this rebuild's.
    key_of: Vec<u64>,
    /// Box key of each point at the last rebuild.
    last_key_of: Vec<u64>,
    /// Cell of each point.
    cell_of: Vec<u32>,
    /// Whether `last_key_of` and `cell_of` hold the last rebuild's keys and cells (false at
    /// first, after the table was cleared, and when the cloth changed size).
    coherent: bool,
    /// Box keys and their cells.
    table: Table,
    /// Cells with points at the last rebuild.
    live: usize,
    /// Per run of points: its count per cell, which the prefix sum turns into its next place in
    /// each cell; and its points whose cell was not found.
    runs: Vec<Run>,
    /// `start[c]..start[c + 1]` is cell `c`'s range in `members` (length cells + 1).
    start: Vec<u32>,
    /// Point indices grouped by cell.
    members: Vec<u32>,
    /// Where [`SpatialHash::relayout`] writes the next `members`.
    spare: Vec<u32>,
    /// The moves of a relayout (see there).
    moves: Vec<u64>,
    /// The points' positions in `members` order: a box's points are contiguous, so the pair
    /// loops read consecutive memory instead of gathering from the whole cloth for each pair.
    /// Filled by each box the resolution looks into, when it looks.
    ///
    /// NOTE: not by the layout. Writing every point's position to its slot there was a
    /// scattered write of the whole cloth each step, for boxes most of which the resolution
    /// then skips on their allowance; a box it does look into gathers its few points itself.
    sorted: Vec<Vec3>,
    /// Per point: its position when its box was last found clear, the position its
    /// allowance is measured from.
    anchor: Vec<Vec3>,
    /// Per cell: the resolution moved one of its points.
    touched: Vec<bool>,
    /// Per cell: what the resolution remembers of the box.
    memory: Vec<Memory>,
}

/// Points a thread takes at once in the threaded passes: enough to amortise rayon's task cost.
pub(crate) const PARALLEL_CHUNK: usize = 4096;

/// Squared distance of two points, summed as `(x^2 + y^2) + z^2` like nalgebra's `norm`.
#[inline]
pub(crate) fn dist2(d: &Vec3) -> f64 {
    d.x * d.x + d.y * d.y + d.z * d.z
}

impl SpatialHash {
    /// Box sizes `(w, h, t)` for `mesh`, metres.
    #[must_use]
    pub fn box_size(mesh: &ClothMesh) -> (f64, f64, f64) {
        let spec = mesh.spec();
        let w = 3.0 * spec.width / mesh.nw() as f64;
        let h = 3.0 * spec.height / mesh.nh() as f64;
        (w, h, w.max(h))
    }

    /// Rebuilds the hash from `positions`.
    pub fn rebuild(&mut self, mesh: &ClothMesh, positions: &[Vec3]) {
        self.rebuild_in(mesh, positions, None);
    }

    /// The points in point `i`'s box (including `i`), in index order, as of the last rebuild.
    #[cfg(test)]
    fn box_of(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let c = self.cell_of[i] as usize;
        let range = self.start[c] as usize..self.start[c + 1] as usize;
        self.members[range].iter().map(|&j| j as usize)
    }

    /// Pushes every unpinned point away from the other points of its box that are closer than
    /// `2 * thickness`, by the average correction divided by `steps_per_frame`.
    ///
    /// Points are treated in index order and each one sees the already-corrected positions of
    /// those before it, as in the course; the hash itself is built before any correction.
    pub fn resolve(&mut self, mesh: &ClothMesh, positions: &mut [Vec3], steps_per_frame: u32) {
        self.resolve_in(mesh, positions, steps_per_frame, None);
    }
}

#[cfg(test)]
mod tests {
    use super::keys::box_bits;
    use super::*;
    use crate::testing::assert_same_bits;
    use cloth_mesh::GridSpec;

    /// `n` points scattered uniformly in the cube `[lo, hi)^3` (deterministic for a seed).
    fn scattered(n: usize, seed: u64, lo: f64, hi: f64) -> Vec<Vec3> {
        let mut rng = cloth_mesh::SplitMix64::new(seed);
        (0..n)
            .map(|_| {
                Vec3::new(
                    rng.uniform(lo, hi),
                    rng.uniform(lo, hi),
                    rng.uniform(lo, hi),
                )
            })
            .collect()
    }

    #[test]
    fn each_box_lists_exactly_the_points_with_its_integer_box_in_index_order() {
        // A crumpled cloth: points scattered over several boxes (deterministic pseudo-random).
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let positions = scattered(mesh.len(), 7, -0.2, 0.2);
        let mut hash = SpatialHash::default();
        hash.rebuild(&mesh, &positions);
        let size = SpatialHash::box_size(&mesh);
        let box_index = |p: &Vec3| {
            [
                (p.x / size.0).floor(),
                (p.y / size.1).floor(),
                (p.z / size.2).floor(),
            ]
        };
        for i in (0..mesh.len()).step_by(13) {
            let expected: Vec<usize> = (0..mesh.len())
                .filter(|&j| box_index(&positions[j]) == box_index(&positions[i]))
                .collect();
            assert_eq!(hash.box_of(i).collect::<Vec<_>>(), expected);
        }
    }

    /// The default cloth with `nw` x `nh` points.
    fn cloth(nw: usize, nh: usize) -> ClothMesh {
        ClothMesh::new(&GridSpec {
            num_width_points: nw,
            num_height_points: nh,
            ..GridSpec::default()
        })
        .unwrap()
    }

    /// A pool of three threads: an odd count, so runs and boxes split unevenly.
    fn three_threads() -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
    }

    /// Every point's box listing, for comparing two hashes.
    fn listings(hash: &SpatialHash, n: usize) -> Vec<Vec<usize>> {
        (0..n).map(|i| hash.box_of(i).collect()).collect()
    }

    #[test]
    fn a_hash_kept_across_rebuilds_lists_the_boxes_of_a_fresh_one() {
        // A crumpled cloth that then drifts: a few points cross into neighbouring boxes each
        // time (kept cells), the whole cloth moves into new boxes (new cells, the table grows),
        // and after many moves the boxes left behind outnumber those in use (the table is
        // cleared). With and without threads, the kept hash must list what a fresh one lists.
        let mesh = cloth(160, 100);
        let pool = three_threads();
        let mut positions = scattered(mesh.len(), 21, -0.15, 0.15);
        let mut rng = cloth_mesh::SplitMix64::new(22);
        let (mut kept, mut kept_threaded) = (SpatialHash::default(), SpatialHash::default());
        let box_w = SpatialHash::box_size(&mesh).0;
        for round in 0..12 {
            let drift = if round % 4 == 3 { 10.0 * box_w } else { 0.0 };
            for p in &mut positions {
                let h = 0.2 * box_w;
                *p += Vec3::new(
                    drift + rng.uniform(-h, h),
                    rng.uniform(-h, h),
                    rng.uniform(-h, h),
                );
            }
            kept.rebuild(&mesh, &positions);
            kept_threaded.rebuild_in(&mesh, &positions, Some(&pool));
            let mut fresh = SpatialHash::default();
            fresh.rebuild(&mesh, &positions);
            let expected = listings(&fresh, mesh.len());
            assert_eq!(listings(&kept, mesh.len()), expected, "round {round}");
            assert_eq!(
                listings(&kept_threaded, mesh.len()),
                expected,
                "round {round}"
            );
        }
    }

    #[test]
    fn a_relayout_of_a_few_moved_points_lists_the_boxes_of_a_fresh_one() {
        // About one point in two hundred jumps each round: most to a box nearby (boxes gain and
        // lose points, some empty out), one in ten far away, into boxes no point was in (new
        // cells, after every old one). That is a relayout's case, not a full layout's, and
        // with and without threads it must list what a fresh hash lists.
        let mesh = cloth(160, 100);
        let n = mesh.len();
        let pool = three_threads();
        let mut positions = scattered(n, 31, -0.15, 0.15);
        let mut rng = cloth_mesh::SplitMix64::new(32);
        let (mut kept, mut kept_threaded) = (SpatialHash::default(), SpatialHash::default());
        kept.rebuild(&mesh, &positions);
        kept_threaded.rebuild_in(&mesh, &positions, Some(&pool));
        let box_w = SpatialHash::box_size(&mesh).0;
        for round in 0..20 {
            for _ in 0..n / 200 {
                let i = (rng.uniform(0.0, n as f64) as usize).min(n - 1);
                let h = if rng.uniform(0.0, 1.0) < 0.1 {
                    30.0 * box_w
                } else {
                    box_w
                };
                positions[i] +=
                    Vec3::new(rng.uniform(-h, h), rng.uniform(-h, h), rng.uniform(-h, h));
            }
            kept.moves.clear();
            kept.rebuild(&mesh, &positions);
            kept_threaded.rebuild_in(&mesh, &positions, Some(&pool));
            assert!(!kept.moves.is_empty(), "round {round} was not a relayout");
            let mut fresh = SpatialHash::default();
            fresh.rebuild(&mesh, &positions);
            let expected = listings(&fresh, n);
            assert_eq!(listings(&kept, n), expected, "round {round}");
            assert_eq!(listings(&kept_threaded, n), expected, "round {round}");
            // Every point is listed once, and the boxes tile the layout.
            assert_eq!(kept.start.last().copied(), Some(n as u32));
            assert!(kept.start.windows(2).all(|w| w[0] <= w[1]));
        }
    }

    #[test]
    fn box_by_box_resolution_makes_the_courses_point_by_point_corrections_bit_for_bit() {
        // A cloth crumpled into a 6 cm cube: many boxes with several pairs within reach, so
        // corrections chain through points corrected earlier in the same box.
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let start = scattered(mesh.len(), 5, 0.0, 0.06);
        // The course's sweep, written out: points in index order, boxes from the start.
        let mut hash = SpatialHash::default();
        hash.rebuild(&mesh, &start);
        let boxes: Vec<Vec<usize>> = (0..mesh.len()).map(|i| hash.box_of(i).collect()).collect();
        let reach = 2.0 * mesh.thickness();
        let mut course = start.clone();
        for i in 0..mesh.len() {
            if mesh.pinned()[i] {
                continue;
            }
            let (mut correction, mut count) = (Vec3::zeros(), 0u32);
            for &j in &boxes[i] {
                let d = course[i] - course[j];
                let dist = d.norm();
                if j != i && dist < reach && dist > 0.0 {
                    correction += d * ((reach - dist) / dist);
                    count += 1;
                }
            }
            if count > 0 {
                course[i] += correction / f64::from(count) / 30.0;
            }
        }
        let mut fast = start.clone();
        hash.resolve(&mesh, &mut fast, 30);
        let moved = course.iter().zip(&start).filter(|(a, b)| a != b).count();
        assert!(moved > mesh.len() / 2, "the test must exercise corrections");
        assert_same_bits(&fast, &course);
    }

    /// `positions` resolved by a fresh hash, which has no memory and so looks into every box,
    /// after checking that `kept`, on one thread and on `pool`'s, correct them the same, bit
    /// for bit.
    fn resolved_as_fresh(
        mesh: &ClothMesh,
        positions: &[Vec3],
        [kept, kept_threaded]: [&mut SpatialHash; 2],
        pool: &rayon::ThreadPool,
    ) -> Vec<Vec3> {
        let mut fresh = positions.to_vec();
        SpatialHash::default().resolve(mesh, &mut fresh, 30);
        let mut one = positions.to_vec();
        kept.resolve(mesh, &mut one, 30);
        let mut three = positions.to_vec();
        kept_threaded.resolve_in(mesh, &mut three, 30, Some(pool));
        assert_same_bits(&one, &fresh);
        assert_same_bits(&three, &fresh);
        fresh
    }

    #[test]
    fn boxes_skipped_on_their_allowance_make_the_corrections_of_a_fresh_hash() {
        // A flat cloth whose boxes are clear (spacing 1 cm, reach 4 mm) trembles by a few
        // micrometres a step, so boxes keep their anchors and are skipped; meanwhile one point
        // walks towards its neighbour and comes within reach (a skip must not hide it), and at
        // step 30 a band of rows jumps a third of a box (the layout changes). A hash kept across
        // the steps, with and without threads, must correct exactly as a fresh hash that has
        // no memory and so looks into every box.
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 100,
            num_height_points: 100,
            thickness: 0.002,
            ..GridSpec::default()
        })
        .unwrap();
        let pool = three_threads();
        let (walker, neighbour) = (mesh.index(50, 50), mesh.index(51, 50));
        let box_w = SpatialHash::box_size(&mesh).0;
        let mut rng = cloth_mesh::SplitMix64::new(31);
        let mut positions = mesh.start_positions().to_vec();
        let (mut kept, mut kept_threaded) = (SpatialHash::default(), SpatialHash::default());
        let (mut skipped, mut walker_pushed) = (0, false);
        for step in 0..60 {
            for p in &mut positions {
                let h = 2e-5;
                *p += Vec3::new(rng.uniform(-h, h), rng.uniform(-h, h), rng.uniform(-h, h));
            }
            let towards = positions[neighbour] - positions[walker];
            positions[walker] += towards * 0.05;
            if step == 30 {
                for p in &mut positions[mesh.index(0, 10)..mesh.index(0, 15)] {
                    p.x += box_w / 3.0;
                }
            }
            let fresh =
                resolved_as_fresh(&mesh, &positions, [&mut kept, &mut kept_threaded], &pool);
            skipped += kept.memory.iter().filter(|m| m.skips > 0).count();
            walker_pushed |= fresh[walker] != positions[walker];
            positions = fresh;
        }
        assert!(
            skipped > 1000,
            "the test must exercise skipped boxes ({skipped})"
        );
        assert!(walker_pushed, "the walker must come within reach");
    }

    #[test]
    fn boxes_carried_along_by_the_cloth_stay_skipped_and_still_see_a_point_come_close() {
        // A flat cloth whose pairs are just out of reach (spacing 1 cm, reach 9.8 mm: an
        // allowance of about 0.1 mm) drifts 1 mm a step, ten allowances, as a falling cloth
        // does: its boxes' points all move, but not against each other, so the boxes that no
        // point entered must still be skipped. Meanwhile one point creeps towards its
        // neighbour, 0.05 mm a step against the drift, and must be found when it comes within
        // reach. A kept hash must correct exactly as a fresh one, with and without threads.
        let mesh = ClothMesh::new(&GridSpec {
            width: 0.6,
            height: 0.6,
            num_width_points: 61,
            num_height_points: 61,
            thickness: 0.0049,
            ..GridSpec::default()
        })
        .unwrap();
        let pool = three_threads();
        let (walker, neighbour) = (mesh.index(30, 30), mesh.index(31, 30));
        let mut positions = mesh.start_positions().to_vec();
        let (mut kept, mut kept_threaded) = (SpatialHash::default(), SpatialHash::default());
        let (mut skipped, mut looked_at_walker) = (0, false);
        let mut skips: Vec<u32> = Vec::new();
        for step in 0..40 {
            let drift = Vec3::new(1e-3, 0.0, 0.7e-3);
            for p in &mut positions {
                *p += drift;
            }
            let towards = (positions[neighbour] - positions[walker]).normalize();
            positions[walker] += towards * 5e-5;
            let fresh =
                resolved_as_fresh(&mesh, &positions, [&mut kept, &mut kept_threaded], &pool);
            if step > 0 {
                // Boxes of two points or more, against those skipped at this step.
                let boxes = kept.start.windows(2).filter(|w| w[1] - w[0] >= 2).count();
                let now = (kept.memory.iter().zip(&skips))
                    .filter(|(m, before)| m.skips > **before)
                    .count();
                assert!(
                    2 * now > boxes,
                    "step {step}: {now} of {boxes} boxes skipped"
                );
                skipped += now;
            }
            skips = kept.memory.iter().map(|m| m.skips).collect();
            looked_at_walker |= fresh[walker] != positions[walker];
            positions = fresh;
        }
        assert!(skipped > 0);
        assert!(looked_at_walker, "the walker must come within reach");
    }

    #[test]
    fn threads_make_the_same_corrections_bit_for_bit() {
        // 20,000 points crumpled into a 12 cm cube: many boxes with pairs in reach, split
        // between tasks at several places.
        let mesh = cloth(200, 100);
        let start = scattered(mesh.len(), 13, 0.0, 0.12);
        let mut one = start.clone();
        SpatialHash::default().resolve(&mesh, &mut one, 30);
        let pool = three_threads();
        let mut three = start.clone();
        SpatialHash::default().resolve_in(&mesh, &mut three, 30, Some(&pool));
        let moved = one.iter().zip(&start).filter(|(a, b)| a != b).count();
        assert!(moved > mesh.len() / 4, "the test must exercise corrections");
        assert_same_bits(&one, &three);
    }

    #[test]
    fn box_bits_are_the_floor_offset_and_wrapped_to_21_bits() {
        let expected = |v: f64| ((v.floor() as i64 + (1 << 20)) as u64) & 0x1F_FFFF;
        for v in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            0.3,
            0.5,
            1.5,
            2.5,
            -0.5,
            -1.5,
            1.0,
            7.999_999,
            -7.000_001,
            1_048_575.9,
            1_048_576.0,
            -1_048_577.2,
            3.0e9 + 0.5,
            -(2f64.powi(50)) - 0.5,
            2f64.powi(51) - 1.0,
        ] {
            assert_eq!(box_bits(v), expected(v), "{v}");
        }
        // Every value between two integers, on a fine grid.
        for k in -4000..4000 {
            let v = f64::from(k) / 64.0 + 1e-3;
            assert_eq!(box_bits(v), expected(v), "{v}");
        }
    }
}
