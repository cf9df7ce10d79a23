//! The layout: the points grouped box by box (`start`, `members`), each box listing its points
//! in index order whatever the thread count, moved in place from one rebuild to the next when
//! few points changed box, laid out afresh by a counting sort otherwise.

use cloth_mesh::{ClothMesh, Vec3};
use rayon::prelude::*;

use super::keys::compute_keys;
use super::memory::Memory;
use super::table::{SLOT_BYTES, Table, table_size};
use super::{PARALLEL_CHUNK, SpatialHash};
use crate::disjoint::Disjoint;

/// What a run of points keeps between the passes of a rebuild.
#[derive(Debug, Default, Clone)]
pub(super) struct Run {
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

/// Relayouts take at most one point in this many: a bound on the share of the sort of the
/// moves (`n log n` in the moves), which stays well under the cost of a full layout below it.
/// A cloth whose points change box wholesale (one jumping to a new place) takes the full
/// layout.
const RELAYOUT_SHARE: usize = 16;

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
    let mut k = 0;
    // NOTE: a run of points in one cell takes consecutive places.
    for cells in cell_of.chunk_by(|a, b| a == b) {
        let c = cells[0] as usize;
        let place = next[c] as usize;
        // SAFETY: the prefix sum gave this run of points places `next[c]..` in cell `c`,
        // exactly as many as it counted there and disjoint from every other run's and cell's;
        // only this run writes them, each once.
        #[allow(unsafe_code)]
        let places = unsafe { members.run(place, cells.len()) };
        for (slot, point) in places.iter_mut().zip(first + k..) {
            *slot = point as u32;
        }
        k += cells.len();
        next[c] = (place + cells.len()) as u32;
    }
}

impl SpatialHash {
    /// Bytes the hash allocates for a cloth of `points` points resolved on `threads` threads,
    /// for a cloth near its rest spacing (as the stretch limit keeps it).
    ///
    /// Per point: its keys (this rebuild's and the last), its cell, its place in the two
    /// member lists, its sorted and anchor positions, and at worst a miss and a move record in
    /// its run. Per cell: its start, mark, memory, up to four table slots (the table is at
    /// most half full and doubles) and one count per run. A box is three grid spacings wide
    /// and long, so it holds about nine points of a cloth at rest; the estimate allows four,
    /// and twice as many cells as boxes in use (the table is cleared past that), so half a
    /// cell per point.
    #[must_use]
    pub fn memory_estimate(points: usize, threads: usize) -> u64 {
        let n = points as u64;
        let runs = threads.clamp(1, points.div_ceil(PARALLEL_CHUNK).max(1)) as u64;
        let per_point = 2 * size_of::<u64>()
            + 3 * size_of::<u32>()
            + 2 * size_of::<Vec3>()
            + size_of::<u32>()
            + size_of::<Moved>();
        let moves = 2 * size_of::<u64>() as u64 * (n / RELAYOUT_SHARE as u64);
        let cells = n / 2 + 64;
        // NOTE: `memory` grows with the cells one rebuild at a time, so its capacity may be
        // twice its length.
        let per_cell = size_of::<u32>() as u64
            + size_of::<bool>() as u64
            + 2 * size_of::<Memory>() as u64
            + 4 * SLOT_BYTES as u64
            + size_of::<u32>() as u64 * runs;
        n * per_point as u64 + moves + cells * per_cell
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
        if was_coherent && moved <= n / RELAYOUT_SHARE {
            // NOTE: nearly every step gets here: a step takes a point a small fraction of a
            // box, and about one point in two hundred changes box on the falling 256 x 256
            // cloth (none on a settled one).
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
}
