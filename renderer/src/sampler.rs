//! Deterministic samplers: every value is a function of the pixel index, the sample index
//! and the dimension, so images are identical for any thread count and order.
//!
//! - `independent`: a hash of (pixel, sample, dimension).
//! - `stratified`: each dimension (pairs of dimensions when spp is a perfect square) is cut
//!   into spp strata; sample k takes a stratum through a per-(pixel, dimension) random
//!   permutation and jitters inside it.
//! - `sobol`: the (0,2)-sequence formed by the first two Sobol dimensions, Owen-scrambled
//!   (nested uniform scrambling, by a hash per (pixel, dimension): Burley 2020, "Practical
//!   hash-based Owen scrambling", with Vegdahl's 2021 constants) and with the sample index
//!   shuffled per dimension pair (Kollig and Keller 2002, "Efficient multidimensional
//!   sampling"), by the same scrambling of the index's bits, read from the top, as Burley
//!   does: low discrepancy in every pair of dimensions, and each point uniformly random
//!   inside its elementary intervals, which a random XOR (a digital shift) is not. At a
//!   power-of-two count the index runs over a set of that many; at any other count the
//!   samples are the first of the shuffled sequence of [`SEQUENCE`].

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
    hash_mixed(mix_first(a), b, c)
}

/// [`hash3`]'s first step, which depends on `a` alone: a sampler does it once per pixel.
#[inline]
fn mix_first(a: u64) -> u64 {
    mix64(a ^ 0x9e37_79b9_7f4a_7c15)
}

/// [`hash3`] from `mix_first(a)`.
#[inline]
fn hash_mixed(first: u64, b: u64, c: u64) -> u64 {
    mix64(mix64(first.wrapping_add(b)).wrapping_add(c))
}

/// The top 53 bits of `h` as a number in [0, 1).
#[inline]
pub(crate) fn to_unit(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform number in [0, 1) for (pixel, sample, dimension).
#[inline]
pub fn uniform(pixel: u64, sample: u64, dim: u64) -> f64 {
    to_unit(hash3(pixel, sample, dim))
}

/// `(cos 2πu, sin 2πu)` for `u` in [0, 1): the azimuth of a sampled direction. Written
/// out in plain arithmetic, so that it gives the same bits on every machine and, on the
/// x86-64-v3 build, costs no call into the system's maths library (whose `sincos` took 7 %
/// of a physical render): there `mul_add` is one FMA instruction (elsewhere libm's `fma`,
/// correctly rounded, so the same bits).
/// `8u` splits into an octant `k` and a fraction `f`; the angle inside the octant,
/// `x = f·π/4` (or `(1 − f)·π/4` in the odd octants, measured from the octant's far
/// end), is at most π/4, where Taylor series to x¹⁵ and x¹⁶ are within 5·10⁻¹⁷ of sin x
/// and cos x; the octant then swaps the pair and sets their signs, with no branch.
#[inline]
pub fn cos_sin_turn(u: f64) -> (f64, f64) {
    let v = u * 8.0;
    let k = v.floor();
    let f = v - k;
    let k = k as i64 as u64 & 7;
    let odd = k & 1 == 1;
    let x = if odd { 1.0 - f } else { f } * std::f64::consts::FRAC_PI_4;
    let x2 = x * x;
    // Horner from the highest term: sin x = x(1 − x²/3! + x⁴/5! − ...), cos x = 1 − x²/2! + ...
    const SIN: [f64; 8] = [
        -1.0 / 1_307_674_368_000.0,
        1.0 / 6_227_020_800.0,
        -1.0 / 39_916_800.0,
        1.0 / 362_880.0,
        -1.0 / 5_040.0,
        1.0 / 120.0,
        -1.0 / 6.0,
        1.0,
    ];
    const COS: [f64; 9] = [
        1.0 / 20_922_789_888_000.0,
        -1.0 / 87_178_291_200.0,
        1.0 / 479_001_600.0,
        -1.0 / 3_628_800.0,
        1.0 / 40_320.0,
        -1.0 / 720.0,
        1.0 / 24.0,
        -1.0 / 2.0,
        1.0,
    ];
    let s = x * SIN[1..].iter().fold(SIN[0], |acc, &c| acc.mul_add(x2, c));
    let c = COS[1..].iter().fold(COS[0], |acc, &c| acc.mul_add(x2, c));
    // Octants 1, 2, 5 and 6 swap the pair (the angle is π/2 away from the octant's x);
    // the cosine is negative in octants 2 to 5, the sine in 4 to 7.
    let swap = (k + 1) & 2 != 0;
    let (a, b) = if swap { (s, c) } else { (c, s) };
    let neg_cos = ((k + 2) & 4) << 61;
    let neg_sin = (k & 4) << 61;
    (
        f64::from_bits(a.to_bits() ^ neg_cos),
        f64::from_bits(b.to_bits() ^ neg_sin),
    )
}

/// `i % n`, by a mask when `n` is a power of two (sample counts usually are): the same
/// value without a division's latency. `n > 0`.
#[inline(always)]
fn rem(i: u32, n: u32) -> u32 {
    if n.is_power_of_two() {
        i & (n - 1)
    } else {
        i % n
    }
}

/// `i / n`, by a shift when `n` is a power of two, as [`rem`].
#[inline(always)]
fn quot(i: u32, n: u32) -> u32 {
    if n.is_power_of_two() {
        i >> n.trailing_zeros()
    } else {
        i / n
    }
}

/// `x / n`, by a multiplication when `n` is a power of two: its reciprocal is exact, so
/// the product is the quotient, bit for bit (for the `x` here, far from the subnormals).
#[inline(always)]
fn over(x: f64, n: u32) -> f64 {
    if n.is_power_of_two() {
        x * (1.0 / n as f64)
    } else {
        x / n as f64
    }
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
    // The final rotation by the key, without the wrap-around of `(i + key) % n` in 32
    // bits (as the paper writes it): when i + key passes 2³², the wrapped sum is a
    // different rotation for those i, and two indices can land on the same output.
    let s = u64::from(i) + u64::from(rem(key, n));
    (if s >= u64::from(n) {
        s - u64::from(n)
    } else {
        s
    }) as u32
}

/// The first two dimensions of Sobol's sequence at index `i`, as 32-bit fractions: the
/// definition, bit by bit, which [`sobol_reversed`] computes by tables.
#[cfg(test)]
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

/// Sobol's second dimension, its bits reversed, by bytes of the index: entry `[k][x]` is
/// the XOR of the (reversed) direction numbers of the set bits of byte `x` at byte `k` of
/// the index (direction number `j` is `v_j`, `v_0 = 2^31`, `v_{j+1} = v_j ^ (v_j >> 1)`).
const SOBOL_REVERSED: [[u32; 256]; 4] = {
    let mut dirs = [0u32; 32];
    let mut v = 1u32 << 31;
    let mut j = 0;
    while j < 32 {
        dirs[j] = v.reverse_bits();
        v ^= v >> 1;
        j += 1;
    }
    let mut t = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut x = 0;
        while x < 256 {
            let mut bit = 0;
            while bit < 8 {
                if (x >> bit) & 1 != 0 {
                    t[k][x] ^= dirs[8 * k + bit];
                }
                bit += 1;
            }
            x += 1;
        }
        k += 1;
    }
    t
};

