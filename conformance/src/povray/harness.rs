//! Checking a catalog scene against POV-Ray: render it at pixel centres, check its
//! reference is fresh, compare (re-tracing the pixels outside tolerance).

use super::compare::{compare, Comparison, Sample};
use super::outcome::Outcome;
use crate::catalog::{load, repo_root, Entry};
use crate::manifest::{freshness, Freshness, Manifest};
use crate::verdict::Verdict;
use anyhow::{Context, Result};
use renderer::real::Real;
use renderer::render::{render, Image, Options};
use renderer::scene::Scene;
use renderer::shading::Shader;

/// Renders a scene the way the conformance suite does: pixel centres, every core.
pub fn render_for_conformance(scene: &Scene) -> Image {
    render(scene, &Options::default())
}

/// Traces one sample of `scene` rendered with `opts` at a continuous pixel position, the
/// way the render loop traces the pixel centre: the classic model's camera ray through
/// (x, y), shaded by [`Shader::trace_primary`], non-finite channels written as 0.
///
/// The comparison calls it for pixels outside tolerance, so it must be given the scene
/// and options the image was rendered with (a test that injects a fault re-traces with
/// the fault). It panics on a scene the classic pixel-centre render does not apply to.
pub fn retrace<'a>(scene: &'a Scene, opts: &Options) -> impl Fn(f64, f64) -> Sample + 'a {
    let spp = opts.samples.unwrap_or(scene.settings.samples);
    assert!(
        scene.settings.integrator == renderer::scene::Integrator::Classic && spp <= 1,
        "the pixel-centre comparison re-traces classic scenes at 1 sample per pixel"
    );
    let shader = Shader::new(scene, opts.spawn);
    move |x, y| {
        let ray = scene.camera.ray_at(x, y);
        let hit = scene.root.intersect(&ray, 0.0, Real::INFINITY);
        let c = shader.trace_primary_hit(&ray, hit);
        let secondary = hit.is_some_and(|h| {
            let m = scene.material(h.material);
            m.reflection > 0.0 || m.filter > 0.0 || m.transmit > 0.0
        });
        Sample {
            rgb: c.to_array().map(|v| if v.is_finite() { v } else { 0.0 }),
            object: hit.map_or(0, |h| h.object_id),
            secondary,
        }
    }
}

/// Compares `ours`, rendered from `scene` with `opts`, with reference pixels (RGB),
/// re-tracing the pixels outside tolerance with the same scene and options.
pub fn compare_render(
    scene: &Scene,
    opts: &Options,
    ours: &Image,
    reference: &[f32],
) -> Comparison {
    compare(
        &ours.rgb,
        reference,
        ours.width as usize,
        ours.height as usize,
        &retrace(scene, opts),
    )
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
pub fn check(entry: &Entry, manifest: &Manifest) -> Result<Outcome> {
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
    let cmp = compare_render(&scene, &Options::default(), &ours, &rgb);
    let verdict = match (fresh, cmp.passed()) {
        (Freshness::Stale, _) => Verdict::Stale,
        (_, true) => Verdict::Pass,
        _ => Verdict::Fail,
    };
    Ok(Outcome {
        scene: entry.name.clone(),
        verdict,
        cmp: Some(cmp),
        ours,
        reference_rgb: Some(rgb),
        seconds,
    })
}
