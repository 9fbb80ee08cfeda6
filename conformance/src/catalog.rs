//! The scene catalog: data files in `conformance/scenes/<reference>/*.toml`, one feature
//! each. The catalog for POV-Ray is written by `scripts/gen_catalog.py`.

use anyhow::{Context, Result};
use renderer::scene::Scene;
use std::path::{Path, PathBuf};

/// The repository root (the workspace holding this crate), or `$CONFORMANCE_ROOT` when
/// set: a folder with the same layout (`conformance/scenes/`, `conformance/waivers.toml`,
/// `references/`), so a script can run the workflows on a scratch copy of the catalog
/// without touching the checkout (scripts/check-workflows.sh).
pub fn repo_root() -> PathBuf {
    if let Some(r) = std::env::var_os("CONFORMANCE_ROOT").filter(|r| !r.is_empty()) {
        return PathBuf::from(r);
    }
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("conformance/ has a parent")
        .to_path_buf()
}

/// A catalog entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Scene name (the file stem).
    pub name: String,
    /// Path of the scene file.
    pub path: PathBuf,
}

/// The scenes checked against `reference` (e.g. "povray") whose name contains `filter`,
/// sorted by name.
pub fn scenes(reference: &str, filter: &str) -> std::io::Result<Vec<Entry>> {
    let dir = repo_root().join("conformance/scenes").join(reference);
    let mut v = Vec::new();
    for e in std::fs::read_dir(&dir)? {
        let path = e?.path();
        if path.extension().is_some_and(|x| x == "toml") {
            let name = path
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            if name.contains(filter) {
                v.push(Entry { name, path });
            }
        }
    }
    v.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(v)
}

/// The scenes of `reference` that a command line's FILTER selects: the scene of exactly
/// that name if there is one, else every scene whose name contains it. An empty selection
/// is an error that lists close names.
pub fn select(reference: &str, filter: &str) -> Result<Vec<Entry>> {
    let all = scenes(reference, "")
        .with_context(|| format!("reading conformance/scenes/{reference}/"))?;
    if let Some(e) = all.iter().find(|e| e.name == filter) {
        return Ok(vec![e.clone()]);
    }
    let chosen: Vec<Entry> = all
        .iter()
        .filter(|e| e.name.contains(filter))
        .cloned()
        .collect();
    if chosen.is_empty() {
        let names: Vec<String> = all.into_iter().map(|e| e.name).collect();
        let close = close_names(filter, &names);
        anyhow::bail!(
            "no {reference} catalog scene matches '{filter}'{}",
            if close.is_empty() {
                format!(" (the catalog is conformance/scenes/{reference}/)")
            } else {
                format!("; close names: {}", close.join(", "))
            }
        );
    }
    Ok(chosen)
}

/// Loads a catalog scene and returns it with its text.
pub fn load(entry: &Entry) -> Result<(Scene, String)> {
    let text = std::fs::read_to_string(&entry.path)
        .with_context(|| format!("reading {}", entry.path.display()))?;
    let base = entry.path.parent().unwrap_or(std::path::Path::new("."));
    let scene = Scene::from_str(&text, &entry.path, base)?;
    Ok((scene, text))
}

/// A fresh scratch folder under the system temp dir for one reference run.
pub fn scratch_dir(name: &str) -> Result<PathBuf> {
    let d = std::env::temp_dir().join(format!("conformance-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d)?;
    Ok(d)
}

/// Names of `candidates` close to `wanted` (sharing a word or within a small edit
/// distance), best first: for "no scene matches" messages.
pub fn close_names<'a>(wanted: &str, candidates: &'a [String]) -> Vec<&'a str> {
    let mut scored: Vec<(usize, &str)> = candidates
        .iter()
        .filter_map(|c| {
            let d = (0..=c.len().saturating_sub(wanted.len()))
                .filter_map(|i| c.get(i..i + wanted.len().min(c.len())))
                .map(|sub| edit_distance(wanted, sub))
                .min()
                .unwrap_or(usize::MAX)
                .min(edit_distance(wanted, c));
            let limit = (wanted.len() / 3).max(1);
            (d <= limit).then_some((d, c.as_str()))
        })
        .collect();
    scored.sort();
    scored.into_iter().map(|(_, c)| c).take(8).collect()
}

/// Levenshtein distance.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + (ca != *cb) as usize)
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test01_close_names_suggest_typos_and_parts() {
        let names: Vec<String> = [
            "prim_cone_shear",
            "prim_cone_rotate",
            "shade_phong",
            "mi_cornell",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            close_names("prim_cnoe", &names),
            ["prim_cone_rotate", "prim_cone_shear"]
        );
        assert_eq!(close_names("shade_phnog", &names), ["shade_phong"]);
        assert_eq!(close_names("cornel", &names), ["mi_cornell"]);
        assert!(close_names("typo", &names).is_empty());
    }
}
