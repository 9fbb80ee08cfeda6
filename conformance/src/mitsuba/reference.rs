//! Mitsuba 3 as a [`Reference`]: the physical catalog, compared statistically (radiance)
//! and geometrically (AOVs).

use super::harness::GATE_SPP;
use crate::catalog::Entry;
use crate::checked::Checked;
use crate::manifest::Manifest;
use crate::reference::{ExportOptions, Reference, RegenOptions, WorstPlot};
use anyhow::{Context, Result};
use renderer::scene::Scene;
use std::path::Path;

/// Samples per pixel of a radiance reference unless `--spp` says otherwise.
pub const REFERENCE_SPP: u32 = 8192;

/// Samples per pixel of an exported scene's sampler unless `--spp` says otherwise.
pub const EXPORT_SPP: u32 = 64;

/// Mitsuba 3: `moment` radiance references and pixel-centre geometry of the physical
/// catalog.
pub struct Mitsuba;

impl Reference for Mitsuba {
    fn name(&self) -> &'static str {
        "mitsuba"
    }

    fn title(&self) -> &'static str {
        "Mitsuba 3"
    }

    fn catalog(&self) -> &'static str {
        "mitsuba"
    }

    fn checks(&self) -> &'static [&'static str] {
        &["radiance", "geometry"]
    }

    fn starter(&self) -> Option<&'static str> {
        Some("mi_diffuse_point")
    }

    fn how(&self) -> String {
        format!("{GATE_SPP} spp (Mitsuba)")
    }

    fn export(
        &self,
        scene: &Scene,
        title: &str,
        opts: &ExportOptions,
        output: &Path,
    ) -> Result<()> {
        let _ = title;
        let e = super::export(scene, opts.spp.unwrap_or(EXPORT_SPP), opts.moment)?;
        e.write(output)
            .with_context(|| format!("writing {}", output.display()))
    }

    fn regenerate(&self, entries: &[Entry], opts: &RegenOptions) -> Result<()> {
        super::refgen::regenerate(entries, opts.spp.unwrap_or(REFERENCE_SPP))
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
        "Mitsuba scenes: the z image shows per-pixel z of the two-sample \
test, grey up to 2, <span class=\"sw\" style=\"background:rgb(255,160,0)\"></span> orange above, \
<span class=\"sw\" style=\"background:rgb(230,0,0)\"></span> red past the Šidák threshold. \
See conformance/docs/mitsuba.md."
            .into()
    }

    fn worst_plot(&self) -> WorstPlot {
        WorstPlot {
            title: "Largest per-pixel z per scene (Mitsuba)",
            label: "largest z over pixels and channels (log)",
            mark: None,
        }
    }
}