/// The first two dimensions of Sobol's sequence at index `i`, each as a 32-bit fraction
/// with its bits reversed (the digit of weight ½ lowest), which is how [`owen_reversed`]
/// takes them: the first is `i` itself (van der Corput's radical inverse reverses the
/// bits), the second four table lookups. (A loop over the index's bits, branch-free, cost
/// a mispredicted exit per call; with the reversals that [`owen_reversed`] spares, the
/// sobol sampler took 22 % of a `direct` frame.)
#[inline]
fn sobol_reversed(i: u32) -> (u32, u32) {
    let t = &SOBOL_REVERSED;
    let b = t[0][i as u8 as usize]
        ^ t[1][(i >> 8) as u8 as usize]
        ^ t[2][(i >> 16) as u8 as usize]
        ^ t[3][(i >> 24) as u8 as usize];
    (i, b)
}

/// Owen's nested uniform scrambling of a 32-bit fraction, keyed by `seed`, given the
/// fraction's bits reversed (so that its most significant digit is the lowest bit): they
/// go through a hash in which each bit can flip only as a function of the bits below it
/// (an addition, multiplications by odd numbers, and XORs with multiples by even numbers
/// carry only upwards), and are reversed back. So the flip of each digit depends on the
/// digits above it alone: every elementary interval is mapped onto one of the same size,
/// and a (0, m, 2)-net stays one.
#[inline(always)]
fn owen_reversed(v: u32, seed: u32) -> u32 {
    reverse32(owen_hash(v, seed))
}

/// [`owen_reversed`] of two fractions at once: the two hashes, then both reversals in one
/// register ([`reverse32x2`]).
#[inline(always)]
fn owen_reversed2(a: u32, seed_a: u32, b: u32, seed_b: u32) -> (u32, u32) {
    reverse32x2(owen_hash(a, seed_a), owen_hash(b, seed_b))
}

/// [`owen_reversed`]'s hash, before the bits are reversed back.
#[inline(always)]
fn owen_hash(mut v: u32, seed: u32) -> u32 {
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v
}

/// `v.reverse_bits()`. x86-64 has no instruction for it, and the standard library's form
/// (a byte swap, then three rounds of masks and shifts, each on the last) is a chain of
/// about ten cycles on the way of every sobol number ([`owen_reversed`]). Where SSSE3 is
/// there (the x86-64-v3 build), [`reverse32x2`]'s byte shuffles; elsewhere four lookups
/// of a byte's reversal, which run side by side. Same bits.
#[inline(always)]
fn reverse32(v: u32) -> u32 {
    #[cfg(all(target_arch = "x86_64", target_feature = "ssse3"))]
    {
        reverse32x2(v, 0).0
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "ssse3")))]
    {
        reverse32_by_bytes(v)
    }
}

