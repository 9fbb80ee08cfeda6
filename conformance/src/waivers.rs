//! Deliberate divergences from a reference: `conformance/waivers.toml`.
//!
//! A waiver names one scene, the one check it is excused from, why, and since when:
//!
//! ```toml
//! [[waiver]]
//! scene = "povray/shade_phong"   # <reference>/<scene name>
//! check = "pixels"               # one of the reference's checks (`Reference::checks`):
//!                                # povray: pixels; mitsuba: radiance or geometry
//! reason = "POV-Ray 3.7 clamps the phong exponent; we follow the 3.8 fix"
//! date = "2026-11-24"
//! ```
//!
//! A waived scene is reported as WAIVED, never as a pass. Once the scene passes the waived
//! check again, the waiver is **stale**, and the gate fails until it is removed. A stale
//! reference is never waived: a waiver excuses a divergence, not an outdated reference.

use crate::registry::Registry;
use anyhow::{bail, Context, Result};
use serde::Deserialize;
use std::path::Path;

/// One waiver.
#[derive(Clone, Debug, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waiver {
    /// `<reference>/<scene name>`, e.g. `povray/shade_phong`.
    pub scene: String,
    /// The check it excuses (one of its reference's `checks`).
    pub check: String,
    /// Why the divergence is deliberate.
    pub reason: String,
    /// When it was granted (YYYY-MM-DD).
    pub date: String,
    /// Line of the entry in the file (filled in when loading).
    #[serde(skip)]
    pub line: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    waiver: Vec<Waiver>,
}

/// The waivers of a catalog.
#[derive(Clone, Debug, Default)]
pub struct Waivers {
    /// Every entry, in file order.
    pub list: Vec<Waiver>,
    /// The file they came from (for messages).
    pub path: std::path::PathBuf,
}

impl Waivers {
    /// Loads `path` for the committed references; a missing file means no waivers.
    /// Errors name the file, line and column, and the field.
    pub fn load(path: &Path) -> Result<Waivers> {
        Self::load_with(path, &Registry::committed())
    }

    /// [`Self::load`] for the references of `registry`.
    pub fn load_with(path: &Path, registry: &Registry) -> Result<Waivers> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Ok(Waivers {
                    list: Vec::new(),
                    path: path.to_path_buf(),
                })
            }
            Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
        };
        Self::parse_with(&text, path, registry)
    }

    /// Parses the text of a waivers file for the committed references.
    pub fn parse(text: &str, path: &Path) -> Result<Waivers> {
        Self::parse_with(text, path, &Registry::committed())
    }

    /// Parses the text of a waivers file whose entries name the references of `registry`.
    pub fn parse_with(text: &str, path: &Path, registry: &Registry) -> Result<Waivers> {
        let file: File = toml::from_str(text).map_err(|e| {
            let (line, col) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
            anyhow::anyhow!("{}:{line}:{col}: {}", path.display(), e.message())
        })?;
        // Entries in file order: the n-th `[[waiver]]` header gives the n-th line.
        let headers: Vec<usize> = text
            .lines()
            .enumerate()
            .filter(|(_, l)| l.trim_start().starts_with("[[waiver]]"))
            .map(|(i, _)| i + 1)
            .collect();
        let mut list = file.waiver;
        for (k, w) in list.iter_mut().enumerate() {
            w.line = headers.get(k).copied().unwrap_or(0);
            let at = format!("{}:{}", path.display(), w.line);
            let Some((reference, name)) = w.scene.split_once('/') else {
                bail!(
                    "{at}: waiver.scene `{}` is not <reference>/<scene>",
                    w.scene
                );
            };
            let Ok(r) = registry.get(reference) else {
                bail!(
                    "{at}: waiver.scene: unknown reference `{reference}` (one of: {})",
                    registry.names().join(", ")
                );
            };
            let checks = r.checks();
            if !checks.contains(&w.check.as_str()) {
                bail!(
                    "{at}: waiver.check `{}` is not a check of {reference} (one of: {})",
                    w.check,
                    checks.join(", ")
                );
            }
            if name.is_empty() || w.reason.trim().is_empty() {
                bail!("{at}: a waiver needs a scene name and a reason");
            }
            if !is_date(&w.date) {
                bail!("{at}: waiver.date `{}` is not YYYY-MM-DD", w.date);
            }
        }
        Ok(Waivers {
            list,
            path: path.to_path_buf(),
        })
    }

    /// The waiver of `reference/scene`'s `check`, if any.
    pub fn find(&self, reference: &str, scene: &str, check: &str) -> Option<&Waiver> {
        let key = format!("{reference}/{scene}");
        self.list
            .iter()
            .find(|w| w.scene == key && w.check == check)
    }

    /// The committed waivers (`conformance/waivers.toml`).
    pub fn committed() -> Result<Waivers> {
        Self::load(&crate::catalog::repo_root().join("conformance/waivers.toml"))
    }
}

impl std::fmt::Display for Waiver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} check waived since {}: {}",
            self.check, self.date, self.reason
        )
    }
}

fn is_date(s: &str) -> bool {
    let b = s.as_bytes();
    b.len() == 10
        && b[4] == b'-'
        && b[7] == b'-'
        && b.iter()
            .enumerate()
            .all(|(i, c)| i == 4 || i == 7 || c.is_ascii_digit())
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Waivers> {
        Waivers::parse(text, Path::new("waivers.toml"))
    }

    #[test]
    fn test01_entries_keep_their_lines_and_are_found_by_check() {
        let w = parse(
            "# comment\n\n[[waiver]]\nscene = \"povray/a\"\ncheck = \"pixels\"\nreason = \"r\"\ndate = \"2026-11-24\"\n\n[[waiver]]\nscene = \"mitsuba/b\"\ncheck = \"radiance\"\nreason = \"q\"\ndate = \"2026-01-02\"\n",
        )
        .unwrap();
        assert_eq!(w.list.len(), 2);
        assert_eq!((w.list[0].line, w.list[1].line), (3, 9));
        assert!(w.find("povray", "a", "pixels").is_some());
        assert!(w.find("mitsuba", "b", "geometry").is_none());
        assert!(w.find("povray", "b", "pixels").is_none());
    }

    #[test]
    fn test02_bad_entries_are_located_errors() {
        let entry = |scene: &str, check: &str, date: &str| {
            format!("[[waiver]]\nscene = \"{scene}\"\ncheck = \"{check}\"\nreason = \"r\"\ndate = \"{date}\"\n")
        };
        for (text, want) in [
            (entry("a", "pixels", "2026-01-01"), "waiver.scene `a`"),
            (entry("pbrt/a", "pixels", "2026-01-01"), "unknown reference"),
            (entry("povray/a", "radiance", "2026-01-01"), "waiver.check"),
            (entry("povray/a", "pixels", "yesterday"), "waiver.date"),
            (
                entry("povray/a", "pixels", "2026-01-01") + "extra = 1\n",
                "extra",
            ),
        ] {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} should mention {want:?}");
            assert!(e.starts_with("waivers.toml:"), "{e:?} should be located");
        }
        let e = parse("[[waiver]]\nscene = 1\n").unwrap_err().to_string();
        assert!(e.starts_with("waivers.toml:2:"), "{e}");
    }
}
