//! One AVX2 pass per row that emits row `y`'s springs and sums row `y - 2`'s forces.
//!
//! # Why
//!
//! The spring loops are bound by the divider: a square root and a division per spring, which
//! this CPU's one divider takes about 14 cycles to do for four lanes. The rest of the force
//! sweep (thirteen terms summed per point) is adds, loads and stores that could run on the
//! other execution units meanwhile, but only from the same loop: in loops of their own they
//! ran after the divider work, not beside it. This pass puts a row's springs and the sums two
//! rows behind into one loop over four columns at a time, so the sums fill the divider's
//! shadow, and the six spring directions share one loop instead of six short ones.
//!
//! # Same bits
//!
//! Each lane does the operations of `spring_forces` and of the sum in [`Stencil::sum_row`], in
//! the same order, with the same IEEE double operations (no fused multiply-add, no
//! reassociation). A lane whose spring does not exist (an edge column) writes `+0.0`, which is
//! what the portable loops leave there. The last group of a row that is not a multiple of four
//! wide overlaps the one before it: recomputing a column writes the very same bits.

#![allow(unsafe_code)]

use std::arch::x86_64::{
    __m256i, _CMP_EQ_OQ, _mm256_add_epi64, _mm256_add_pd, _mm256_and_pd, _mm256_and_si256,
    _mm256_andnot_pd, _mm256_castsi256_pd, _mm256_cmp_pd, _mm256_cmpgt_epi64, _mm256_div_pd,
    _mm256_loadu_pd, _mm256_mul_pd, _mm256_set_epi64x, _mm256_set1_epi64x, _mm256_set1_pd,
    _mm256_setzero_pd, _mm256_sqrt_pd, _mm256_storeu_pd, _mm256_sub_pd,
};

use super::{DIRECTIONS, PAD, RowScratch, Stencil, SweepParams, valid_columns};

/// `len` values of `s` from `start + shift`: a stream the loop reads four lanes at a time.
#[inline(always)]
fn stream(s: &[f64], start: usize, shift: isize, len: usize) -> &[f64] {
    &s[start.wrapping_add_signed(shift)..][..len]
}

impl Stencil {
    /// Whether row `y` can take the fused pass: every spring type enabled (a disabled one is a
    /// row of zeros, which the portable loop writes), every partner row present, and a row at
    /// least one four-lane group wide.
    pub(super) fn fusable(&self, params: &SweepParams, y: usize) -> bool {
        y >= 2 && y < self.nh && self.nw >= 4 && params.k.iter().all(|&k| k != 0.0)
    }

    /// The springs of row `y` into the force ring and the summed force of row `y - 2` into
    /// `scratch.total`: what [`Stencil::emit_row`] then [`Stencil::sum_row`] would write, bit
    /// for bit. Row `y`'s positions must be in the ring; `y` must be [`Stencil::fusable`].
    #[target_feature(enable = "avx2")]
    pub(super) fn emit_and_sum_avx2(
        &self,
        scratch: &mut RowScratch,
        params: &SweepParams,
        y: usize,
    ) {
        let (nw, stride) = (self.nw, self.nw + 2 * PAD);
        // Every stream below is a checked slice of exactly `nw` values; the loop reads and
        // writes lanes `j..j + 4` of them with `j + 4 <= nw`.
        let ring = &scratch.pos[..];
        let pos = |q: usize, c: usize| ((q % 3) * 3 + c) * stride + PAD;
        let mut a = [std::ptr::null::<f64>(); 3];
        let mut b = [[std::ptr::null::<f64>(); 3]; 6];
        let mut rest = [std::ptr::null::<f64>(); 6];
        // Per direction, its valid columns `lo..hi` as `lo - 1` and `hi`, for lane compares.
        let mut above = [_mm256_set1_epi64x(0); 6];
        let mut below = [_mm256_set1_epi64x(0); 6];
        for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
            let q = y.wrapping_add_signed(dy);
            for (c, b) in b[t].iter_mut().enumerate() {
                *b = stream(ring, pos(q, c), dx, nw).as_ptr();
            }
            rest[t] = stream(&self.rest[t], y * nw, 0, nw).as_ptr();
            let cols = valid_columns(nw, dx);
            above[t] = _mm256_set1_epi64x(cols.start as i64 - 1);
            below[t] = _mm256_set1_epi64x(cols.end as i64);
        }
        for (c, a) in a.iter_mut().enumerate() {
            *a = stream(ring, pos(y, c), 0, nw).as_ptr();
        }

