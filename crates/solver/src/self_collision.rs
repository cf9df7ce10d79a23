//! Self-collision through a spatial hash (step 3 of the course's step).

use cloth_mesh::{ClothMesh, Vec3};
use rayon::prelude::*;

use crate::disjoint::Disjoint;

#[cfg(target_arch = "x86_64")]
mod lanes;

/// Off x86-64 there are no lanes: an uninhabited stand-in with their interface, so the pair
/// search (`Pairs`) reads the same on every target and never holds one.
#[cfg(not(target_arch = "x86_64"))]
mod lanes {
    use cloth_mesh::Vec3;

    /// No bound: no lanes are ever made here.
    pub(super) const MAX_POINTS: usize = usize::MAX;

    pub(super) enum BoxLanes {}

    impl BoxLanes {
        pub(super) fn new() -> Option<Self> {
            None
        }
        pub(super) fn load(&mut self, _: &[Vec3]) {
            match *self {}
        }
        pub(super) fn set(&mut self, _: usize, _: &Vec3) {
            match *self {}
        }
        pub(super) fn closest_pair_out_of_reach(&self, _: f64) -> Option<f64> {
            match *self {}
        }
        pub(super) fn within_reach(&self, _: usize, _: f64) -> u64 {
            match *self {}
        }
    }
}

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
/// before it takes new ones, so a moving cloth does not pay for them. When no point changed
/// box, the layout of the last rebuild is kept as it is.
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

/// What the resolution remembers of a box between passes.
#[derive(Debug, Clone, Copy)]
struct Memory {
    /// How far (squared) each of its points may move from its anchor with the box still
    /// certainly clear of pairs within reach (see [`Repulsion::allowance`]); negative when the
    /// box has no anchors.
    allowed: f64,
    /// Passes skipped on the current anchors.
    skips: u32,
    /// Looks at the box, found clear, before it may take anchors again.
    wait: u32,
    /// Anchors lost in a row without having paid for themselves; each doubles the wait.
    strikes: u32,
}

impl Memory {
    /// A box the resolution knows nothing of.
    const NEW: Self = Self {
        allowed: -1.0,
        skips: 0,
        wait: 0,
        strikes: 0,
    };
}

/// What a run of points keeps between the passes of a rebuild.
#[derive(Debug, Default, Clone)]
struct Run {
    counts: Vec<u32>,
    /// Points (from the run's first) whose cell is still to be found.
    misses: Vec<u32>,
    /// Points whose box changed since the last rebuild (only recorded when the last rebuild's
    /// cells are valid).
    changed: Vec<Moved>,
}

/// A point of a run that changed box since the last rebuild.
#[derive(Debug, Clone, Copy)]
struct Moved {
    /// The point, from the run's first.
    point: u32,
    /// Its cell at the last rebuild.
    from: u32,
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

/// Relayouts take at most one point in this many: a bound on the share of the sort of the
/// moves (`n log n` in the moves), which stays well under the cost of a full layout below it.
/// A cloth whose points change box wholesale (one jumping to a new place) takes the full
/// layout.
const RELAYOUT_SHARE: usize = 16;

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
    /// Keys and cells of the run of points starting at point `first` (`keys`, `last_keys` and
    /// `cell_of` are its windows). Points whose box has no cell yet are [`PENDING`] and listed
    /// in `run.misses`; when the last cells are valid, points whose box changed are listed in
    /// `run.changed`.
    fn run(
        &self,
        first: usize,
        keys: &mut [u64],
        last_keys: &[u64],
        cell_of: &mut [u32],
        run: &mut Run,
    ) {
        compute_keys(keys, &self.positions[first..first + keys.len()], self.size);
        run.misses.clear();
        run.changed.clear();
        let nw = self.nw;
        for k in 0..keys.len() {
            let key = keys[k];
            // NOTE: cheapest first. A point that stayed in its box keeps its cell; boxes are
            // three spacings wide, so most other points share the box of the point before them
            // or of the one a row up. Either way the lookup (a cache miss on a big cloth) is
            // skipped and the cell is the one the table would give.
            if self.coherent && last_keys[k] == key {
                continue;
            }
            if self.coherent {
                run.changed.push(Moved {
                    point: k as u32,
                    from: cell_of[k],
                });
            }
            cell_of[k] = if k >= 1 && keys[k - 1] == key && cell_of[k - 1] != PENDING {
                cell_of[k - 1]
            } else if k >= nw && keys[k - nw] == key && cell_of[k - nw] != PENDING {
                cell_of[k - nw]
            } else if let Some(cell) = self.table.find(key) {
                cell
            } else {
                run.misses.push(k as u32);
                PENDING
            };
        }
    }
}

