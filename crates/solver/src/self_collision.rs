//! Self-collision through a spatial hash (step 3 of the course's step).

use cloth_mesh::{ClothMesh, Vec3};

/// A spatial hash of the cloth's points in boxes of `3 * width / nw` by `3 * height / nh` by the
/// larger of the two, exactly the course's boxes, so the same pairs of points interact.
///
/// The course keys a `std::unordered_map` by a float hash of the box. We key by the box's integer
/// coordinates and group points with a counting sort:
///
/// 1. each point's box key goes through an open-addressing table (linear probing, at least
///    twice as many slots as boxes in use) that hands out dense cell numbers, unless the point
///    before it or the one a row up has the same key; slots are marked with a generation stamp,
///    so the table is never cleared between steps;
/// 2. a count per cell, a prefix sum and one placement pass lay the points out cell by cell.
///
/// Every pass is linear in the number of points and, once the arrays have grown, nothing is
/// allocated. The placement visits points in index order, so each box lists its points in index
/// order, the order in which the correction sums are taken (part of the faithful result).
#[derive(Debug, Default, Clone)]
pub struct SpatialHash {
    /// Cell number of each point.
    cell_of: Vec<u32>,
    /// Box key of each point (lets a point reuse the cell of a neighbour in the same box).
    key_of: Vec<u64>,
    /// Each point's position in `members`.
    slot_of: Vec<u32>,
    /// The points' positions in `members` order: a box's points are contiguous, so the pair
    /// loop reads consecutive memory instead of gathering from the whole cloth.
    sorted: Vec<Vec3>,
    /// `start[c]..start[c + 1]` is cell `c`'s range in `members` (length cells + 1).
    start: Vec<u32>,
    /// Point indices grouped by cell.
    members: Vec<u32>,
    /// The open-addressing table: box key, cell number, and the generation that wrote the slot
    /// (a slot whose stamp is not the current one is empty).
    slots: Vec<Slot>,
    /// The current generation; bumped by every rebuild.
    stamp: u32,
}

#[derive(Debug, Default, Clone, Copy)]
struct Slot {
    key: u64,
    cell: u32,
    stamp: u32,
}

/// Squared distance of two points, summed as `(x^2 + y^2) + z^2` like nalgebra's `norm`.
#[inline]
pub(crate) fn dist2(d: &Vec3) -> f64 {
    d.x * d.x + d.y * d.y + d.z * d.z
}

