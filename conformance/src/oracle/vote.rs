//! The three-way vote on a classic catalog scene: our renderer, POV-Ray's committed
//! reference and the oracle, each pair compared pixel by pixel with the POV-Ray
//! comparison (`povray/compare.rs`: the tolerance, and the excuse of a pixel only by
//! geometry, re-traced by whichever image is on the render side).
//!
//! | pair | render side (re-traced) | reference side | tolerance |
//! |---|---|---|---|
//! | ours~POV-Ray | ours | POV-Ray's half-float EXR | `tol(r)`: half rounding |
//! | oracle~POV-Ray | oracle | POV-Ray's half-float EXR | `tol(r)`: half rounding |
//! | ours~oracle | ours | oracle (`f64`, as `f32`) | `tol(r)`, which bounds ours |
//!
//! conformance/docs/oracle.md derives why the same `tol` serves all three.

use super::render::Oracle;
use crate::catalog::{load, Entry};
use crate::povray::compare::{compare, error_in_tolerances, Comparison};
use crate::povray::harness::{compare_render, read_reference, render_for_conformance};
use anyhow::{ensure, Result};
use renderer::render::{Image, Options};
use renderer::scene::Scene;

/// The pairs of a vote, as the report and the failure messages name them.
pub const PAIRS: [&str; 3] = ["ours~POV-Ray", "oracle~POV-Ray", "ours~oracle"];

/// The three comparisons of one scene.
pub struct Vote {
    /// Scene name.
    pub scene: String,
    /// Ours against POV-Ray (`None` without a fresh POV-Ray reference).
    pub ours_povray: Option<Comparison>,
    /// The oracle against POV-Ray (`None` without a fresh POV-Ray reference).
    pub oracle_povray: Option<Comparison>,
    /// Ours against the oracle.
    pub ours_oracle: Comparison,
    /// The oracle's image (RGB).
    pub oracle_rgb: Vec<f32>,
    /// Our image (RGB).
    pub ours_rgb: Vec<f32>,
    /// POV-Ray's reference (RGB), when fresh.
    pub povray_rgb: Option<Vec<f32>>,
}

impl Vote {
    /// The vote on `scene`, given our image and, when POV-Ray's reference is fresh, its
    /// pixels and the comparison of ours with them (the POV-Ray harness's).
    pub fn new(
        scene: &Scene,
        name: &str,
        oracle: &Oracle,
        ours: &Image,
        povray: Option<(Vec<f32>, Comparison)>,
    ) -> Vote {
        let (w, h) = oracle.size();
        let oracle_rgb = oracle.render();
        let sample = |x: f64, y: f64| oracle.sample(x, y);
        let oracle_povray = povray
            .as_ref()
            .map(|(p, _)| compare(&oracle_rgb, p, w, h, &sample));
        let ours_oracle = compare_render(scene, &Options::default(), ours, &oracle_rgb);
        let (povray_rgb, ours_povray) = povray.unzip();
        Vote {
            scene: name.into(),
            ours_povray,
            oracle_povray,
            ours_oracle,
            oracle_rgb,
            ours_rgb: ours.rgb.clone(),
            povray_rgb,
        }
    }

    /// The comparison of each pair of [`PAIRS`], in that order (`None` without a fresh
    /// POV-Ray reference).
    pub fn pairs(&self) -> [Option<&Comparison>; 3] {
        [
            self.ours_povray.as_ref(),
            self.oracle_povray.as_ref(),
            Some(&self.ours_oracle),
        ]
    }

    /// Whether the oracle's checks pass: ours agrees with the oracle, and the oracle with
    /// POV-Ray when there is a fresh POV-Ray reference (ours against POV-Ray is the
    /// POV-Ray reference's own check).
    pub fn passed(&self) -> bool {
        self.ours_oracle.passed() && self.oracle_povray.as_ref().is_none_or(|c| c.passed())
    }

    /// Who agrees with whom: each pair's word, and its failing pixels when it disagrees.
    pub fn summary(&self) -> String {
        let word = |c: Option<&Comparison>| match c {
            None => "no POV-Ray reference".to_string(),
            Some(c) if c.passed() => "agree".to_string(),
            Some(c) => format!("DISAGREE ({} failing, {} excused)", c.failing, c.silhouette),
        };
        PAIRS
            .iter()
            .zip(self.pairs())
            .map(|(name, c)| format!("{name} {}", word(c)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// How far pixel `k` is outside the tolerance in the pair `pair` (index into
    /// [`PAIRS`]), in tolerances.
    pub fn error(&self, pair: usize, k: usize) -> f64 {
        let povray = self.povray_rgb.as_deref().unwrap_or(&self.oracle_rgb);
        match pair {
            0 => error_in_tolerances(&self.ours_rgb, povray, k),
            1 => error_in_tolerances(&self.oracle_rgb, povray, k),
            _ => error_in_tolerances(&self.ours_rgb, &self.oracle_rgb, k),
        }
    }

    /// For each pair that disagrees: the scene, the pair, and up to `n` of its failing
    /// pixels (x, y) with the three values, worst first.
    pub fn failure_message(&self, n: usize) -> String {
        let mut out = String::new();
        let w = self.ours_oracle.size.0;
        let px = |img: &[f32], k: usize| [img[3 * k], img[3 * k + 1], img[3 * k + 2]];
        for (pair, (name, c)) in PAIRS.iter().zip(self.pairs()).enumerate() {
            let Some(c) = c.filter(|c| !c.passed()) else {
                continue;
            };
            out += &format!(
                "{}: {name} DISAGREE: {} failing pixels, {} excused (budget {})\n",
                self.scene,
                c.failing,
                c.silhouette,
                c.budget()
            );
            let mut bad: Vec<usize> = (0..c.class.len()).filter(|&k| c.class[k] == 2).collect();
            bad.sort_by(|&a, &b| self.error(pair, b).total_cmp(&self.error(pair, a)));
            for &k in bad.iter().take(n) {
                out += &format!(
                    "  pixel ({}, {}): ours {:?}, oracle {:?}, POV-Ray {:?} ({:.1} tolerances)\n",
                    k % w,
                    k / w,
                    px(&self.ours_rgb, k),
                    px(&self.oracle_rgb, k),
                    self.povray_rgb.as_deref().map(|p| px(p, k)),
                    self.error(pair, k)
                );
            }
        }
        out
    }
}

/// Runs the vote on one POV-Ray catalog scene against the POV-Ray image at `reference`,
/// or says why the oracle declines it (`Ok(Err(reason))`).
pub fn vote(
    entry: &Entry,
    reference: &std::path::Path,
) -> Result<std::result::Result<Vote, String>> {
    let (scene, _) = load(entry)?;
    let oracle = match Oracle::new(&scene) {
        Ok(o) => o,
        Err(why) => return Ok(Err(why)),
    };
    let (w, h, povray) = read_reference(reference)?;
    ensure!(
        (w, h) == oracle.size(),
        "{}: reference is {w}x{h}",
        entry.name
    );
    let ours = render_for_conformance(&scene);
    let cmp = compare_render(&scene, &Options::default(), &ours, &povray);
    Ok(Ok(Vote::new(
        &scene,
        &entry.name,
        &oracle,
        &ours,
        Some((povray, cmp)),
    )))
}
