//! Regenerating POV-Ray references: export each scene to SDL, render it with POV-Ray at
//! pixel centres (`-A`) to a half-float EXR, and record the manifest entry.

use super::harness::read_reference;
use crate::catalog::{load, repo_root, scratch_dir, Entry};
use crate::manifest::{sha256, today, Manifest, Record};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;

/// The POV-Ray version string, e.g. "3.7.0.10.unofficial".
pub fn povray_version() -> Result<String> {
    let out = Command::new("povray").arg("--version").output().context(
        "cannot run povray (install it with scripts/regen-povray.sh, which uses apt-get)",
    )?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    text.lines()
        .find_map(|l| l.trim().strip_prefix("POV-Ray "))
        .map(|v| v.trim().to_string())
        .context("povray --version printed no version")
}

/// The POV-Ray command line for a scene (relative file names, run inside `dir`).
pub fn povray_args(name: &str, width: u32, height: u32) -> Vec<String> {
    vec![
        format!("+I{name}.pov"),
        format!("+O{name}.exr"),
        "+FE".into(),
        format!("+W{width}"),
        format!("+H{height}"),
        "-D".into(),
        "-A".into(),
        "+WT2".into(),
        "-GA".into(),
    ]
}

/// Renders one scene with POV-Ray into `out_dir/<name>.exr` and returns its record.
pub fn render_povray(entry: &Entry, out_dir: &Path, version: &str) -> Result<Record> {
    let (scene, text) = load(entry)?;
    let sdl = super::sdl::export(&scene, &entry.name);
    let work = scratch_dir(&entry.name)?;
    std::fs::write(work.join(format!("{}.pov", entry.name)), &sdl)?;
    let args = povray_args(&entry.name, scene.settings.width, scene.settings.height);
    let out = Command::new("povray")
        .args(&args)
        .current_dir(&work)
        .output()
        .context("running povray")?;
    let produced = work.join(format!("{}.exr", entry.name));
    if !out.status.success() || !produced.exists() {
        bail!(
            "povray failed on {}:\n{}",
            entry.name,
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .rev()
                .take(20)
                .collect::<Vec<_>>()
                .join("\n")
        );
    }
    std::fs::create_dir_all(out_dir)?;
    std::fs::copy(&produced, out_dir.join(format!("{}.exr", entry.name)))?;
    std::fs::remove_dir_all(&work).ok();
    Ok(Record {
        tool: "povray".into(),
        version: version.into(),
        command: format!("povray {}", args.join(" ")),
        scene_hash: sha256(text.as_bytes()),
        export_hash: sha256(sdl.as_bytes()),
        date: today(),
        file: format!("povray/{}.exr", entry.name),
        spp: None,
    })
}

/// Regenerates the references of `entries` and updates the manifest.
pub fn regenerate(entries: &[Entry]) -> Result<()> {
    let version = povray_version()?;
    let root = repo_root();
    let manifest_path = crate::manifest::committed_path();
    let mut manifest = Manifest::load(&manifest_path)?;
    for e in entries {
        let rec = render_povray(e, &root.join("references/povray"), &version)?;
        eprintln!("{:<32} {}", e.name, rec.command);
        manifest.reference.insert(format!("povray/{}", e.name), rec);
    }
    manifest.save(&manifest_path)
}

/// Re-renders `entries` from scratch into a temporary folder and checks that the pixels
/// equal the committed references exactly, and that the manifest records the same version
/// and command. Returns the names that differ.
pub fn check(entries: &[Entry]) -> Result<Vec<String>> {
    let version = povray_version()?;
    let root = repo_root();
    let manifest = Manifest::committed()?;
    let tmp = scratch_dir("check")?;
    let mut bad = Vec::new();
    for e in entries {
        let rec = render_povray(e, &tmp, &version)?;
        let (_, _, fresh) = read_reference(&tmp.join(format!("{}.exr", e.name)))?;
        let (_, _, committed) = read_reference(
            &root
                .join("references/povray")
                .join(format!("{}.exr", e.name)),
        )?;
        let old = manifest.reference.get(&format!("povray/{}", e.name));
        let same_record = old.is_some_and(|o| {
            o.command == rec.command
                && o.scene_hash == rec.scene_hash
                && o.export_hash == rec.export_hash
                && o.version == rec.version
        });
        let same_pixels = fresh.len() == committed.len()
            && fresh
                .iter()
                .zip(&committed)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        eprintln!(
            "{:<32} pixels {} manifest {}",
            e.name,
            if same_pixels { "identical" } else { "DIFFER" },
            if same_record { "matches" } else { "DIFFERS" }
        );
        if !(same_pixels && same_record) {
            bad.push(e.name.clone());
        }
    }
    std::fs::remove_dir_all(&tmp).ok();
    Ok(bad)
}
