//! One scene against its POV-Ray reference: the pixel-centre comparison's verdict, its
//! metrics, its worst pixels and its difference image, as the gate reads them
//! ([`Checked`]).

use super::compare::{diff_image, error_in_tolerances, Comparison};
use crate::checked::{abs_difference, worst_pixels, Checked, Figure, Pixel};
use crate::verdict::Verdict;
use renderer::render::Image;

/// One scene against POV-Ray.
pub struct Outcome {
    /// Scene name.
    pub scene: String,
    /// The verdict before waivers.
    pub verdict: Verdict,
    /// The comparison, when a reference exists.
    pub cmp: Option<Comparison>,
    /// Our render.
    pub ours: Image,
    /// The reference pixels (RGB), when they exist.
    pub reference_rgb: Option<Vec<f32>>,
    /// Seconds our render took.
    pub seconds: f64,
}

impl Checked for Outcome {
    fn reference(&self) -> &str {
        "povray"
    }

    fn catalog(&self) -> &str {
        "povray"
    }

    fn scene(&self) -> &str {
        &self.scene
    }

    fn verdict(&self) -> Verdict {
        self.verdict
    }

    fn checks(&self) -> Vec<(&'static str, bool)> {
        self.cmp.iter().map(|c| ("pixels", c.passed())).collect()
    }

    fn metrics(&self) -> String {
        match &self.cmp {
            Some(c) => format!(
                "{} failing pixels, {} excused by geometry ({}; budget {}), max abs {:.3e}, mean abs {:.3e}, RMSE {:.3e}",
                c.failing,
                c.silhouette,
                c.excused,
                c.budget(),
                c.max_abs,
                c.mean_abs,
                c.rmse
            ),
            None => "no reference".into(),
        }
    }

    fn ours(&self) -> &Image {
        &self.ours
    }

    fn reference_rgb(&self) -> Option<&[f32]> {
        self.reference_rgb.as_deref()
    }

    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn worst(&self, n: usize) -> Vec<Pixel> {
        let (Some(c), Some(reference)) = (&self.cmp, &self.reference_rgb) else {
            return Vec::new();
        };
        let ours = &self.ours.rgb;
        let class = |k: usize| {
            match c.class[k] {
                0 => "within tolerance",
                1 => "excused (geometry)",
                _ => "FAILING",
            }
            .to_string()
        };
        // Failing pixels first, then excused ones, each by the size of the error.
        let score = |k: usize| c.class[k] as f64 * 1e12 + error_in_tolerances(ours, reference, k);
        worst_pixels(self.ours.width as usize, ours, reference, n, &score, &class)
    }

    fn pixel_note(&self, pixel: &Pixel) -> String {
        format!(", {:.1}× the tolerance", pixel.score.rem_euclid(1e12))
    }

    fn worst_score(&self) -> f64 {
        self.reference_rgb.as_ref().map_or(0.0, |r| {
            (0..r.len() / 3)
                .map(|k| error_in_tolerances(&self.ours.rgb, r, k))
                .fold(0.0, f64::max)
        })
    }

    fn figure(&self) -> Option<Figure> {
        let (Some(c), Some(reference)) = (&self.cmp, &self.reference_rgb) else {
            return None;
        };
        Some(Figure {
            name: "difference",
            linear: abs_difference(&self.ours.rgb, reference),
            png: diff_image(c, &self.ours.rgb, reference),
        })
    }
}
