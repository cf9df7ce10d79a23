//! The one place the solver learns which vector instructions the CPU runs.
//!
//! A [`Simd`] is detected once, when a solver is built, and handed
//! to every fast path. The AVX2 builds of the passes take its [`Avx2`] proof as an argument:
//! holding one is the invariant their `unsafe` calls rest on, and nothing else in the crate asks
//! the CPU.

/// Proof that the CPU runs AVX2: only [`Simd::detect`] makes one, after asking the CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Avx2(());

/// The vector instructions the fast paths may use on this CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Simd {
    avx2: Option<Avx2>,
}

impl Simd {
    /// What this CPU runs.
    pub(crate) fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Self {
                avx2: Some(Avx2(())),
            };
        }
        Self::PORTABLE
    }

    /// No vector extension: the portable builds everywhere.
    pub(crate) const PORTABLE: Self = Self { avx2: None };

    /// AVX2, when the CPU runs it.
    pub(crate) fn avx2(self) -> Option<Avx2> {
        self.avx2
    }
}

/// The vector instruction sets the solver's kernels use on this build and this CPU: those the
/// compiler was allowed to use everywhere, and on x86-64 the wider ones the kernels choose at
/// run time when the CPU has them (what `--version` reports).
#[must_use]
pub fn vector_paths() -> String {
    let mut compiled = Vec::new();
    for (on, name) in [
        (cfg!(target_feature = "sse2"), "sse2"),
        (cfg!(target_feature = "avx2"), "avx2"),
        (cfg!(target_feature = "fma"), "fma"),
        (cfg!(target_feature = "avx512f"), "avx512f"),
        (cfg!(target_feature = "neon"), "neon"),
    ] {
        if on {
            compiled.push(name);
        }
    }
    let compiled = if compiled.is_empty() {
        "none".to_owned()
    } else {
        compiled.join(", ")
    };
    #[allow(unused_mut)]
    let mut text = format!("{} compiled in ({})", compiled, std::env::consts::ARCH);
    #[cfg(target_arch = "x86_64")]
    {
        let avx2 = if Simd::detect().avx2().is_some() {
            "present"
        } else {
            "absent"
        };
        text.push_str("; chosen at run time: avx2 (");
        text.push_str(avx2);
        text.push_str(" on this CPU)");
    }
    text
}

impl Default for Simd {
    /// [`Simd::detect`]: a solver built by default uses what the CPU runs.
    fn default() -> Self {
        Self::detect()
    }
}

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{__m256d, _mm256_blend_pd, _mm256_permute2f128_pd, _mm256_shuffle_pd};

/// The first four values of `values` as an AVX register: the vector passes' load, bounds
/// checked, with no `unsafe`.
///
/// # Panics
/// When `values` holds fewer than four values.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) fn load4(values: &[f64]) -> __m256d {
    bytemuck::pod_read_unaligned(bytemuck::cast_slice(&values[..4]))
}

/// Writes `v` into the first four values of `values` ([`load4`]'s inverse).
///
/// # Panics
/// When `values` holds fewer than four values.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) fn store4(values: &mut [f64], v: __m256d) {
    values[..4].copy_from_slice(bytemuck::cast_slice(&[v]));
}

/// The x, y and z lanes of four points stored as `x y z x | y z x y | z x y z` in `m`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) fn deinterleave(m: [__m256d; 3]) -> [__m256d; 3] {
    let xy = _mm256_blend_pd::<0b1100>(m[0], m[1]); // x0 y0 x2 y2
    let zx = _mm256_permute2f128_pd::<0x21>(m[0], m[2]); // z0 x1 z2 x3
    let yz = _mm256_blend_pd::<0b1100>(m[1], m[2]); // y1 z1 y3 z3
    [
        _mm256_blend_pd::<0b1010>(xy, zx),
        _mm256_shuffle_pd::<0b0101>(xy, yz),
        _mm256_blend_pd::<0b1010>(zx, yz),
    ]
}

/// [`deinterleave`]'s inverse: four points' x, y and z lanes as they lie in memory.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) fn interleave([x, y, z]: [__m256d; 3]) -> [__m256d; 3] {
    let xy = _mm256_shuffle_pd::<0b0000>(x, y); // x0 y0 x2 y2
    let yz = _mm256_shuffle_pd::<0b1111>(y, z); // y1 z1 y3 z3
    let zx = _mm256_blend_pd::<0b1010>(z, x); // z0 x1 z2 x3
    [
        _mm256_permute2f128_pd::<0x20>(xy, zx),
        _mm256_blend_pd::<0b1100>(yz, xy),
        _mm256_permute2f128_pd::<0x31>(zx, yz),
    ]
}
