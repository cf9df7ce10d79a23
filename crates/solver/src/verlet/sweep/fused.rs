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
    __m256i, _CMP_EQ_OQ, _mm256_add_epi64, _mm256_add_pd, _mm256_and_pd, _mm256_and_si256,
    _mm256_andnot_pd, _mm256_blend_pd, _mm256_castsi256_pd, _mm256_cmp_pd, _mm256_cmpgt_epi64,
    _mm256_div_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_permute2f128_pd, _mm256_set_epi64x,
    _mm256_set1_epi64x, _mm256_set1_pd, _mm256_setzero_pd, _mm256_shuffle_pd, _mm256_sqrt_pd,
    _mm256_storeu_pd, _mm256_sub_pd, _mm256_unpackhi_pd, _mm256_unpacklo_pd,
};

use cloth_mesh::Vec3;

use super::{DIRECTIONS, PAD, POS_SLOTS, RowScratch, Stencil, SweepParams, valid_columns};
use crate::simd::{load4, store4};

/// `len` values of `s` from `start + shift`: a stream the loop reads four lanes at a time.
#[inline(always)]
fn stream(s: &[f64], start: usize, shift: isize, len: usize) -> &[f64] {
    &s[start.wrapping_add_signed(shift)..][..len]
}

impl Stencil {
    /// The springs of row `y` into the force ring, the summed force of row `r = y - 2` into
    /// `scratch.total`, and the new positions of row `r` into `next` (row `r` of the last
    /// positions, overwritten): what [`Stencil::emit_row`], [`Stencil::sum_row`] and
    /// `integrate_row` would write, bit for bit, except that pinned points are integrated like
    /// the others and the columns from the returned one on are not integrated (the caller
    /// finishes both). `positions` is row `r` of the positions; row `y`'s must be in the ring;
    /// `y` must be [`Stencil::fusable`].
    #[allow(unsafe_code)]
    #[target_feature(enable = "avx2")]
    pub(super) fn emit_sum_integrate_avx2<const STRIDE: usize>(
        &self,
        scratch: &mut RowScratch,
        params: &SweepParams,
        y: usize,
        positions: &[Vec3],
        ahead: &[Vec3],
        next: &mut [Vec3],
    ) -> usize {
        // The rings' row stride: `STRIDE`, a constant (see `ring_strides!`), or when 0
        // the scratch's.
        let nw = self.nw;
        let stride = if STRIDE == 0 { scratch.stride } else { STRIDE };
        assert_eq!(stride, scratch.stride, "the build for the scratch's stride");
        // NOTE: the rings are read through one pointer per slot (three rows of
        // positions, two of forces), at a fixed offset per stream once `stride` is a
        // constant: a pointer per stream (about 80) spilled to the stack and was
        // reloaded at every use.
        // Every ring access below is `slot + (k * stride + PAD + shift + j)` for a row
        // `k` of the slot, a shift in `-PAD..=PAD` and lanes `j..j + 4` with
        // `j + 4 <= nw`: inside row `k`, as `stride >= nw + 2 PAD` (checked here).
        assert!(stride >= nw + 2 * PAD, "rows fit their stride");
        // The position ring, checked, and its slots of rows y, y - 1 and y - 2 (`-dy`)
        // and y + 1 (written), three rows (`x`, `y`, `z`) each: four distinct slots.
        let mut slots = [std::ptr::null_mut::<f64>(); POS_SLOTS];
        for (slot, chunk) in slots
            .iter_mut()
            .zip(scratch.pos[..POS_SLOTS * 3 * stride].chunks_exact_mut(3 * stride))
        {
            *slot = chunk.as_mut_ptr();
        }
        let slot = |q: usize| slots[q % POS_SLOTS];
        let p = [slot(y), slot(y - 1), slot(y - 2)].map(<*mut f64>::cast_const);
        let written = slot(y + 1);
        let mut rest = [std::ptr::null::<f64>(); 6];
        // Per direction, its valid columns `lo..hi` as `lo - 1` and `hi`, for lane
        // compares.
        let mut above = [_mm256_set1_epi64x(0); 6];
        let mut below = [_mm256_set1_epi64x(0); 6];
        for (t, &(dx, _, _)) in DIRECTIONS.iter().enumerate() {
            rest[t] = stream(&self.rest[t], y * nw, 0, nw).as_ptr();
            let cols = valid_columns(nw, dx);
            above[t] = _mm256_set1_epi64x(cols.start as i64 - 1);
            below[t] = _mm256_set1_epi64x(cols.end as i64);
        }

        // The force ring's three row slots: row y's is written; rows r = y - 2 and r + 1
        // are read.
        let block = 18 * stride;
        let (s0, tail) = scratch.f[..3 * block].split_at_mut(block);
        let (s1, s2) = tail.split_at_mut(block);
        let (own, fr1, fr) = match y % 3 {
            0 => (s0, &*s2, &*s1),
            1 => (s1, &*s0, &*s2),
            _ => (s2, &*s1, &*s0),
        };
        // Row `t * 3 + c` of a force slot: direction `t`, component `c`.
        let term = |t: usize, c: usize| (t * 3 + c) * stride + PAD;
        let (fr, fr1) = (fr.as_ptr(), fr1.as_ptr());
        let mut out = [std::ptr::null_mut::<f64>(); 18];
        let mut rows = own.chunks_exact_mut(stride);
        for out in &mut out {
            if let Some(row) = rows.next() {
                *out = row[PAD..][..nw].as_mut_ptr();
            }
        }
        let mut total = [std::ptr::null_mut::<f64>(); 3];
        for (total, row) in total.iter_mut().zip(scratch.total.chunks_exact_mut(stride)) {
            *total = row[..nw].as_mut_ptr();
        }
        // `own` holds 18 rows and `scratch.total` three, so every pointer is set; checked,
        // as the loop's SAFETY rests on it (once a row, next to 4 * 18 stores a column
        // group).
        assert!(out.iter().chain(&total).all(|p| !p.is_null()));

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
            // The pointer loads and stores below rest on one argument: each stream pointer
            // starts `nw` values (checked slices above) and `j + 4 <= nw`; each ring
            // access is inside its slot (`3 stride` values, checked slices) and its row
            // (`stride >= nw + 2 PAD`, see above), and force slots are 18 rows (`block`).
            // The written streams (row y + 1's slot of the position ring, row y's slot of
            // the force ring, the totals) are disjoint from each other and from every
            // stream read after them: the rings' slots are split apart.
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
                let xy_even = _mm256_blend_pd::<0b1100>(m[0], m[1]);
                let yz = _mm256_blend_pd::<0b1100>(m[1], m[2]);
                let zx = _mm256_permute2f128_pd::<0x21>(m[0], m[2]);
                let xy_odd = _mm256_shuffle_pd::<0b0101>(zx, yz);
                let split = [
                    _mm256_unpacklo_pd(xy_even, xy_odd),
                    _mm256_unpackhi_pd(xy_even, xy_odd),
                    _mm256_blend_pd::<0b1010>(zx, yz),
                ];
                for (c, v) in split.into_iter().enumerate() {
                    // SAFETY: lanes `j..j + 4` of row `c` of row y + 1's slot (see above).
                    unsafe { _mm256_storeu_pd(written.add(c * stride + PAD + j), v) };
                }
            }
            // NOTE: the six square roots first, then the six divisions: each division
            // waits about 20 cycles for its root, and with the roots issued together the
            // divider has the next one queued meanwhile.
            let mut dirs = [[zero; 3]; 6];
            let mut lens = [zero; 6];
            let mut last = [zero; 3];
            // SAFETY: loads of lanes `j..j + 4` of rows of the position ring's slots
            // (shifted by `dx` in `-PAD..=PAD`) and of the rest lengths' stream; stores
            // to the same lanes of row y's slot of the force ring (see above).
            unsafe {
                let av = [0, 1, 2].map(|c| _mm256_loadu_pd(p[0].add(c * stride + PAD + j)));
                for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
                    // Row `y + dy`, shifted by `dx`.
                    let row = p[dy.unsigned_abs()];
                    let d = [0, 1, 2].map(|c| {
                        let at = row.add(c * stride + j).offset(PAD as isize + dx);
                        _mm256_sub_pd(_mm256_loadu_pd(at), av[c])
                    });
                    let len2 = _mm256_add_pd(
                        _mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
                        _mm256_mul_pd(d[2], d[2]),
                    );
                    lens[t] = _mm256_sqrt_pd(len2);
                    dirs[t] = d;
                }
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
            }
            // Row r's sum in the course's order: its own six springs, then the ones it is
            // the far end of; `last` holds row y's direction-5 forces, the final term.
            let mut sums = [zero; 3];
            // SAFETY: loads of lanes `j..j + 4` (shifted by -1 to 2) of rows of the force
            // ring's read slots, stores to the same lanes of the totals (see above).
            unsafe {
                for c in 0..3 {
                    let mut sum = weight[c];
                    for t in 0..6 {
                        sum = _mm256_add_pd(sum, _mm256_loadu_pd(fr.add(term(t, c) + j)));
                    }
                    // The springs row r is the far end of, in the sum's order (see
                    // `sum_row`): `(slot, row, shift)`.
                    let far = [
                        (fr, term(0, c), 1),
                        (fr, term(4, c), 2),
                        (fr1, term(3, c), -1),
                        (fr1, term(1, c), 0),
                        (fr1, term(2, c), 1),
                    ];
                    for (slot, row, shift) in far {
                        let at = slot.add(row + j).offset(shift);
                        sum = _mm256_sub_pd(sum, _mm256_loadu_pd(at));
                    }
                    sum = _mm256_sub_pd(sum, last[c]);
                    _mm256_storeu_pd(total[c].add(j), sum);
                    sums[c] = sum;
                }
            }
            if integrate {
                // The four points' forces interleaved as they lie in memory, `x y z x |
                // y z x y | z x y z`, then Verlet on three vectors of four values each.
                let [fx, fy, fz] = sums;
                let xy_even = _mm256_unpacklo_pd(fx, fy);
                let xy_odd = _mm256_unpackhi_pd(fx, fy);
                let zx = _mm256_unpacklo_pd(fz, xy_odd);
                let yz = _mm256_unpackhi_pd(xy_odd, fz);
                let f = [
                    _mm256_permute2f128_pd::<0x20>(xy_even, zx),
                    _mm256_blend_pd::<0b1100>(yz, xy_even),
                    _mm256_permute2f128_pd::<0x31>(zx, yz),
                ];
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
