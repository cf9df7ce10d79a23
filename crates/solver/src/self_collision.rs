//! Self-collision through a spatial hash (step 3 of the course's step).

use cloth_mesh::{ClothMesh, Vec3};
use rayon::prelude::*;

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
/// 2. a count per cell, a prefix sum and one placement pass lay the points out box by box.
///
/// With threads, the points are cut into one contiguous run per thread. Each run computes its
/// keys, finds their cells (the table is only read) and counts into its own counters; the few
/// points whose box has no cell yet get one afterwards, in index order, on one thread. The
/// prefix sum gives each run its own places in each box, after those of the runs before it, so
/// each box lists its points in index order whatever the thread count: the order in which the
/// correction sums are taken, part of the faithful result.
///
/// Every pass is linear in the number of points or cells (at most about twice the boxes in use:
/// the table is cleared when the cloth has left more boxes behind) and, once the arrays have
/// grown, nothing is allocated.
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
    /// The points' positions in `members` order: a box's points are contiguous, so the pair
    /// loop reads consecutive memory instead of gathering from the whole cloth.
    sorted: Vec<Vec3>,
    /// Per cell: the resolution moved one of its points.
    touched: Vec<bool>,
}

/// What a run of points keeps between the passes of a rebuild.
#[derive(Debug, Default, Clone)]
struct Run {
    counts: Vec<u32>,
    /// Points (from the run's first) whose cell is still to be found.
    misses: Vec<u32>,
}

/// A run's windows of `key_of`, `last_key_of` and `cell_of`, and its [`Run`].
type RunWindows<'a> = (((&'a mut [u64], &'a [u64]), &'a mut [u32]), &'a mut Run);

/// The cell of a point whose cell is still to be found.
const PENDING: u32 = u32::MAX;

/// A key no box has: box keys use the low 63 bits.
const EMPTY: u64 = u64::MAX;

/// An open-addressing table from box keys to cells (linear probing, at most half full).
#[derive(Debug, Default, Clone)]
struct Table {
    slots: Vec<Slot>,
    /// Cells handed out, which is the number of keys in the table.
    cells: usize,
}

#[derive(Debug, Clone, Copy)]
struct Slot {
    key: u64,
    cell: u32,
}

impl Table {
    /// Empties the table and gives it `size` slots (a power of two).
    fn clear(&mut self, size: usize) {
        self.slots.clear();
        self.slots.resize(
            size,
            Slot {
                key: EMPTY,
                cell: 0,
            },
        );
        self.cells = 0;
    }

    /// Where `key` is, or the empty slot where it would go.
    #[inline]
    fn home(&self, key: u64) -> usize {
        let size = self.slots.len();
        // Fibonacci hashing: the top bits of key * 2^64/phi spread neighbouring boxes.
        let mut slot =
            (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - size.trailing_zeros())) as usize;
        loop {
            let seen = self.slots[slot].key;
            if seen == key || seen == EMPTY {
                return slot;
            }
            slot = (slot + 1) & (size - 1);
        }
    }

    /// The cell of `key`, if it has one.
    #[inline]
    fn find(&self, key: u64) -> Option<u32> {
        let slot = self.slots[self.home(key)];
        (slot.key == key).then_some(slot.cell)
    }

    /// The cell of `key`, a new one (the next number) when the key is new.
    fn cell(&mut self, key: u64) -> u32 {
        let slot = self.home(key);
        if self.slots[slot].key == key {
            return self.slots[slot].cell;
        }
        if 2 * (self.cells + 1) > self.slots.len() {
            // NOTE: cells keep their numbers, so the points' cells stay valid.
            let old = std::mem::take(&mut self.slots);
            self.slots = vec![
                Slot {
                    key: EMPTY,
                    cell: 0
                };
                2 * old.len()
            ];
            for s in old.iter().filter(|s| s.key != EMPTY) {
                let home = self.home(s.key);
                self.slots[home] = *s;
            }
            return self.cell(key);
        }
        let cell = self.cells as u32;
        self.slots[slot] = Slot { key, cell };
        self.cells += 1;
        cell
    }
}

/// A table for `boxes` boxes in use: a quarter full, so the cloth can enter as many boxes again
/// before it grows.
fn table_size(boxes: usize) -> usize {
    (4 * boxes).max(64).next_power_of_two()
}

/// What the runs of a rebuild's cell pass share.
struct CellPass<'a> {
    table: &'a Table,
    positions: &'a [Vec3],
    size: (f64, f64, f64),
    nw: usize,
    /// Whether the points' cells from the last rebuild are valid.
    coherent: bool,
}

