//! One scene against its Cycles references. The tests and what they measure are Mitsuba's
//! (`crate::mitsuba::outcome`); only the reference's name differs.

use crate::checked::{Checked, Figure, Pixel};
use crate::mitsuba::outcome::Outcome as Measured;
use crate::verdict::Verdict;
use renderer::render::Image;

/// One scene against Cycles: Mitsuba's measured outcome, reported as Cycles'.
pub struct Outcome(pub Measured);

impl Checked for Outcome {
    fn reference(&self) -> &str {
        "cycles"
    }

    fn catalog(&self) -> &str {
        self.0.catalog()
    }

    fn scene(&self) -> &str {
        self.0.scene()
    }

    fn verdict(&self) -> Verdict {
        self.0.verdict()
    }

    fn checks(&self) -> Vec<(&'static str, bool)> {
        self.0.checks()
    }

    fn metrics(&self) -> String {
        self.0.metrics()
    }

    fn ours(&self) -> &Image {
        self.0.ours()
    }

    fn reference_rgb(&self) -> Option<&[f32]> {
        self.0.reference_rgb()
    }

    fn seconds(&self) -> f64 {
        self.0.seconds()
    }

    fn worst(&self, n: usize) -> Vec<Pixel> {
        self.0.worst(n)
    }

    fn worst_score(&self) -> f64 {
        self.0.worst_score()
    }

    fn figure(&self) -> Option<Figure> {
        self.0.figure()
    }
}