/// `floor(v)` as an integer, for box indices.
///
/// NOTE: `f64::floor` is a libm call on baseline x86-64 (no SSE4.1) and was 4 % of a step.
/// Truncate-and-correct gives the same integer for every |v| < 2^53; beyond that (a point
/// millions of boxes away) the box index may differ by one, which only changes which far-away
/// points share a box, never a correction, because such points are far beyond `2 * thickness`.
#[inline]
fn floor_to_i64(v: f64) -> i64 {
    let t = v as i64;
    // NOTE: wrapping: a diverged (huge or infinite) coordinate saturates `t`, and must not
    // overflow here; any box will do for it, the step reports the non-finite state.
    t.wrapping_sub(i64::from((t as f64) > v))
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

    #[inline]
    fn key(p: &Vec3, (w, h, t): (f64, f64, f64)) -> u64 {
        // 21 bits per axis, offset so negative boxes stay distinct; a box index beyond +-2^20
        // (a cloth a million boxes away) wraps, which only merges far-apart boxes: harmless,
        // the distance test still rejects the pairs.
        let q = |v: f64, s: f64| floor_to_i64(v / s).wrapping_add(1 << 20) as u64 & 0x1F_FFFF;
        (q(p.x, w) << 42) | (q(p.y, h) << 21) | q(p.z, t)
    }

    /// Rebuilds the hash from `positions`.
    pub fn rebuild(&mut self, mesh: &ClothMesh, positions: &[Vec3]) {
        let size = Self::box_size(mesh);
        let n = positions.len();
        // NOTE: a load factor of at most 1/2 keeps linear-probing chains short. The table is
        // sized to the number of boxes in use (about a ninth of the points on a smooth cloth),
        // not to the points: a big cloth's table then stays in cache. It doubles, and the
        // assignment restarts, when a rebuild finds more boxes; it halves when far too big.
        let most = (2 * n).next_power_of_two().max(16);
        let mut table = self.slots.len().clamp(16, most);
        while table > 16 && 16 * self.start.len() < table {
            table /= 2;
        }
        loop {
            self.clear_table(table);
            if self.assign_cells(mesh.nw(), positions, size) {
                break;
            }
            table *= 2;
        }

        // Exclusive prefix sum, then place points in index order; afterwards `start[c]` has
        // advanced to the end of cell c, so shifting by one restores the starts.
        let mut sum = 0;
        for s in &mut self.start {
            let count = *s;
            *s = sum;
            sum += count;
        }
        self.start.push(sum);
        self.members.resize(n, 0);
        self.slot_of.resize(n, 0);
        self.sorted.resize(n, Vec3::zeros());
        for (i, &c) in self.cell_of.iter().enumerate() {
            let s = &mut self.start[c as usize];
            self.members[*s as usize] = i as u32;
            self.slot_of[i] = *s;
            self.sorted[*s as usize] = positions[i];
            *s += 1;
        }
        self.start.rotate_right(1);
        self.start[0] = 0;
    }

    /// Makes `slots` an empty table of `table` slots (a new generation when the size is kept).
    fn clear_table(&mut self, table: usize) {
        if self.slots.len() != table {
            self.slots.clear();
            self.slots.resize(table, Slot::default());
            self.stamp = 0;
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            // NOTE: after 2^32 rebuilds the stamps wrap; clear so no stale slot looks current.
            self.slots.fill(Slot::default());
            self.stamp = 1;
        }
    }

    /// Gives every point the cell of its box (cells numbered in order of first appearance) and
    /// counts the points per cell into `start`; false, with the work abandoned, when the boxes
    /// fill more than half the table.
    fn assign_cells(&mut self, nw: usize, positions: &[Vec3], size: (f64, f64, f64)) -> bool {
        let n = positions.len();
        let table = self.slots.len();
        let shift = 64 - table.trailing_zeros();
        let mask = table - 1;
        self.cell_of.resize(n, 0);
        self.key_of.resize(n, 0);
        self.start.clear();
        for (i, p) in positions.iter().enumerate() {
            let key = Self::key(p, size);
            self.key_of[i] = key;
            // NOTE: boxes are three spacings wide, so most points share the box of the point
            // before them or of the one a row up. Taking the cell from them skips the probe
            // (a cache miss on a big cloth) and hands out the same cell as the table would: a
            // key seen before is in the table with that cell.
            let cell = if i >= 1 && self.key_of[i - 1] == key {
                self.cell_of[i - 1]
            } else if i >= nw && self.key_of[i - nw] == key {
                self.cell_of[i - nw]
            } else {
                let cell = self.probe(key, shift, mask);
                if 2 * self.start.len() > table {
                    return false;
                }
                cell
            };
            self.cell_of[i] = cell;
            self.start[cell as usize] += 1;
        }
        true
    }

    /// The cell of `key`, from the open-addressing table (a new cell when the key is new).
    #[inline]
    fn probe(&mut self, key: u64, shift: u32, mask: usize) -> u32 {
        // Fibonacci hashing: the top bits of key * 2^64/phi spread neighbouring boxes.
        let mut slot = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
        loop {
            let s = &mut self.slots[slot];
            if s.stamp != self.stamp {
                *s = Slot {
                    key,
                    cell: self.start.len() as u32,
                    stamp: self.stamp,
                };
                self.start.push(0);
                return s.cell;
            }
            if s.key == key {
                return s.cell;
            }
            slot = (slot + 1) & mask;
        }
    }

    /// The points in point `i`'s box (including `i`), in index order, as of the last rebuild.
    pub fn box_of(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.cell_members(i).iter().map(|&j| j as usize)
    }

    #[inline]
    fn cell_members(&self, i: usize) -> &[u32] {
        &self.members[self.cell_range(i)]
    }

    /// Point `i`'s box as a range of `members` (and of `sorted`).
    #[inline]
    fn cell_range(&self, i: usize) -> std::ops::Range<usize> {
        let c = self.cell_of[i] as usize;
        self.start[c] as usize..self.start[c + 1] as usize
    }

    /// Pushes every unpinned point away from the other points of its box that are closer than
    /// `2 * thickness`, by the average correction divided by `steps_per_frame`.
    ///
    /// Points are treated in index order and each one sees the already-corrected positions of
    /// those before it, as in the course; the hash itself is built before any correction.
    pub fn resolve(&mut self, mesh: &ClothMesh, positions: &mut [Vec3], steps_per_frame: u32) {
        self.rebuild(mesh, positions);
        let repulsion = Repulsion::new(mesh, steps_per_frame);
        let pinned = mesh.pinned();
        // NOTE: a point's correction reads only the points of its own box, and only the
        // points of that box write them, so boxes are independent: sweeping box by box, each
        // box's points in index order, makes exactly the corrections of the course's sweep over
        // all points in index order. That lets a box with no pair within reach at the start of
        // the pass (most of them) be skipped after one look at each pair, half the work of
        // asking every point about every other.
        for c in 0..self.start.len() - 1 {
            let range = self.start[c] as usize..self.start[c + 1] as usize;
            if !repulsion.any_pair_within_reach(&self.sorted[range.clone()]) {
                continue;
            }
            for slot in range.clone() {
                let i = self.members[slot] as usize;
                if pinned[i] {
                    continue;
                }
                let members = &self.sorted[range.clone()];
                if let Some(p) = repulsion.corrected(members, slot - range.start) {
                    // NOTE: `sorted` mirrors `positions`: later points see this correction.
                    positions[i] = p;
                    self.sorted[slot] = p;
                }
            }
        }
    }

    /// [`SpatialHash::resolve`] in an order threads can share ([`ConstraintOrder::Parallel`]):
    /// every point's correction is computed from the positions at the start of the pass
    /// (kept in the hash's cell-ordered copy), rather than from the already-corrected positions
    /// of the points before it. The pairs, the repulsion and its averaging are the course's.
    ///
    /// [`ConstraintOrder::Parallel`]: crate::ConstraintOrder::Parallel
    pub(crate) fn resolve_from_snapshot(
        &mut self,
        mesh: &ClothMesh,
        positions: &mut [Vec3],
        steps_per_frame: u32,
        pool: Option<&rayon::ThreadPool>,
    ) {
        use rayon::prelude::*;
        // Chunks of a few thousand points amortise rayon's task cost; the result does not
        // depend on the chunking or the thread count.
        const CHUNK: usize = 4096;
        self.rebuild(mesh, positions);
        let repulsion = Repulsion::new(mesh, steps_per_frame);
        let pinned = mesh.pinned();
        // NOTE: `sorted` holds the positions at the start of the pass and is never written
        // during it, so it is the snapshot the corrections are computed from.
        let hash = &*self;
        let correct = |c: usize, out: &mut [Vec3]| {
            for (k, p) in out.iter_mut().enumerate() {
                let i = c * CHUNK + k;
                if !pinned[i] {
                    let (range, slot) = (hash.cell_range(i), hash.slot_of[i] as usize);
                    let members = &hash.sorted[range.clone()];
                    if let Some(q) = repulsion.corrected(members, slot - range.start) {
                        *p = q;
                    }
                }
            }
        };
        match pool {
            Some(pool) => pool.install(|| {
                positions
                    .par_chunks_mut(CHUNK)
                    .enumerate()
                    .for_each(|(c, out)| correct(c, out));
            }),
            None => positions
                .chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(c, out)| correct(c, out)),
        }
    }
}

