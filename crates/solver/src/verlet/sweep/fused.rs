//! One AVX2 pass per row that emits row `y`'s springs, sums row `y - 2`'s forces and moves
//! row `y - 2`'s points.
//!
//! # Why
//!
//! The spring loops are bound by the divider: a square root and a division per spring, which
//! this CPU's one divider takes about 14 cycles to do for four lanes. The rest of the force
//! sweep (thirteen terms summed per point, then the Verlet update) is adds, loads, stores and
//! shuffles that could run on the other execution units meanwhile, but only from the same loop:
//! in loops of their own they ran after the divider work, not beside it. This pass puts a row's
//! springs, and the sums and Verlet update two rows behind, into one loop over four columns at a
//! time, so that work fills the divider's shadow; the six spring directions share the loop
//! instead of running six short ones.
//!
//! # Same bits
//!
//! Each lane does the operations of `spring_forces`, of the sum in [`Stencil::sum_row`] and of
//! `integrate_row`, in the same order, with the same IEEE double operations (no fused
//! multiply-add, no reassociation). A lane whose spring does not exist (an edge column) writes
//! `+0.0`, which is what the portable loops leave there. The last group of a row that is not a
//! multiple of four wide overlaps the one before it: recomputing a column's forces and sums
//! writes the very same bits, and its Verlet update is left to `integrate_row`, as is putting
//! pinned points back.

use std::arch::x86_64::{
    __m256d, __m256i, _CMP_EQ_OQ, _mm256_add_epi64, _mm256_add_pd, _mm256_and_pd, _mm256_and_si256,
    _mm256_andnot_pd, _mm256_castsi256_pd, _mm256_cmp_pd, _mm256_cmpgt_epi64, _mm256_div_pd,
    _mm256_loadu_pd, _mm256_mul_pd, _mm256_set_epi64x, _mm256_set1_epi64x, _mm256_set1_pd,
    _mm256_setzero_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd,
};
use std::marker::PhantomData;

use super::{
    DIRECTIONS, FusedRow, PAD, POS_SLOTS, RowScratch, Stencil, SweepParams, valid_columns,
};
use crate::simd::{deinterleave, interleave, load4, store4};

/// A buffer of the fused pass's streams (`B`: its borrow, shared or mutable), read and written
/// four columns at a time: `rows` rows `stride` values apart, each with `margin` values, then
/// the `nw` columns, then `margin` values again.
///
/// NOTE: the pass reads and writes about 80 streams a group of columns. As offsets from a few
/// base pointers (a constant offset each once the stride is a constant), their tests are the
/// one of the group's column, the same for every stream; as slices, each stream would keep a
/// bounds test of its own in the loop, beside the divider's work.
#[derive(Debug)]
struct Rows<B> {
    /// The buffer's start; written through only when `B` is a mutable borrow.
    start: *mut f64,
    /// How many rows.
    height: usize,
    stride: usize,
    margin: usize,
    /// The last group's first column, `nw - 4`.
    last: usize,
    borrow: PhantomData<B>,
}

impl<'a> Rows<&'a [f64]> {
    /// The rows of `values`, to read (see [`Rows::of`]).
    #[inline(always)]
    fn new(values: &'a [f64], rows: usize, stride: usize, nw: usize, margin: usize) -> Self {
        Self::of(
            values.as_ptr().cast_mut(),
            values.len(),
            [rows, stride, nw, margin],
        )
    }
}

impl<'a> Rows<&'a mut [f64]> {
    /// The rows of `values`, to read and write (see [`Rows::of`]).
    #[inline(always)]
    fn new_mut(
        values: &'a mut [f64],
        rows: usize,
        stride: usize,
        nw: usize,
        margin: usize,
    ) -> Self {
        Self::of(
            values.as_mut_ptr(),
            values.len(),
            [rows, stride, nw, margin],
        )
    }

    /// Writes `v` into columns `j..j + 4` of row `row` (see [`Rows::at`]).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn store(&mut self, row: usize, j: usize, v: __m256d) {
        let at = self.at(row, j, 0);
        // SAFETY: `at..at + 4` is inside the values borrowed mutably for `'a` (`Rows::at`).
        #[allow(unsafe_code)]
        unsafe {
            _mm256_storeu_pd(self.start.add(at), v);
        }
    }
}

impl<B> Rows<B> {
    /// The rows of the `len` values borrowed (`B`) from `start`.
    ///
    /// # Panics
    /// Unless `nw >= 4` and the values hold every row: `(rows - 1) stride + nw + 2 margin`
    /// values at least.
    #[inline(always)]
    fn of(start: *mut f64, len: usize, [rows, stride, nw, margin]: [usize; 4]) -> Self {
        let needed = (rows.checked_sub(1))
            .and_then(|r| r.checked_mul(stride))
            .and_then(|v| v.checked_add(nw)?.checked_add(margin)?.checked_add(margin));
        assert!(nw >= 4 && needed.is_some_and(|needed| needed <= len));
        Self {
            start,
            height: rows,
            stride,
            margin,
            last: nw - 4,
            borrow: PhantomData,
        }
    }

