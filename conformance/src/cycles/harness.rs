//! Checking catalog scenes against Cycles: geometry (our pixel-centre AOVs against Cycles'
//! geometry render) and radiance (the two-sample statistical test against the mean and
//! seed variance of the reference), with the same tests and tolerances as Mitsuba's
//! (`crate::mitsuba::compare`).

use super::refgen::export_text;
use super::refs::read_radiance;
use crate::catalog::{load, repo_root, Entry};
use crate::manifest::{freshness, Freshness, Manifest};
use super::outcome::Outcome;
use crate::mitsuba::harness::{our_geometry, read_geometry, render_estimate};
use crate::mitsuba::outcome::Outcome as Measured;
use crate::mitsuba::compare::{geometry_test, radiance_test, Estimate};
use crate::verdict::Verdict;
use anyhow::{Context, Result};
use renderer::physical::Fault;

/// Checks one catalog scene against its Cycles references, rendering ours at `spp`.
pub fn check(
    entry: &Entry,
    manifest: &Manifest,
    spp: u32,
    fault: Option<Fault>,
) -> Result<Outcome> {
    let (scene, text) = load(entry)?;
    anyhow::ensure!(
        !scene.settings.adaptive,
        "{}: render.adaptive is set, but the radiance test takes every pixel's mean to be of \
`spp` samples; render the catalog scene without it",
        entry.name
    );
    let t0 = std::time::Instant::now();
    let ours = render_estimate(&scene, spp, fault);
    let seconds = t0.elapsed().as_secs_f64();
    let rad = manifest.reference.get(&format!("cycles/{}", entry.name));
    let geo = manifest
        .reference
        .get(&format!("cycles-geometry/{}", entry.name));
    let (Some(rad), Some(geo)) = (rad, geo) else {
        return Ok(Outcome(Measured {
            scene: entry.name.clone(),
            verdict: Verdict::Missing,
            geometry: None,
            radiance: None,
            ours,
            reference_rgb: None,
            seconds,
        }));
    };
    let n = rad.spp.context("a Cycles radiance record has spp")?;
    let json = export_text(&scene)?;
    let fresh = [
        freshness(Some(rad), text.as_bytes(), json.as_bytes()),
        freshness(Some(geo), text.as_bytes(), json.as_bytes()),
    ];
    let dir = repo_root().join("references");
    let (ref_rgb, ref_est) = read_radiance(&dir.join(&rad.file), n)?;
    let ref_geo = read_geometry(&dir.join(&geo.file))?;
    let size = (ours.width as usize, ours.height as usize);
    anyhow::ensure!(
        ref_est.size == size && ref_geo.size == size,
        "{}: reference size differs from the render",
        entry.name
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
    Ok(Outcome(Measured {
        scene: entry.name.clone(),
        verdict,
        geometry: Some(geometry),
        radiance: Some(radiance),
        ours,
        reference_rgb: Some(ref_rgb),
        seconds,
    }))
}
