//! Comparing a render with a deterministic pixel-centre reference.
//!
//! POV-Ray writes EXR as half floats, so a reference value r is only known to within its
//! rounding error, `2⁻¹¹·|r|` (half has an 11-bit significand). The per-channel tolerance is
//!
//! ```text
//! tol(r) = 1.05 · 2⁻¹¹ · |r| + 1e-6
//! ```
//!
//! The 5 % margin covers this renderer's own f32 rounding: measured over the catalog,
//! agreeing pixels never exceed 1.02× the half bound. The absolute floor covers values
//! below the smallest normal half. Pixels outside tolerance are then split in two:
//!
//! - **silhouette** pixels are those whose value lies, channel by channel, within the range
//!   (± tol) of the reference's 3×3 neighbourhood. The pixel-centre ray fell on the other
//!   side of an edge (of an object, a shadow, or an edge seen through glass), so the value
//!   is one the reference also takes nearby. They are counted apart and must stay within
//!   [`SILHOUETTE_BUDGET`] of the image;
//! - **failing** pixels are all the others. A single one fails the comparison.

/// Relative tolerance: the half-float rounding bound with a 5 % margin.
pub const REL_TOL: f64 = 1.05 / 2048.0;
/// Absolute floor of the tolerance.
pub const ABS_TOL: f64 = 1e-6;
/// Largest allowed fraction of silhouette pixels.
pub const SILHOUETTE_BUDGET: f64 = 0.0025;

/// The tolerance for a reference value.
#[inline]
pub fn tol(r: f64) -> f64 {
    REL_TOL * r.abs() + ABS_TOL
}

/// What a comparison found.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// Width and height.
    pub size: (usize, usize),
    /// Largest absolute channel difference.
    pub max_abs: f64,
    /// Mean absolute channel difference.
    pub mean_abs: f64,
    /// Root mean square channel difference.
    pub rmse: f64,
    /// Pixels outside tolerance that are not silhouette pixels.
    pub failing: usize,
    /// Silhouette pixels.
    pub silhouette: usize,
    /// Per pixel: 0 within tolerance, 1 silhouette, 2 failing.
    pub class: Vec<u8>,
}

impl Comparison {
    /// The silhouette budget in pixels for this image size.
    pub fn budget(&self) -> usize {
        ((self.size.0 * self.size.1) as f64 * SILHOUETTE_BUDGET).floor() as usize
    }

    /// Whether the render agrees with the reference.
    pub fn passed(&self) -> bool {
        self.failing == 0 && self.silhouette <= self.budget()
    }
}

/// Compares RGB images (3 floats per pixel, row-major, top row first).
pub fn compare(ours: &[f32], reference: &[f32], width: usize, height: usize) -> Comparison {
    assert_eq!(ours.len(), width * height * 3, "image size");
    assert_eq!(reference.len(), width * height * 3, "reference size");
    let px = |img: &[f32], x: usize, y: usize, c: usize| img[3 * (y * width + x) + c] as f64;
    let (mut max_abs, mut sum, mut sum2) = (0f64, 0f64, 0f64);
    let mut class = vec![0u8; width * height];
    let (mut failing, mut silhouette) = (0, 0);
    for y in 0..height {
        for x in 0..width {
            let mut within = true;
            for c in 0..3 {
                let (a, r) = (px(ours, x, y, c), px(reference, x, y, c));
                let d = (a - r).abs();
                max_abs = max_abs.max(d);
                sum += d;
                sum2 += d * d;
                within &= d <= tol(r);
            }
            if within {
                continue;
            }
            let in_range = (0..3).all(|c| {
                let a = px(ours, x, y, c);
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for yy in y.saturating_sub(1)..(y + 2).min(height) {
                    for xx in x.saturating_sub(1)..(x + 2).min(width) {
                        let r = px(reference, xx, yy, c);
                        lo = lo.min(r - tol(r));
                        hi = hi.max(r + tol(r));
                    }
                }
                (lo..=hi).contains(&a)
            });
            if in_range {
                silhouette += 1;
                class[y * width + x] = 1;
            } else {
                failing += 1;
                class[y * width + x] = 2;
            }
        }
    }
    let n = (width * height * 3) as f64;
    Comparison {
        size: (width, height),
        max_abs,
        mean_abs: sum / n,
        rmse: (sum2 / n).sqrt(),
        failing,
        silhouette,
        class,
    }
}

/// A false-colour difference image (8-bit RGB): the reference's luminance dimmed to grey
/// where the pixel agrees, orange for silhouette pixels, and red, brighter with the error,
/// for failing pixels.
pub fn diff_image(cmp: &Comparison, ours: &[f32], reference: &[f32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(cmp.class.len() * 3);
    for (k, &c) in cmp.class.iter().enumerate() {
        let lum = (0.2126 * reference[3 * k]
            + 0.7152 * reference[3 * k + 1]
            + 0.0722 * reference[3 * k + 2])
            .clamp(0.0, 1.0);
        match c {
            0 => {
                let g = (lum * 90.0) as u8;
                out.extend_from_slice(&[g, g, g]);
            }
            1 => out.extend_from_slice(&[255, 160, 0]),
            _ => {
                let err = (0..3)
                    .map(|i| (ours[3 * k + i] - reference[3 * k + i]).abs())
                    .fold(0.0f32, f32::max);
                let v = (128.0 + 127.0 * (err * 20.0).min(1.0)) as u8;
                out.extend_from_slice(&[v, 0, 0]);
            }
        }
    }
    out
}
