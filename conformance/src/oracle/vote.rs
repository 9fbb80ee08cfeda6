//! The three-way vote on a classic catalog scene: our renderer, POV-Ray's committed
//! reference and the oracle, each pair compared pixel by pixel with the POV-Ray
//! comparison (`povray/compare.rs`: the tolerance, and the excuse of a pixel only by
//! geometry, re-traced by whichever image is on the render side).
//!
//! | pair | render side (re-traced) | reference side | tolerance |
//! |---|---|---|---|
//! | ours vs POV-Ray | ours | POV-Ray's half-float EXR | `tol(r)`: half rounding |
//! | oracle vs POV-Ray | oracle | POV-Ray's half-float EXR | `tol(r)`: half rounding |
//! | ours vs oracle | ours | oracle (`f64`, as `f32`) | `tol(r)`, which bounds ours |
//!
//! conformance/docs/oracle.md derives why the same `tol` serves all three.

use super::Oracle;
use crate::catalog::{load, Entry};
use crate::povray::compare::{compare, tol, Comparison};
use crate::povray::harness::{compare_render, read_reference, render_for_conformance};
use anyhow::{ensure, Result};
use renderer::render::Options;

/// The three comparisons of one scene.
pub struct Vote {
    /// Scene name.
    pub scene: String,
    /// Ours against POV-Ray.
    pub ours_povray: Comparison,
    /// The oracle against POV-Ray.
    pub oracle_povray: Comparison,
    /// Ours against the oracle.
    pub ours_oracle: Comparison,
    /// The oracle's image (RGB).
    pub oracle_rgb: Vec<f32>,
    /// Our image (RGB).
    pub ours_rgb: Vec<f32>,
    /// POV-Ray's reference (RGB).
    pub povray_rgb: Vec<f32>,
}

/// Who agrees with whom, in words: "all three agree", or which pair disagrees.
impl Vote {
    /// One line: each pair's verdict.
    pub fn summary(&self) -> String {
        let word = |c: &Comparison| if c.passed() { "agree" } else { "DISAGREE" };
        format!(
            "ours~POV-Ray {} ({} failing), oracle~POV-Ray {} ({} failing), ours~oracle {} ({} failing)",
            word(&self.ours_povray),
            self.ours_povray.failing,
            word(&self.oracle_povray),
            self.oracle_povray.failing,
            word(&self.ours_oracle),
            self.ours_oracle.failing,
        )
    }
}

/// The pairs of a vote, as the report and the failure messages name them.
pub const PAIRS: [&str; 3] = ["ours~POV-Ray", "oracle~POV-Ray", "ours~oracle"];

impl Vote {
    /// The comparison of each pair of [`PAIRS`], in that order.
    pub fn pairs(&self) -> [&Comparison; 3] {
        [&self.ours_povray, &self.oracle_povray, &self.ours_oracle]
    }

    /// Whether the oracle's checks pass: ours agrees with the oracle and the oracle with
    /// POV-Ray (ours against POV-Ray is the POV-Ray reference's own check).
    pub fn passed(&self) -> bool {
        self.oracle_povray.passed() && self.ours_oracle.passed()
    }

    /// For each pair that disagrees: the scene, the pair, and up to `n` of its failing
    /// pixels (x, y) with the three values, worst first.
    pub fn failure_message(&self, n: usize) -> String {
        let (ours, povray) = (&self.ours_rgb[..], &self.povray_rgb[..]);
        let mut out = String::new();
        let w = self.ours_oracle.size.0;
        for (name, c) in PAIRS.iter().zip(self.pairs()) {
            if c.passed() {
                continue;
            }
            out += &format!(
                "{}: {name} DISAGREE: {} failing pixels, {} excused (budget {})\n",
                self.scene,
                c.failing,
                c.silhouette,
                c.budget()
            );
            let px = |img: &[f32], k: usize| [img[3 * k], img[3 * k + 1], img[3 * k + 2]];
            let err = |k: usize| {
                let (a, r) = match *name {
                    "ours~POV-Ray" => (px(ours, k), px(povray, k)),
                    "oracle~POV-Ray" => (px(&self.oracle_rgb, k), px(povray, k)),
                    _ => (px(ours, k), px(&self.oracle_rgb, k)),
                };
                (0..3)
                    .map(|i| (a[i] as f64 - r[i] as f64).abs() / tol(r[i] as f64))
                    .fold(0.0, f64::max)
            };
            let mut bad: Vec<usize> = (0..c.class.len()).filter(|&k| c.class[k] == 2).collect();
            bad.sort_by(|&a, &b| err(b).total_cmp(&err(a)));
            for &k in bad.iter().take(n) {
                out += &format!(
                    "  pixel ({}, {}): ours {:?}, oracle {:?}, POV-Ray {:?} ({:.1} tolerances)\n",
                    k % w,
                    k / w,
                    px(ours, k),
                    px(&self.oracle_rgb, k),
                    px(povray, k),
                    err(k)
                );
            }
        }
        out
    }
}

/// Runs the vote on one POV-Ray catalog scene, or says why the oracle declines it
/// (`Ok(Err(reason))`).
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
    let oracle_rgb = oracle.render();
    let opts = Options::default();
    let sample = |x: f64, y: f64| oracle.sample(x, y);
    Ok(Ok(Vote {
        scene: entry.name.clone(),
        ours_povray: compare_render(&scene, &opts, &ours, &povray),
        oracle_povray: compare(&oracle_rgb, &povray, w, h, &sample),
        ours_oracle: compare_render(&scene, &opts, &ours, &oracle_rgb),
        oracle_rgb,
        ours_rgb: ours.rgb,
        povray_rgb: povray,
    }))
}
