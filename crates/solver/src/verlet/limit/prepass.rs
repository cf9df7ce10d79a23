//! The pre-pass's rows in AVX2 intrinsics: all six directions of four points per loop turn.
//!
//! # Why
//!
//! The portable row (`marks_row`) runs one loop per direction and gathers each direction's
//! marks in memory, a load, an or and a store per point and direction. Here the six compares
//! of a group of four points are or-ed in a register and narrowed to four bytes once, so each
//! point costs its arithmetic and one store.
//!
//! # Same decisions
//!
//! Each lane computes the squared length of `marks_row` (the course's `positions[b] -
//! positions[a]` and `dist2`, operand for operand, no fused multiply-add) and compares it with
//! the same bound, so a spring that exists gets the same mark. Lanes of springs that do not
//! exist (edge columns, whose partner is in the row before or after) compare real points of
//! the window and set bits the sweep never reads: it masks every point's marks with the
//! springs it emits.

use std::arch::x86_64::{
    _CMP_NLE_UQ, _mm_cvtsi128_si32, _mm256_add_pd, _mm256_and_si256, _mm256_castpd_si256,
    _mm256_castsi256_si128, _mm256_cmp_pd, _mm256_extracti128_si256, _mm256_mul_pd,
    _mm256_or_si256, _mm256_set1_epi64x, _mm256_set1_pd, _mm256_setr_epi8, _mm256_setzero_si256,
    _mm256_shuffle_epi8, _mm256_sub_pd,
};

use super::super::sweep::DIRECTIONS;
use crate::simd::{Avx2, load4};

/// How far the directions reach before (`dx < 0`) and after the emitter's column, in the row
/// `dy` = 0, -1 and -2 from it.
const LO: [usize; 3] = [2, 1, 0];
const HI: [usize; 3] = [0, 1, 0];

/// The marks of the `out.len()` springs emitters starting at index `a0` of the window copied
/// into `soa`, a row of a grid `out.len()` wide whose direction-`(dx, dy)` partners are at
/// `dx + dy out.len()` from them (all negative, at least `-a0`: every partner row is in the
/// window), against the direction bounds `floor`.
/// `out.len()` must be at least 4; the last group overlaps the one before when it is not a
/// multiple of 4, and writes the same bytes again.
///
/// # Panics
/// When a partner or an emitter is outside `soa` (never, under the conditions above).
#[target_feature(enable = "avx2")]
pub(super) fn marks_row_avx2(
    _: Avx2,
    soa: &[Vec<f64>; 3],
    floor: &[f64; 6],
    a0: usize,
    out: &mut [u8],
) {
    let nw = out.len();
    assert!(nw >= 4, "a row of at least one four-lane group");
    let floor = floor.map(|f| _mm256_set1_pd(f));
    let bit = [0, 1, 2, 3, 4, 5].map(|t| _mm256_set1_epi64x(1 << t));
    // Byte 0 of each 64-bit lane to bytes 0 and 1 of its 128-bit half.
    let narrow = _mm256_setr_epi8(
        0, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, //
        0, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    );
    // The three rows (`dy` = 0, -1, -2) of each coordinate as slices of the window, from
    // `LO[k]` values before the row's first emitter to `HI[k]` after its last: with `j + 4 <=
    // nw` the compiler finds each load in bounds once the direction loop is unrolled.
    let mut rows: [[&[f64]; 3]; 3] = [[&[]; 3]; 3];
    for (k, row) in rows.iter_mut().enumerate() {
        let start = a0 - (k * nw + LO[k]);
        for (r, s) in row.iter_mut().zip(soa) {
            *r = &s[start..][..LO[k] + nw + HI[k]];
        }
    }
    let mut i = 0;
    while i < nw {
        let j = i.min(nw - 4);
        i += 4;
        let own = rows[0];
        let at = j + LO[0];
        let pa = [
            load4(&own[0][at..]),
            load4(&own[1][at..]),
            load4(&own[2][at..]),
        ];
        let mut marks = _mm256_setzero_si256();
        for (t, &(dx, dy, _)) in DIRECTIONS.iter().enumerate() {
            let k = dy.unsigned_abs();
            let (row, at) = (rows[k], (j + LO[k]).wrapping_add_signed(dx));
            let d = [
                _mm256_sub_pd(load4(&row[0][at..]), pa[0]),
                _mm256_sub_pd(load4(&row[1][at..]), pa[1]),
                _mm256_sub_pd(load4(&row[2][at..]), pa[2]),
            ];
            let len2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(d[0], d[0]), _mm256_mul_pd(d[1], d[1])),
                _mm256_mul_pd(d[2], d[2]),
            );
            // Not proven inside: `!(len2 <= floor)`, true for a NaN too.
            let out = _mm256_castpd_si256(_mm256_cmp_pd::<_CMP_NLE_UQ>(len2, floor[t]));
            marks = _mm256_or_si256(marks, _mm256_and_si256(out, bit[t]));
        }
        let bytes = _mm256_shuffle_epi8(marks, narrow);
        let low = _mm_cvtsi128_si32(_mm256_castsi256_si128(bytes)) as u32 & 0xffff;
        let high = _mm_cvtsi128_si32(_mm256_extracti128_si256::<1>(bytes)) as u32 & 0xffff;
        out[j..j + 4].copy_from_slice(&(low | high << 16).to_le_bytes());
    }
}
