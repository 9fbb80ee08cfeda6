//! One catalog scene against one reference, judged for the gate and the report: the
//! verdict after waivers, and, for a scene that does not pass, a message that points at
//! the problem (metrics, the worst pixels, failure images on disk, the command that fixes
//! or shows it). Every reference is judged the same way, through [`Checked`]; the scenes
//! that several references check get a verdict from each ([`by_scene`]).

use crate::catalog::{repo_root, Entry};
use crate::checked::{abs_difference, Checked, Pixel};
use crate::manifest::Manifest;
use crate::reference::Reference;
use crate::registry::Registry;
use crate::verdict::Verdict;
use crate::waivers::{Waiver, Waivers};
use anyhow::{Context, Result};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Where build products and reports go: `$CARGO_TARGET_DIR` when set (relative to the
/// current directory, as cargo reads it), else `<repo>/target`.
pub fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) if !d.is_empty() => {
            let d = PathBuf::from(d);
            if d.is_absolute() {
                d
            } else {
                std::env::current_dir().map(|c| c.join(&d)).unwrap_or(d)
            }
        }
        _ => repo_root().join("target"),
    }
}

/// The folder of the conformance report (`<target>/conformance`).
pub fn report_dir() -> PathBuf {
    target_dir().join("conformance")
}

/// The folder of one scene's failure images.
pub fn failure_dir(scene: &str) -> PathBuf {
    report_dir().join("failures").join(scene)
}

/// A scene judged against its reference, waivers applied.
pub struct Judged {
    /// The comparison.
    pub checked: Box<dyn Checked>,
    /// The verdict: a failure whose every failing check is waived is [`Verdict::Waived`].
    pub verdict: Verdict,
    /// The waivers that excuse this scene's failing checks.
    pub waived: Vec<Waiver>,
    /// Waivers of checks that pass again: they must be removed.
    pub stale_waivers: Vec<Waiver>,
}

/// Checks one scene against `reference` and applies the waivers.
pub fn check(
    reference: &dyn Reference,
    entry: &Entry,
    manifest: &Manifest,
    waivers: &Waivers,
) -> Result<Judged> {
    let checked = reference.compare(entry, manifest)?;
    anyhow::ensure!(
        checked.reference() == reference.name() && checked.scene() == entry.name,
        "{}'s comparison of {} says it is {}'s of {}",
        reference.name(),
        entry.name,
        checked.reference(),
        checked.scene()
    );
    Ok(judge(checked, waivers))
}

/// Checks every scene of `registry` that `filter` selects ([`Registry::select`]), in
/// reference then name order.
pub fn check_all(
    registry: &Registry,
    filter: &str,
    manifest: &Manifest,
    waivers: &Waivers,
) -> Result<Vec<Judged>> {
    let mut judged = Vec::new();
    for (reference, e) in registry.select(filter)? {
        judged.push(
            check(reference, &e, manifest, waivers)
                .with_context(|| format!("{}/{}", reference.name(), e.name))?,
        );
    }
    Ok(judged)
}

/// Applies the waivers to a comparison.
pub fn judge(checked: Box<dyn Checked>, waivers: &Waivers) -> Judged {
    let verdict = checked.verdict();
    let (reference, scene) = (checked.reference().to_string(), checked.scene().to_string());
    let mut j = Judged {
        checked,
        verdict,
        waived: Vec::new(),
        stale_waivers: Vec::new(),
    };
    // Staleness and missing references are never waived, and say nothing about whether
    // a waived check passes.
    if !matches!(verdict, Verdict::Pass | Verdict::Fail) {
        return j;
    }
    let mut unwaived_failure = false;
    for (check, passed) in j.checked.checks() {
        match (waivers.find(&reference, &scene, check), passed) {
            (Some(w), true) => j.stale_waivers.push(w.clone()),
            (Some(w), false) => j.waived.push(w.clone()),
            (None, false) => unwaived_failure = true,
            (None, true) => {}
        }
    }
    if verdict == Verdict::Fail && !unwaived_failure {
        j.verdict = Verdict::Waived;
    }
    j
}

