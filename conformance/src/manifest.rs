//! The reference manifest, `references/manifest.toml`: for every committed reference, which
//! tool and version made it, the exact command, hashes of the scene it was made from, and
//! the date. A reference whose hashes no longer match its scene is **stale**.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One reference image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// The reference renderer ("povray" or "mitsuba").
    pub tool: String,
    /// Its version, as it reports it.
    pub version: String,
    /// The exact command that rendered the reference.
    pub command: String,
    /// SHA-256 of the scene file.
    pub scene_hash: String,
    /// SHA-256 of the exported scene (SDL or XML), which includes mesh data.
    pub export_hash: String,
    /// UTC date of generation, YYYY-MM-DD.
    pub date: String,
    /// The image, relative to `references/`.
    pub file: String,
    /// Samples per pixel of a Monte Carlo reference.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
}

/// All records, keyed by `<tool>/<scene>`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Records by key.
    #[serde(default)]
    pub reference: BTreeMap<String, Record>,
}

/// `sha256:<hex>` of some bytes.
pub fn sha256(bytes: &[u8]) -> String {
    let d = Sha256::digest(bytes);
    let hex: String = d.iter().map(|b| format!("{b:02x}")).collect();
    format!("sha256:{hex}")
}

/// The committed manifest's file: `references/manifest.toml` under the repository root.
pub fn committed_path() -> PathBuf {
    crate::catalog::repo_root().join("references/manifest.toml")
}

impl Manifest {
    /// Reads the committed manifest ([`committed_path`]).
    pub fn committed() -> anyhow::Result<Manifest> {
        Manifest::load(&committed_path())
    }

    /// Reads the manifest (empty when the file does not exist).
    pub fn load(path: &Path) -> anyhow::Result<Manifest> {
        if !path.exists() {
            return Ok(Manifest::default());
        }
        let text = std::fs::read_to_string(path)?;
        toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// Writes the manifest.
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        let text = format!(
            "# Reference images: tool, version, exact command, scene hashes, date.\n# Written by `cargo run --release -p conformance -- regen-povray`; do not edit by hand.\n\n{}",
            toml::to_string(self)?
        );
        std::fs::write(path, text)?;
        Ok(())
    }
}

/// Whether a reference still matches its scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Freshness {
    /// Both hashes match.
    Fresh,
    /// The scene or its export changed since the reference was made.
    Stale,
    /// No record.
    Missing,
}

/// Checks a record against the current scene text and export.
pub fn freshness(record: Option<&Record>, scene_text: &[u8], export_text: &[u8]) -> Freshness {
    match record {
        None => Freshness::Missing,
        Some(r) if r.scene_hash == sha256(scene_text) && r.export_hash == sha256(export_text) => {
            Freshness::Fresh
        }
        Some(_) => Freshness::Stale,
    }
}

/// Today's UTC date as YYYY-MM-DD.
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (y, m, d) = civil_from_days(secs.div_euclid(86_400));
    format!("{y:04}-{m:02}-{d:02}")
}

/// The date (year, month, day) in the proleptic Gregorian calendar of `days` since
/// 1970-01-01 (civil-from-days, H. Hinnant's algorithm).
pub(crate) fn civil_from_days(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}