/// The course's repulsion between points of a box.
#[derive(Debug, Clone, Copy)]
struct Repulsion {
    /// `2 * thickness`, metres.
    reach: f64,
    /// Squared distances at or above this are certainly out of reach (see `corrected`).
    reach2_out: f64,
    /// Steps per frame: the averaged correction is divided by it.
    steps: f64,
}

impl Repulsion {
    fn new(mesh: &ClothMesh, steps_per_frame: u32) -> Self {
        let reach = 2.0 * mesh.thickness();
        // NOTE: a pair is skipped without its square root when `d^2 >= reach2_out`. That is
        // exact: `reach2_out` is at least the real reach^2 (the product's rounding, half an ulp,
        // is far inside the 4-ulp margin), so such a pair has a real distance >= reach, and the
        // correctly rounded sqrt cannot fall below the representable `reach` either.
        Self {
            reach,
            reach2_out: reach * reach * (1.0 + 4.0 * f64::EPSILON),
            steps: f64::from(steps_per_frame),
        }
    }

    /// Whether any two of `members` are closer than the reach, by the test `corrected` skips
    /// pairs with (`d^2` is the same bits whichever point comes first: `a - b` is exactly
    /// `-(b - a)`).
    #[inline]
    fn any_pair_within_reach(&self, members: &[Vec3]) -> bool {
        members.iter().enumerate().any(|(k, p)| {
            members[k + 1..]
                .iter()
                .any(|q| dist2(&(p - q)) < self.reach2_out)
        })
    }

