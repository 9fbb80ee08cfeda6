//! The scene catalog: data files in `conformance/scenes/<reference>/*.toml`, one feature
//! each. The catalog for POV-Ray is written by `scripts/gen_catalog.py`.

use anyhow::{Context, Result};
use renderer::scene::Scene;
use std::path::{Path, PathBuf};

/// The repository root (the workspace holding this crate).
pub fn repo_root() -> PathBuf {
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
