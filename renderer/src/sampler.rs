//! Deterministic per-sample random numbers: every value is a hash of the pixel index, the
//! sample index and a dimension, so images are identical for any thread count and order.

/// SplitMix64's finaliser: a bijective 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform number in [0, 1) for (pixel, sample, dimension).
#[inline]
pub fn uniform(pixel: u64, sample: u64, dim: u64) -> f64 {
    let h =
        mix64(mix64(mix64(pixel ^ 0x9e37_79b9_7f4a_7c15).wrapping_add(sample)).wrapping_add(dim));
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The position inside the pixel (in [0, 1)²) of sample `s` of `n`. A single sample is
/// the pixel centre; more samples are jittered uniformly.
#[inline]
pub fn pixel_offset(pixel: u64, s: u32, n: u32) -> (f64, f64) {
    if n == 1 {
        return (0.5, 0.5);
    }
    (uniform(pixel, s as u64, 0), uniform(pixel, s as u64, 1))
}