/// `(a.reverse_bits(), b.reverse_bits())`. With SSSE3 both words go into one register,
/// where two byte shuffles look up each half byte's reversal in a 16-entry table held in a
/// register and a third reverses the bytes of each word: about a dozen instructions for
/// the pair, against about 15 a word for the lookups of [`reverse32_by_bytes`] (which were
/// 6.5 % of an adaptive `sobol` render's instructions on the Cornell box, the sampler's
/// largest part; renderer/docs/performance.md, 2026-11-29 evening).
#[inline(always)]
fn reverse32x2(a: u32, b: u32) -> (u32, u32) {
    #[cfg(all(target_arch = "x86_64", target_feature = "ssse3"))]
    {
        use std::arch::x86_64::*;
        // SAFETY: the cfg above makes SSE2 and SSSE3 part of the build's target; the only
        // memory read is of the two 16-byte constant tables, in bounds.
        unsafe {
            let v = _mm_cvtsi64_si128((u64::from(b) << 32 | u64::from(a)) as i64);
            let low = _mm_set1_epi8(0x0f);
            // Entry n: n's four bits reversed, in a byte's high half or its low one.
            const NIBBLE: [u8; 16] = [0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15];
            const TO_HIGH: [u8; 16] = {
                let mut t = NIBBLE;
                let mut k = 0;
                while k < 16 {
                    t[k] <<= 4;
                    k += 1;
                }
                t
            };
            let to_high = _mm_loadu_si128(TO_HIGH.as_ptr().cast());
            let to_low = _mm_loadu_si128(NIBBLE.as_ptr().cast());
            let lo = _mm_and_si128(v, low);
            let hi = _mm_and_si128(_mm_srli_epi16::<4>(v), low);
            let bytes = _mm_or_si128(_mm_shuffle_epi8(to_high, lo), _mm_shuffle_epi8(to_low, hi));
            // Each word's bytes in reverse order (the upper 8 bytes are not read).
            let order = _mm_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
            let r = _mm_cvtsi128_si64(_mm_shuffle_epi8(bytes, order)) as u64;
            (r as u32, (r >> 32) as u32)
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "ssse3")))]
    {
        (reverse32_by_bytes(a), reverse32_by_bytes(b))
    }
}

/// Each byte's bits reversed: [`reverse32_by_bytes`]' table.
#[cfg_attr(
    all(target_arch = "x86_64", target_feature = "ssse3"),
    allow(dead_code)
)]
const REVERSED_BYTE: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut x = 0;
    while x < 256 {
        t[x] = (x as u8).reverse_bits();
        x += 1;
    }
    t
};

/// `v.reverse_bits()` by four lookups of a byte's reversal: [`reverse32`] where SSSE3 is
/// not there. (On the sobol renders of the Mitsuba comparison's scenes, 4–6 % less time
/// than the standard library's form; renderer/docs/performance.md, 2026-11-29.)
#[cfg_attr(
    all(target_arch = "x86_64", target_feature = "ssse3"),
    allow(dead_code)
)]
#[inline(always)]
fn reverse32_by_bytes(v: u32) -> u32 {
    let r = |byte: u32| u32::from(REVERSED_BYTE[(byte & 0xff) as usize]);
    r(v) << 24 | r(v >> 8) << 16 | r(v >> 16) << 8 | r(v >> 24)
}

/// The sequence whose first samples the `sobol` sampler takes at a count under it that is
/// not a power of two, and that an adaptive render's `independent` and `sobol` samples
/// come from (render.rs's `Pass::adaptive`): a power of two above any adaptive pixel's
/// count (the pilot is under 2³⁰, a quarter of a 32-bit budget, and adaptive.rs caps the
/// rest at [`crate::adaptive::MAX_EXTRA`]).
pub const SEQUENCE: u32 = 1 << 31;

/// The samples of one pixel sample: call [`PixelSampler::next_2d`] and
/// [`PixelSampler::next_1d`] in a fixed order per path.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    kind: SamplerKind,
    /// `mix_first(pixel)`, the part of every hash that the pixel alone decides.
    pixel_mix: u64,
    /// For the independent sampler, `mix64(pixel_mix + sample)`: the hash of (pixel,
    /// sample) that each dimension finishes with one more mix (the same bits as
    /// [`uniform`]).
    sample_mix: u64,
    /// For the sobol sampler, the sample index with its bits reversed: what
    /// [`PixelSampler::sobol_index`] shuffles.
    sample_rev: u32,
    /// For the sobol sampler, the mask of the set the shuffled index runs over: `spp − 1`
    /// at a power-of-two count, else `SEQUENCE − 1` under `SEQUENCE`, and every bit past it.
    sobol_mask: u32,
    sample: u32,
    spp: u32,
    dim: u32,
    square: u32,
}

impl PixelSampler {
    /// Sample `sample` of `spp` in pixel `pixel`.
    pub fn new(kind: SamplerKind, pixel: u64, sample: u32, spp: u32) -> Self {
        // Only the stratified sampler reads the square root (a square root a sample
        // otherwise: 0.4 % of a `direct` frame's instructions).
        let root = if kind == SamplerKind::Stratified {
            (spp as f64).sqrt().round() as u32
        } else {
            0
        };
        // Only the sobol sampler reads its reversed index and mask (the reversal for every
        // sampler cost a same-algorithm `direct` render, bench_mixed_lights, 0.6 % more
        // instructions).
        let (sample_rev, sobol_mask) = if kind == SamplerKind::Sobol {
            let mask = match spp {
                n if n.is_power_of_two() => n - 1,
                n if n < SEQUENCE => SEQUENCE - 1,
                // A count past the sequence (which no scene needs) takes the whole index,
                // so that no two samples share one.
                _ => u32::MAX,
            };
            (reverse32(sample), mask)
        } else {
            (0, 0)
        };
        let pixel_mix = mix_first(pixel);
        PixelSampler {
            kind,
            pixel_mix,
            sample_mix: if kind == SamplerKind::Independent {
                mix64(pixel_mix.wrapping_add(sample as u64))
            } else {
                0
            },
            sample_rev,
            sobol_mask,
            sample,
            spp,
            dim: 0,
            square: if root * root == spp { root } else { 0 },
        }
    }

