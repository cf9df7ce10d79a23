//! Steps 1 and 2 of the course's step (spring forces, damped Verlet) in one sweep over rows.
//!
//! # Why this layout
//!
//! The course's springs form a stencil: every point `(x, y)` emits the same six springs, to
//! `(x + dx, y + dy)` for the six [`DIRECTIONS`]. So instead of walking a list of spring records
//! (an index gather per end and a scatter of forces, which no compiler vectorises), the sweep
//! computes one direction for a whole row at a time from contiguous slices: the emitting row and
//! the partner row shifted by `dx`. The rows are copied into small struct-of-arrays buffers (x,
//! y and z each contiguous) so those loops run on packed SIMD lanes, square roots and divisions
//! included; the buffers hold three rows, so they stay in L1/L2 whatever the cloth's size.
//!
//! # Same bits as the course's spring loop
//!
//! The course adds each spring's force to its two ends in spring order. For point `i` that order
//! is: gravity, its own six springs in direction order, then the springs it is the far end of,
//! by emitter index: from `i + 1` (direction 0), `i + 2` (4), `i + nw - 1` (3), `i + nw` (1),
//! `i + nw + 1` (2) and `i + 2 nw` (5). [`Stencil::sweep`] adds the terms in exactly that order,
//! so every force, and hence every position, is bit-identical to the straightforward loop. A
//! spring that does not exist (at an edge) or is disabled contributes `+0.0`, which leaves a sum
//! unchanged (the only exception, `-0.0 + 0.0`, cannot occur: each sum starts from
//! `mass * gravity`, and the course's -0.0 gravity would need a negative-zero component).
//!
//! # Ping-pong
//!
//! The new position of point `i` is written into `last[i]`, the only slot that needed the old
//! last position, and the caller then swaps the two arrays. The sweep therefore only reads the
//! old positions, so it has no ordering hazards and rows can be shared out between threads with
//! the same bits.

// NOTE: the sweep's helpers are `#[inline(always)]` so they are compiled into the AVX2 build of
// the sweep (a function that is merely called would run in the caller-independent baseline
// build, two lanes wide).
#![allow(clippy::inline_always)]

use cloth_mesh::{ClothMesh, GridSpec, SpringKind, Vec3};

use crate::SolveError;
#[cfg(target_arch = "x86_64")]
use crate::simd::Avx2;
use crate::simd::Simd;

#[cfg(target_arch = "x86_64")]
mod fused;

/// The six springs a point emits, in the course's emission order: `(dx, dy, kind)`.
pub(crate) const DIRECTIONS: [(isize, isize, SpringKind); 6] = [
    (-1, 0, SpringKind::Structural),
    (0, -1, SpringKind::Structural),
    (-1, -1, SpringKind::Shearing),
    (1, -1, SpringKind::Shearing),
    (-2, 0, SpringKind::Bending),
    (0, -2, SpringKind::Bending),
];

/// The rows `rows` of a sweep: it reads the old `positions` (all rows), the `pinned` flags
/// (all rows) and the last positions of its rows (in `next`), and writes each new position into
/// `next` (pinned points keep theirs).
pub(crate) struct Band<'a> {
    pub(crate) positions: &'a [Vec3],
    pub(crate) pinned: &'a [bool],
    pub(crate) next: &'a mut [Vec3],
    pub(crate) rows: std::ops::Range<usize>,
}

/// A row of the fused pass (`sweep/fused.rs`): it emits row `y`'s springs, and sums and
/// integrates row `y - 2`, whose positions are `positions` and whose new positions go to `next`;
/// `ahead` is row `y + 1`'s positions (none past the last row).
pub(crate) struct FusedRow<'a> {
    y: usize,
    positions: &'a [Vec3],
    ahead: &'a [Vec3],
    next: &'a mut [Vec3],
}

