//! What every reference renderer does for the gate, as one interface: its name and the
//! catalog scenes it covers, the checks a waiver can name, the export of a scene to its
//! input format, the regeneration of its references (and `--check`), the comparison of
//! our render with a reference, and its part of the report.
//!
//! A reference is a folder (`conformance/src/<name>/`) with a type implementing
//! [`Reference`], and one line in [`crate::registry`]; the gate, the report, the waivers
//! and the command line only iterate over the registry (conformance/docs/references.md).

use crate::catalog::Entry;
use crate::checked::Checked;
use crate::manifest::Manifest;
use anyhow::Result;
use renderer::scene::Scene;
use std::path::Path;

/// Options of `conformance export`; a reference refuses one it has no use for.
#[derive(Clone, Debug, Default)]
pub struct ExportOptions {
    /// Samples per pixel of the exported scene's sampler.
    pub spp: Option<u32>,
    /// Wrap the integrator in one that also writes second moments.
    pub moment: bool,
}

/// Options of `conformance regen` and `new-scene`; a reference refuses one it has no
/// use for.
#[derive(Clone, Debug, Default)]
pub struct RegenOptions {
    /// Samples per pixel of a sampled reference.
    pub spp: Option<u32>,
}

/// How the report plots a reference's worst score per scene.
#[derive(Clone, Copy, Debug)]
pub struct WorstPlot {
    /// The plot's title.
    pub title: &'static str,
    /// The value axis' label.
    pub label: &'static str,
    /// A value marked on the axis, with its name (e.g. 1 tolerance).
    pub mark: Option<(f64, &'static str)>,
}

/// One reference renderer, as the gate, the report, the waivers and the command line see
/// it.
pub trait Reference: Send + Sync {
    /// The short name: the folder `conformance/src/<name>/`, the keys `<name>/<scene>` of
    /// the manifest and the waivers, the tests `<name>::<scene>`, `scripts/regen-<name>.sh`.
    fn name(&self) -> &'static str;

    /// The tool as people name it ("POV-Ray 3.7").
    fn title(&self) -> &'static str;

    /// The catalog whose scenes it checks: the folder `conformance/scenes/<catalog>/`.
    /// The reference whose name is its catalog's name is that catalog's home: it starts
    /// `new-scene`'s scenes, and its scenes keep their bare names in the report's anchors
    /// and failure folders.
    fn catalog(&self) -> &'static str;

    /// Whether it checks this scene of its catalog (every scene by default). A reference
    /// that knows only part of the scene format (physical scenes, certain primitives)
    /// says so here; the scene is then not its test, and not its waiver's.
    fn covers(&self, entry: &Entry) -> Result<bool> {
        let _ = entry;
        Ok(true)
    }

    /// The checks its comparison makes, each of which a waiver can name.
    fn checks(&self) -> &'static [&'static str];

    /// The catalog scene `new-scene` copies when it is given none (home references).
    fn starter(&self) -> Option<&'static str> {
        None
    }

    /// How our renders are made for it, as `results.json` records ("pixel centres").
    fn how(&self) -> String;

    /// Writes `scene` (loaded from a file named `title`) in its input format at `output`.
    fn export(&self, scene: &Scene, title: &str, opts: &ExportOptions, output: &Path)
        -> Result<()>;

    /// Regenerates the references of `entries` with the tool and records them in
    /// `references/manifest.toml`.
    fn regenerate(&self, entries: &[Entry], opts: &RegenOptions) -> Result<()>;

    /// Regenerates the references of `entries` into a scratch folder and compares them with
    /// the committed ones; returns the scenes that differ.
    fn check_regenerated(&self, entries: &[Entry]) -> Result<Vec<String>>;

    /// Renders the scene as the comparison needs and compares it with the committed
    /// reference: the verdict before waivers, and what it measured.
    fn compare(&self, entry: &Entry, manifest: &Manifest) -> Result<Box<dyn Checked>>;

    /// Its paragraph of the report's "How to read it" (HTML).
    fn legend(&self) -> String;

    /// How the report plots [`Checked::worst_score`].
    fn worst_plot(&self) -> WorstPlot;
}

impl std::fmt::Debug for dyn Reference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