    fn key(&self, dim: u32) -> u64 {
        hash_mixed(self.pixel_mix, 0x5eed_0000 + dim as u64, self.kind as u64)
    }

    /// The sobol sampler's 64 random bits for dimension `dim`: one mix of the pixel's hash
    /// stepped by the dimension (SplitMix64's stream, which starts each pixel at its own
    /// random place). A 2D point takes the keys of both its dimensions, two independent
    /// mixes that run side by side.
    #[inline(always)]
    fn sobol_key(&self, dim: u32) -> u64 {
        mix64(
            self.pixel_mix
                .wrapping_add((u64::from(dim) + 1).wrapping_mul(0xd1b5_4a32_d192_ed03)),
        )
    }

    /// The Sobol index of this sample in the dimensions keyed by `seed`: the sample index
    /// shuffled (Kollig and Keller), so that each pair of dimensions pairs the samples
    /// differently, by Owen's scrambling of the index's bits read from the top (Burley
    /// 2020, section 4: `owen_reversed` of the reversed index). Every bit flips as a
    /// function of the bits above it, so the low `m` bits of the result run over `0..2^m`
    /// once for the first `2^m` samples, and the first of them, which sets a point's first
    /// digit, depends on all of them (a scrambling read from the bottom would flip it by a
    /// constant, and every pair of dimensions would share their first digit). At a
    /// power-of-two count `n` the index is kept to `0..n`: the samples are a
    /// (0, m, 2)-net in every pair. At any other count it runs over [`SEQUENCE`]: the
    /// samples are the first of that shuffled sequence, whose prefixes of `2^m` samples are
    /// such nets, and a render of a count has the samples of every smaller one that is not
    /// a power of two, as the adaptive render's pilot and rest are one sequence. (Kensler's
    /// permutation of the first `n` indices, used here before, gave the same error at the
    /// same count in the Mitsuba comparison's scenes and cost more: a hash of a dozen
    /// multiplications, walked again with the chance `1 − n/2^⌈log₂ n⌉`; performance.md,
    /// 2026-11-29.)
    #[inline(always)]
    fn sobol_index(&self, seed: u32) -> u32 {
        owen_reversed(self.sample_rev, seed) & self.sobol_mask
    }

    /// The dimensions drawn so far.
    pub fn dimensions(&self) -> u32 {
        self.dim
    }

    /// The next number in [0, 1). Inlined at every call (out of line, these calls, each
    /// with its match on the kind, were 5 % of a same-algorithm `direct` render's
    /// instructions; inlined, that render takes 5.8 % fewer, sobol renders about 3 %).
    #[inline(always)]
    pub fn next_1d(&mut self) -> f64 {
        let d = self.dim;
        self.dim += 1;
        match self.kind {
            SamplerKind::Independent => to_unit(mix64(self.sample_mix.wrapping_add(d as u64))),
            SamplerKind::Stratified => {
                let key = self.key(d);
                let stratum = permute(self.sample, self.spp, key as u32);
                over(
                    stratum as f64 + to_unit(hash3(key, self.sample as u64, 1)),
                    self.spp,
                )
            }
            SamplerKind::Sobol => {
                let key = self.sobol_key(d);
                let (a, _) = sobol_reversed(self.sobol_index(key as u32));
                (owen_reversed(a, (key >> 32) as u32) as f64) * (1.0 / 4_294_967_296.0)
            }
        }
    }

