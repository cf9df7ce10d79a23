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
    /// Per cell: the threaded pass moved one of its points.
    touched: Vec<bool>,
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

/// One axis of a box key: `floor(v) + 2^20`, wrapped to 21 bits, for `v` the coordinate in
/// box sizes.
///
/// NOTE: written with plain float adds and integer bit operations, not `f64::floor` (a libm
/// call on baseline x86-64) or an `as i64` cast (no AVX2 instruction for it), so the key pass
/// runs on SIMD lanes. Adding `1.5 * 2^52` rounds `v` to the nearest integer and leaves that
/// integer, in two's complement, in the low mantissa bits; one is taken off where rounding went
/// up. That is `floor(v)` exactly for every |v| < 2^51. Beyond (a point a million boxes away, or
/// a non-finite one) the key is some box: such points are far beyond `2 * thickness` of any
/// other, and a diverged step is reported by the solver anyway.
#[inline(always)]
#[allow(clippy::inline_always)]
fn box_bits(v: f64) -> u64 {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let m = v + ROUND;
    let rounded_up = m - ROUND > v;
    m.to_bits()
        .wrapping_sub(u64::from(rounded_up))
        .wrapping_add(1 << 20)
        & 0x1F_FFFF
}

/// The box key of every point into `keys` (see [`SpatialHash::key`]).
#[inline(always)]
#[allow(clippy::inline_always)]
fn keys_portable(keys: &mut [u64], positions: &[Vec3], size: (f64, f64, f64)) {
    for (k, p) in keys.iter_mut().zip(positions) {
        *k = SpatialHash::key(p, size);
    }
}

/// [`keys_portable`] compiled for AVX2: four points' divisions and bit operations at once, the
/// same operations, so the same keys.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx2")]
unsafe fn keys_avx2(keys: &mut [u64], positions: &[Vec3], size: (f64, f64, f64)) {
    keys_portable(keys, positions, size);
}