/// The fused pass of a sweep's build, given the scratch and a row; it returns the columns it
/// integrated.
type Fused<'a> = dyn Fn(&mut RowScratch, FusedRow) -> usize + 'a;

/// Zero columns on each side of a row buffer, so a point can read the forces of springs emitted
/// up to two columns away without bounds tests.
const PAD: usize = 2;

/// Rows of positions in the ring: the three a row's springs read, and the next one, which the
/// fused pass copies in while it emits the row (see `sweep/fused.rs`).
const POS_SLOTS: usize = 4;

/// Declares the row strides the fused pass is compiled for, and its dispatch by stride.
///
/// NOTE: the fused pass reads and writes about 80 streams, the rows of the rings, and with a
/// stride known only at run time each is a pointer of its own, and with 16 general registers
/// the loop reloads them from the stack. With the
/// stride a constant, every stream of a ring slot is the slot's pointer plus a fixed offset,
/// and the reloads go. So the rings' stride is rounded up to one of a few classes (each at most
/// 1.5 times the one before, so a ring grows by less than half), and the pass is compiled once
/// per class; wider rows take a build with the stride a variable.
macro_rules! ring_strides {
    ($($stride:literal),+) => {
        /// The row strides the fused pass is compiled for, smallest first: a power of two
        /// or 1.5 times one, plus `2 PAD` (so rows of a power of two points fit exactly).
        const RING_STRIDES: &[usize] = &[$($stride),+];

        /// Runs the fused pass compiled for the scratch's stride, or the one with the stride a
        /// variable when it is not in [`RING_STRIDES`].
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn fused_pass(
            _: Avx2,
            stencil: &Stencil,
            scratch: &mut RowScratch,
            params: &SweepParams,
            row: FusedRow,
        ) -> usize {
            match scratch.stride {
                $(
                    $stride => stencil.emit_sum_integrate_avx2::<$stride>(scratch, params, row),
                )+
                _ => stencil.emit_sum_integrate_avx2::<0>(scratch, params, row),
            }
        }
    };
}

ring_strides!(
    12, 20, 28, 36, 52, 68, 100, 132, 196, 260, 388, 516, 772, 1028
);

/// The row stride of the rings for rows of `nw` points: the smallest of [`RING_STRIDES`] that
/// holds a row and its padding, or just that for wider rows.
fn ring_stride(nw: usize) -> usize {
    let needed = nw + 2 * PAD;
    RING_STRIDES
        .iter()
        .copied()
        .find(|&stride| stride >= needed)
        .unwrap_or(needed)
}

/// The mesh's springs rearranged by direction; rebuilt only when the mesh changes.
#[derive(Debug, Clone)]
pub(crate) struct Stencil {
    /// The spec the mesh was built from: meshes are a pure function of it, so equal specs mean
    /// equal springs (cheaper than comparing 14,502 springs every step).
    spec: GridSpec,
    nw: usize,
    nh: usize,
    /// `rest[t][j]`: rest length of the direction-`t` spring emitted by point `j` (0 where none).
    rest: [Vec<f64>; 6],
    /// Pinned point indices.
    pub(crate) pins: Vec<usize>,
}

/// The live parameters the sweep needs, derived once per step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SweepParams {
    /// Stiffness per direction, N/m (0 when disabled).
    pub k: [f64; 6],
    /// `mass * gravity`, N.
    pub weight: Vec3,
    /// Verlet's `1 - damping / 100`.
    pub keep: f64,
    /// `dt^2 / mass`.
    pub scale: f64,
}

