//! POV-Ray 3.7 as a [`Reference`]: the classic catalog, compared pixel by pixel.

use super::compare::SILHOUETTE_BUDGET;
use crate::catalog::Entry;
use crate::checked::Checked;
use crate::manifest::Manifest;
use crate::reference::{ExportOptions, Reference, RegenOptions, WorstPlot};
use anyhow::{Context, Result};
use renderer::scene::Scene;
use std::path::Path;

/// POV-Ray 3.7: deterministic pixel-centre references of the classic catalog.
pub struct PovRay;

impl Reference for PovRay {
    fn name(&self) -> &'static str {
        "povray"
    }

    fn title(&self) -> &'static str {
        "POV-Ray 3.7"
    }

    fn catalog(&self) -> &'static str {
        "povray"
    }

    fn checks(&self) -> &'static [&'static str] {
        &["pixels"]
    }

    fn starter(&self) -> Option<&'static str> {
        Some("prim_sphere_identity")
    }

    fn how(&self) -> String {
        "pixel centres (POV-Ray)".into()
    }

    fn export(
        &self,
        scene: &Scene,
        title: &str,
        opts: &ExportOptions,
        output: &Path,
    ) -> Result<()> {
        anyhow::ensure!(
            opts.spp.is_none() && !opts.moment,
            "--spp and --moment do not apply to POV-Ray (a pixel-centre render)"
        );
        std::fs::write(output, super::export(scene, title))
            .with_context(|| format!("writing {}", output.display()))
    }

    fn regenerate(&self, entries: &[Entry], opts: &RegenOptions) -> Result<()> {
        anyhow::ensure!(
            opts.spp.is_none(),
            "--spp does not apply to POV-Ray references (pixel centres, one sample each)"
        );
        super::refgen::regenerate(entries)
    }

    fn check_regenerated(&self, entries: &[Entry]) -> Result<Vec<String>> {
        super::refgen::check(entries)
    }

    fn compare(&self, entry: &Entry, manifest: &Manifest) -> Result<Box<dyn Checked>> {
        Ok(Box::new(super::harness::check(entry, manifest)?))
    }

    fn legend(&self) -> String {
        format!(
            "POV-Ray scenes: the difference image shows agreeing pixels as dimmed grey, pixels excused by geometry \
<span class=\"sw\" style=\"background:rgb(0,160,255)\"></span> blue, and failing pixels by the size of the error \
relative to the per-pixel tolerance (1.05·2<sup>−11</sup>·|ref| + 1e-6): 1× <span class=\"legend\"></span> ≥ 1000× (log scale). \
A pixel is excused only when our own renderer, traced again within 1e-3 pixel of the centre (or 1e-2 across a discontinuity), takes \
the reference's value; at most {:.2} % of pixels may be excused. See conformance/docs/tolerances.md.",
            SILHOUETTE_BUDGET * 100.0
        )
    }

    fn worst_plot(&self) -> WorstPlot {
        WorstPlot {
            title: "Largest pixel error per scene, in tolerances (POV-Ray)",
            label: "largest |ours − reference| / tolerance (log)",
            mark: Some((1.0, "tolerance")),
        }
    }
}
