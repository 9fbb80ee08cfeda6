//! The closed-form oracle as a [`Reference`]: it checks the classic catalog's scenes it
//! covers, and its image is computed at gate time, so it has nothing to export,
//! regenerate or commit.

use super::outcome::CHECKS;
use super::render::Oracle;
use crate::catalog::{load, Entry};
use crate::checked::Checked;
use crate::manifest::Manifest;
use crate::povray::compare::SILHOUETTE_BUDGET;
use crate::reference::{ExportOptions, Reference, RegenOptions, WorstPlot};
use anyhow::{bail, Result};
use renderer::scene::Scene;
use std::path::Path;

/// The closed-form oracle (conformance/docs/oracle.md).
pub struct ClosedForm;

impl Reference for ClosedForm {
    fn name(&self) -> &'static str {
        "oracle"
    }

    fn title(&self) -> &'static str {
        "the closed-form oracle"
    }

    fn catalog(&self) -> &'static str {
        "povray"
    }

    fn covers(&self, entry: &Entry) -> Result<bool> {
        let (scene, _) = load(entry)?;
        Ok(Oracle::new(&scene).is_ok())
    }

    fn checks(&self) -> &'static [&'static str] {
        &CHECKS
    }

    fn how(&self) -> String {
        "pixel centres (the oracle, f64)".into()
    }

    fn export(&self, _: &Scene, _: &str, _: &ExportOptions, _: &Path) -> Result<()> {
        bail!("the oracle has no input format: it reads the scene itself, at gate time")
    }

    fn regenerate(&self, entries: &[Entry], _: &RegenOptions) -> Result<()> {
        eprintln!(
            "the oracle computes its images at gate time: nothing to regenerate for {} scene(s)",
            entries.len()
        );
        Ok(())
    }

    fn check_regenerated(&self, _: &[Entry]) -> Result<Vec<String>> {
        // Nothing is committed, so nothing can differ.
        Ok(Vec::new())
    }

    fn compare(&self, entry: &Entry, manifest: &Manifest) -> Result<Box<dyn Checked>> {
        Ok(Box::new(super::harness::check(entry, manifest)?))
    }

    fn legend(&self) -> String {
        format!(
            "Oracle rows: a third opinion on the classic scenes, an independent f64 re-derivation of POV-Ray's model with \
closed-form intersections (conformance/docs/oracle.md). Each row gives the three-way vote: ours~POV-Ray, oracle~POV-Ray and \
ours~oracle, each by the POV-Ray comparison (the same tolerance, pixels excused only by geometry, at most {:.2} % of them). The row \
passes when ours agrees with the oracle and the oracle with POV-Ray; its reference image is the oracle's, and its difference image \
shows ours against the oracle (or the oracle against POV-Ray when only that pair disagrees).",
            SILHOUETTE_BUDGET * 100.0
        )
    }

    fn worst_plot(&self) -> WorstPlot {
        WorstPlot {
            title: "Largest pixel error per scene, in tolerances (the oracle: ours~oracle and oracle~POV-Ray)",
            label: "largest error / tolerance (log)",
            mark: Some((1.0, "tolerance")),
        }
    }
}
