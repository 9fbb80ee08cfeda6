//! Running the oracle on a catalog scene: POV-Ray's harness renders ours and compares it
//! with the committed POV-Ray reference (freshness included), then the oracle renders the
//! scene and the vote adds the two comparisons it owns.

use super::outcome::Outcome;
use super::render::Oracle;
use super::vote::Vote;
use crate::catalog::{load, Entry};
use crate::manifest::Manifest;
use crate::verdict::Verdict;
use anyhow::{anyhow, Result};

/// Checks one classic catalog scene against the oracle. POV-Ray's image takes part only
/// when its reference is fresh (a stale or missing one is POV-Ray's own verdict, never a
/// pass); the scene must be one the oracle covers.
pub fn check(entry: &Entry, manifest: &Manifest) -> Result<Outcome> {
    let povray = crate::povray::harness::check(entry, manifest)?;
    let (scene, _) = load(entry)?;
    let oracle = Oracle::new(&scene)
        .map_err(|why| anyhow!("{}: the oracle declines it: {why}", entry.name))?;
    let fresh = matches!(povray.verdict, Verdict::Pass | Verdict::Fail);
    let pair = match (fresh, povray.reference_rgb, povray.cmp) {
        (true, Some(rgb), Some(cmp)) => Some((rgb, cmp)),
        _ => None,
    };
    let t0 = std::time::Instant::now();
    let vote = Vote::new(&scene, &entry.name, &oracle, &povray.ours, pair);
    Ok(Outcome {
        verdict: if vote.passed() {
            Verdict::Pass
        } else {
            Verdict::Fail
        },
        vote,
        ours: povray.ours,
        seconds: povray.seconds,
        oracle_seconds: t0.elapsed().as_secs_f64(),
    })
}