/// Per-thread row buffers (three rows of positions and of per-direction forces, and one row of
/// summed forces), grown once.
#[derive(Debug, Default, Clone)]
pub(crate) struct RowScratch {
    /// `pos[((row % POS_SLOTS) * 3 + c) * stride + PAD + x]`, `stride` being
    /// [`RowScratch::stride`].
    pos: Vec<f64>,
    /// `f[(((row % 3) * 6 + t) * 3 + c) * stride + PAD + x]`.
    f: Vec<f64>,
    /// Summed force of the row being integrated, `total[c * stride + x]`.
    total: Vec<f64>,
    /// A row of zero forces, standing for the springs of rows past the last one.
    zeros: Vec<f64>,
    /// The row stride ([`ring_stride`]) the buffers were laid out for, and `f` zeroed for
    /// (0: never).
    stride: usize,
}

impl RowScratch {
    /// Bytes one band's row buffers take for rows of `nw` points.
    pub(crate) fn bytes_for(nw: usize) -> u64 {
        let stride = ring_stride(nw) as u64;
        let values = (POS_SLOTS as u64 * 3 + 3 * 6 * 3 + 3) * stride + nw as u64;
        values * size_of::<f64>() as u64
    }
}

impl Stencil {
    /// Bytes the stencil of a cloth of `points` points with `pins` pins takes: a rest length
    /// per point and direction, the pin list, and while it is built a flag per point and
    /// direction.
    pub(crate) fn bytes_for(points: usize, pins: usize) -> u64 {
        let per_point = 6 * (size_of::<f64>() + size_of::<bool>());
        (points * per_point + pins * size_of::<usize>()) as u64
    }

    /// Rearranges `mesh`'s springs by direction.
    ///
    /// # Errors
    /// [`SolveError::Method`] if the springs are not the course's grid stencil (they always are
    /// for a [`ClothMesh`]; the check guards the bit-identity argument above).
    pub(crate) fn new(mesh: &ClothMesh) -> Result<Self, SolveError> {
        let (nw, nh) = (mesh.nw(), mesh.nh());
        let n = nw * nh;
        let mut rest: [Vec<f64>; 6] = Default::default();
        let mut seen: [Vec<bool>; 6] = Default::default();
        for t in 0..6 {
            rest[t] = vec![0.0; n];
            seen[t] = vec![false; n];
        }
        let bad = |what: &str| SolveError::Method {
            solver: "verlet",
            reason: format!("the mesh's springs are not the course's grid stencil ({what})"),
        };
        for s in mesh.springs() {
            let (a, b) = (s.a as usize, s.b as usize);
            let dx = (b % nw) as isize - (a % nw) as isize;
            let dy = (b / nw) as isize - (a / nw) as isize;
            let t = DIRECTIONS
                .iter()
                .position(|&d| d == (dx, dy, s.kind))
                .ok_or_else(|| bad("a spring in an unknown direction"))?;
            if std::mem::replace(&mut seen[t][a], true) {
                return Err(bad("a duplicate spring"));
            }
            rest[t][a] = s.rest;
        }
        let expected: usize = DIRECTIONS
            .iter()
            .map(|&(dx, dy, _)| valid_columns(nw, dx).len() * nh.saturating_sub((-dy) as usize))
            .sum();
        if mesh.springs().len() != expected {
            return Err(bad("missing springs"));
        }
        Ok(Self {
            spec: mesh.spec().clone(),
            nw,
            nh,
            rest,
            pins: (0..n).filter(|&i| mesh.pinned()[i]).collect(),
        })
    }

    /// Whether this stencil was built for `mesh`.
    pub(crate) fn matches(&self, mesh: &ClothMesh) -> bool {
        self.spec == *mesh.spec()
    }

    /// Points per row.
    pub(crate) fn nw(&self) -> usize {
        self.nw
    }

    /// Rows.
    pub(crate) fn nh(&self) -> usize {
        self.nh
    }

    /// Rest lengths of the direction-`t` springs by emitting point (0 where none).
    pub(crate) fn rest(&self, t: usize) -> &[f64] {
        &self.rest[t]
    }