    /// The corrected position of the point at `me` among the `members` of its box (their
    /// positions, in index order), or `None` when no other member is within reach.
    #[inline]
    fn corrected(&self, members: &[Vec3], me: usize) -> Option<Vec3> {
        if members.len() < 2 {
            return None;
        }
        let p = members[me];
        let mut correction = Vec3::zeros();
        let mut count = 0u32;
        for (k, q) in members.iter().enumerate() {
            if k == me {
                continue;
            }
            let d = p - q;
            let d2 = dist2(&d);
            if d2 >= self.reach2_out {
                continue;
            }
            let dist = d2.sqrt();
            // NOTE: coincident points (dist == 0) have no direction to separate along; the
            // course would produce NaN here, we skip the pair.
            if dist < self.reach && dist > 0.0 {
                correction += d * ((self.reach - dist) / dist);
                count += 1;
            }
        }
        (count > 0).then(|| p + correction / f64::from(count) / self.steps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::GridSpec;

    #[test]
    fn each_box_lists_exactly_the_points_with_its_integer_box_in_index_order() {
        // A crumpled cloth: points scattered over several boxes (deterministic pseudo-random).
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let mut rng = cloth_mesh::SplitMix64::new(7);
        let positions: Vec<Vec3> = (0..mesh.len())
            .map(|_| {
                Vec3::new(
                    rng.uniform(-0.2, 0.2),
                    rng.uniform(-0.2, 0.2),
                    rng.uniform(-0.2, 0.2),
                )
            })
            .collect();
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

    #[test]
    fn box_by_box_resolution_makes_the_courses_point_by_point_corrections_bit_for_bit() {
        // A cloth crumpled into a 6 cm cube: many boxes with several pairs within reach, so
        // corrections chain through points corrected earlier in the same box.
        let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
        let mut rng = cloth_mesh::SplitMix64::new(5);
        let start: Vec<Vec3> = (0..mesh.len())
            .map(|_| {
                Vec3::new(
                    rng.uniform(0.0, 0.06),
                    rng.uniform(0.0, 0.06),
                    rng.uniform(0.0, 0.06),
                )
            })
            .collect();
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
        for (i, (a, b)) in fast.iter().zip(&course).enumerate() {
            for c in 0..3 {
                assert_eq!(a[c].to_bits(), b[c].to_bits(), "point {i} axis {c}");
            }
        }
    }

    #[test]
    fn integer_floor_matches_floor() {
        for v in [
            -2.5, -2.0, -1e-300, -0.0, 0.0, 0.3, 1.0, 7.999_999, -7.000_001,
        ] {
            assert_eq!(floor_to_i64(v), v.floor() as i64, "{v}");
        }
    }
}
