//! A tiny deterministic random number generator.

/// SplitMix64 (Steele, Lea and Flood 2014): a 64-bit generator with a one-word state.
///
/// The course seeds the vertical cloth's z-jitter with C's `rand()`; we need the same kind of
/// tiny offsets but bit-identical runs on every machine, so the generator is fixed here rather
/// than taken from a crate whose stream may change between versions.
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator whose stream is fully determined by `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform number in `[lo, hi)`, from the top 53 bits so every value is exact in `f64`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_gives_same_stream_and_values_stay_in_range() {
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        for _ in 0..1000 {
            let x = a.uniform(-0.001, 0.001);
            assert_eq!(x.to_bits(), b.uniform(-0.001, 0.001).to_bits());
            assert!((-0.001..0.001).contains(&x));
        }
    }
}
