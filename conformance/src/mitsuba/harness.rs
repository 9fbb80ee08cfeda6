//! Checking catalog scenes against Mitsuba 3: geometry (our pixel-centre AOVs against
//! Mitsuba's `ray_intersect`) and radiance (a statistical test against the `moment`
//! integrator's mean and variance).

use super::compare::{geometry_test, radiance_test, Estimate, Geometry};
use super::outcome::Outcome;
use crate::catalog::load;
use crate::catalog::{repo_root, Entry};
use crate::manifest::{freshness, Freshness, Manifest};
use crate::verdict::Verdict;
use anyhow::{Context, Result};
use renderer::output::read_exr;
use renderer::physical::Fault;
use renderer::render::{render, Image, Options};
use renderer::scene::Scene;
use std::path::Path;

/// Samples per pixel of our render in the gate.
pub const GATE_SPP: u32 = 256;

/// Our render for the statistical test: `spp` samples, second moments and AOVs.
pub fn render_estimate(scene: &Scene, spp: u32, fault: Option<Fault>) -> Image {
    let opts = Options {
        aov: true,
        moments: true,
        fault,
        samples: Some(spp),
        ..Options::default()
    };
    render(scene, &opts)
}

/// Makes a scene's light brighter by `factor`: its first light, or with no lights every
/// emitting material (and the area lights built from them). The gates' perturbation tests
/// (`tests/mitsuba_gate.rs`, `tests/cycles_gate.rs`) check that a light 2 % too bright
/// fails.
pub fn brighten_light(scene: &mut Scene, factor: f32) {
    if scene.lights.is_empty() {
        for m in scene.materials.iter_mut() {
            m.radiance *= factor;
        }
        for l in scene.area_lights.iter_mut() {
            l.radiance *= factor;
        }
    } else {
        scene.lights[0].color *= factor;
    }
}

/// Our geometry channels from the AOVs.
pub fn our_geometry(img: &Image) -> Geometry {
    let a = img.aov.as_ref().expect("rendered with AOVs");
    Geometry {
        size: (img.width as usize, img.height as usize),
        z: a.z.iter().map(|&v| v as f64).collect(),
        n: a.n.iter().map(|&v| v as f64).collect(),
        hit: a.object_id.iter().map(|&v| v > 0.0).collect(),
    }
}

/// Reads a geometry reference (Z, N.X/Y/Z, mask).
pub fn read_geometry(path: &Path) -> Result<Geometry> {
    let e = read_exr(path)?;
    let get = |n: &str| {
        e.channel(n)
            .with_context(|| format!("{}: no channel {n}", path.display()))
    };
    let (z, nx, ny, nz, mask) = (
        get("Z")?,
        get("N.X")?,
        get("N.Y")?,
        get("N.Z")?,
        get("mask")?,
    );
    let px = e.width * e.height;
    let mut n = Vec::with_capacity(px * 3);
    for k in 0..px {
        n.extend_from_slice(&[nx[k] as f64, ny[k] as f64, nz[k] as f64]);
    }
    Ok(Geometry {
        size: (e.width, e.height),
        z: z.iter().map(|&v| v as f64).collect(),
        n,
        hit: mask.iter().map(|&v| v > 0.5).collect(),
    })
}

/// Reads a radiance reference: RGB mean, and the XYZ estimate from the moment channels.
pub fn read_radiance(path: &Path, spp: u32) -> Result<(Vec<f32>, Estimate)> {
    let e = read_exr(path)?;
    let get = |n: &str| {
        e.channel(n)
            .with_context(|| format!("{}: no channel {n}", path.display()))
    };
    let px = e.width * e.height;
    let (r, g, b) = (get("R")?, get("G")?, get("B")?);
    let m1 = [get("_arg_0.X")?, get("_arg_0.Y")?, get("_arg_0.Z")?];
    let m2 = [
        get("m2__arg_0.X")?,
        get("m2__arg_0.Y")?,
        get("m2__arg_0.Z")?,
    ];
    let mut rgb = Vec::with_capacity(px * 3);
    let (mut mean, mut var) = (Vec::with_capacity(px * 3), Vec::with_capacity(px * 3));
    for k in 0..px {
        rgb.extend_from_slice(&[r[k], g[k], b[k]]);
        for c in 0..3 {
            let m = m1[c][k] as f64;
            mean.push(m);
            var.push((m2[c][k] as f64 - m * m).max(0.0));
        }
    }
    Ok((
        rgb,
        Estimate {
            size: (e.width, e.height),
            mean,
            var,
            n: spp as f64,
        },
    ))
}