/// Counts the run of points whose cells are `cell_of` into `counts` (one per cell).
fn count_run(cell_of: &[u32], counts: &mut Vec<u32>, cells: usize) {
    counts.clear();
    counts.resize(cells, 0);
    // NOTE: runs of points in one cell are counted in a register and added at the run's end:
    // a memory counter bumped point after point waits for its own previous store.
    let (mut run_cell, mut run_len) = (PENDING, 0u32);
    for &cell in cell_of {
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

/// Places the run of points starting at `first` (whose cells are `cell_of`) in `members`,
/// `next[c]` being the run's next place in cell `c`.
fn place_run(members: &Disjoint<'_, u32>, first: usize, cell_of: &[u32], next: &mut [u32]) {
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
                members.set(place as usize, (first + k) as u32);
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
/// NOTE: on the caller's thread even when the solver has threads: the pass is a few
/// arithmetic operations a point, less than what handing it to a pool costs.
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
        let was_coherent = std::mem::replace(&mut self.coherent, true);
        if !was_coherent {
            self.memory.clear();
        }
        self.memory.resize(cells, Memory::NEW);
        let mut moved = 0;
        // NOTE: a box a point enters loses its allowance (a new pair may be close); a box a
        // point leaves keeps it: its remaining pairs were all counted when it was computed.
        for (r, run) in self.runs.iter().enumerate() {
            for m in &run.changed {
                let i = r * chunk + m.point as usize;
                self.memory[self.cell_of[i] as usize].allowed = -1.0;
            }
            moved += run.changed.len();
        }
        if was_coherent && moved == 0 {
            // NOTE: every point kept its box, so every box keeps its points, in the same
            // order: the layout (`start`, `members`) is the last one. A settled cloth gets here
            // most steps.
            return;
        }
        if was_coherent && moved <= n / RELAYOUT_SHARE {
            // NOTE: a moving cloth gets here most steps: a step takes a point a small fraction
            // of a box, and about one point in two hundred changes box on the falling 256 x 256
            // cloth.
            self.relayout(chunk);
            return;
        }

        // 3. Counts per cell, run by run.
        let count = |(cell_of, run): (&[u32], &mut Run)| count_run(cell_of, &mut run.counts, cells);
        let (cell_of, runs) = (&self.cell_of, &mut self.runs);
        match pool {
            Some(pool) if runs.len() > 1 => pool.install(|| {
                cell_of
                    .par_chunks(chunk)
                    .zip(runs.par_iter_mut())
                    .for_each(count);
            }),
            _ => cell_of.chunks(chunk).zip(runs.iter_mut()).for_each(count),
        }

        // 4. Exclusive prefix sum over the cells, run within cell: each run's count per cell
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

        // 5. Placement.
        self.place(chunk, pool);
    }

    /// Moves the points that changed box (`runs[..].changed`) in the last layout: the boxes
    /// between them keep their points and slide as a block, one sequential copy; the boxes
    /// that points left or entered merge their kept points with the newcomers in index order.
    /// The result is the layout [`SpatialHash::place`] would make, at the cost of a copy of
    /// `members` rather than a scattered write of every point.
    fn relayout(&mut self, chunk: usize) {
        let n = self.members.len();
        // NOTE: a move as one integer, (cell, point, entering) from high bits to low, so a
        // plain integer sort orders them by cell, then by point.
        self.moves.clear();
        for (r, run) in self.runs.iter().enumerate() {
            for m in &run.changed {
                let i = (r * chunk) as u64 + u64::from(m.point);
                let to = u64::from(self.cell_of[i as usize]);
                self.moves.push((u64::from(m.from) << 33) | (i << 1));
                self.moves.push((to << 33) | (i << 1) | 1);
            }
        }
        self.moves.sort_unstable();
        let cells = self.table.cells;
        let old_cells = self.start.len() - 1;
        // New boxes start empty, after the last one.
        self.start.resize(cells + 1, self.start[old_cells]);
        let (start, members, spare) = (&mut self.start, &self.members, &mut self.spare);
        let mut live = self.live;
        // `out`: the next place in the new layout; `next`: the first box not yet laid out.
        let (mut out, mut next) = (0usize, 0usize);
        // Slides boxes `from..to` (old places) to start at `out`.
        let slide = |start: &mut [u32], spare: &mut [u32], out: &mut usize, from, to| {
            let (lo, hi) = (start[from] as usize, start[to] as usize);
            spare[*out..*out + hi - lo].copy_from_slice(&members[lo..hi]);
            let shift = (*out).wrapping_sub(lo) as u32;
            for s in &mut start[from..to] {
                *s = s.wrapping_add(shift);
            }
            *out += hi - lo;
        };
        let mut moves = &self.moves[..];
        while let Some(&first) = moves.first() {
            let c = (first >> 33) as usize;
            let len = moves.partition_point(|&m| (m >> 33) as usize == c);
            let (group, rest) = moves.split_at(len);
            moves = rest;
            slide(start, spare, &mut out, next, c);
            let (lo, hi) = (start[c] as usize, start[c + 1] as usize);
            start[c] = out as u32;
            let point = |m: &u64| ((m >> 1) & 0xFFFF_FFFF) as u32;
            let mut leaving = group.iter().filter(|&&m| m & 1 == 0).map(point).peekable();
            let mut entering = group.iter().filter(|&&m| m & 1 == 1).map(point).peekable();
            for &p in &members[lo..hi] {
                if leaving.next_if_eq(&p).is_some() {
                    continue;
                }
                while let Some(q) = entering.next_if(|&q| q < p) {
                    spare[out] = q;
                    out += 1;
                }
                spare[out] = p;
                out += 1;
            }
            for q in entering {
                spare[out] = q;
                out += 1;
            }
            debug_assert!(leaving.next().is_none(), "a point left a box it was not in");
            live = live + usize::from(out > start[c] as usize) - usize::from(hi > lo);
            next = c + 1;
        }
        // The boxes after the last move, and the end of the last one.
        slide(start, spare, &mut out, next, cells);
        start[cells] = out as u32;
        debug_assert_eq!(out, n, "the new layout places every point once");
        std::mem::swap(&mut self.members, &mut self.spare);
        self.live = live;
    }

    /// Lays the points out box by box (`members`), each run at its own places.
    fn place(&mut self, chunk: usize, pool: Option<&rayon::ThreadPool>) {
        let n = self.cell_of.len();
        self.members.resize(n, 0);
        // NOTE: a relayout's room, made here, before any: so its first does not allocate.
        self.spare.resize(n, 0);
        self.moves.reserve(2 * (n / RELAYOUT_SHARE));
        let members = Disjoint::new(&mut self.members);
        let each = |(r, (cells, run)): (usize, (&[u32], &mut Run))| {
            place_run(&members, r * chunk, cells, &mut run.counts);
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
        // NOTE: a point's correction reads only the points of its own box, and only the
        // points of that box write them, so boxes are independent: sweeping box by box, each
        // box's points in index order, makes exactly the corrections of the course's sweep over
        // all points in index order. That lets a box with no pair within reach at the start of
        // the pass (most of them) be skipped after one look at each pair, half the work of
        // asking every point about every other; a box whose points have barely moved since it
        // was last found clear is skipped without even that (see `Repulsion::allowance`); and
        // threads can take whole boxes.
        // The boxes correct `sorted` (their own contiguous runs), on the pool's threads when
        // there is one, and mark themselves when they moved a point; then the points of the
        // marked boxes (few) take their positions back from their slots.
        let cells = self.start.len() - 1;
        self.touched.clear();
        self.touched.resize(cells, false);
        self.anchor.resize(positions.len(), Vec3::zeros());
        self.sorted.resize(positions.len(), Vec3::zeros());
        let boxes = Boxes {
            repulsion: &repulsion,
            pinned: mesh.pinned(),
            start: &self.start,
            members: &self.members,
            positions,
            anchors: Disjoint::new(&mut self.anchor),
            threaded: pool.is_some(),
        };
        let cuts = Cuts {
            sorted: &mut self.sorted,
            touched: &mut self.touched,
            memory: &mut self.memory[..cells],
        };
        match pool {
            Some(pool) => pool.install(|| boxes.resolve(cuts, 0..cells, 0)),
            None => boxes.resolve(cuts, 0..cells, 0),
        }
        for (c, _) in self.touched.iter().enumerate().filter(|(_, t)| **t) {
            let range = self.start[c] as usize..self.start[c + 1] as usize;
            for (&i, p) in self.members[range.clone()].iter().zip(&self.sorted[range]) {
                positions[i as usize] = *p;
            }
        }
    }
}

/// Looks a box that outran its allowance waits before it takes new anchors, at first.
const ANCHOR_WAIT: u32 = 4;

/// How far a box's first point may move from its anchor, squared, in squared allowances, with
/// the box still skipped on the other points' moves relative to its move: a thousand
/// allowances (see [`Repulsion::allowance`] for why there is a bound).
const FOLLOW2: f64 = 1e6;

/// The most times the wait doubles (to 256 looks).
const MAX_STRIKES: u32 = 6;

/// Points a thread takes at once in the threaded passes: enough to amortise rayon's task cost.
pub(crate) const PARALLEL_CHUNK: usize = 4096;

/// What the self-collision pass shares between its tasks.
struct Boxes<'a> {
    repulsion: &'a Repulsion,
    pinned: &'a [bool],
    start: &'a [u32],
    members: &'a [u32],
    /// The positions at the start of the pass (corrections go to `sorted`).
    positions: &'a [Vec3],
    /// The points' anchors; a box's task reads and writes those of its own points.
    anchors: Disjoint<'a, Vec3>,
    /// Whether to split the boxes between the current pool's threads.
    threaded: bool,
}

/// The per-slot and per-cell arrays a task of the pass writes: windows starting at a slot and
/// at a cell.
struct Cuts<'a> {
    sorted: &'a mut [Vec3],
    touched: &'a mut [bool],
    memory: &'a mut [Memory],
}