impl CellPass<'_> {
    /// Keys, cells and per-cell counts of the run of points starting at point `first` (`keys`,
    /// `last_keys` and `cell_of` are its windows). Points whose box has no cell yet are
    /// [`PENDING`], listed in `run.misses` and not counted.
    fn run(
        &self,
        first: usize,
        keys: &mut [u64],
        last_keys: &[u64],
        cell_of: &mut [u32],
        run: &mut Run,
    ) {
        compute_keys(keys, &self.positions[first..first + keys.len()], self.size);
        run.counts.clear();
        run.counts.resize(self.table.cells, 0);
        run.misses.clear();
        let (counts, nw) = (&mut run.counts[..], self.nw);
        // NOTE: runs of points in one cell are counted in a register and added at the run's
        // end: a memory counter bumped point after point waits for its own previous store.
        let (mut run_cell, mut run_len) = (PENDING, 0u32);
        for k in 0..keys.len() {
            let key = keys[k];
            // NOTE: cheapest first. A point that stayed in its box keeps its cell; boxes are
            // three spacings wide, so most other points share the box of the point before them
            // or of the one a row up. Either way the lookup (a cache miss on a big cloth) is
            // skipped and the cell is the one the table would give.
            let cell = if self.coherent && last_keys[k] == key {
                cell_of[k]
            } else if k >= 1 && keys[k - 1] == key && cell_of[k - 1] != PENDING {
                cell_of[k - 1]
            } else if k >= nw && keys[k - nw] == key && cell_of[k - nw] != PENDING {
                cell_of[k - nw]
            } else if let Some(cell) = self.table.find(key) {
                cell
            } else {
                run.misses.push(k as u32);
                PENDING
            };
            cell_of[k] = cell;
            if cell != run_cell {
                if run_cell != PENDING {
                    counts[run_cell as usize] += run_len;
                }
                (run_cell, run_len) = (cell, 0);
            }
            run_len += 1;
        }
        if run_cell != PENDING {
            counts[run_cell as usize] += run_len;
        }
    }
}

/// `members` and `sorted` as the placement's runs share them.
///
/// NOTE: raw pointers because the runs write interleaved, disjoint places of the same arrays
/// (each run has its own places in every box), which no safe split of a slice can express.
struct Places {
    members: *mut u32,
    sorted: *mut Vec3,
    len: usize,
}

// SAFETY: `Places` is only used by `place_run`, whose runs write disjoint places.
#[allow(unsafe_code)]
unsafe impl Sync for Places {}

impl Places {
    /// Writes point `i` at `place`.
    ///
    /// # Safety
    /// No other thread may write `place` at the same time.
    #[allow(unsafe_code)]
    #[inline]
    unsafe fn put(&self, place: u32, i: usize, p: Vec3) {
        let place = place as usize;
        assert!(place < self.len, "a place past the end of the layout");
        // SAFETY: in bounds (just checked); the caller guarantees no concurrent write.
        unsafe {
            *self.members.add(place) = i as u32;
            *self.sorted.add(place) = p;
        }
    }
}