/// The box key of every point into `keys`.
///
/// NOTE: on the caller's thread even when the solver has threads: the pass takes about 1.4 ns a
/// point, and handing it to a pool cost more than it saved on a 256 x 256 cloth.
fn compute_keys(keys: &mut [u64], positions: &[Vec3], size: (f64, f64, f64)) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        #[allow(unsafe_code)]
        unsafe {
            keys_avx2(keys, positions, size);
        }
        return;
    }
    keys_portable(keys, positions, size);
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

    /// The key of `p`'s box: its integer box coordinates, 21 bits per axis.
    #[inline(always)]
    #[allow(clippy::inline_always)]
    fn key(p: &Vec3, (w, h, t): (f64, f64, f64)) -> u64 {
        // Offset so negative boxes stay distinct; a box index beyond +-2^20 (a cloth a million
        // boxes away) wraps, which only merges far-apart boxes: harmless, the distance test
        // still rejects the pairs.
        (box_bits(p.x / w) << 42) | (box_bits(p.y / h) << 21) | box_bits(p.z / t)
    }

    /// Rebuilds the hash from `positions`.
    ///
    /// NOTE: on one thread whatever the solver's thread count. Two threaded versions were
    /// measured on a 256 x 256 cloth and dropped: threads numbering the cells of their runs of
    /// points needed a merge that cannot use the neighbour shortcut of `assign_cells` and cost
    /// what the threads saved; threads owning boxes by key each scanned every key, branching on
    /// an owner that changes at random from box to box, and two were slower than one.
    pub fn rebuild(&mut self, mesh: &ClothMesh, positions: &[Vec3]) {
        let size = Self::box_size(mesh);
        let n = positions.len();
        self.key_of.resize(n, 0);
        compute_keys(&mut self.key_of, positions, size);
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
            if self.assign_cells(mesh.nw()) {
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
        self.sorted.resize(n, Vec3::zeros());
        // NOTE: local slices, so the compiler knows the stores into one array do not change the
        // others' pointers; and runs of points in one cell take consecutive slots from a
        // register rather than from a counter in memory (see `assign_cells`).
        let (start, members, sorted) = (
            &mut self.start[..],
            &mut self.members[..],
            &mut self.sorted[..],
        );
        let cell_of = &self.cell_of[..];
        let mut i = 0;
        while i < n {
            let c = cell_of[i] as usize;
            let mut s = start[c];
            loop {
                members[s as usize] = i as u32;
                sorted[s as usize] = positions[i];
                s += 1;
                i += 1;
                if i == n || cell_of[i] as usize != c {
                    break;
                }
            }
            start[c] = s;
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

    /// Gives every point the cell of its box key (cells numbered in order of first appearance)
    /// and counts the points per cell into `start`; false, with the work abandoned, when the
    /// boxes fill more than half the table.
    fn assign_cells(&mut self, nw: usize) -> bool {
        let n = self.key_of.len();
        let table = self.slots.len();
        let shift = 64 - table.trailing_zeros();
        let mask = table - 1;
        self.cell_of.resize(n, 0);
        self.start.clear();
        let (keys, cell_of, start) = (&self.key_of[..], &mut self.cell_of[..], &mut self.start);
        let (slots, stamp) = (&mut self.slots[..], self.stamp);
        // NOTE: runs of points in one box are counted in a register and added at the run's end:
        // a memory counter bumped point after point waits for its own previous store.
        let (mut run_cell, mut run_len) = (0u32, 0u32);
        for i in 0..n {
            let key = keys[i];
            // NOTE: boxes are three spacings wide, so most points share the box of the point
            // before them or of the one a row up. Taking the cell from them skips the probe
            // (a cache miss on a big cloth) and hands out the same cell as the table would: a
            // key seen before is in the table with that cell.
            if i >= 1 && keys[i - 1] == key {
                cell_of[i] = run_cell;
                run_len += 1;
                continue;
            }
            let cell = if i >= nw && keys[i - nw] == key {
                cell_of[i - nw]
            } else {
                let cell = probe(slots, stamp, start, key, shift, mask);
                if 2 * start.len() > table {
                    return false;
                }
                cell
            };
            if run_len > 0 {
                start[run_cell as usize] += run_len;
            }
            cell_of[i] = cell;
            (run_cell, run_len) = (cell, 1);
        }
        if run_len > 0 {
            start[run_cell as usize] += run_len;
        }
        true
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
        self.resolve_in(mesh, positions, steps_per_frame, None);
    }

    /// [`SpatialHash::resolve`] with its boxes shared out among `pool`'s threads when there is
    /// one: the same corrections, bit for bit, on any number of threads.
    pub(crate) fn resolve_in(
        &mut self,
        mesh: &ClothMesh,
        positions: &mut [Vec3],
        steps_per_frame: u32,
        pool: Option<&rayon::ThreadPool>,
    ) {
        self.rebuild(mesh, positions);
        let repulsion = Repulsion::new(mesh, steps_per_frame);
        let pinned = mesh.pinned();
        // NOTE: a point's correction reads only the points of its own box, and only the
        // points of that box write them, so boxes are independent: sweeping box by box, each
        // box's points in index order, makes exactly the corrections of the course's sweep over
        // all points in index order. That lets a box with no pair within reach at the start of
        // the pass (most of them) be skipped after one look at each pair, half the work of
        // asking every point about every other; and it lets threads take whole boxes.
        // The boxes correct `sorted` (their own contiguous runs), on the pool's threads when
        // there is one, and mark themselves when they moved a point; then the points of the
        // marked boxes (few) take their positions back from their slots.
        let cells = self.start.len() - 1;
        self.touched.clear();
        self.touched.resize(cells, false);
        let boxes = Boxes {
            repulsion: &repulsion,
            pinned,
            start: &self.start,
            members: &self.members,
            threaded: pool.is_some(),
        };
        let (sorted, touched) = (&mut self.sorted[..], &mut self.touched[..]);
        match pool {
            Some(pool) => pool.install(|| boxes.resolve(sorted, touched, 0..cells, 0)),
            None => boxes.resolve(sorted, touched, 0..cells, 0),
        }
        for (c, _) in self.touched.iter().enumerate().filter(|(_, t)| **t) {
            let range = self.start[c] as usize..self.start[c + 1] as usize;
            for (&i, p) in self.members[range.clone()].iter().zip(&self.sorted[range]) {
                positions[i as usize] = *p;
            }
        }
    }
}

/// The cell of `key`, from the open-addressing table `slots` (a new cell, counted in `start`,
/// when the key is new).
#[inline]
fn probe(
    slots: &mut [Slot],
    stamp: u32,
    start: &mut Vec<u32>,
    key: u64,
    shift: u32,
    mask: usize,
) -> u32 {
    // Fibonacci hashing: the top bits of key * 2^64/phi spread neighbouring boxes.
    let mut slot = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize;
    loop {
        let s = &mut slots[slot];
        if s.stamp != stamp {
            *s = Slot {
                key,
                cell: start.len() as u32,
                stamp,
            };
            start.push(0);
            return s.cell;
        }
        if s.key == key {
            return s.cell;
        }
        slot = (slot + 1) & mask;
    }
}

/// Points a thread takes at once in the threaded passes: enough to amortise rayon's task cost.
const PARALLEL_CHUNK: usize = 4096;

/// Resolves one box in place: `box_points` are its points' positions in index order (a run of
/// `sorted`) and `members` their indices. True when some point moved.
#[inline]
fn resolve_box(
    repulsion: &Repulsion,
    pinned: &[bool],
    members: &[u32],
    box_points: &mut [Vec3],
) -> bool {
    if !repulsion.any_pair_within_reach(box_points) {
        return false;
    }
    let mut any = false;
    for (k, &i) in members.iter().enumerate() {
        let i = i as usize;
        if pinned[i] {
            continue;
        }
        if let Some(p) = repulsion.corrected(box_points, k) {
            // NOTE: later points of the box see this correction, as in the course.
            box_points[k] = p;
            any = true;
        }
    }
    any
}

/// What the self-collision pass shares between its tasks.
struct Boxes<'a> {
    repulsion: &'a Repulsion,
    pinned: &'a [bool],
    start: &'a [u32],
    members: &'a [u32],
    /// Whether to split the boxes between the current pool's threads.
    threaded: bool,
}

impl Boxes<'_> {
    /// Resolves `cells` (whose points are `sorted`, a window starting at slot `offset`, and
    /// whose flags are `touched`, a window starting at cell `cells.start`); when threaded,
    /// halving the run of boxes between threads down to about [`PARALLEL_CHUNK`] points.
    /// Recursion rather than a list of chunks, so nothing is allocated.
    fn resolve(
        &self,
        sorted: &mut [Vec3],
        touched: &mut [bool],
        cells: std::ops::Range<usize>,
        offset: usize,
    ) {
        let start = self.start;
        let (lo, hi) = (start[cells.start] as usize, start[cells.end] as usize);
        if !self.threaded || hi - lo <= PARALLEL_CHUNK || cells.len() < 2 {
            for (c, touched) in cells.clone().zip(touched) {
                let range = start[c] as usize..start[c + 1] as usize;
                let window = range.start - offset..range.end - offset;
                let members = &self.members[range];
                *touched = resolve_box(self.repulsion, self.pinned, members, &mut sorted[window]);
            }
            return;
        }
        // Split at the first box starting in the second half of the points (always inside the
        // run: the run has two boxes or more).
        let half = usize::midpoint(lo, hi);
        let mid = (cells.start + start[cells.clone()].partition_point(|&s| (s as usize) <= half))
            .clamp(cells.start + 1, cells.end - 1);
        let split = start[mid] as usize;
        let (left, right) = sorted.split_at_mut(split - offset);
        let (touched_left, touched_right) = touched.split_at_mut(mid - cells.start);
        rayon::join(
            || self.resolve(left, touched_left, cells.start..mid, offset),
            || self.resolve(right, touched_right, mid..cells.end, split),
        );
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

    #[test]
    fn threads_make_the_same_corrections_bit_for_bit() {
        // 20,000 points crumpled into a 12 cm cube: many boxes with pairs in reach, split
        // between tasks at several places.
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 200,
            num_height_points: 100,
            ..GridSpec::default()
        })
        .unwrap();
        let start = scattered(mesh.len(), 13, 0.0, 0.12);
        let mut one = start.clone();
        SpatialHash::default().resolve(&mesh, &mut one, 30);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
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

    #[test]
    fn the_avx2_key_pass_gives_the_portable_keys() {
        let positions = scattered(1001, 9, -3.0, 3.0);
        let size = (0.06, 0.05, 0.06);
        let mut portable = vec![0; positions.len()];
        keys_portable(&mut portable, &positions, size);
        let mut dispatched = vec![1; positions.len()];
        compute_keys(&mut dispatched, &positions, size);
        assert_eq!(portable, dispatched);
    }
}