impl Boxes<'_> {
    /// Resolves `cells` (whose points' slots start at `offset`, and whose per-cell windows in
    /// `cuts` start at `cells.start`); when threaded, halving the run of boxes between threads
    /// down to about [`PARALLEL_CHUNK`] points. Recursion rather than a list of chunks, so
    /// nothing is allocated.
    fn resolve(&self, cuts: Cuts<'_>, cells: std::ops::Range<usize>, offset: usize) {
        let Cuts {
            sorted,
            touched,
            memory,
        } = cuts;
        let start = self.start;
        let (lo, hi) = (start[cells.start] as usize, start[cells.end] as usize);
        if !self.threaded || hi - lo <= PARALLEL_CHUNK || cells.len() < 2 {
            let mut scratch = lanes::BoxLanes::new();
            for (c, (touched, memory)) in cells.zip(touched.iter_mut().zip(memory)) {
                let range = start[c] as usize..start[c + 1] as usize;
                let window = range.start - offset..range.end - offset;
                let (members, slots) = (&self.members[range], &mut sorted[window]);
                *touched = self.resolve_box(members, slots, memory, &mut scratch);
            }
            return;
        }
        // Split at the first box starting in the second half of the points (always inside the
        // run: the run has two boxes or more).
        let half = usize::midpoint(lo, hi);
        let mid = (cells.start + start[cells.clone()].partition_point(|&s| (s as usize) <= half))
            .clamp(cells.start + 1, cells.end - 1);
        let split = start[mid] as usize;
        let (sorted_left, sorted_right) = sorted.split_at_mut(split - offset);
        let (touched_left, touched_right) = touched.split_at_mut(mid - cells.start);
        let (memory_left, memory_right) = memory.split_at_mut(mid - cells.start);
        let left = Cuts {
            sorted: sorted_left,
            touched: touched_left,
            memory: memory_left,
        };
        let right = Cuts {
            sorted: sorted_right,
            touched: touched_right,
            memory: memory_right,
        };
        rayon::join(
            || self.resolve(left, cells.start..mid, offset),
            || self.resolve(right, mid..cells.end, split),
        );
    }

    /// Resolves one box: `members` are its points' indices in index order, `slots` its run of
    /// `sorted`, `memory` what is known of it (updated), `scratch` the task's lanes. True when
    /// it moved a point.
    #[inline]
    fn resolve_box(
        &self,
        members: &[u32],
        slots: &mut [Vec3],
        memory: &mut Memory,
        scratch: &mut LaneScratch,
    ) -> bool {
        // A lone point has no pair.
        if members.len() < 2 {
            return false;
        }
        // SAFETY (both blocks): only this box's points' anchors are touched, and only this
        // task resolves this box.
        // NOTE: a box whose points all moved, since they were anchored, within its allowance of
        // the move of its first point is still clear (see `Repulsion::allowance`): nothing to
        // do. A NaN distance fails the test, so a diverged point is always looked at.
        if memory.allowed >= 0.0 {
            #[allow(unsafe_code)]
            let moved = |i: u32| {
                let i = i as usize;
                self.positions[i] - unsafe { self.anchors.get(i) }
            };
            let (allowed, shift) = (memory.allowed, moved(members[0]));
            if dist2(&shift) <= FOLLOW2 * allowed
                && members[1..]
                    .iter()
                    .all(|&i| dist2(&(moved(i) - shift)) <= allowed)
            {
                memory.skips = memory.skips.saturating_add(1);
                return false;
            }
            // NOTE: the box outran its allowance. Anchors that saved fewer than two looks cost
            // more than they saved (writing them, testing them), so such a box waits before it
            // takes new ones, twice as long each time: a moving cloth soon stops paying for
            // anchors, a settling one gets them back.
            memory.strikes = if memory.skips < 2 {
                (memory.strikes + 1).min(MAX_STRIKES)
            } else {
                0
            };
            memory.wait = ANCHOR_WAIT << memory.strikes;
            memory.allowed = -1.0;
        }
        for (slot, &i) in slots.iter_mut().zip(members) {
            *slot = self.positions[i as usize];
        }
        let mut pairs = Pairs::new(slots, scratch);
        if let Some(closest2) = pairs.closest_pair_out_of_reach(self.repulsion, slots) {
            if memory.wait > 0 {
                memory.wait -= 1;
                return false;
            }
            memory.allowed = self.repulsion.allowance(closest2);
            if memory.allowed >= 0.0 {
                memory.skips = 0;
                for (slot, &i) in slots.iter().zip(members) {
                    #[allow(unsafe_code)]
                    unsafe {
                        self.anchors.set(i as usize, *slot);
                    }
                }
            }
            return false;
        }
        memory.allowed = -1.0;
        let mut any = false;
        for (k, &i) in members.iter().enumerate() {
            if self.pinned[i as usize] {
                continue;
            }
            if let Some(p) = pairs.corrected(self.repulsion, slots, k) {
                // NOTE: later points of the box see this correction, as in the course.
                slots[k] = p;
                pairs.moved(k, &p);
                any = true;
            }
        }
        any
    }
}