/// Places the run of points starting at `first` (whose cells are `cell_of`) at their places,
/// `next[c]` being the run's next place in cell `c`.
fn place_run(places: &Places, positions: &[Vec3], first: usize, cell_of: &[u32], next: &mut [u32]) {
    let n = cell_of.len();
    let mut k = 0;
    while k < n {
        let c = cell_of[k] as usize;
        let mut place = next[c];
        // NOTE: a run of points in one cell takes consecutive places from a register.
        loop {
            // SAFETY: the prefix sum gave this run of points places `next[c]..` in cell `c`,
            // exactly as many as it counted there and disjoint from every other run's and
            // cell's; only this run writes them, each once.
            #[allow(unsafe_code)]
            unsafe {
                places.put(place, first + k, positions[first + k]);
            }
            place += 1;
            k += 1;
            if k == n || cell_of[k] as usize != c {
                break;
            }
        }
        next[c] = place;
    }
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
    pub fn rebuild(&mut self, mesh: &ClothMesh, positions: &[Vec3]) {
        self.rebuild_in(mesh, positions, None);
    }

    /// [`SpatialHash::rebuild`], on `pool`'s threads when there is one and the cloth is big
    /// enough to share: the same boxes, each listing its points in index order.
    pub(crate) fn rebuild_in(
        &mut self,
        mesh: &ClothMesh,
        positions: &[Vec3],
        pool: Option<&rayon::ThreadPool>,
    ) {
        let n = positions.len();
        let threads = pool.map_or(1, rayon::ThreadPool::current_num_threads);
        // Runs of at least `PARALLEL_CHUNK` points: fewer points are not worth a thread.
        let chunk = n.div_ceil(threads.min(n / PARALLEL_CHUNK).max(1)).max(1);
        let runs = n.div_ceil(chunk);
        if self.key_of.len() != n {
            self.key_of.resize(n, 0);
            self.cell_of.resize(n, 0);
            self.coherent = false;
        }
        std::mem::swap(&mut self.key_of, &mut self.last_key_of);
        self.key_of.resize(n, 0);
        self.runs.resize_with(runs, Run::default);
        // NOTE: cells of boxes the cloth has left stay numbered (and are empty) until the
        // table is cleared: once they outnumber the boxes in use. The table is sized to the
        // boxes in use (about a ninth of the points on a smooth cloth), not to the points, so a
        // big cloth's table stays in cache.
        let live = if self.start.len() > 1 {
            self.live
        } else {
            n / 8
        };
        if !self.coherent || self.table.cells > 2 * live + 64 {
            self.table.clear(table_size(live));
            self.coherent = false;
        }

        // 1. Keys, and cells where the table has them, run by run.
        let pass = CellPass {
            table: &self.table,
            positions,
            size: Self::box_size(mesh),
            nw: mesh.nw(),
            coherent: self.coherent,
        };
        let each = |(r, (((keys, last), cells), run)): (usize, RunWindows<'_>)| {
            pass.run(r * chunk, keys, last, cells, run);
        };
        let (keys, last, cells) = (&mut self.key_of, &self.last_key_of, &mut self.cell_of);
        match pool {
            Some(pool) if runs > 1 => pool.install(|| {
                keys.par_chunks_mut(chunk)
                    .zip(last.par_chunks(chunk))
                    .zip(cells.par_chunks_mut(chunk))
                    .zip(self.runs.par_iter_mut())
                    .enumerate()
                    .for_each(each);
            }),
            _ => keys
                .chunks_mut(chunk)
                .zip(last.chunks(chunk))
                .zip(cells.chunks_mut(chunk))
                .zip(self.runs.iter_mut())
                .enumerate()
                .for_each(each),
        }

        // 2. The points the table did not know, in index order, so new boxes are numbered in
        //    order of first appearance whatever the thread count.
        for (r, run) in self.runs.iter().enumerate() {
            for &k in &run.misses {
                let i = r * chunk + k as usize;
                self.cell_of[i] = self.table.cell(self.key_of[i]);
            }
        }
        let cells = self.table.cells;
        for (r, run) in self.runs.iter_mut().enumerate() {
            run.counts.resize(cells, 0);
            for &k in &run.misses {
                run.counts[self.cell_of[r * chunk + k as usize] as usize] += 1;
            }
        }
        self.coherent = true;

        // 3. Exclusive prefix sum over the cells, run within cell: each run's count per cell
        //    becomes its first place there.
        self.start.resize(cells + 1, 0);
        let (mut sum, mut live) = (0u32, 0usize);
        for (c, start) in self.start[..cells].iter_mut().enumerate() {
            *start = sum;
            for run in &mut self.runs {
                let count = run.counts[c];
                run.counts[c] = sum;
                sum += count;
            }
            live += usize::from(sum > *start);
        }
        self.start[cells] = sum;
        self.live = live;

        // 4. Placement.
        self.place(positions, chunk, pool);
    }

    /// Lays the points out box by box (`members`, `sorted`), each run at its own places.
    fn place(&mut self, positions: &[Vec3], chunk: usize, pool: Option<&rayon::ThreadPool>) {
        let n = positions.len();
        self.members.resize(n, 0);
        self.sorted.resize(n, Vec3::zeros());
        let places = Places {
            members: self.members.as_mut_ptr(),
            sorted: self.sorted.as_mut_ptr(),
            len: n,
        };
        let each = |(r, (cells, run)): (usize, (&[u32], &mut Run))| {
            place_run(&places, positions, r * chunk, cells, &mut run.counts);
        };
        let (cells, runs) = (&self.cell_of, &mut self.runs);
        match pool {
            Some(pool) if n > chunk => pool.install(|| {
                cells
                    .par_chunks(chunk)
                    .zip(runs.par_iter_mut())
                    .enumerate()
                    .for_each(each);
            }),
            _ => cells
                .chunks(chunk)
                .zip(runs.iter_mut())
                .enumerate()
                .for_each(each),
        }
    }

    /// The points in point `i`'s box (including `i`), in index order, as of the last rebuild.
    pub fn box_of(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.members[self.cell_range(i)].iter().map(|&j| j as usize)
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
        self.rebuild_in(mesh, positions, pool);
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
