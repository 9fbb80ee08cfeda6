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
    /// The catalog (the folder `conformance/scenes/<catalog>/`).
    pub catalog: String,
    /// Scene name (the file stem).
    pub name: String,
    /// Path of the scene file.
    pub path: PathBuf,
}

/// Scene `name` of `catalog`, exactly that name.
pub fn find(catalog: &str, name: &str) -> Result<Entry> {
    scenes(catalog, name)?
        .into_iter()
        .find(|e| e.name == name)
        .with_context(|| format!("no scene {name} in conformance/scenes/{catalog}"))
}

/// The scenes of `catalog` (e.g. "povray") whose name contains `filter`, sorted by name.
pub fn scenes(catalog: &str, filter: &str) -> std::io::Result<Vec<Entry>> {
    let dir = repo_root().join("conformance/scenes").join(catalog);
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
                v.push(Entry {
                    catalog: catalog.to_string(),
                    name,
                    path,
                });
            }
        }
    }
    v.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(v)
}

/// The scenes of the catalog `catalog` that a command line's FILTER selects ([`choose`]).
pub fn select(catalog: &str, filter: &str) -> Result<Vec<Entry>> {
    Ok(select_in(&[catalog], filter)?
        .into_iter()
        .map(|(_, e)| e)
        .collect())
}

/// The scenes of the catalogs `catalogs` that a command line's FILTER selects, with their
/// catalog, in catalog then name order ([`choose`]).
pub fn select_in<'r>(catalogs: &[&'r str], filter: &str) -> Result<Vec<(&'r str, Entry)>> {
    let sources: Vec<Source<'_, &'r str>> = catalogs
        .iter()
        .map(|&c| Source {
            key: c,
            name: c,
            folder: c,
            list: Box::new(move || {
                scenes(c, "").with_context(|| format!("reading conformance/scenes/{c}/"))
            }),
        })
        .collect();
    choose(&sources, filter)
}

/// Where a selection looks: a named set of catalog scenes (a catalog, or the scenes of a
/// catalog that one reference covers).
pub struct Source<'a, K> {
    /// What a selected scene is returned with.
    pub key: K,
    /// The name a FILTER's `NAME::` prefix picks it by.
    pub name: &'a str,
    /// Its catalog, for messages.
    pub folder: &'a str,
    /// Its scenes, listed only when the FILTER looks in it.
    pub list: Box<dyn Fn() -> Result<Vec<Entry>> + 'a>,
}