        // The force ring's three row slots: row y's is written; rows r = y - 2 and r + 1 are
        // read.
        let block = 18 * stride;
        let (s0, tail) = scratch.f[..3 * block].split_at_mut(block);
        let (s1, s2) = tail.split_at_mut(block);
        let (own, fr1, fr) = match y % 3 {
            0 => (s0, &*s2, &*s1),
            1 => (s1, &*s0, &*s2),
            _ => (s2, &*s1, &*s0),
        };
        let term = |t: usize, c: usize| (t * 3 + c) * stride + PAD;
        let mut terms = [[std::ptr::null::<f64>(); 6]; 3];
        let mut far = [[std::ptr::null::<f64>(); 5]; 3];
        for c in 0..3 {
            for (t, term_t) in terms[c].iter_mut().enumerate() {
                *term_t = stream(fr, term(t, c), 0, nw).as_ptr();
            }
            // The springs row r is the far end of, in the sum's order (see `sum_row`).
            far[c] = [
                stream(fr, term(0, c), 1, nw).as_ptr(),
                stream(fr, term(4, c), 2, nw).as_ptr(),
                stream(fr1, term(3, c), -1, nw).as_ptr(),
                stream(fr1, term(1, c), 0, nw).as_ptr(),
                stream(fr1, term(2, c), 1, nw).as_ptr(),
            ];
        }
        let mut out = [std::ptr::null_mut::<f64>(); 18];
        let mut rows = own.chunks_exact_mut(stride);
        for out in &mut out {
            if let Some(row) = rows.next() {
                *out = row[PAD..][..nw].as_mut_ptr();
            }
        }
        let mut total = [std::ptr::null_mut::<f64>(); 3];
        for (total, row) in total.iter_mut().zip(scratch.total.chunks_exact_mut(nw)) {
            *total = row[..nw].as_mut_ptr();
        }
        // `out` and `total` are filled: `own` holds 18 rows and `scratch.total` three.
        debug_assert!(out.iter().chain(&total).all(|p| !p.is_null()));

        let k = params.k.map(|k| _mm256_set1_pd(k));
        let weight = [0, 1, 2].map(|c| _mm256_set1_pd(params.weight[c]));
        let zero = _mm256_setzero_pd();
        let lane: __m256i = _mm256_set_epi64x(3, 2, 1, 0);
        let mut i = 0;
        while i < nw {
            let j = i.min(nw - 4);
            i += 4;
            let column = _mm256_add_epi64(_mm256_set1_epi64x(j as i64), lane);
            // SAFETY (every load and store below): each pointer is the start of a stream of
            // `nw` values (checked slices above), and `j + 4 <= nw`. The written streams (row
            // y's slot of the force ring, the totals) are disjoint from each other and from
            // every stream read after them: the ring's slots are split apart.
            unsafe {
                let av = [0, 1, 2].map(|c| _mm256_loadu_pd(a[c].add(j)));
                // NOTE: the six square roots first, then the six divisions: each division waits
                // about 20 cycles for its root, and with the roots issued together the divider
                // has the next one queued meanwhile (measured: 0.93 x the separate loops' time
                // where root-then-division per direction gave 0.97 x).
                let mut dirs = [[zero; 3]; 6];
                let mut lens = [zero; 6];
                for t in 0..6 {
                    let d =
                        [0, 1, 2].map(|c| _mm256_sub_pd(_mm256_loadu_pd(b[t][c].add(j)), av[c]));
                    let len2 = _mm256_add_pd(
                        _mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
                        _mm256_mul_pd(d[2], d[2]),
                    );
                    lens[t] = _mm256_sqrt_pd(len2);
                    dirs[t] = d;
                }
                let mut last = [zero; 3];
                for t in 0..6 {
                    let (d, len) = (dirs[t], lens[t]);
                    let stretch = _mm256_sub_pd(len, _mm256_loadu_pd(rest[t].add(j)));
                    let s = _mm256_div_pd(_mm256_mul_pd(k[t], stretch), len);
                    // A zero-length spring contributes +0.0, as the portable select gives.
                    let s = _mm256_andnot_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(len, zero), s);
                    let valid = _mm256_castsi256_pd(_mm256_and_si256(
                        _mm256_cmpgt_epi64(column, above[t]),
                        _mm256_cmpgt_epi64(below[t], column),
                    ));
                    for c in 0..3 {
                        last[c] = _mm256_and_pd(valid, _mm256_mul_pd(d[c], s));
                        _mm256_storeu_pd(out[t * 3 + c].add(j), last[c]);
                    }
                }
                // Row r's sum in the course's order: its own six springs, then the ones it is
                // the far end of; `last` holds row y's direction-5 forces, the final term.
                for c in 0..3 {
                    let mut sum = weight[c];
                    for term in terms[c] {
                        sum = _mm256_add_pd(sum, _mm256_loadu_pd(term.add(j)));
                    }
                    for term in far[c] {
                        sum = _mm256_sub_pd(sum, _mm256_loadu_pd(term.add(j)));
                    }
                    sum = _mm256_sub_pd(sum, last[c]);
                    _mm256_storeu_pd(total[c].add(j), sum);
                }
            }
        }
    }
}