/// How a box's pairs are searched: on AVX2 lanes (`lanes`) when the CPU has AVX2 and the box
/// is neither too small to pay for loading them nor too big for them, else by the scalar
/// loops. Both find the same pairs (see `lanes`).
enum Pairs<'a> {
    Scalar,
    Lanes(&'a mut lanes::BoxLanes),
}

/// The fewest points of a box searched on lanes: below, loading the lanes costs more than the
/// scalar loops save, above all in a box with a pair within reach, which the scalar search
/// leaves at that pair.
const LANES_FROM: usize = 16;

/// The lanes a task loads boxes into, when the CPU has them.
type LaneScratch = Option<lanes::BoxLanes>;

impl<'a> Pairs<'a> {
    /// The search for the box at `slots`, loaded into `scratch` when lanes take it.
    #[inline]
    fn new(slots: &[Vec3], scratch: &'a mut LaneScratch) -> Self {
        if (LANES_FROM..=lanes::MAX_POINTS).contains(&slots.len())
            && let Some(lanes) = scratch
        {
            lanes.load(slots);
            return Self::Lanes(lanes);
        }
        Self::Scalar
    }

    /// [`Repulsion::closest_pair_out_of_reach`] of the box at `slots`.
    #[inline]
    fn closest_pair_out_of_reach(&self, repulsion: &Repulsion, slots: &[Vec3]) -> Option<f64> {
        match self {
            Self::Scalar => repulsion.closest_pair_out_of_reach(slots),
            Self::Lanes(lanes) => lanes.closest_pair_out_of_reach(repulsion.reach2_out),
        }
    }

