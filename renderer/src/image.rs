//! A rendered image: linear RGB with its optional geometry channels (AOVs) and per-pixel
//! second moments, and the moments' layout. The render loop (render.rs) and the light
//! paths (physical/light_paths.rs) both write it; the output (output.rs) reads it.

/// Geometry channels for every pixel, from the pixel-centre ray. Misses are 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aov {
    /// Euclidean distance from the eye to the hit.
    pub z: Vec<f32>,
    /// Unit, outward, world-space geometric normal (3 per pixel).
    pub n: Vec<f32>,
    /// World hit point (3 per pixel).
    pub p: Vec<f32>,
    /// 1-based object id, 0 for background.
    pub object_id: Vec<f32>,
}

/// The channel pairs of [`Image::moments`], in their order: RR, GG, BB, RG, RB, GB.
pub const MOMENT_PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// Adds an RGB value's products, in the order of [`MOMENT_PAIRS`], to the six sums of a
/// pixel's second moments (what a sample, or a light path's contribution, adds).
#[inline(always)]
pub fn add_moment_products(sums: &mut [f64], c: [f64; 3]) {
    for (m, &(a, b)) in sums.iter_mut().zip(&MOMENT_PAIRS) {
        *m += c[a] * c[b];
    }
}

/// A rendered image: linear RGB, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// RGB, 3 floats per pixel.
    pub rgb: Vec<f32>,
    /// Geometry channels, when requested.
    pub aov: Option<Aov>,
    /// Pixel channels that came out NaN or infinite and were written as 0.
    pub non_finite: usize,
    /// Per-pixel second moments of the samples, when requested: E[R²], E[G²], E[B²],
    /// E[RG], E[RB], E[GB] (6 per pixel). With the mean they give the variance of any linear
    /// function of RGB (for example XYZ), for statistical tests against references.
    pub moments: Option<Vec<f32>>,
    /// Samples traced, over all pixels: width · height · spp, or with adaptive sampling
    /// about that (adaptive.rs).
    pub samples: u64,
}
