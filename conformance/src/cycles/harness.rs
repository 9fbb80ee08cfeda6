//! Checking catalog scenes against Cycles: geometry (our pixel-centre AOVs against Cycles'
//! geometry render) and radiance (the two-sample statistical test against the mean and
//! seed variance of the reference), with the same tests and tolerances as Mitsuba's
//! (`crate::mitsuba::compare`).

use super::outcome::Outcome;
use super::refgen::export_text;
use super::refs::read_radiance;
use crate::catalog::{repo_root, Entry};
use crate::manifest::{freshness, Manifest};
use crate::mitsuba::compare::{radiance_test, Estimate, RadianceTest};
use crate::mitsuba::harness::{compared, read_geometry, rendered, Render};
use crate::mitsuba::outcome::Outcome as Measured;
use anyhow::{Context, Result};
use renderer::physical::Fault;

/// Checks one catalog scene against its Cycles references, rendering ours at `spp`.
pub fn check(
    entry: &Entry,
    manifest: &Manifest,
    spp: u32,
    fault: Option<Fault>,
) -> Result<Outcome> {
    let (scene, text, Render { ours, spp, seconds }) = rendered(entry, spp, fault)?;
    let rad = manifest.reference.get(&format!("cycles/{}", entry.name));
    let geo = manifest
        .reference
        .get(&format!("cycles-geometry/{}", entry.name));
    let (Some(rad), Some(geo)) = (rad, geo) else {
        return Ok(Outcome {
            references: None,
            measured: Measured::missing(&entry.name, ours, seconds),
        });
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
    let references = references_agree(entry, manifest, &ref_est)?;
    let measured = compared(
        &entry.name,
        Render { ours, spp, seconds },
        &fresh,
        (ref_rgb, ref_est, ref_geo),
    )?;
    Ok(Outcome {
        measured,
        references,
    })
}

/// Mitsuba's radiance reference of the scene against Cycles' `cycles` (both are estimates
/// with a variance, so the two-sample test applies as it does to ours), when Mitsuba has
/// one. The third side of the three-way verdict: when the two references disagree beyond
/// their noise, conformance/docs/cycles.md says which one we side with and why.
pub fn references_agree(
    entry: &Entry,
    manifest: &Manifest,
    cycles: &Estimate,
) -> Result<Option<RadianceTest>> {
    let Some(rec) = manifest.reference.get(&format!("mitsuba/{}", entry.name)) else {
        return Ok(None);
    };
    let spp = rec.spp.context("a Mitsuba radiance record has spp")?;
    let (_, mitsuba) = crate::mitsuba::harness::read_radiance(
        &repo_root().join("references").join(&rec.file),
        spp,
    )?;
    if mitsuba.size != cycles.size {
        return Ok(None);
    }
    Ok(Some(radiance_test(&mitsuba, cycles)))
}
