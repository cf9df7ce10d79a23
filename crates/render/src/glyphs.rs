//! Glyph ramps and ordered (Bayer) dithering: how an intensity becomes a character.
//!
//! Every ramp starts at a visible glyph, so a lit surface in shadow never looks like a hole.
//! The front and back faces of the cloth, the sphere and the floor use disjoint glyph sets, so
//! the picture reads without colour.

/// The cloth's front face (the side its normals point to), dark to bright.
pub const FRONT_RAMP: &[char] = &['.', ':', '-', '=', '+', '*', '#', '%', '@'];
/// The cloth's back face, dark to bright.
pub const BACK_RAMP: &[char] = &['`', '\'', ',', ';', '~', 'v', 'x', 'X', 'W'];
/// Spheres, dark to bright.
pub const SPHERE_RAMP: &[char] = &['^', '"', 'c', 'u', 'o', 'a', 'e', 'Q', 'B'];
/// One colour of floor tile (the other is blank) and a floor seen edge-on.
pub const FLOOR_GLYPH: char = '_';
/// A pinned point.
pub const PIN_GLYPH: char = 'O';
/// The point a hand holds.
pub const HAND_GLYPH: char = '&';

/// The 4 x 4 Bayer matrix: thresholds in a pattern that spreads each level evenly.
const BAYER4: [[u8; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

/// The dither threshold of pixel `(x, y)`, in (0, 1): the cell's Bayer rank plus a half, / 16.
#[inline]
#[must_use]
pub fn bayer_threshold(x: usize, y: usize) -> f32 {
    (f32::from(BAYER4[y & 3][x & 3]) + 0.5) / 16.0
}

/// The ramp level for `intensity` in [0, 1] at pixel `(x, y)`, among `levels` levels.
///
/// The intensity is placed between two adjacent levels; the fraction of the way to the upper
/// one is compared with the Bayer threshold, so over a 4 x 4 patch of equal intensity the mean
/// level equals `intensity * (levels - 1)` to within 1/16 of a level. Deterministic: it depends
/// on the pixel's position only, never on its neighbours (no error diffusion).
#[inline]
#[must_use]
pub fn dithered_level(intensity: f32, levels: usize, x: usize, y: usize) -> usize {
    let top = levels.saturating_sub(1);
    let v = intensity.clamp(0.0, 1.0) * top as f32;
    // v >= 0, so truncation is floor (and needs no libm call).
    let base = v as usize;
    let up = usize::from(v - base as f32 > bayer_threshold(x, y));
    (base + up).min(top)
}

/// The glyph of `ramp` for `intensity` at pixel `(x, y)`.
#[inline]
#[must_use]
pub fn ramp_glyph(ramp: &[char], intensity: f32, x: usize, y: usize) -> char {
    ramp.get(dithered_level(intensity, ramp.len(), x, y))
        .copied()
        .unwrap_or(' ')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_are_disjoint_and_start_visible() {
        let all: Vec<char> = [FRONT_RAMP, BACK_RAMP, SPHERE_RAMP]
            .concat()
            .into_iter()
            .chain([FLOOR_GLYPH, PIN_GLYPH, HAND_GLYPH])
            .collect();
        for (i, a) in all.iter().enumerate() {
            assert_ne!(*a, ' ');
            assert!(!all[i + 1..].contains(a), "{a} used twice");
        }
    }

    #[test]
    fn extremes_map_to_the_ends_of_the_ramp() {
        for (x, y) in [(0, 0), (3, 1), (2, 2)] {
            assert_eq!(ramp_glyph(FRONT_RAMP, 0.0, x, y), '.');
            assert_eq!(ramp_glyph(FRONT_RAMP, 1.0, x, y), '@');
            assert_eq!(ramp_glyph(FRONT_RAMP, 7.0, x, y), '@');
        }
    }

    #[test]
    fn dithering_preserves_the_mean_level_over_a_bayer_tile() {
        // 16 distinct thresholds (k + 0.5) / 16: a fraction f goes up on exactly round(16 f) of
        // them, so the tile's mean level is within half a sixteenth (1/32) of the exact one;
        // 1e-4 covers f32 rounding of the intensity.
        for k in 0..=100 {
            let intensity = k as f32 / 100.0;
            let levels = FRONT_RAMP.len();
            let sum: usize = (0..4)
                .flat_map(|y| (0..4).map(move |x| (x, y)))
                .map(|(x, y)| dithered_level(intensity, levels, x, y))
                .sum();
            let mean = sum as f32 / 16.0;
            let exact = intensity * (levels - 1) as f32;
            assert!(
                (mean - exact).abs() <= 1.0 / 32.0 + 1e-4,
                "{intensity}: {mean} vs {exact}"
            );
        }
    }

    #[test]
    fn levels_never_decrease_with_intensity_at_a_pixel() {
        for (x, y) in [(0, 0), (1, 2), (3, 3)] {
            let mut last = 0;
            for k in 0..=1000 {
                let l = dithered_level(k as f32 / 1000.0, 9, x, y);
                assert!(l >= last);
                last = l;
            }
        }
    }
}