    /// Forces and the damped Verlet update for `band`'s rows (see [`Band`]).
    ///
    /// Runs the AVX2 build of the sweep, with the fused pass, when `simd` has AVX2 (see
    /// [`Stencil::sweep_avx2`]).
    pub(crate) fn sweep(
        &self,
        simd: Simd,
        scratch: &mut RowScratch,
        params: &SweepParams,
        band: Band,
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = simd.avx2() {
            // SAFETY: the CPU runs AVX2: an `Avx2` exists.
            #[allow(unsafe_code)]
            unsafe {
                self.sweep_avx2(avx2, scratch, params, band);
            }
            return;
        }
        self.sweep_rows(None, scratch, params, band);
    }

    /// The sweep compiled for AVX2: four f64 lanes per instruction instead of baseline
    /// x86-64's two, for the square roots and divisions of the spring loop above all.
    ///
    /// NOTE: only the vector width changes. FMA is deliberately not enabled (a fused
    /// multiply-add rounds once where the course rounds twice), and Rust never contracts or
    /// reassociates float operations, so every lane does the same IEEE operations in the same
    /// order as the portable build: the results are bit-identical (tested below).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn sweep_avx2(&self, avx2: Avx2, scratch: &mut RowScratch, params: &SweepParams, band: Band) {
        // NOTE: a closure written here takes this function's target features, so it calls the
        // AVX2 pass without `unsafe`.
        let fused =
            |scratch: &mut RowScratch, row: FusedRow| fused_pass(avx2, self, scratch, params, row);
        self.sweep_rows(Some(&fused), scratch, params, band);
    }

    /// The sweep itself, for whatever instruction set the caller was compiled for: everything
    /// it calls is inlined into it, so [`Stencil::sweep_avx2`] vectorises all of it. With
    /// no fused pass it is the portable sweep; otherwise the rows that can take it emit their
    /// springs, and sum and integrate two rows behind, in one pass of the given build
    /// (`fused`).
    #[inline(always)]
    pub(crate) fn sweep_rows(
        &self,
        fused: Option<&Fused<'_>>,
        scratch: &mut RowScratch,
        params: &SweepParams,
        band: Band,
    ) {
        let Band {
            positions,
            pinned,
            next,
            rows: std::ops::Range { start: r0, end: r1 },
        } = band;
        let (nw, nh) = (self.nw, self.nh);
        let stride = ring_stride(nw);
        scratch.pos.resize(POS_SLOTS * 3 * stride, 0.0);
        if scratch.stride != stride {
            // NOTE: zeroed once per layout. Spring forces are only ever written to a
            // direction's valid columns (or a whole row of zeros), so the columns outside them
            // stay zero from here on, and `emit_row` need not clear them each row (that was
            // 36 tiny `memset` calls a row).
            scratch.f.clear();
            scratch.f.resize(3 * 6 * 3 * stride, 0.0);
            scratch.stride = stride;
        }
        scratch.total.resize(3 * stride, 0.0);
        scratch.zeros.resize(nw, 0.0);
        for y in r0.saturating_sub(2)..r0 {
            self.load_row(scratch, positions, y);
        }
        // Whether the last fused pass copied row `y` into the ring already.
        let mut loaded = false;
        for y in r0..(r1 + 2) {
            // Rows before `r0 + 2` have no row of this band to sum; past the last row there is
            // nothing to emit.
            let fuse = fused.is_some() && y >= r0 + 2 && self.fusable(params, y);
            if y < nh {
                if !loaded {
                    self.load_row(scratch, positions, y);
                }
                if !fuse {
                    self.emit_row(scratch, params, y);
                }
            }
            if y >= r0 + 2 {
                let r = y - 2;
                let row = &mut next[(r - r0) * nw..(r - r0 + 1) * nw];
                // The fused pass copies row `y + 1` into the ring, if there is one.
                let ahead = if y + 1 < nh {
                    &positions[(y + 1) * nw..][..nw]
                } else {
                    &[]
                };
                loaded = fuse && !ahead.is_empty();
                let (positions, pinned) = (&positions[r * nw..][..nw], &pinned[r * nw..][..nw]);
                // Columns already integrated by the fused pass.
                let done = match fused {
                    Some(fused) if fuse => {
                        let next = &mut *row;
                        fused(
                            scratch,
                            FusedRow {
                                y,
                                positions,
                                ahead,
                                next,
                            },
                        )
                    }
                    _ => {
                        self.sum_row(scratch, params, r);
                        0
                    }
                };
                let total = &scratch.total;
                integrate_row(total, stride, params, positions, pinned, row, done);
            }
        }
        // NOTE: the fused pass integrates pinned points like any other, so they are put back
        // here, from the list of pins (a handful), rather than by testing every point's flag
        // in each row.
        let band = r0 * nw..r1 * nw;
        let first = self.pins.partition_point(|&i| i < band.start);
        for &i in self.pins[first..].iter().take_while(|&&i| i < band.end) {
            next[i - band.start] = positions[i];
        }
    }

    /// Whether row `y` can take the fused pass: every spring type enabled (a disabled one is a
    /// row of zeros, which the portable loop writes), every partner row present and a row at
    /// least one four-lane group wide.
    #[inline(always)]
    fn fusable(&self, params: &SweepParams, y: usize) -> bool {
        y >= 2 && y < self.nh && self.nw >= 4 && params.k.iter().all(|&k| k != 0.0)
    }

    /// Copies row `y` of `positions` into the struct-of-arrays ring.
    #[inline(always)]
    fn load_row(&self, scratch: &mut RowScratch, positions: &[Vec3], y: usize) {
        let stride = scratch.stride;
        let base = (y % POS_SLOTS) * 3 * stride + PAD;
        let row = &positions[y * self.nw..(y + 1) * self.nw];
        for c in 0..3 {
            let dst = &mut scratch.pos[base + c * stride..base + c * stride + self.nw];
            for (d, p) in dst.iter_mut().zip(row) {
                *d = p[c];
            }
        }
    }

    /// The force of every spring emitted by row `y`, per direction, into the force ring.
    #[inline(always)]
    fn emit_row(&self, scratch: &mut RowScratch, params: &SweepParams, y: usize) {
        let (nw, stride) = (self.nw, scratch.stride);
        for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
            let out = ((y % 3) * 6 + t) * 3 * stride;
            let out = &mut scratch.f[out..out + 3 * stride];
            let cols = valid_columns(nw, dx);
            let partner_row = y as isize + dy;
            if params.k[t] == 0.0 || partner_row < 0 || cols.is_empty() {
                out.fill(0.0);
                continue;
            }
            let (fx, rest_f) = out.split_at_mut(stride);
            let (fy, fz) = rest_f.split_at_mut(stride);
            let a = (y % POS_SLOTS) * 3 * stride + PAD;
            let b = (partner_row as usize % POS_SLOTS) * 3 * stride + PAD;
            let b = (b as isize + dx) as usize;
            let pos = &scratch.pos;
            let row = |base: usize, c: usize| &pos[base + c * stride + cols.start..][..cols.len()];
            let rest = &self.rest[t][y * nw + cols.start..y * nw + cols.end];
            let span = PAD + cols.start..PAD + cols.end;
            spring_forces(
                params.k[t],
                [row(a, 0), row(a, 1), row(a, 2)],
                [row(b, 0), row(b, 1), row(b, 2)],
                rest,
                [&mut fx[span.clone()], &mut fy[span.clone()], &mut fz[span]],
            );
        }
    }

    /// The total force on each point of row `r`, summed in the course's order (module docs).
    #[inline(always)]
    fn sum_row(&self, scratch: &mut RowScratch, params: &SweepParams, r: usize) {
        let (nw, stride) = (self.nw, scratch.stride);
        let f = &scratch.f;
        let zeros = &scratch.zeros[..nw];
        // Direction t, component c of emitter row `row`, starting `shift` columns to the right
        // of each point; a row past the last one emits nothing (zeros: subtracting +0.0 leaves
        // every sum unchanged).
        // NOTE: plain calls, not `array::map`: its closures are not inlined into the AVX2
        // build, and a call per slice would sit in the loop.
        let term = |row: usize, t: usize, c: usize, shift: isize| -> &[f64] {
            if row >= self.nh {
                return zeros;
            }
            let start = (((row % 3) * 6 + t) * 3 + c) * stride + PAD;
            &f[start.wrapping_add_signed(shift)..][..nw]
        };
        for c in 0..3 {
            let total = &mut scratch.total[c * stride..][..nw];
            // NOTE: each slice cut to `nw` here, so the compiler drops the loop's bounds tests.
            let cut = |row: usize, t: usize, shift: isize| &term(row, t, c, shift)[..nw];
            let (o0, o1, o2) = (cut(r, 0, 0), cut(r, 1, 0), cut(r, 2, 0));
            let (o3, o4, o5) = (cut(r, 3, 0), cut(r, 4, 0), cut(r, 5, 0));
            let (f0, f1, f2) = (cut(r, 0, 1), cut(r, 4, 2), cut(r + 1, 3, -1));
            let (f3, f4, f5) = (cut(r + 1, 1, 0), cut(r + 1, 2, 1), cut(r + 2, 5, 0));
            let w = params.weight[c];
            // NOTE: one pass, left to right: the same operations in the same order as adding
            // the own terms and then subtracting the far ones, without storing and reloading
            // the partial sums six more times.
            for (x, out) in total.iter_mut().enumerate() {
                *out = w + o0[x] + o1[x] + o2[x] + o3[x] + o4[x] + o5[x]
                    - f0[x]
                    - f1[x]
                    - f2[x]
                    - f3[x]
                    - f4[x]
                    - f5[x];
            }
        }
    }
}