/// The XML whose hash a Mitsuba reference records.
pub fn export_text(scene: &Scene, spp: u32) -> Result<String> {
    let e = super::xml::export(scene, spp, true)?;
    let mut text = e.xml;
    for (name, obj) in e.meshes {
        text.push_str(&format!("\n<!-- {name} -->\n{obj}"));
    }
    Ok(text)
}

/// Checks one catalog scene against its Mitsuba references, rendering ours at `spp`.
pub fn check(
    entry: &Entry,
    manifest: &Manifest,
    spp: u32,
    fault: Option<Fault>,
) -> Result<Outcome> {
    let (scene, text, Render { ours, spp, seconds }) = rendered(entry, spp, fault)?;
    let rad = manifest.reference.get(&format!("mitsuba/{}", entry.name));
    let geo = manifest
        .reference
        .get(&format!("mitsuba-geometry/{}", entry.name));
    let (Some(rad), Some(geo)) = (rad, geo) else {
        return Ok(Outcome::missing(&entry.name, ours, seconds));
    };
    let ref_spp = rad.spp.context("a Mitsuba radiance record has spp")?;
    let xml = export_text(&scene, ref_spp)?;
    let fresh = [
        freshness(Some(rad), text.as_bytes(), xml.as_bytes()),
        freshness(Some(geo), text.as_bytes(), xml.as_bytes()),
    ];
    let dir = repo_root().join("references");
    let (ref_rgb, ref_est) = read_radiance(&dir.join(&rad.file), ref_spp)?;
    let ref_geo = read_geometry(&dir.join(&geo.file))?;
    compared(
        &entry.name,
        Render { ours, spp, seconds },
        &fresh,
        (ref_rgb, ref_est, ref_geo),
    )
}

/// Loads a catalog scene and renders it as the statistical comparison needs (every pixel
/// at `spp`, with moments and AOVs, timed): the scene, its text, and the render. What
/// Mitsuba's `check` and Cycles' share.
pub fn rendered(entry: &Entry, spp: u32, fault: Option<Fault>) -> Result<(Scene, String, Render)> {
    let (scene, text) = load(entry)?;
    anyhow::ensure!(
        !scene.settings.adaptive,
        "{}: render.adaptive is set, but the radiance test takes every pixel's mean to be of \
`spp` samples (its standard errors); render the catalog scene without it",
        entry.name
    );
    let t0 = std::time::Instant::now();
    let ours = render_estimate(&scene, spp, fault);
    let seconds = t0.elapsed().as_secs_f64();
    Ok((scene, text, Render { ours, spp, seconds }))
}

/// Our render for a comparison: the image, its samples per pixel, and the seconds it took.
pub struct Render {
    /// Our render (RGB mean, AOVs, moments).
    pub ours: Image,
    /// Its samples per pixel.
    pub spp: u32,
    /// Seconds it took.
    pub seconds: f64,
}

/// The outcome of comparing our render with a radiance reference (RGB mean and XYZ
/// estimate) and a geometry reference of a scene (`scene`), given the freshness of their
/// records: what Mitsuba's `check` and Cycles' share.
pub fn compared(
    scene: &str,
    render: Render,
    fresh: &[Freshness],
    (ref_rgb, ref_est, ref_geo): (Vec<f32>, Estimate, Geometry),
) -> Result<Outcome> {
    let Render { ours, spp, seconds } = render;
    let size = (ours.width as usize, ours.height as usize);
    anyhow::ensure!(
        ref_est.size == size && ref_geo.size == size,
        "{scene}: reference size differs from the render",
    );
    let est = Estimate::from_rgb_moments(
        size,
        &ours.rgb,
        ours.moments.as_ref().expect("moments"),
        spp,
    );
    let radiance = radiance_test(&est, &ref_est);
    let geometry = geometry_test(&our_geometry(&ours), &ref_geo);
    let verdict = if fresh.contains(&Freshness::Stale) {
        Verdict::Stale
    } else if radiance.passed() && geometry.passed() {
        Verdict::Pass
    } else {
        Verdict::Fail
    };
    Ok(Outcome {
        scene: scene.to_string(),
        verdict,
        geometry: Some(geometry),
        radiance: Some(radiance),
        ours,
        reference_rgb: Some(ref_rgb),
        seconds,
    })
}