fn rgb(v: [f32; 3]) -> String {
    format!("({:.5}, {:.5}, {:.5})", v[0], v[1], v[2])
}

/// The command that regenerates a scene's reference.
pub fn regen_command(reference: &str, scene: &str) -> String {
    format!("scripts/regen-{reference}.sh {scene}")
}

/// The command that shows a scene in the report (every reference's verdict of it), and
/// the anchor of its row (`key`, [`Judged::key`]).
pub fn show_command(scene: &str, key: &str) -> String {
    format!(
        "cargo run --release -p conformance -- run {scene}   # then open {}#{key}",
        report_dir().join("index.html").display()
    )
}

/// [`Judged::key`] of a comparison.
pub fn key(checked: &dyn Checked) -> String {
    if checked.reference() == checked.catalog() {
        checked.scene().to_string()
    } else {
        format!("{}@{}", checked.scene(), checked.reference())
    }
}

/// Every reference's verdict of one catalog scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneVerdicts {
    /// The scene's catalog.
    pub catalog: String,
    /// The scene.
    pub scene: String,
    /// Each reference that checked it and its verdict (after waivers), in the order
    /// judged.
    pub verdicts: Vec<(String, Verdict)>,
}

impl SceneVerdicts {
    /// The pairs of references that disagree about the scene: one passes it where the
    /// other fails it (a waived failure is a failure). A stale or missing reference says
    /// nothing either way.
    pub fn disagreements(&self) -> Vec<(&str, &str)> {
        let mut v = Vec::new();
        for (i, (a, va)) in self.verdicts.iter().enumerate() {
            for (b, vb) in &self.verdicts[i + 1..] {
                let fails = |v: &Verdict| matches!(v, Verdict::Fail | Verdict::Waived);
                let disagree =
                    (*va == Verdict::Pass && fails(vb)) || (fails(va) && *vb == Verdict::Pass);
                if disagree {
                    v.push((a.as_str(), b.as_str()));
                }
            }
        }
        v
    }
}

/// The verdicts grouped by scene (catalog and name), in the order the scenes first come
/// in `judged`.
pub fn by_scene(judged: &[Judged]) -> Vec<SceneVerdicts> {
    let mut out: Vec<SceneVerdicts> = Vec::new();
    for j in judged {
        let (catalog, scene) = (j.checked.catalog(), j.checked.scene());
        let at = match out
            .iter()
            .position(|s| s.catalog == catalog && s.scene == scene)
        {
            Some(k) => k,
            None => {
                out.push(SceneVerdicts {
                    catalog: catalog.to_string(),
                    scene: scene.to_string(),
                    verdicts: Vec::new(),
                });
                out.len() - 1
            }
        };
        out[at]
            .verdicts
            .push((j.checked.reference().to_string(), j.verdict));
    }
    out
}

impl Judged {
    /// Whether the gate accepts the scene: it passes, or fails only in waived checks, and
    /// no waiver of it is stale.
    pub fn accepted(&self) -> bool {
        matches!(self.verdict, Verdict::Pass | Verdict::Waived) && self.stale_waivers.is_empty()
    }

    /// The scene's key in the report's anchors and the failure folders: its name when
    /// the reference is its catalog's home ([`Reference::catalog`]), else
    /// `<scene>@<reference>`, so that every reference of a scene has its own.
    pub fn key(&self) -> String {
        key(&*self.checked)
    }

    /// The pixels of the failure message: the 8 worst.
    pub fn worst(&self) -> Vec<Pixel> {
        self.checked.worst(8)
    }

