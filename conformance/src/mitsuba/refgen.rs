//! Regenerating Mitsuba references: export each scene to XML, render geometry (pixel-centre
//! ray casts) and radiance (the `moment` integrator) with `scripts/mitsuba_refs.py`, and
//! record the manifest entries.

use super::harness::{export_text, read_geometry, read_radiance};
use crate::catalog::{load, repo_root, scratch_dir, Entry};
use crate::manifest::{sha256, today, Manifest, Record};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;

/// The Mitsuba version, as the reference script reports it.
pub fn mitsuba_version() -> Result<String> {
    let out = Command::new("python3")
        .arg(repo_root().join("scripts/mitsuba_refs.py"))
        .arg("version")
        .output()
        .context("cannot run python3 (install Mitsuba with scripts/regen-mitsuba.sh)")?;
    anyhow::ensure!(
        out.status.success(),
        "mitsuba is not importable: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Renders one scene's Mitsuba references (geometry and radiance at `spp`) into `out_dir`
/// and returns their records (radiance, geometry).
pub fn render_mitsuba(
    entry: &Entry,
    out_dir: &Path,
    version: &str,
    spp: u32,
) -> Result<(Record, Record)> {
    let (scene, text) = load(entry)?;
    let export = super::export(&scene, spp, true)?;
    let hash_text = export_text(&scene, spp)?;
    let work = scratch_dir(&format!("mi-{}", entry.name))?;
    let xml = work.join(format!("{}.xml", entry.name));
    export.write(&xml)?;
    let script = repo_root().join("scripts/mitsuba_refs.py");
    let (geo_file, rad_file) = (
        format!("{}.geom.exr", entry.name),
        format!("{}.exr", entry.name),
    );
    let run = |args: &[&str]| -> Result<()> {
        let out = Command::new("python3")
            .arg(&script)
            .args(args)
            .current_dir(&work)
            .output()?;
        if !out.status.success() {
            bail!(
                "mitsuba failed on {}: {}",
                entry.name,
                String::from_utf8_lossy(&out.stderr)
            );
        }
        Ok(())
    };
    let xml_name = format!("{}.xml", entry.name);
    let spp_s = spp.to_string();
    run(&["geometry", &xml_name, &geo_file])?;
    run(&["radiance", &xml_name, &rad_file, &spp_s])?;
    std::fs::create_dir_all(out_dir)?;
    std::fs::copy(work.join(&geo_file), out_dir.join(&geo_file))?;
    std::fs::copy(work.join(&rad_file), out_dir.join(&rad_file))?;
    std::fs::remove_dir_all(&work).ok();
    let record = |command: String, file: String, spp: Option<u32>| Record {
        tool: "mitsuba".into(),
        version: version.into(),
        command,
        scene_hash: sha256(text.as_bytes()),
        export_hash: sha256(hash_text.as_bytes()),
        date: today(),
        file,
        spp,
    };
    Ok((
        record(
            format!("python3 scripts/mitsuba_refs.py radiance {xml_name} {rad_file} {spp}"),
            format!("mitsuba/{rad_file}"),
            Some(spp),
        ),
        record(
            format!("python3 scripts/mitsuba_refs.py geometry {xml_name} {geo_file}"),
            format!("mitsuba/{geo_file}"),
            None,
        ),
    ))
}

/// Regenerates the Mitsuba references of `entries` at `spp` and updates the manifest.
pub fn regenerate(entries: &[Entry], spp: u32) -> Result<()> {
    let version = mitsuba_version()?;
    let root = repo_root();
    let manifest_path = root.join("references/manifest.toml");
    let mut manifest = Manifest::load(&manifest_path)?;
    for e in entries {
        let t0 = std::time::Instant::now();
        let (rad, geo) = render_mitsuba(e, &root.join("references/mitsuba"), &version, spp)?;
        eprintln!(
            "{:<24} {:.1} s  {}",
            e.name,
            t0.elapsed().as_secs_f64(),
            rad.command
        );
        manifest
            .reference
            .insert(format!("mitsuba/{}", e.name), rad);
        manifest
            .reference
            .insert(format!("mitsuba-geometry/{}", e.name), geo);
        manifest.save(&manifest_path)?;
    }
    Ok(())
}

/// Re-renders `entries` from scratch at the committed spp and checks the result: geometry
/// bit for bit, radiance by the statistical test against the committed reference (Mitsuba
/// seeds per render block, so its bits depend on the thread count). Returns the names
/// that differ.
pub fn check(entries: &[Entry]) -> Result<Vec<String>> {
    let version = mitsuba_version()?;
    let root = repo_root();
    let manifest = Manifest::load(&root.join("references/manifest.toml"))?;
    let tmp = scratch_dir("mi-check")?;
    let mut bad = Vec::new();
    for e in entries {
        let old = manifest
            .reference
            .get(&format!("mitsuba/{}", e.name))
            .with_context(|| format!("no record for {}", e.name))?;
        let spp = old.spp.context("spp")?;
        let (rad, geo) = render_mitsuba(e, &tmp, &version, spp)?;
        let committed = root.join("references/mitsuba");
        let g_new = read_geometry(&tmp.join(format!("{}.geom.exr", e.name)))?;
        let g_old = read_geometry(&committed.join(format!("{}.geom.exr", e.name)))?;
        let same_geometry = g_new.z == g_old.z && g_new.n == g_old.n && g_new.hit == g_old.hit;
        let (_, r_new) = read_radiance(&tmp.join(format!("{}.exr", e.name)), spp)?;
        let (_, r_old) = read_radiance(&committed.join(format!("{}.exr", e.name)), spp)?;
        let stat = super::stats::radiance_test(&r_new, &r_old);
        let old_geo = manifest
            .reference
            .get(&format!("mitsuba-geometry/{}", e.name));
        let same_record = old.scene_hash == rad.scene_hash
            && old.export_hash == rad.export_hash
            && old.command == rad.command
            && old_geo
                .is_some_and(|g| g.command == geo.command && g.export_hash == geo.export_hash);
        eprintln!(
            "{:<24} geometry {} radiance {} (pixel pass {:.2} %, global z {:.2?}) manifest {}",
            e.name,
            if same_geometry {
                "identical"
            } else {
                "DIFFERS"
            },
            if stat.passed() {
                "consistent"
            } else {
                "INCONSISTENT"
            },
            stat.pass_fraction * 100.0,
            stat.global_z,
            if same_record { "matches" } else { "DIFFERS" }
        );
        if !(same_geometry && stat.passed() && same_record) {
            bad.push(e.name.clone());
        }
    }
    std::fs::remove_dir_all(&tmp).ok();
    Ok(bad)
}
