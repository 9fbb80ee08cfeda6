//! One catalog scene against one reference, judged for the gate and the report: the
//! verdict after waivers, and, for a scene that does not pass, a message that points at
//! the problem (metrics, the worst pixels, failure images on disk, the command that fixes
//! or shows it).

use crate::catalog::{repo_root, Entry};
use crate::manifest::Manifest;
use crate::mitsuba::harness::{check_mitsuba, MiOutcome, GATE_SPP};
use crate::povray::compare::{diff_image, tol};
use crate::povray::harness::{check_povray, Outcome};
use crate::verdict::Verdict;
use crate::waivers::{Waiver, Waivers};
use anyhow::Result;
use renderer::render::Image;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The references a catalog scene can be checked against (`conformance/scenes/<ref>/`).
pub const REFERENCES: [&str; 2] = ["povray", "mitsuba"];

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

/// What was checked.
pub enum Checked {
    /// Pixel by pixel against POV-Ray.
    Povray(Outcome),
    /// Statistically (radiance) and geometrically against Mitsuba 3.
    Mitsuba(MiOutcome),
}

/// A scene judged against its reference, waivers applied.
pub struct Judged {
    /// The comparison.
    pub checked: Checked,
    /// The verdict: a failure whose every failing check is waived is [`Verdict::Waived`].
    pub verdict: Verdict,
    /// The waivers that excuse this scene's failing checks.
    pub waived: Vec<Waiver>,
    /// Waivers of checks that pass again: they must be removed.
    pub stale_waivers: Vec<Waiver>,
}

/// Checks one scene of the `reference` catalog and applies the waivers.
pub fn check(
    reference: &str,
    entry: &Entry,
    manifest: &Manifest,
    waivers: &Waivers,
) -> Result<Judged> {
    let checked = match reference {
        "povray" => Checked::Povray(check_povray(entry, manifest)?),
        "mitsuba" => Checked::Mitsuba(check_mitsuba(entry, manifest, GATE_SPP, None)?),
        other => anyhow::bail!("unknown reference {other} (one of {REFERENCES:?})"),
    };
    Ok(judge(checked, waivers))
}

