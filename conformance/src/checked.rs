//! One scene compared with one reference, as every reference reports it: the verdict
//! before waivers, each check that a waiver can name, the metrics, the images, and the
//! pixels a failure message shows. Each reference's outcome (`povray::outcome`,
//! `mitsuba::outcome`) implements [`Checked`]; the gate, the report and the waivers read
//! only this.

use crate::verdict::Verdict;
use renderer::render::Image;

/// What a comparison with a reference found.
pub trait Checked: Send + Sync {
    /// The reference's name ([`crate::reference::Reference::name`]).
    fn reference(&self) -> &str;

    /// The catalog the scene is in.
    fn catalog(&self) -> &str;

    /// The scene's name.
    fn scene(&self) -> &str;

    /// The verdict before waivers.
    fn verdict(&self) -> Verdict;

    /// Each check of the comparison and whether it passed (empty without a reference).
    fn checks(&self) -> Vec<(&'static str, bool)>;

    /// One line of metrics; top-level `; ` separates measurements.
    fn metrics(&self) -> String;

    /// Our render.
    fn ours(&self) -> &Image;

    /// The reference's RGB pixels, when there is a reference.
    fn reference_rgb(&self) -> Option<&[f32]>;

    /// Seconds our render took.
    fn seconds(&self) -> f64;

    /// The `n` worst pixels, worst first (none without a reference).
    fn worst(&self, n: usize) -> Vec<Pixel>;

    /// What a failure message adds after a worst pixel's class (nothing by default).
    fn pixel_note(&self, pixel: &Pixel) -> String {
        let _ = pixel;
        String::new()
    }

    /// The scene's worst score for `results.json` and the report's plot (0 without a
    /// reference).
    fn worst_score(&self) -> f64;

    /// The image that shows where the comparison failed (a difference or a z image), for
    /// the failure output and the report's third column; `None` without a reference.
    fn figure(&self) -> Option<Figure>;
}

/// An image a comparison makes: linear values for EXR, and how it is shown as PNG.
pub struct Figure {
    /// The file stem: `difference` replaces the plain |ours − reference| image.
    pub name: &'static str,
    /// Linear RGB, for the EXR.
    pub linear: Vec<f32>,
    /// 8-bit RGB, for the PNG.
    pub png: Vec<u8>,
}

/// One pixel of a failure message.
#[derive(Clone, Debug, PartialEq)]
pub struct Pixel {
    /// Column (0 at the left).
    pub x: usize,
    /// Row (0 at the top).
    pub y: usize,
    /// Our value.
    pub ours: [f32; 3],
    /// The reference's value.
    pub reference: [f32; 3],
    /// How the comparison classed it: failing, excused, within tolerance, or (Mitsuba)
    /// the pixel's z.
    pub class: String,
    /// The ranking key (larger is worse).
    pub score: f64,
}

/// The `n` worst pixels: by `score(k)`, largest first (ties by position).
pub fn worst_pixels(
    width: usize,
    ours: &[f32],
    reference: &[f32],
    n: usize,
    score: &dyn Fn(usize) -> f64,
    class: &dyn Fn(usize) -> String,
) -> Vec<Pixel> {
    let px = ours.len() / 3;
    let mut order: Vec<usize> = (0..px).collect();
    order.sort_by(|&a, &b| score(b).total_cmp(&score(a)).then(a.cmp(&b)));
    order
        .into_iter()
        .take(n)
        .map(|k| Pixel {
            x: k % width,
            y: k / width,
            ours: [0, 1, 2].map(|c| ours[3 * k + c]),
            reference: [0, 1, 2].map(|c| reference[3 * k + c]),
            class: class(k),
            score: score(k),
        })
        .collect()
}

/// |ours − reference| per channel.
pub fn abs_difference(ours: &[f32], reference: &[f32]) -> Vec<f32> {
    ours.iter()
        .zip(reference)
        .map(|(a, b)| (a - b).abs())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test01_worst_pixels_rank_by_score_then_position() {
        let ours = [
            0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0,
        ];
        let reference = [0.0f32; 12];
        let score = |k: usize| ours[3 * k] as f64;
        let p = worst_pixels(2, &ours, &reference, 3, &score, &|k| k.to_string());
        let at: Vec<(usize, usize)> = p.iter().map(|p| (p.x, p.y)).collect();
        assert_eq!(at, [(1, 0), (1, 1), (0, 1)]);
        assert_eq!(p[0].ours, [1.0; 3]);
    }
}