/// Per direction, the index of a point's partner relative to the point, in a grid `nw` wide
/// (all negative: partners are earlier points).
pub(crate) fn offsets(nw: usize) -> [isize; 6] {
    DIRECTIONS.map(|(dx, dy, _)| dx + dy * nw as isize)
}

/// The columns `x` whose direction-`dx` partner `x + dx` lies inside a row of `nw` points.
pub(crate) fn valid_columns(nw: usize, dx: isize) -> std::ops::Range<usize> {
    let lo = (-dx).max(0) as usize;
    let hi = nw.saturating_sub(dx.max(0) as usize);
    lo..hi.max(lo)
}

/// Hooke forces `k (|b - a| - rest) (b - a) / |b - a|` on the emitting ends `a`, lane by lane.
///
/// NOTE: the operations and their order are the course's (`k * (len - rest) / len`, then times
/// each component), so the forces are bit-identical; a zero-length spring contributes nothing.
#[inline(always)]
fn spring_forces(k: f64, a: [&[f64]; 3], b: [&[f64]; 3], rest: &[f64], f: [&mut [f64]; 3]) {
    let n = rest.len();
    let [ax, ay, az] = a.map(|s| &s[..n]);
    let [bx, by, bz] = b.map(|s| &s[..n]);
    let [fx, fy, fz] = f;
    let (fx, fy, fz) = (&mut fx[..n], &mut fy[..n], &mut fz[..n]);
    for i in 0..n {
        let (dx, dy, dz) = (bx[i] - ax[i], by[i] - ay[i], bz[i] - az[i]);
        let len = (dx * dx + dy * dy + dz * dz).sqrt();
        // NOTE: divide first, then select: a branch here keeps the loop scalar, a select lets
        // it run on SIMD lanes (the NaN of 0/0 is discarded).
        let s = k * (len - rest[i]) / len;
        let s = if len == 0.0 { 0.0 } else { s };
        fx[i] = dx * s;
        fy[i] = dy * s;
        fz[i] = dz * s;
    }
}