    /// Writes ours, the reference, the difference and the comparison's own figure (e.g.
    /// the z image) as EXR and PNG into `dir`, and returns the paths written.
    pub fn write_images(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir)?;
        let ours = self.checked.ours();
        let (w, h) = (ours.width, ours.height);
        let mut written = Vec::new();
        let mut save = |name: &str, linear: &[f32], png: Option<Vec<u8>>| -> Result<()> {
            let img = crate::images::image_of(w, h, linear);
            let exr = dir.join(format!("{name}.exr"));
            renderer::output::write_exr(&img, &exr)?;
            let png_path = dir.join(format!("{name}.png"));
            let bytes = png.unwrap_or_else(|| {
                renderer::output::to_rgb8(&img, renderer::output::ToneMap::Srgb)
            });
            crate::images::save_png(&png_path, w, h, bytes)?;
            written.extend([exr, png_path]);
            Ok(())
        };
        save("ours", &ours.rgb, None)?;
        let Some(reference) = self.checked.reference_rgb() else {
            return Ok(written);
        };
        save("reference", reference, None)?;
        let figure = self.checked.figure();
        if figure.as_ref().is_none_or(|f| f.name != "difference") {
            save("difference", &abs_difference(&ours.rgb, reference), None)?;
        }
        if let Some(f) = figure {
            save(f.name, &f.linear, Some(f.png))?;
        }
        Ok(written)
    }

    /// What the gate prints for a scene it does not accept: the verdict and metrics, the
    /// worst pixels, the failure images (written under [`failure_dir`]), and the commands
    /// that show or fix it.
    pub fn failure_message(&self) -> String {
        self.failure_message_to(&failure_dir(&self.key()))
    }

    /// [`Self::failure_message`] with the images written into `dir`.
    pub fn failure_message_to(&self, dir: &Path) -> String {
        let (reference, scene) = (self.checked.reference(), self.checked.scene());
        let mut m = format!("{reference}/{scene}: {}\n", self.verdict);
        let scene_file = format!("conformance/scenes/{}/{scene}.toml", self.checked.catalog());
        match self.verdict {
            Verdict::Missing => {
                writeln!(
                    m,
                    "  {scene_file} has no reference in references/manifest.toml.\n  Fix: {}   (installs {reference} if needed, writes the reference and its manifest entry; commit both)",
                    regen_command(reference, scene)
                )
                .unwrap();
            }
            Verdict::Stale => {
                writeln!(
                    m,
                    "  {scene_file} (or its export) changed since its reference was made: the recorded hashes in references/manifest.toml differ.\n  \
If the change is deliberate, fix: {}   and commit the new reference; if not, undo the change to the scene or the exporter.",
                    regen_command(reference, scene)
                )
                .unwrap();
            }
            _ => {}
        }
        writeln!(m, "  {}", self.checked.metrics()).unwrap();
        for w in &self.stale_waivers {
            writeln!(
                m,
                "  STALE WAIVER: the `{}` check passes again; remove the entry at {}:{} ({})",
                w.check,
                self.waived_path(),
                w.line,
                w.reason
            )
            .unwrap();
        }
        for w in &self.waived {
            writeln!(m, "  WAIVED ({}:{}): {w}", self.waived_path(), w.line).unwrap();
        }
        let worst = self.worst();
        if !worst.is_empty() {
            writeln!(
                m,
                "  worst pixels (x, y from the top left): ours, reference, |difference|, class"
            )
            .unwrap();
            for p in &worst {
                let d = [0, 1, 2].map(|c| (p.ours[c] - p.reference[c]).abs());
                writeln!(
                    m,
                    "    ({:>4}, {:>4})  {}  {}  {}  {}{}",
                    p.x,
                    p.y,
                    rgb(p.ours),
                    rgb(p.reference),
                    rgb(d),
                    p.class,
                    self.checked.pixel_note(p)
                )
                .unwrap();
            }
        }
        match self.write_images(dir) {
            Ok(paths) => {
                writeln!(m, "  images: {}", dir.display()).unwrap();
                for p in paths {
                    writeln!(m, "    {}", p.display()).unwrap();
                }
            }
            Err(e) => writeln!(
                m,
                "  could not write failure images to {}: {e:#}",
                dir.display()
            )
            .unwrap(),
        }
        writeln!(
            m,
            "  show it in the report: {}",
            show_command(scene, &self.key())
        )
        .unwrap();
        writeln!(
            m,
            "  workflows (regenerate, review, waive): conformance/docs/workflows.md"
        )
        .unwrap();
        m
    }

    fn waived_path(&self) -> &'static str {
        "conformance/waivers.toml"
    }
}