/// The scenes of `sources` that a command line's FILTER selects, each with its source's
/// key, in source then name order. The same rules everywhere (`conformance run`, the
/// regeneration commands, the catalog test's filter; conformance/docs/workflows.md):
/// - `NAME::SCENE` (a test's name, `povray::shade_phong`) looks in the source of that
///   name only, with SCENE as the filter;
/// - a FILTER that is a scene's whole name selects that scene alone (`shade_phong`, not
///   also `shade_phong_size`);
/// - any other FILTER selects every scene whose name contains it (empty: every scene).
///
/// An empty selection is an error that lists close names.
pub fn choose<K: Clone>(sources: &[Source<'_, K>], filter: &str) -> Result<Vec<(K, Entry)>> {
    let (sources, name): (Vec<&Source<'_, K>>, &str) = match filter.split_once("::") {
        Some((prefix, name)) => {
            let Some(s) = sources.iter().find(|s| s.name == prefix) else {
                let names: Vec<&str> = sources.iter().map(|s| s.name).collect();
                anyhow::bail!(
                    "'{filter}': no catalog named '{prefix}' here (catalogs: {})",
                    names.join(", ")
                );
            };
            (vec![s], name)
        }
        None => (sources.iter().collect(), filter),
    };
    let mut all = Vec::new();
    for s in &sources {
        for e in (s.list)()? {
            all.push((s.key.clone(), e));
        }
    }
    let exact = all.iter().any(|(_, e)| e.name == name);
    let chosen: Vec<(K, Entry)> = all
        .iter()
        .filter(|(_, e)| {
            if exact {
                e.name == name
            } else {
                e.name.contains(name)
            }
        })
        .cloned()
        .collect();
    if chosen.is_empty() {
        let names: Vec<String> = all.into_iter().map(|(_, e)| e.name).collect();
        let close = close_names(name, &names);
        let mut folders: Vec<String> = Vec::new();
        for s in &sources {
            let f = format!("conformance/scenes/{}/", s.folder);
            if !folders.contains(&f) {
                folders.push(f);
            }
        }
        anyhow::bail!(
            "no catalog scene matches '{filter}'{}",
            if close.is_empty() {
                format!(" (the catalogs are {})", folders.join(" and "))
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

/// A copy of a catalog scene with a comment added before its `[render]` table, in a new
/// folder of the system's temporary directory named by `tag` (the caller removes it): the
/// same scene, but a file whose hash no longer matches its references' records, for the
/// gates' "a stale reference is never a pass" tests.
pub fn edited_copy(entry: &Entry, tag: &str) -> Result<(PathBuf, Entry)> {
    let text = std::fs::read_to_string(&entry.path)
        .with_context(|| format!("reading {}", entry.path.display()))?
        .replace("[render]", "# edited\n[render]");
    let dir = std::env::temp_dir().join(format!("{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("{}.toml", entry.name));
    std::fs::write(&path, text)?;
    Ok((
        dir,
        Entry {
            path,
            ..entry.clone()
        },
    ))
}

/// Names of `candidates` close to `wanted` (a part of the name, or the whole name, within
/// the edit distance `renderer::suggest` allows), best first: for "no scene matches"
/// messages.
pub fn close_names<'a>(wanted: &str, candidates: &'a [String]) -> Vec<&'a str> {
    use renderer::suggest::{edit_distance, max_distance};
    let mut scored: Vec<(usize, &str)> = candidates
        .iter()
        .filter_map(|c| {
            let d = (0..=c.len().saturating_sub(wanted.len()))
                .filter_map(|i| c.get(i..i + wanted.len().min(c.len())))
                .map(|sub| edit_distance(wanted, sub))
                .min()
                .unwrap_or(usize::MAX)
                .min(edit_distance(wanted, c));
            (d <= max_distance(wanted)).then_some((d, c.as_str()))
        })
        .collect();
    scored.sort();
    scored.into_iter().map(|(_, c)| c).take(8).collect()
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

    /// The names `select_in` picks from the committed catalogs for `filter`, as
    /// `catalog::name`, or the error's text.
    fn picked(filter: &str) -> Result<Vec<String>, String> {
        select_in(&["povray", "mitsuba"], filter)
            .map(|v| {
                v.into_iter()
                    .map(|(r, e)| format!("{r}::{}", e.name))
                    .collect()
            })
            .map_err(|e| e.to_string())
    }

    #[test]
    fn test02_a_filter_means_one_thing() {
        // A whole name: that scene alone, though another name contains it.
        assert_eq!(picked("shade_phong").unwrap(), ["povray::shade_phong"]);
        // A test's name: the catalog, then the same rules.
        assert_eq!(
            picked("povray::shade_phong").unwrap(),
            ["povray::shade_phong"]
        );
        assert_eq!(
            picked("povray::shade_phong_").unwrap(),
            ["povray::shade_phong_size"]
        );
        // A part of names: every scene that contains it, in catalog and name order.
        let cones = picked("prim_cone").unwrap();
        assert!(cones.len() > 1, "{cones:?}");
        assert!(
            cones.iter().all(|c| c.starts_with("povray::prim_cone")),
            "{cones:?}"
        );
        assert!(cones.windows(2).all(|w| w[0] < w[1]), "{cones:?}");
        // The empty filter: every scene of both catalogs.
        let all = picked("").unwrap();
        assert!(
            all.iter().any(|n| n.starts_with("mitsuba::")),
            "{}",
            all.len()
        );
        // Nothing matches: an error with close names, or the catalogs.
        let e = picked("mitsuba::shade_phong").unwrap_err();
        assert!(
            e.contains("close names: ") || e.contains("conformance/scenes/mitsuba/"),
            "{e}"
        );
        let e = picked("shade_phnog").unwrap_err();
        assert!(e.contains("close names: shade_phong"), "{e}");
        let e = picked("blender::x").unwrap_err();
        assert!(e.contains("no catalog named 'blender'"), "{e}");
    }
}