/// Damped Verlet for one row: `x' = x + keep (x - x_last) + F dt^2 / m`, written over the last
/// positions in `next`, with the forces' components at `total[c * stride..]`; pinned points keep
/// their position. Columns before `from` are skipped (the fused pass integrated them; the caller
/// puts pinned ones back).
#[inline(always)]
fn integrate_row(
    total: &[f64],
    stride: usize,
    params: &SweepParams,
    positions: &[Vec3],
    pinned: &[bool],
    next: &mut [Vec3],
    from: usize,
) {
    let nw = positions.len();
    // NOTE: plain slices, not `array::map` (see `sum_row`).
    let (fx, fy, fz) = (
        &total[..nw],
        &total[stride..][..nw],
        &total[2 * stride..][..nw],
    );
    let done = from.min(nw);
    let (fx, fy, fz) = (&fx[done..], &fy[done..], &fz[done..]);
    for (x, ((p, l), &pin)) in positions[done..]
        .iter()
        .zip(&mut next[done..nw])
        .zip(&pinned[done..])
        .enumerate()
    {
        let f = Vec3::new(fx[x], fy[x], fz[x]);
        *l = if pin {
            *p
        } else {
            *p + (*p - *l) * params.keep + f * params.scale
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::assert_same_bits;

    /// Sweeps rows `rows` of a `nw` x `nh` cloth, its points and their last positions jittered
    /// at random, with the dispatched (AVX2 and fused, on such CPUs) and the portable sweep,
    /// and asserts the same bits.
    fn assert_dispatch_matches_portable(nw: usize, nh: usize, rows: std::ops::Range<usize>) {
        let mesh = ClothMesh::new(&GridSpec {
            width: nw as f64 / 49.0,
            height: nh as f64 / 49.0,
            num_width_points: nw,
            num_height_points: nh,
            // Pins on both sides of every band's edges: the first point of every row, and
            // the last of every other row.
            pinned: (0..nh)
                .flat_map(|y| {
                    [(0, y), (nw - 1, y)]
                        .into_iter()
                        .take(1 + usize::from(y % 2 == 0))
                })
                .collect(),
            ..GridSpec::default()
        })
        .unwrap();
        let mut rng = cloth_mesh::SplitMix64::new((nw * 1000 + nh) as u64);
        let mut jitter = |p: &Vec3| {
            p + Vec3::new(
                rng.uniform(-0.01, 0.01),
                rng.uniform(-0.01, 0.01),
                rng.uniform(-0.01, 0.01),
            )
        };
        let mut positions: Vec<Vec3> = mesh.start_positions().iter().map(&mut jitter).collect();
        // A zero-length spring inside the fused pass's rows and columns (direction 0 of (3, 2)).
        positions[2 * nw + 3] = positions[2 * nw + 2];
        let last: Vec<Vec3> = positions.iter().map(&mut jitter).collect();
        let stencil = Stencil::new(&mesh).unwrap();
        let params = SweepParams {
            k: [5000.0, 5000.0, 5000.0, 5000.0, 1000.0, 1000.0],
            weight: Vec3::new(0.0, -0.0294, 0.0),
            keep: 0.998,
            scale: 1.0e-7 / 0.003,
        };
        let band = rows.start * nw..rows.end * nw;
        let pinned = mesh.pinned();
        let mut portable = last[band.clone()].to_vec();
        let (positions, rows) = (&positions, rows.clone());
        let next = &mut portable;
        let sweep = Band {
            positions,
            pinned,
            next,
            rows: rows.clone(),
        };
        stencil.sweep_rows(None, &mut RowScratch::default(), &params, sweep);
        assert_ne!(portable, last[band.clone()], "the sweep moved the points");
        let mut dispatched = last[band.clone()].to_vec();
        let (next, scratch) = (&mut dispatched, &mut RowScratch::default());
        let sweep = Band {
            positions,
            pinned,
            next,
            rows,
        };
        stencil.sweep(Simd::detect(), scratch, &params, sweep);
        assert_same_bits(&dispatched, &portable);
    }

    #[test]
    fn the_dispatched_sweep_has_the_bits_of_the_portable_one() {
        // Scattered positions and velocities so every lane sees different lengths, a
        // zero-length spring, and ragged row ends (53 is not a multiple of any lane count).
        assert_dispatch_matches_portable(53, 53, 0..53);
    }

    #[test]
    fn narrow_rows_and_bands_keep_the_portable_bits() {
        // 4 wide: one four-lane group holds both edges. 5 to 7: the last group overlaps the
        // one before it. 3: too narrow for the fused pass. Bands starting and ending inside
        // the cloth, as threads sweep them, sum rows whose partners lie outside the band.
        for nw in [3, 4, 5, 6, 7, 8, 9] {
            assert_dispatch_matches_portable(nw, 9, 0..9);
        }
        assert_dispatch_matches_portable(21, 17, 5..11);
        assert_dispatch_matches_portable(21, 17, 1..2);
        assert_dispatch_matches_portable(21, 17, 14..17);
    }

    #[test]
    fn every_ring_stride_keeps_the_portable_bits() {
        // The fused pass is compiled once per ring stride: the narrowest and the widest rows
        // of each class, and rows wider than the last class (the build with the stride a
        // variable), each against the portable sweep.
        let mut narrowest = 4;
        for &stride in RING_STRIDES {
            let widest = stride - 2 * PAD;
            assert_eq!(ring_stride(narrowest), stride);
            assert_eq!(ring_stride(widest), stride);
            assert_dispatch_matches_portable(narrowest, 5, 0..5);
            assert_dispatch_matches_portable(widest, 5, 0..5);
            narrowest = widest + 1;
        }
        assert_eq!(ring_stride(narrowest), narrowest + 2 * PAD);
        assert_dispatch_matches_portable(narrowest, 5, 0..5);
        assert_dispatch_matches_portable(narrowest + 3, 5, 0..5);
    }

    #[test]
    fn a_scratch_reused_for_another_width_gives_the_bits_of_a_fresh_one() {
        // The force ring's edge columns are zeroed once per layout: a scratch that swept a
        // wider cloth (non-zero forces everywhere in its layout) must not leak them into a
        // narrower one, nor a bending-free sweep (a row of zeros) into the next.
        let params = |bending: f64| SweepParams {
            k: [5000.0, 5000.0, 5000.0, 5000.0, bending, bending],
            weight: Vec3::new(0.0, -0.0294, 0.0),
            keep: 0.998,
            scale: 1.0e-7 / 0.003,
        };
        let mut reused = RowScratch::default();
        for (n, bending) in [(41, 1000.0), (29, 0.0), (29, 1000.0), (41, 1000.0)] {
            let mesh = ClothMesh::pinned_grid(n).unwrap();
            let stencil = Stencil::new(&mesh).unwrap();
            let mut rng = cloth_mesh::SplitMix64::new(n as u64);
            let positions: Vec<Vec3> = mesh
                .start_positions()
                .iter()
                .map(|p| p + Vec3::new(rng.uniform(-0.01, 0.01), 0.0, rng.uniform(-0.01, 0.01)))
                .collect();
            let (nh, pinned) = (stencil.nh(), mesh.pinned());
            let run = |scratch: &mut RowScratch| {
                let mut next = mesh.start_positions().to_vec();
                let band = Band {
                    positions: &positions,
                    pinned,
                    next: &mut next,
                    rows: 0..nh,
                };
                stencil.sweep(Simd::detect(), scratch, &params(bending), band);
                next
            };
            let fresh = run(&mut RowScratch::default());
            assert_same_bits(&run(&mut reused), &fresh);
        }
    }
}