    /// [`Repulsion::corrected`] position of point `me` of the box at `slots`.
    #[inline]
    fn corrected(&self, repulsion: &Repulsion, slots: &[Vec3], me: usize) -> Option<Vec3> {
        match self {
            Self::Scalar => repulsion.corrected(slots, me, (0..slots.len()).filter(|&k| k != me)),
            Self::Lanes(lanes) => {
                let mut within = lanes.within_reach(me, repulsion.reach2_out);
                let found = std::iter::from_fn(|| {
                    (within != 0).then(|| {
                        let k = within.trailing_zeros() as usize;
                        within &= within - 1;
                        k
                    })
                });
                repulsion.corrected(slots, me, found)
            }
        }
    }

    /// Point `k` of the box moved to `p`.
    #[inline]
    fn moved(&mut self, k: usize, p: &Vec3) {
        match self {
            Self::Scalar => {}
            Self::Lanes(lanes) => lanes.set(k, p),
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

    /// The smallest squared distance between two of `members`, or `None` when some pair is
    /// within reach by the test `corrected` skips pairs with (`d^2` is the same bits whichever
    /// point comes first: `a - b` is exactly `-(b - a)`). Infinite for fewer than two points.
    #[inline]
    fn closest_pair_out_of_reach(&self, members: &[Vec3]) -> Option<f64> {
        // NOTE: the minimum of the bit patterns: squared distances are never negative, and
        // non-negative floats order as their bits do (a NaN above infinity, so it is only the
        // minimum when every distance is NaN). An integer minimum is one cheap instruction;
        // `f64::min`'s NaN handling is several, and this loop runs over every pair.
        let mut closest = f64::INFINITY.to_bits();
        for (k, p) in members.iter().enumerate() {
            for q in &members[k + 1..] {
                let d2 = dist2(&(p - q));
                if d2 < self.reach2_out {
                    return None;
                }
                closest = closest.min(d2.to_bits());
            }
        }
        Some(f64::from_bits(closest))
    }

    /// How far (squared) each point of a box found clear may move from where it is, with the
    /// box still certainly clear, given the smallest squared distance `closest2` between two of
    /// its points; negative when no move is safe.
    ///
    /// Two points that each moved less than `a` are closer than before by less than `2 a`
    /// (triangle inequality), so with `a = (closest - reach) / 2` every pair stays at least
    /// `reach` apart, and [`Repulsion::closest_pair_out_of_reach`] would find the box clear
    /// again. A pair's distance changes only by the difference of its two points' moves, which
    /// is unchanged when the same shift is taken off both: so the moves are measured from the
    /// move of the box's first point. A box carried along by the cloth stays skipped: a
    /// falling cloth moves its points several allowances a step, but a box's points barely
    /// against each other. Why that holds in floating point too: every quantity here and in
    /// the displacement test (a squared distance, its root, a product) is within a few ulps, under 1e-15
    /// relative, of its real value; each term below is shrunk (or, for the reach, grown) by
    /// 1e-12 relative, a thousand times that, and the 4-ulp margin of `reach2_out` lies well
    /// inside it. Taking the shift off a move rounds in proportion to the moves, not to what is
    /// left: the shift is therefore bounded by a thousand allowances ([`FOLLOW2`]), which keeps
    /// that rounding under 2.3e-13 of the allowance, inside the slack too. So a box skipped by
    /// the test is one whose pair test would have found no pair within reach: skipping it
    /// changes nothing, bit for bit.
    #[inline]
    fn allowance(&self, closest2: f64) -> f64 {
        const SLACK: f64 = 1e-12;
        let spare = closest2.sqrt() * (1.0 - SLACK) - self.reach * (1.0 + SLACK);
        let each = spare / 2.0 * (1.0 - SLACK);
        // NOTE: finite only: a box with points at infinity (a diverged step) gets no anchors.
        if each > 0.0 && each.is_finite() {
            each * each * (1.0 - SLACK)
        } else {
            -1.0
        }
    }

    /// The corrected position of the point at `me` among the `members` of its box (their
    /// positions, in index order), or `None` when no other member is within reach.
    /// `candidates`: the other members, in increasing order, or those of them within
    /// `reach2_out` (the others are skipped below anyway).
    #[inline]
    fn corrected(
        &self,
        members: &[Vec3],
        me: usize,
        candidates: impl Iterator<Item = usize>,
    ) -> Option<Vec3> {
        let p = members[me];
        let mut correction = Vec3::zeros();
        let mut count = 0u32;
        for k in candidates {
            let d = p - members[k];
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

    #[test]
    fn lanes_find_the_pairs_and_make_the_corrections_of_the_scalar_loops() {
        let mut scratch = lanes::BoxLanes::new();
        if scratch.is_none() {
            return; // No AVX2 (or not x86-64): no lanes to compare.
        }
        let reach = 0.019;
        let repulsion = Repulsion {
            reach,
            reach2_out: reach * reach * (1.0 + 4.0 * f64::EPSILON),
            steps: 30.0,
        };
        let (mut clear, mut crowded, mut corrected) = (0, 0, 0);
        for n in LANES_FROM..=lanes::MAX_POINTS {
            for seed in 0..4 {
                // Boxes from sparse (every pair out of reach, so a closest distance) to dense
                // (corrections chaining through points corrected before them); a NaN point, an
                // infinite one and two coincident points (no direction: skipped) among them.
                let side = reach * [40.0, 4.0, 2.0, 1.0][seed as usize];
                let mut slots = scattered(n, seed * 100 + n as u64, 0.0, side);
                match seed {
                    1 => slots[n / 2].y = f64::NAN,
                    2 => slots[n - 1] = Vec3::new(f64::INFINITY, 0.0, 0.0),
                    3 => slots[3] = slots[1],
                    _ => {}
                }
                let mut pairs = Pairs::new(&slots, &mut scratch);
                assert!(matches!(pairs, Pairs::Lanes(_)));
                let closest = pairs.closest_pair_out_of_reach(&repulsion, &slots);
                assert_eq!(
                    closest.map(f64::to_bits),
                    repulsion
                        .closest_pair_out_of_reach(&slots)
                        .map(f64::to_bits),
                    "{n} points, seed {seed}"
                );
                if closest.is_some() {
                    clear += 1;
                    continue;
                }
                crowded += 1;
                let (mut on_lanes, mut scalar) = (slots.clone(), slots.clone());
                for me in 0..n {
                    if let Some(p) = pairs.corrected(&repulsion, &on_lanes, me) {
                        on_lanes[me] = p;
                        pairs.moved(me, &p);
                        corrected += 1;
                    }
                    if let Some(p) = Pairs::Scalar.corrected(&repulsion, &scalar, me) {
                        scalar[me] = p;
                    }
                }
                assert_same_bits(&on_lanes, &scalar);
            }
        }
        assert!(
            clear > 0 && crowded > 0 && corrected > 1000,
            "{clear} {crowded} {corrected}"
        );
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
