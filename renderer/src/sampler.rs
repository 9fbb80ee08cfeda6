//! Deterministic samplers: every value is a function of the pixel index, the sample index
//! and the dimension, so images are identical for any thread count and order.
//!
//! - `independent`: a hash of (pixel, sample, dimension).
//! - `stratified`: each dimension (pairs of dimensions when spp is a perfect square) is cut
//!   into spp strata; sample k takes a stratum through a per-(pixel, dimension) random
//!   permutation and jitters inside it.
//! - `sobol`: the (0,2)-sequence formed by the first two Sobol dimensions, Owen-style
//!   scrambled by a random XOR per (pixel, dimension pair) and with the sample index
//!   shuffled per dimension pair (Kollig and Keller 2002, "Efficient multidimensional
//!   sampling"): low discrepancy in every pair of dimensions.

/// Which sampler places the samples.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
pub enum SamplerKind {
    /// Independent uniform samples.
    #[default]
    Independent,
    /// Stratified (jittered) samples.
    Stratified,
    /// A scrambled (0,2)-sequence.
    Sobol,
}

/// SplitMix64's finaliser: a bijective 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[inline]
fn hash3(a: u64, b: u64, c: u64) -> u64 {
    mix64(mix64(mix64(a ^ 0x9e37_79b9_7f4a_7c15).wrapping_add(b)).wrapping_add(c))
}

#[inline]
fn to_unit(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform number in [0, 1) for (pixel, sample, dimension).
#[inline]
pub fn uniform(pixel: u64, sample: u64, dim: u64) -> f64 {
    to_unit(hash3(pixel, sample, dim))
}

/// A random permutation of `0..n` evaluated at `i` (Kensler's "Correlated multi-jittered
/// sampling", 2013, permute()), keyed by `key`.
#[inline]
pub fn permute(mut i: u32, n: u32, key: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let mut w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= key;
        i = i.wrapping_mul(0xe170_893d);
        i ^= key >> 16;
        i ^= (i & w) >> 4;
        i ^= key >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= key >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | key >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            break;
        }
    }
    (i.wrapping_add(key)) % n
}

/// The first two dimensions of Sobol's sequence at index `i`, as 32-bit fractions.
#[inline]
fn sobol2(i: u32) -> (u32, u32) {
    let a = i.reverse_bits(); // van der Corput
    let mut b = 0u32;
    let mut v = 1u32 << 31;
    let mut k = i;
    while k != 0 {
        if k & 1 != 0 {
            b ^= v;
        }
        k >>= 1;
        v ^= v >> 1;
    }
    (a, b)
}

/// The samples of one pixel sample: call [`PixelSampler::next_2d`] and
/// [`PixelSampler::next_1d`] in a fixed order per path.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    kind: SamplerKind,
    pixel: u64,
    sample: u32,
    spp: u32,
    dim: u32,
    square: u32,
}

impl PixelSampler {
    /// Sample `sample` of `spp` in pixel `pixel`.
    pub fn new(kind: SamplerKind, pixel: u64, sample: u32, spp: u32) -> Self {
        let root = (spp as f64).sqrt().round() as u32;
        PixelSampler {
            kind,
            pixel,
            sample,
            spp,
            dim: 0,
            square: if root * root == spp { root } else { 0 },
        }
    }

    fn key(&self, dim: u32) -> u64 {
        hash3(self.pixel, 0x5eed_0000 + dim as u64, self.kind as u64)
    }

    /// The next number in [0, 1).
    pub fn next_1d(&mut self) -> f64 {
        let d = self.dim;
        self.dim += 1;
        match self.kind {
            SamplerKind::Independent => uniform(self.pixel, self.sample as u64, d as u64),
            SamplerKind::Stratified => {
                let key = self.key(d);
                let stratum = permute(self.sample, self.spp, key as u32);
                (stratum as f64 + to_unit(hash3(key, self.sample as u64, 1))) / self.spp as f64
            }
            SamplerKind::Sobol => {
                let key = self.key(d);
                let i = permute(self.sample, self.spp, key as u32);
                let (a, _) = sobol2(i);
                ((a ^ (key >> 32) as u32) as f64) * (1.0 / 4_294_967_296.0)
            }
        }
    }

    /// The next point in [0, 1)².
    pub fn next_2d(&mut self) -> (f64, f64) {
        match self.kind {
            SamplerKind::Independent => (self.next_1d(), self.next_1d()),
            SamplerKind::Stratified if self.square > 0 => {
                let d = self.dim;
                self.dim += 2;
                let key = self.key(d);
                let n = self.square;
                let stratum = permute(self.sample, self.spp, key as u32);
                let (sx, sy) = (stratum % n, stratum / n);
                let jx = to_unit(hash3(key, self.sample as u64, 1));
                let jy = to_unit(hash3(key, self.sample as u64, 2));
                ((sx as f64 + jx) / n as f64, (sy as f64 + jy) / n as f64)
            }
            SamplerKind::Stratified => (self.next_1d(), self.next_1d()),
            SamplerKind::Sobol => {
                let d = self.dim;
                self.dim += 2;
                let key = self.key(d);
                let i = permute(self.sample, self.spp, key as u32);
                let (a, b) = sobol2(i);
                let (sa, sb) = ((key >> 32) as u32, key as u32 ^ 0x9e37_79b9);
                let s = 1.0 / 4_294_967_296.0;
                ((a ^ sa) as f64 * s, (b ^ sb) as f64 * s)
            }
        }
    }
}