    /// The next point in [0, 1)², inlined as [`PixelSampler::next_1d`].
    #[inline(always)]
    pub fn next_2d(&mut self) -> (f64, f64) {
        match self.kind {
            SamplerKind::Independent => (self.next_1d(), self.next_1d()),
            SamplerKind::Stratified if self.square > 0 => {
                let d = self.dim;
                self.dim += 2;
                let key = self.key(d);
                let n = self.square;
                let stratum = permute(self.sample, self.spp, key as u32);
                let (sx, sy) = (rem(stratum, n), quot(stratum, n));
                let jx = to_unit(hash3(key, self.sample as u64, 1));
                let jy = to_unit(hash3(key, self.sample as u64, 2));
                (over(sx as f64 + jx, n), over(sy as f64 + jy, n))
            }
            SamplerKind::Stratified => (self.next_1d(), self.next_1d()),
            SamplerKind::Sobol => {
                let d = self.dim;
                self.dim += 2;
                let (key, second) = (self.sobol_key(d), self.sobol_key(d + 1));
                let (a, b) = sobol_reversed(self.sobol_index(key as u32));
                let (sa, sb) = ((key >> 32) as u32, second as u32);
                let s = 1.0 / 4_294_967_296.0;
                let (x, y) = owen_reversed2(a, sa, b, sb);
                (x as f64 * s, y as f64 * s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numbers each call position of a path gets, over all samples of one pixel: a
    /// path asks for a 2D point, a 1D number, two more 2D points and two more 1D numbers.
    fn dimensions(kind: SamplerKind, pixel: u64, spp: u32) -> Vec<Vec<f64>> {
        dimensions_of(kind, pixel, spp, spp)
    }

    /// [`dimensions`] over the first `samples` samples of a set of `set`.
    fn dimensions_of(kind: SamplerKind, pixel: u64, samples: u32, set: u32) -> Vec<Vec<f64>> {
        let mut dims = vec![Vec::new(); 9];
        for s in 0..samples {
            let mut smp = PixelSampler::new(kind, pixel, s, set);
            let (a, b) = smp.next_2d();
            let c = smp.next_1d();
            let (d, e) = smp.next_2d();
            let (f, g) = smp.next_2d();
            let (h, i) = (smp.next_1d(), smp.next_1d());
            for (k, v) in [a, b, c, d, e, f, g, h, i].into_iter().enumerate() {
                assert!((0.0..1.0).contains(&v), "{kind:?}: {v} outside [0, 1)");
                dims[k].push(v);
            }
        }
        dims
    }

    /// That the first `2^m` samples of `dims` are a (0, m, 2)-net in every pair of call
    /// positions that is a 2D point: each box of `2^a × 2^(m − a)` holds one point.
    fn assert_nets(dims: &[Vec<f64>], m: u32, what: &str) {
        let n = 1usize << m;
        for (x, y) in TWO_D {
            for a in 0..=m {
                let (nx, ny) = (1usize << a, 1usize << (m - a));
                let mut seen = vec![0u32; n];
                for s in 0..n {
                    let cx = (dims[x][s] * nx as f64) as usize;
                    let cy = (dims[y][s] * ny as f64) as usize;
                    seen[cy * nx + cx] += 1;
                }
                assert!(
                    seen.iter().all(|&c| c == 1),
                    "{what}, call positions ({x}, {y}), the first {n} samples: boxes of \
                     {nx} x {ny} hold {seen:?} points (one each expected: the scrambling \
                     must keep the (0, m, 2)-net; renderer/src/sampler.rs owen_reversed, \
                     PixelSampler::sobol_index)"
                );
            }
        }
    }

    /// At a count that is not a power of two, the sobol sampler's samples are the first of
    /// the shuffled sequence of `SEQUENCE`: the numbers of a sampler over that whole set
    /// (an adaptive render's), so that the first `2^m` of them, for the largest `2^m`
    /// under the count, are a (0, m, 2)-net in every pair.
    #[test]
    fn sobol_at_other_counts_is_the_start_of_its_sequence() {
        for spp in [3u32, 5, 6, 7, 12, 13, 100] {
            for pixel in [0u64, 3, 99991, u64::MAX] {
                let dims = dimensions(SamplerKind::Sobol, pixel, spp);
                assert_eq!(
                    dims,
                    dimensions_of(SamplerKind::Sobol, pixel, spp, SEQUENCE),
                    "Sobol, {spp} spp, pixel {pixel}: not the first {spp} samples of the \
                     sequence of SEQUENCE (renderer/src/sampler.rs PixelSampler::sobol_index)"
                );
                assert_nets(
                    &dims,
                    spp.ilog2(),
                    &format!("Sobol, {spp} spp, pixel {pixel}"),
                );
            }
        }
    }

    /// The sobol sampler's first 2D point at a count that is not a power of two, and at
    /// one sample: the twelve samples at 12 spp of pixels 77 to 92, folded into one hash,
    /// and sample 0 of pixel 77 at 1 spp (index 0), as 32-bit fractions. The twelve are
    /// the start of the sequence of `SEQUENCE`, whose size they pin: their indices' high
    /// bits are a pixel's random constant, so sixteen pixels hold one with the bit of 2³⁰
    /// (a smaller sequence would change it). Past the sequence the index keeps every bit,
    /// so that no two samples share one (`owen_reversed` is a bijection).
    #[test]
    fn sobol_numbers_at_other_counts_are_pinned() {
        let first = |pixel: u64, sample: u32, spp: u32| {
            let (x, y) = PixelSampler::new(SamplerKind::Sobol, pixel, sample, spp).next_2d();
            ((x * 4_294_967_296.0) as u32, (y * 4_294_967_296.0) as u32)
        };
        let twelve = (77..93)
            .flat_map(|p| (0..12).map(move |k| (p, k)))
            .fold(0u64, |h, (p, k)| {
                let (x, y) = first(p, k, 12);
                mix64(h ^ (u64::from(x) << 32 | u64::from(y)))
            });
        assert_eq!(
            (twelve, first(77, 0, 1)),
            PINNED_SOBOL_OTHER,
            "the sobol sampler's numbers at 12 and 1 spp changed (renderer/src/sampler.rs \
             PixelSampler::sobol_index, SEQUENCE)"
        );
        let past = PixelSampler::new(SamplerKind::Sobol, 77, 5, 3 << 30);
        assert_eq!(
            past.sobol_mask,
            u32::MAX,
            "past SEQUENCE the sobol index must keep every bit (renderer/src/sampler.rs \
             PixelSampler::new)"
        );
    }

    const PINNED_SOBOL_OTHER: (u64, (u32, u32)) =
        (9_332_942_466_393_206_496, (3_581_947_067, 3_046_843_313));

    /// Call positions of [`dimensions`] that are 1D numbers, and the pairs that are 2D points.
    const ONE_D: [usize; 3] = [2, 7, 8];
    const TWO_D: [(usize, usize); 3] = [(0, 1), (3, 4), (5, 6)];

    fn strata(values: &[f64], n: usize) -> Vec<u32> {
        let mut seen = vec![0u32; n];
        for v in values {
            seen[(v * n as f64) as usize] += 1;
        }
        seen
    }

    /// Stratified and Sobol samples put exactly one of a pixel's `spp` numbers in each
    /// interval [k/spp, (k+1)/spp) of every 1D dimension, and so do Sobol's 2D points in
    /// each coordinate (for powers of two, whose first 2^m points are a (0, m, 2)-net).
    /// Stratified 2D points fall one in each cell of the √spp × √spp grid when spp is a
    /// square, and are two stratified 1D numbers otherwise.
    #[test]
    fn stratified_and_sobol_samples_fill_every_stratum_once() {
        for (kind, counts) in [
            (
                SamplerKind::Stratified,
                &[1u32, 2, 5, 8, 16, 64, 100, 256][..],
            ),
            (SamplerKind::Sobol, &[1, 2, 4, 8, 16, 64, 256][..]),
        ] {
            for &spp in counts {
                let root = (spp as f64).sqrt() as usize;
                let grid = kind == SamplerKind::Stratified && root * root == spp as usize;
                for pixel in [0u64, 1, 7, 12345, u64::MAX] {
                    let dims = dimensions(kind, pixel, spp);
                    let at = |what: &str, k: usize, seen: Vec<u32>| {
                        assert!(
                            seen.iter().all(|&c| c == 1),
                            "{kind:?}, {spp} spp, pixel {pixel}, {what} {k}: strata counts \
                             {seen:?} (one each expected; renderer/src/sampler.rs)"
                        );
                    };
                    for k in ONE_D {
                        at("1D number", k, strata(&dims[k], spp as usize));
                    }
                    for (x, y) in TWO_D {
                        if grid {
                            let cells: Vec<f64> = (0..spp as usize)
                                .map(|s| {
                                    let cell = (dims[y][s] * root as f64) as usize * root
                                        + (dims[x][s] * root as f64) as usize;
                                    (cell as f64 + 0.5) / spp as f64
                                })
                                .collect();
                            at("2D grid cell of point", x, strata(&cells, spp as usize));
                        } else {
                            at("2D coordinate", x, strata(&dims[x], spp as usize));
                            at("2D coordinate", y, strata(&dims[y], spp as usize));
                        }
                    }
                }
            }
        }
    }

    /// Sobol's 2D points at spp = 2^m are a (0, m, 2)-net after scrambling: every
    /// elementary box of 2^-a × 2^-(m-a) holds exactly one of them, for each a. And Owen's
    /// scrambling places each point at random inside its box: a 1D number's offsets inside
    /// its strata of width 1/spp differ from sample to sample, where a digital shift (one
    /// XOR for all samples) would give them all the same offset, a shifted lattice.
    #[test]
    fn sobol_points_are_an_owen_scrambled_net() {
        for m in [1u32, 2, 4, 6, 8] {
            let spp = 1u32 << m;
            for pixel in [0u64, 3, 99991, u64::MAX] {
                let dims = dimensions(SamplerKind::Sobol, pixel, spp);
                assert_nets(&dims, m, &format!("Sobol, {spp} spp, pixel {pixel}"));
                if spp >= 4 {
                    for k in ONE_D.into_iter().chain(TWO_D.into_iter().map(|(x, _)| x)) {
                        let mut offsets: Vec<f64> =
                            dims[k].iter().map(|v| (v * spp as f64).fract()).collect();
                        offsets.sort_by(f64::total_cmp);
                        offsets.dedup();
                        assert!(
                            offsets.len() > spp as usize / 2,
                            "Sobol, {spp} spp, pixel {pixel}, call position {k}: only \
                             {} distinct offsets inside the strata (a digital shift, not \
                             Owen's scrambling; renderer/src/sampler.rs owen_reversed)",
                            offsets.len()
                        );
                    }
                }
            }
        }
    }

    /// Sample 5 of 16 in pixel 77, its first two 2D points and two 1D numbers, as 32-bit
    /// fractions: what the sobol sampler gives since its keys became one mix per dimension
    /// and its shuffle at powers of two Owen's scrambling of the index (2026-11-25; before,
    /// from d6dd87d on, they were (3945344138, 3295374891), (1067349807, 2336251960) and
    /// (1763481376, 1255205158)).
    const PINNED_SOBOL: [(u32, u32); 3] = [
        (2_662_843_107, 3_367_179_604),
        (2_869_945_806, 2_921_466_453),
        (2_672_533_897, 1_246_412_272),
    ];

    /// Sample 5 in pixel 77 of the stratified sampler at 16, 8, 12 and 9 spp (square and a
    /// power of two, a power of two, neither, square), its first two 2D points and two 1D
    /// numbers as `f64` bits: what it gave before its divisions by powers of two became
    /// masks, shifts and exact multiplications (d6dd87d). No catalog scene uses it.
    #[test]
    fn stratified_numbers_are_pinned() {
        const PINNED: [(u32, [(u64, u64); 3]); 4] = [
            (
                16,
                [
                    (4606640750576253620, 4605012142815332528),
                    (4605032311798993197, 4600972273444449352),
                    (4605215273014140374, 4605358324624246066),
                ],
            ),
            (
                8,
                [
                    (4606911584688135514, 4604372996744756358),
                    (4593875005543227994, 4607083120765092764),
                    (4603248127228263339, 4591507710869787429),
                ],
            ),
            (
                12,
                [
                    (4603999462973849148, 4605309470763176708),
                    (4598243014753717107, 4590139630646727486),
                    (4606811357565866611, 4600816967788836999),
                ],
            ),
            (
                9,
                [
                    (4603457794750085360, 4578110321855751552),
                    (4599947600254829347, 4606044721647885701),
                    (4606687670487816345, 4599195550743706916),
                ],
            ),
        ];
        for (spp, want) in PINNED {
            let mut smp = PixelSampler::new(SamplerKind::Stratified, 77, 5, spp);
            let got = [smp.next_2d(), smp.next_2d(), (smp.next_1d(), smp.next_1d())];
            assert_eq!(
                got.map(|(x, y)| (x.to_bits(), y.to_bits())),
                want,
                "stratified sampler at {spp} spp: its numbers changed (renderer/src/sampler.rs)"
            );
        }
    }

    /// The tables give Sobol's points bit for bit, reversed: every index below 2^16 and a
    /// spread of larger ones (each byte of the index has its own table). And scrambling the
    /// reversed bits is Owen's scrambling of the point (pinned values: these are the
    /// sampler's numbers, and no catalog scene uses the sobol sampler, so no render would
    /// show a change).
    #[test]
    fn sobol_tables_are_the_bitwise_definition() {
        let mut rng = 0x1234_5678_9abc_def0u64;
        let indices = (0..1u32 << 16).chain((0..100_000).map(|_| {
            rng = mix64(rng);
            rng as u32
        }));
        for i in indices.chain([u32::MAX, 1 << 31, 0x8000_0001]) {
            let (a, b) = sobol2(i);
            assert_eq!(
                sobol_reversed(i),
                (a.reverse_bits(), b.reverse_bits()),
                "index {i:#x}: the tables of sobol_reversed (renderer/src/sampler.rs) differ \
                 from the bitwise definition"
            );
        }
        let mut smp = PixelSampler::new(SamplerKind::Sobol, 77, 5, 16);
        let got = [smp.next_2d(), smp.next_2d(), (smp.next_1d(), smp.next_1d())];
        let bits = got.map(|(x, y)| ((x * 4_294_967_296.0) as u32, (y * 4_294_967_296.0) as u32));
        assert_eq!(bits, PINNED_SOBOL, "the sobol sampler's numbers changed");
    }

    /// `reverse32`, `reverse32x2` (both halves of the pair) and the table lookups of
    /// `reverse32_by_bytes` reverse a word's bits as `u32::reverse_bits` does: every value
    /// of each byte in each position, with the other bytes random, and random words.
    #[test]
    fn reverse32_is_reverse_bits() {
        let check = |v: u32, other: u32, what: &str| {
            let want = v.reverse_bits();
            let got = [
                ("reverse32", reverse32(v)),
                ("reverse32x2's first", reverse32x2(v, other).0),
                ("reverse32x2's second", reverse32x2(other, v).1),
                ("reverse32_by_bytes", reverse32_by_bytes(v)),
            ];
            for (name, r) in got {
                assert_eq!(
                    r, want,
                    "{v:#010x} (beside {other:#010x}): {name} (renderer/src/sampler.rs) differs \
                     from u32::reverse_bits {what}"
                );
            }
        };
        let mut rng = 0x0bad_cafe_u64;
        for k in 0..4 {
            for x in 0..256u32 {
                rng = mix64(rng);
                let v = (rng as u32 & !(0xff << (8 * k))) | x << (8 * k);
                check(v, (rng >> 32) as u32, &format!("in byte {k}"));
            }
        }
        for _ in 0..100_000 {
            rng = mix64(rng);
            check(rng as u32, (rng >> 32) as u32, "");
        }
    }

    /// Each call position of a path gets its own numbers: no two dimensions of a pixel
    /// repeat each other (a repeated key would correlate a path's bounces).
    #[test]
    fn every_dimension_gets_its_own_numbers() {
        for kind in [
            SamplerKind::Independent,
            SamplerKind::Stratified,
            SamplerKind::Sobol,
        ] {
            for spp in [4u32, 16, 64] {
                let dims = dimensions(kind, 5, spp);
                for a in 0..dims.len() {
                    for b in a + 1..dims.len() {
                        assert_ne!(
                            dims[a], dims[b],
                            "{kind:?}, {spp} spp: call positions {a} and {b} got the same \
                             numbers (each dimension needs its own key; renderer/src/sampler.rs)"
                        );
                    }
                }
            }
        }
    }

    /// No two call positions of a path are correlated: over 256 pixels × 16 samples, the
    /// Pearson correlation of every pair of positions (and of the two coordinates of each
    /// 2D point) is within 5 standard errors (1/√n) of 0. A dimension that reuses another's
    /// key — a 2D point that does not advance the dimension counter, say — gives numbers
    /// that differ but follow each other, which `every_dimension_gets_its_own_numbers`
    /// cannot see.
    #[test]
    fn dimensions_are_uncorrelated() {
        for kind in [
            SamplerKind::Independent,
            SamplerKind::Stratified,
            SamplerKind::Sobol,
        ] {
            // 16 spp: a square, so stratified 2D points take the grid path.
            let mut dims = vec![Vec::new(); 9];
            for pixel in 0..256u64 {
                for (k, d) in dimensions(kind, pixel * 7919 + 3, 16)
                    .into_iter()
                    .enumerate()
                {
                    dims[k].extend(d);
                }
            }
            let n = dims[0].len() as f64;
            let corr = |x: &[f64], y: &[f64]| {
                let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
                let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
                for (a, b) in x.iter().zip(y) {
                    sxy += (a - mx) * (b - my);
                    sxx += (a - mx) * (a - mx);
                    syy += (b - my) * (b - my);
                }
                sxy / (sxx * syy).sqrt()
            };
            for a in 0..dims.len() {
                for b in a + 1..dims.len() {
                    let r = corr(&dims[a], &dims[b]);
                    assert!(
                        r.abs() < 5.0 / n.sqrt(),
                        "{kind:?}: call positions {a} and {b} are correlated (r = {r:.3} over \
                         {n} samples; each dimension needs its own key and the counter must \
                         advance past a 2D point; renderer/src/sampler.rs)"
                    );
                }
            }
        }
    }

    /// `cos_sin_turn` agrees with the maths library's cosine and sine of 2πu within
    /// 10⁻¹⁵ over [0, 1) (every octant, both ends of each, and a dense sweep; the library's
    /// own argument, 2π·u rounded, is up to 7·10⁻¹⁶ off), and its pair stays on the unit
    /// circle.
    #[test]
    fn cos_sin_turn_matches_the_library() {
        let mut us: Vec<f64> = (0..200_000).map(|i| i as f64 / 200_000.0).collect();
        for k in 0..8 {
            let e = k as f64 / 8.0;
            us.extend([e, e + 1e-12, (e + 0.125) * (1.0 - f64::EPSILON), e + 0.0625]);
        }
        us.push(1.0 - f64::EPSILON / 2.0);
        for u in us {
            let (c, s) = cos_sin_turn(u);
            let phi = 2.0 * std::f64::consts::PI * u;
            assert!(
                (c - phi.cos()).abs() < 1e-15 && (s - phi.sin()).abs() < 1e-15,
                "u = {u}: cos_sin_turn gives ({c}, {s}), the library ({}, {}) \
                 (renderer/src/sampler.rs cos_sin_turn: octant signs or series)",
                phi.cos(),
                phi.sin()
            );
            assert!(
                (c * c + s * s - 1.0).abs() < 1e-15,
                "u = {u}: off the circle"
            );
        }
    }

    /// Every pixel gets its own numbers: over 16,384 pixels (a 128 × 128 image), no two
    /// share the first 2D point of their first sample. A pixel hash that lost bits (an
    /// OR or AND where the seed is mixed in, say) would give pixels that differ only in
    /// those bits the same samples, and so the same noise.
    #[test]
    fn every_pixel_gets_its_own_numbers() {
        for kind in [
            SamplerKind::Independent,
            SamplerKind::Stratified,
            SamplerKind::Sobol,
        ] {
            let mut firsts: Vec<(u64, u64, u64)> = (0..16_384u64)
                .map(|pixel| {
                    let (a, b) = PixelSampler::new(kind, pixel, 0, 16).next_2d();
                    (a.to_bits(), b.to_bits(), pixel)
                })
                .collect();
            firsts.sort_unstable();
            for w in firsts.windows(2) {
                assert!(
                    (w[0].0, w[0].1) != (w[1].0, w[1].1),
                    "{kind:?}: pixels {} and {} got the same first point (the pixel hash \
                     loses bits; renderer/src/sampler.rs mix_first, PixelSampler::key)",
                    w[0].2,
                    w[1].2
                );
            }
        }
    }

    /// The independent sampler's numbers are [`uniform`]'s for (pixel, sample,
    /// dimension), though it hashes the pixel and the sample once, not per number.
    #[test]
    fn independent_samples_are_the_uniform_hash() {
        for pixel in [0u64, 9, 1 << 40, u64::MAX] {
            for sample in [0u32, 1, 77, u32::MAX] {
                let mut smp = PixelSampler::new(SamplerKind::Independent, pixel, sample, 128);
                for dim in 0..8u64 {
                    assert_eq!(
                        smp.next_1d().to_bits(),
                        uniform(pixel, sample as u64, dim).to_bits(),
                        "pixel {pixel}, sample {sample}, dimension {dim} \
                         (renderer/src/sampler.rs PixelSampler::new)"
                    );
                }
            }
        }
    }

    /// Independent numbers are uniform: over many samples each dimension's mean is 1/2
    /// and its variance 1/12, within five standard errors.
    #[test]
    fn independent_samples_are_uniform() {
        let spp = 4096;
        for (k, dim) in dimensions(SamplerKind::Independent, 3, spp)
            .iter()
            .enumerate()
        {
            let n = dim.len() as f64;
            let mean = dim.iter().sum::<f64>() / n;
            let var = dim.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
            assert!(
                (mean - 0.5).abs() < 5.0 * (1.0f64 / 12.0 / n).sqrt(),
                "dimension {k}: mean {mean}"
            );
            // The variance of a uniform sample variance is (1/80 - 1/144) / n.
            assert!(
                (var - 1.0 / 12.0).abs() < 5.0 * ((1.0 / 80.0 - 1.0 / 144.0) / n).sqrt(),
                "dimension {k}: variance {var}"
            );
        }
    }

    /// `permute` is a bijection of 0..n for every key.
    #[test]
    fn permute_is_a_permutation() {
        for n in [1u32, 2, 3, 4, 5, 7, 8, 31, 32, 33, 100, 1000] {
            for key in [0u32, 1, 0xdead_beef, u32::MAX] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let p = permute(i, n, key);
                    assert!(p < n && !seen[p as usize], "n {n}, key {key}: {i} -> {p}");
                    seen[p as usize] = true;
                }
            }
        }
    }
}
