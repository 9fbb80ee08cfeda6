//! Blender Cycles as a [`Reference`]: the physical catalog (the scenes Mitsuba checks),
//! compared with the same statistical (radiance) and geometric (AOV) tests.

use crate::catalog::Entry;
use crate::checked::Checked;
use crate::manifest::Manifest;
use crate::mitsuba::harness::GATE_SPP;
use crate::reference::{ExportOptions, Reference, RegenOptions, WorstPlot};
use anyhow::{Context, Result};
use renderer::scene::Scene;
use std::path::Path;

/// Blender Cycles 5.0 (PyPI `bpy`): seed-variance radiance references and pixel-centre
/// geometry of the physical catalog.
pub struct Cycles;

impl Reference for Cycles {
    fn name(&self) -> &'static str {
        "cycles"
    }

    fn title(&self) -> &'static str {
        "Blender Cycles 5.0"
    }

    fn catalog(&self) -> &'static str {
        "mitsuba"
    }

    fn checks(&self) -> &'static [&'static str] {
        &["radiance", "geometry"]
    }

    fn how(&self) -> String {
        format!("{GATE_SPP} spp (Cycles)")
    }

    fn export(
        &self,
        scene: &Scene,
        title: &str,
        opts: &ExportOptions,
        output: &Path,
    ) -> Result<()> {
        let _ = title;
        anyhow::ensure!(
            opts.spp.is_none() && !opts.moment,
            "the Cycles export takes neither --spp nor --moment: samples and seeds are \
arguments of scripts/cycles_refs.py"
        );
        let text = super::refgen::export_text(scene)?;
        let tmp = output.with_extension("json.tmp");
        std::fs::write(&tmp, text).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, output).with_context(|| format!("writing {}", output.display()))
    }

    fn regenerate(&self, entries: &[Entry], opts: &RegenOptions) -> Result<()> {
        anyhow::ensure!(
            opts.spp.is_none(),
            "Cycles references take no --spp: {} seeds of {} samples (conformance/docs/cycles.md)",
            super::refgen::SEEDS,
            super::refgen::SEED_SPP
        );
        super::refgen::regenerate(entries)
    }

    fn check_regenerated(&self, entries: &[Entry]) -> Result<Vec<String>> {
        super::refgen::check(entries)
    }

    fn compare(&self, entry: &Entry, manifest: &Manifest) -> Result<Box<dyn Checked>> {
        Ok(Box::new(super::harness::check(
            entry, manifest, GATE_SPP, None,
        )?))
    }

    fn legend(&self) -> String {
        "Cycles scenes: as Mitsuba's, the z image shows per-pixel z of the two-sample test \
(the reference's variance from 16 independent seeds). See conformance/docs/cycles.md."
            .into()
    }

    fn worst_plot(&self) -> WorstPlot {
        WorstPlot {
            title: "Largest per-pixel z per scene (Cycles)",
            label: "largest z over pixels and channels (log)",
            mark: None,
        }
    }
}
