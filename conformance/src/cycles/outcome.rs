//! One scene against its Cycles references. The tests and what they measure are Mitsuba's
//! (`crate::mitsuba::outcome`); only the reference's name differs.

use crate::checked::{Checked, Figure, Pixel};
use crate::mitsuba::compare::RadianceTest;
use crate::mitsuba::outcome::Outcome as Measured;
use crate::verdict::Verdict;
use renderer::render::Image;

/// What the report says when Mitsuba's and Cycles' references disagree beyond their
/// noise: which of them we side with, and why. The physical model follows Mitsuba's
/// definitions (renderer/docs/physical.md), and ours must pass against Mitsuba for the
/// gate to pass at all, so a disagreement between the references is read in Mitsuba's
/// favour until the cause is found (conformance/docs/cycles.md, "The three-way verdict").
pub const SIDE_WITH: &str = "INCONSISTENT: we side with Mitsuba, whose definitions the \
physical model follows (conformance/docs/cycles.md)";

/// One scene against Cycles: Mitsuba's measured outcome, reported as Cycles', and the two
/// references against each other.
pub struct Outcome {
    /// Our render against Cycles' references, by Mitsuba's tests.
    pub measured: Measured,
    /// Mitsuba's radiance reference against Cycles' (the same two-sample test; both have
    /// a variance), when both exist.
    pub references: Option<RadianceTest>,
}

impl Checked for Outcome {
    fn reference(&self) -> &str {
        "cycles"
    }

    fn catalog(&self) -> &str {
        self.measured.catalog()
    }

    fn scene(&self) -> &str {
        self.measured.scene()
    }

    fn verdict(&self) -> Verdict {
        self.measured.verdict()
    }

    fn checks(&self) -> Vec<(&'static str, bool)> {
        self.measured.checks()
    }

    fn metrics(&self) -> String {
        let ours = self.measured.metrics();
        match &self.references {
            Some(r) => format!(
                "{ours}; Mitsuba's reference against Cycles': {} ({:.3} % of pixel-channels \
pass, global z {:.2} {:.2} {:.2})",
                if r.passed() { "consistent" } else { SIDE_WITH },
                r.pass_fraction * 100.0,
                r.global_z[0],
                r.global_z[1],
                r.global_z[2]
            ),
            None => ours,
        }
    }

    fn ours(&self) -> &Image {
        self.measured.ours()
    }

    fn reference_rgb(&self) -> Option<&[f32]> {
        self.measured.reference_rgb()
    }

    fn seconds(&self) -> f64 {
        self.measured.seconds()
    }

    fn worst(&self, n: usize) -> Vec<Pixel> {
        self.measured.worst(n)
    }

    fn worst_score(&self) -> f64 {
        self.measured.worst_score()
    }

    fn figure(&self) -> Option<Figure> {
        self.measured.figure()
    }
}