    /// The offset, from the buffer's start, of columns `j + shift..j + shift + 4` of row
    /// `row`: inside the buffer (see [`Rows::of`]).
    ///
    /// # Panics
    /// Unless `row < rows`, `j <= nw - 4` and `|shift| <= margin`. The row and shift are
    /// constants of the pass's unrolled loops, so only the test of `j` stays.
    #[inline(always)]
    fn at(&self, row: usize, j: usize, shift: isize) -> usize {
        assert!(row < self.height && j <= self.last && shift.unsigned_abs() <= self.margin);
        (row * self.stride + self.margin + j).wrapping_add_signed(shift)
    }

    /// Columns `j + shift..j + shift + 4` of row `row` (see [`Rows::at`]).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn load(&self, row: usize, j: usize, shift: isize) -> __m256d {
        let at = self.at(row, j, shift);
        // SAFETY: `at..at + 4` is inside the values borrowed from `start` (`Rows::at`).
        #[allow(unsafe_code)]
        unsafe {
            _mm256_loadu_pd(self.start.add(at))
        }
    }
}

impl Stencil {
    /// The springs of row `y` into the force ring, the summed force of row `r = y - 2` into
    /// `scratch.total`, and the new positions of row `r` into `next` (row `r` of the last
    /// positions, overwritten): what [`Stencil::emit_row`], [`Stencil::sum_row`] and
    /// `integrate_row` would write, bit for bit, except that pinned points are integrated like
    /// the others and the columns from the returned one on are not integrated (the caller
    /// finishes both). Row `y`'s positions must be in the ring; `y` must be
    /// [`Stencil::fusable`].
    #[target_feature(enable = "avx2")]
    pub(super) fn emit_sum_integrate_avx2<const STRIDE: usize>(
        &self,
        scratch: &mut RowScratch,
        params: &SweepParams,
        row: FusedRow,
    ) -> usize {
        let FusedRow {
            y,
            positions,
            ahead,
            next,
        } = row;
        // The rings' row stride: `STRIDE`, a constant (see `ring_strides!`), or when 0
        // the scratch's.
        let nw = self.nw;
        let stride = if STRIDE == 0 { scratch.stride } else { STRIDE };
        assert_eq!(stride, scratch.stride, "the build for the scratch's stride");
        assert!(stride >= nw + 2 * PAD, "rows fit their stride");
        // The position ring's slots, three rows (`x`, `y`, `z`) each, rotated so that they
        // hold rows y - 2, y - 1, y (read) and y + 1 (written).
        let mut chunks = scratch.pos.chunks_exact_mut(3 * stride);
        let mut slots: [&mut [f64]; POS_SLOTS] =
            std::array::from_fn(|_| chunks.next().unwrap_or_default());
        slots.rotate_left((y - 2) % POS_SLOTS);
        let [s2, s1, s0, s3] = slots;
        // Rows y, y - 1 and y - 2: `p[-dy]`.
        let p = [&*s0, &*s1, &*s2].map(|slot| Rows::new(slot, 3, stride, nw, PAD));
        let mut written = Rows::new_mut(s3, 3, stride, nw, PAD);
        let rest: [Rows<&[f64]>; 6] =
            std::array::from_fn(|t| Rows::new(&self.rest[t][y * nw..][..nw], 1, nw, nw, 0));
        // Per direction, its valid columns `lo..hi` as `lo - 1` and `hi`, for lane
        // compares.
        let mut above = [_mm256_set1_epi64x(0); 6];
        let mut below = [_mm256_set1_epi64x(0); 6];
        for (t, &(dx, _, _)) in DIRECTIONS.iter().enumerate() {
            let cols = valid_columns(nw, dx);
            above[t] = _mm256_set1_epi64x(cols.start as i64 - 1);
            below[t] = _mm256_set1_epi64x(cols.end as i64);
        }

        // The force ring's three row slots of 18 rows (row `t * 3 + c`: direction `t`,
        // component `c`): row y's is written; rows r = y - 2 and r + 1 are read.
        let block = 18 * stride;
        let (s0, tail) = scratch.f[..3 * block].split_at_mut(block);
        let (s1, s2) = tail.split_at_mut(block);
        let (own, fr1, fr) = match y % 3 {
            0 => (s0, &*s2, &*s1),
            1 => (s1, &*s0, &*s2),
            _ => (s2, &*s1, &*s0),
        };
        let term = |t: usize, c: usize| t * 3 + c;
        let (fr, fr1) = (
            Rows::new(fr, 18, stride, nw, PAD),
            Rows::new(fr1, 18, stride, nw, PAD),
        );
        let mut out = Rows::new_mut(own, 18, stride, nw, PAD);
        let mut total = Rows::new_mut(&mut scratch.total, 3, stride, nw, 0);

        // The rows of points as flat `x, y, z` streams of `3 nw` values (`Vec3` is
        // `Pod` through nalgebra's `convert-bytemuck`: three f64s, no padding).
        let p_flat: &[f64] = bytemuck::cast_slice(&positions[..nw]);
        let l_flat: &mut [f64] = bytemuck::cast_slice_mut(&mut next[..nw]);
        // Row y + 1, which the loop copies into its ring slot as it goes, or none.
        let ahead_flat: Option<&[f64]> =
            (!ahead.is_empty()).then(|| bytemuck::cast_slice(&ahead[..nw]));
        let keep = _mm256_set1_pd(params.keep);
        let scale = _mm256_set1_pd(params.scale);
        let k = params.k.map(|k| _mm256_set1_pd(k));
        let weight = [0, 1, 2].map(|c| _mm256_set1_pd(params.weight[c]));
        let zero = _mm256_setzero_pd();
        let lane: __m256i = _mm256_set_epi64x(3, 2, 1, 0);
        let mut i = 0;
        while i < nw {
            let j = i.min(nw - 4);
            // The overlapping last group (`j < i`) recomputes forces and sums, but must not
            // integrate its columns again: integration reads what it overwrites.
            let integrate = j == i;
            i += 4;
            let column = _mm256_add_epi64(_mm256_set1_epi64x(j as i64), lane);
            if let Some(ahead) = ahead_flat {
                // NOTE: row y + 1's copy into the ring, four points' `x y z | x y z ...`
                // split into `x`, `y` and `z` by register shuffles, is done here, in the
                // divider's shadow, rather than in a loop of its own before the row. Its
                // slot is none of the three this pass reads.
                let at = 3 * j;
                let m = [
                    load4(&ahead[at..]),
                    load4(&ahead[at + 4..]),
                    load4(&ahead[at + 8..]),
                ];
                let split = deinterleave(m);
                for (c, v) in split.into_iter().enumerate() {
                    written.store(c, j, v);
                }
            }
            // NOTE: the six square roots first, then the six divisions: each division
            // waits about 20 cycles for its root, and with the roots issued together the
            // divider has the next one queued meanwhile.
            let mut dirs = [[zero; 3]; 6];
            let mut lens = [zero; 6];
            let mut last = [zero; 3];
            let av = [0, 1, 2].map(|c| p[0].load(c, j, 0));
            for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
                // Row `y + dy`, shifted by `dx`.
                let row = &p[dy.unsigned_abs()];
                let d = [0, 1, 2].map(|c| _mm256_sub_pd(row.load(c, j, dx), av[c]));
                let len2 = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
                    _mm256_mul_pd(d[2], d[2]),
                );
                lens[t] = _mm256_sqrt_pd(len2);
                dirs[t] = d;
            }
            for t in 0..6 {
                let (d, len) = (dirs[t], lens[t]);
                let stretch = _mm256_sub_pd(len, rest[t].load(0, j, 0));
                let s = _mm256_div_pd(_mm256_mul_pd(k[t], stretch), len);
                // A zero-length spring contributes +0.0, as the portable select gives.
                let s = _mm256_andnot_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(len, zero), s);
                let valid = _mm256_castsi256_pd(_mm256_and_si256(
                    _mm256_cmpgt_epi64(column, above[t]),
                    _mm256_cmpgt_epi64(below[t], column),
                ));
                for c in 0..3 {
                    last[c] = _mm256_and_pd(valid, _mm256_mul_pd(d[c], s));
                    out.store(term(t, c), j, last[c]);
                }
            }
            // Row r's sum in the course's order: its own six springs, then the ones it is
            // the far end of; `last` holds row y's direction-5 forces, the final term.
            let mut sums = [zero; 3];
            for c in 0..3 {
                let mut sum = weight[c];
                for t in 0..6 {
                    sum = _mm256_add_pd(sum, fr.load(term(t, c), j, 0));
                }
                // The springs row r is the far end of, in the sum's order (see `sum_row`):
                // `(slot, row, shift)`.
                let far = [
                    (&fr, term(0, c), 1),
                    (&fr, term(4, c), 2),
                    (&fr1, term(3, c), -1),
                    (&fr1, term(1, c), 0),
                    (&fr1, term(2, c), 1),
                ];
                for (slot, row, shift) in far {
                    sum = _mm256_sub_pd(sum, slot.load(row, j, shift));
                }
                sum = _mm256_sub_pd(sum, last[c]);
                total.store(c, j, sum);
                sums[c] = sum;
            }
            if integrate {
                // The four points' forces interleaved as they lie in memory, `x y z x |
                // y z x y | z x y z`, then Verlet on three vectors of four values each.
                let f = interleave(sums);
                for (q, f) in f.into_iter().enumerate() {
                    let at = 3 * j + 4 * q;
                    let p = load4(&p_flat[at..at + 4]);
                    let l = &mut l_flat[at..at + 4];
                    let previous = load4(l);
                    let moved = _mm256_mul_pd(_mm256_sub_pd(p, previous), keep);
                    let new = _mm256_add_pd(_mm256_add_pd(p, moved), _mm256_mul_pd(f, scale));
                    store4(l, new);
                }
            }
        }
        // Integrated: every group but an overlapping last one.
        nw / 4 * 4
    }
}