/// Applies the waivers to a comparison.
pub fn judge(checked: Checked, waivers: &Waivers) -> Judged {
    let verdict = checked.raw_verdict();
    let (reference, scene) = (checked.reference(), checked.scene().to_string());
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
        match (waivers.find(reference, &scene, check), passed) {
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

impl Checked {
    /// The reference's name.
    pub fn reference(&self) -> &'static str {
        match self {
            Checked::Povray(_) => "povray",
            Checked::Mitsuba(_) => "mitsuba",
        }
    }

    /// The scene's name.
    pub fn scene(&self) -> &str {
        match self {
            Checked::Povray(o) => &o.scene,
            Checked::Mitsuba(o) => &o.scene,
        }
    }

    /// Our render.
    pub fn ours(&self) -> &Image {
        match self {
            Checked::Povray(o) => &o.ours,
            Checked::Mitsuba(o) => &o.ours,
        }
    }

    /// The reference's RGB pixels, when there is a reference.
    pub fn reference_rgb(&self) -> Option<&[f32]> {
        match self {
            Checked::Povray(o) => o.reference_rgb.as_deref(),
            Checked::Mitsuba(o) => o.reference_rgb.as_deref(),
        }
    }

    /// Seconds our render took.
    pub fn seconds(&self) -> f64 {
        match self {
            Checked::Povray(o) => o.seconds,
            Checked::Mitsuba(o) => o.seconds,
        }
    }

    fn raw_verdict(&self) -> Verdict {
        match self {
            Checked::Povray(o) => o.verdict,
            Checked::Mitsuba(o) => o.verdict,
        }
    }

    /// Each check of the comparison and whether it passed (empty without a reference).
    pub fn checks(&self) -> Vec<(&'static str, bool)> {
        match self {
            Checked::Povray(o) => o.cmp.iter().map(|c| ("pixels", c.passed())).collect(),
            Checked::Mitsuba(o) => {
                let mut v = Vec::new();
                if let Some(r) = &o.radiance {
                    v.push(("radiance", r.passed()));
                }
                if let Some(g) = &o.geometry {
                    v.push(("geometry", g.passed()));
                }
                v
            }
        }
    }

    /// One line of metrics.
    pub fn metrics(&self) -> String {
        match self {
            Checked::Povray(o) => match &o.cmp {
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
            },
            Checked::Mitsuba(o) => match (&o.radiance, &o.geometry) {
                (Some(r), Some(g)) => format!(
                    "radiance: {:.3} % of pixel-channels pass (need {:.2} %), global z {:.2} {:.2} {:.2} (need |z| < {}), RMSE {:.3e}; \
geometry: distance error {:.1e}, normal {:.4}°, {} failing and {} edge pixels (budget {})",
                    r.pass_fraction * 100.0,
                    crate::mitsuba::stats::PIXEL_PASS_FRACTION * 100.0,
                    r.global_z[0],
                    r.global_z[1],
                    r.global_z[2],
                    crate::mitsuba::stats::GLOBAL_Z,
                    r.rmse,
                    g.max_rel_distance,
                    g.max_normal_degrees,
                    g.failing,
                    g.silhouette,
                    g.budget
                ),
                _ => "no reference".into(),
            },
        }
    }
}

/// One pixel of a failure message.
#[derive(Clone, Debug, PartialEq)]
pub struct Pixel {
    /// Column (0 at the left).
    pub x: usize,
    /// Row (0 at the top).
    pub y: usize,
    /// Our value.
    pub ours: [f32; 3],
    /// The reference's value.
    pub reference: [f32; 3],
    /// How the comparison classed it: failing, excused, within tolerance, or (Mitsuba)
    /// the pixel's z.
    pub class: String,
    /// The ranking key (larger is worse).
    pub score: f64,
}

/// The `n` worst pixels: by `score(k)`, largest first (ties by position).
pub fn worst_pixels(
    width: usize,
    ours: &[f32],
    reference: &[f32],
    n: usize,
    score: &dyn Fn(usize) -> f64,
    class: &dyn Fn(usize) -> String,
) -> Vec<Pixel> {
    let px = ours.len() / 3;
    let mut order: Vec<usize> = (0..px).collect();
    order.sort_by(|&a, &b| score(b).total_cmp(&score(a)).then(a.cmp(&b)));
    order
        .into_iter()
        .take(n)
        .map(|k| Pixel {
            x: k % width,
            y: k / width,
            ours: [0, 1, 2].map(|c| ours[3 * k + c]),
            reference: [0, 1, 2].map(|c| reference[3 * k + c]),
            class: class(k),
            score: score(k),
        })
        .collect()
}

/// The largest channel error of pixel `k`, in units of the comparison's tolerance.
pub fn error_in_tolerances(ours: &[f32], reference: &[f32], k: usize) -> f64 {
    (0..3)
        .map(|c| {
            let r = reference[3 * k + c] as f64;
            (ours[3 * k + c] as f64 - r).abs() / tol(r)
        })
        .fold(0.0, f64::max)
}

fn rgb(v: [f32; 3]) -> String {
    format!("({:.5}, {:.5}, {:.5})", v[0], v[1], v[2])
}

/// The command that regenerates a scene's reference.
pub fn regen_command(reference: &str, scene: &str) -> String {
    format!("scripts/regen-{reference}.sh {scene}")
}

/// The command that shows a scene in the report.
pub fn show_command(scene: &str) -> String {
    format!(
        "cargo run --release -p conformance -- run {scene}   # then open {}#{scene}",
        report_dir().join("index.html").display()
    )
}

impl Judged {
    /// Whether the gate accepts the scene: it passes, or fails only in waived checks, and
    /// no waiver of it is stale.
    pub fn accepted(&self) -> bool {
        matches!(self.verdict, Verdict::Pass | Verdict::Waived) && self.stale_waivers.is_empty()
    }

    /// The pixels of the failure message: the 8 worst.
    pub fn worst(&self) -> Vec<Pixel> {
        let (ours, Some(reference)) = (self.checked.ours(), self.checked.reference_rgb()) else {
            return Vec::new();
        };
        let w = ours.width as usize;
        match &self.checked {
            Checked::Povray(o) => {
                let Some(c) = &o.cmp else { return Vec::new() };
                let class = |k: usize| {
                    match c.class[k] {
                        0 => "within tolerance",
                        1 => "excused (geometry)",
                        _ => "FAILING",
                    }
                    .to_string()
                };
                // Failing pixels first, then excused ones, each by the size of the error.
                let score = |k: usize| {
                    c.class[k] as f64 * 1e12 + error_in_tolerances(&ours.rgb, reference, k)
                };
                worst_pixels(w, &ours.rgb, reference, 8, &score, &class)
            }
            Checked::Mitsuba(o) => {
                let Some(r) = &o.radiance else {
                    return Vec::new();
                };
                let class = |k: usize| format!("z = {:.1}", r.z_max[k]);
                worst_pixels(w, &ours.rgb, reference, 8, &|k| r.z_max[k], &class)
            }
        }
    }

    /// Writes ours, the reference and the difference (and for Mitsuba the z image) as EXR
    /// and PNG into `dir`, and returns the paths written.
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
        let abs: Vec<f32> = ours
            .rgb
            .iter()
            .zip(reference)
            .map(|(a, b)| (a - b).abs())
            .collect();
        let diff_png = match &self.checked {
            Checked::Povray(o) => o.cmp.as_ref().map(|c| diff_image(c, &ours.rgb, reference)),
            Checked::Mitsuba(_) => None,
        };
        save("difference", &abs, diff_png)?;
        if let Checked::Mitsuba(MiOutcome {
            radiance: Some(r), ..
        }) = &self.checked
        {
            let z: Vec<f32> = r.z_max.iter().flat_map(|&v| [v as f32; 3]).collect();
            let alpha = crate::mitsuba::stats::sidak_alpha((w * h) as usize);
            save("z", &z, Some(crate::images::z_image(&r.z_max, alpha)))?;
        }
        Ok(written)
    }

    /// What the gate prints for a scene it does not accept: the verdict and metrics, the
    /// worst pixels, the failure images (written under [`failure_dir`]), and the commands
    /// that show or fix it.
    pub fn failure_message(&self) -> String {
        self.failure_message_to(&failure_dir(self.checked.scene()))
    }

    /// [`Self::failure_message`] with the images written into `dir`.
    pub fn failure_message_to(&self, dir: &Path) -> String {
        let (reference, scene) = (self.checked.reference(), self.checked.scene());
        let mut m = format!("{reference}/{scene}: {}\n", self.verdict);
        let scene_file = format!("conformance/scenes/{reference}/{scene}.toml");
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
                    match &self.checked {
                        Checked::Povray(_) =>
                            format!(", {:.1}× the tolerance", p.score.rem_euclid(1e12)),
                        Checked::Mitsuba(_) => String::new(),
                    }
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
        writeln!(m, "  show it in the report: {}", show_command(scene)).unwrap();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test02_worst_pixels_rank_by_score_then_position() {
        let ours = [
            0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0,
        ];
        let reference = [0.0f32; 12];
        let score = |k: usize| ours[3 * k] as f64;
        let p = worst_pixels(2, &ours, &reference, 3, &score, &|k| k.to_string());
        let at: Vec<(usize, usize)> = p.iter().map(|p| (p.x, p.y)).collect();
        assert_eq!(at, [(1, 0), (1, 1), (0, 1)]);
        assert_eq!(p[0].ours, [1.0; 3]);
    }
}
