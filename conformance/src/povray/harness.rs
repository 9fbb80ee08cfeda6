//! Running the POV-Ray catalog: render each scene, check its reference is fresh, compare.

use super::compare::{compare, Comparison};
use crate::catalog::{load, repo_root, Entry};
use crate::manifest::{freshness, Freshness, Manifest};
use crate::verdict::Verdict;
use anyhow::{Context, Result};
use renderer::render::{render, Image, Options};
use renderer::scene::Scene;

/// One row of the report.
pub struct Outcome {
    /// Scene name.
    pub scene: String,
    /// Reference tool.
    pub reference: String,
    /// The verdict.
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

/// Renders a scene the way the conformance suite does: pixel centres, every core.
pub fn render_for_conformance(scene: &Scene) -> Image {
    render(scene, &Options::default())
}

/// Reads a reference EXR's RGB channels.
pub fn read_reference(path: &std::path::Path) -> Result<(usize, usize, Vec<f32>)> {
    let e = renderer::output::read_exr(path)?;
    let (w, h) = (e.width, e.height);
    let get = |n: &str| {
        e.channel(n)
            .map(|c| c.to_vec())
            .with_context(|| format!("{}: no channel {n}", path.display()))
    };
    let (r, g, b) = (get("R")?, get("G")?, get("B")?);
    let mut rgb = Vec::with_capacity(w * h * 3);
    for k in 0..w * h {
        rgb.extend_from_slice(&[r[k], g[k], b[k]]);
    }
    Ok((w, h, rgb))
}

/// Checks one catalog scene against its POV-Ray reference.
pub fn check_povray(entry: &Entry, manifest: &Manifest) -> Result<Outcome> {
    let (scene, text) = load(entry)?;
    let sdl = super::export(&scene, &entry.name);
    let key = format!("povray/{}", entry.name);
    let fresh = freshness(
        manifest.reference.get(&key),
        text.as_bytes(),
        sdl.as_bytes(),
    );
    let t0 = std::time::Instant::now();
    let ours = render_for_conformance(&scene);
    let seconds = t0.elapsed().as_secs_f64();
    let path = repo_root()
        .join("references/povray")
        .join(format!("{}.exr", entry.name));
    if fresh == Freshness::Missing || !path.exists() {
        return Ok(Outcome {
            scene: entry.name.clone(),
            reference: "povray".into(),
            verdict: Verdict::Missing,
            cmp: None,
            ours,
            reference_rgb: None,
            seconds,
        });
    }
    let (w, h, rgb) = read_reference(&path)?;
    anyhow::ensure!(
        (w as u32, h as u32) == (ours.width, ours.height),
        "{}: reference is {w}x{h}, render is {}x{}",
        entry.name,
        ours.width,
        ours.height
    );
    let cmp = compare(&ours.rgb, &rgb, w, h);
    let verdict = match (fresh, cmp.passed()) {
        (Freshness::Stale, _) => Verdict::Stale,
        (_, true) => Verdict::Pass,
        _ => Verdict::Fail,
    };
    Ok(Outcome {
        scene: entry.name.clone(),
        reference: "povray".into(),
        verdict,
        cmp: Some(cmp),
        ours,
        reference_rgb: Some(rgb),
        seconds,
    })
}
