//! One scene's vote as the gate reads it ([`Checked`]): the verdict (ours agrees with
//! the oracle, and the oracle with POV-Ray), the two checks a waiver can name, the
//! three-way metrics, and the worst pixels with all three values.

use super::vote::{Vote, PAIRS};
use crate::checked::{abs_difference, worst_pixels, Checked, Figure, Pixel};
use crate::povray::compare::diff_image;
use crate::verdict::Verdict;
use renderer::render::Image;

/// The checks of the oracle reference: ours against the oracle, and the oracle against
/// POV-Ray's committed image.
pub const CHECKS: [&str; 2] = ["oracle", "oracle_povray"];

/// One scene against the oracle.
pub struct Outcome {
    /// The verdict before waivers.
    pub verdict: Verdict,
    /// The three comparisons.
    pub vote: Vote,
    /// Our render.
    pub ours: Image,
    /// Seconds our render took.
    pub seconds: f64,
    /// Seconds the oracle's image and its two comparisons took.
    pub oracle_seconds: f64,
}

impl Outcome {
    /// The pair (index into [`PAIRS`]) a worst pixel is ranked by: the oracle's two.
    fn ranked(&self, k: usize) -> (usize, f64) {
        let class = |pair: usize| self.vote.pairs()[pair].map_or(0, |c| c.class[k]) as f64;
        // Failing pixels first (of either pair), then excused ones, by the error.
        [2, 1]
            .into_iter()
            .map(|p| (p, class(p) * 1e12 + self.vote.error(p, k)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap()
    }
}

impl Checked for Outcome {
    fn reference(&self) -> &str {
        "oracle"
    }

    fn catalog(&self) -> &str {
        "povray"
    }

    fn scene(&self) -> &str {
        &self.vote.scene
    }

    fn verdict(&self) -> Verdict {
        self.verdict
    }

    fn checks(&self) -> Vec<(&'static str, bool)> {
        let mut v = vec![(CHECKS[0], self.vote.ours_oracle.passed())];
        if let Some(c) = &self.vote.oracle_povray {
            v.push((CHECKS[1], c.passed()));
        }
        v
    }

    fn metrics(&self) -> String {
        let c = &self.vote.ours_oracle;
        format!(
            "three-way: {}; ours~oracle max abs {:.3e}, mean abs {:.3e}; oracle {:.2} s",
            self.vote.summary(),
            c.max_abs,
            c.mean_abs,
            self.oracle_seconds
        )
    }

    fn ours(&self) -> &Image {
        &self.ours
    }

    fn reference_rgb(&self) -> Option<&[f32]> {
        Some(&self.vote.oracle_rgb)
    }

    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn worst(&self, n: usize) -> Vec<Pixel> {
        let class = |k: usize| {
            let (pair, score) = self.ranked(k);
            let word = match score / 1e12 {
                s if s >= 2.0 => "FAILING",
                s if s >= 1.0 => "excused (geometry)",
                _ => "within tolerance",
            };
            format!("{word} in {}", PAIRS[pair])
        };
        let score = |k: usize| self.ranked(k).1;
        let w = self.ours.width as usize;
        worst_pixels(w, &self.ours.rgb, &self.vote.oracle_rgb, n, &score, &class)
    }

    fn pixel_note(&self, pixel: &Pixel) -> String {
        let k = pixel.y * self.ours.width as usize + pixel.x;
        let povray = self
            .vote
            .povray_rgb
            .as_ref()
            .map_or("no fresh reference".into(), |p| {
                format!("{:?}", [p[3 * k], p[3 * k + 1], p[3 * k + 2]])
            });
        format!(
            " (the reference column is the oracle), POV-Ray {povray}, {:.1}× the tolerance",
            pixel.score.rem_euclid(1e12)
        )
    }

    fn worst_score(&self) -> f64 {
        (0..self.vote.oracle_rgb.len() / 3)
            .map(|k| self.ranked(k).1.rem_euclid(1e12))
            .fold(0.0, f64::max)
    }

    fn agreement(&self) -> Option<String> {
        Some(format!("three-way: {}", self.vote.summary()))
    }

    fn figure(&self) -> Option<Figure> {
        // The difference of the pair that fails: ours against the oracle, unless only the
        // oracle and POV-Ray disagree.
        let v = &self.vote;
        let (img, reference, c) = match (&v.oracle_povray, &v.povray_rgb) {
            (Some(c), Some(p)) if !c.passed() && v.ours_oracle.passed() => (&v.oracle_rgb, p, c),
            _ => (&v.ours_rgb, &v.oracle_rgb, &v.ours_oracle),
        };
        Some(Figure {
            name: "difference",
            linear: abs_difference(img, reference),
            png: diff_image(c, img, reference),
        })
    }
}
