//! Regenerating Cycles references: export each scene to JSON, render its geometry and K
//! radiance seeds with `scripts/cycles_refs.py` in the Python that has `bpy`, combine the
//! seeds into a mean and a variance (`super::refs`), and record the manifest entries.

use super::refs::{combine_seeds, read_geometry_render, read_seed, write_geometry, write_radiance};
use crate::catalog::{load, repo_root, scratch_dir, Entry};
use crate::manifest::{sha256, today, Manifest, Record};
use crate::mitsuba::compare::{geometry_test, radiance_test};
use crate::mitsuba::harness::read_geometry;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Independent seeds of a radiance reference.
pub const SEEDS: u32 = 16;
/// Samples per pixel of each seed (K · S = 8192, the Mitsuba references' count).
pub const SEED_SPP: u32 = 512;
/// Samples per pixel of the geometry render (pixel filter 0.01 px wide).
pub const GEOMETRY_SPP: u32 = 1;

/// The Python that has `bpy`: `$CYCLES_PYTHON`, else the venv scripts/regen-cycles.sh
/// makes (`target/cycles-venv`).
pub fn python() -> PathBuf {
    match std::env::var_os("CYCLES_PYTHON").filter(|p| !p.is_empty()) {
        Some(p) => PathBuf::from(p),
        None => repo_root().join("target/cycles-venv/bin/python"),
    }
}

/// Blender's version, as the reference script reports it.
pub fn cycles_version() -> Result<String> {
    let out = Command::new(python())
        .arg(repo_root().join("scripts/cycles_refs.py"))
        .arg("version")
        .output()
        .with_context(|| {
            format!(
                "cannot run {} (install bpy with scripts/regen-cycles.sh)",
                python().display()
            )
        })?;
    anyhow::ensure!(
        out.status.success(),
        "bpy is not importable: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // bpy prints its own start-up lines on stdout; the version is the last line.
    let text = String::from_utf8_lossy(&out.stdout);
    Ok(text.lines().last().unwrap_or("").trim().to_string())
}

/// The exported JSON text (what the records hash).
pub fn export_text(scene: &renderer::scene::Scene) -> Result<String> {
    Ok(serde_json::to_string_pretty(&super::export(scene)?)? + "\n")
}

/// Renders one scene's Cycles references into `out_dir` and returns their records
/// (radiance, geometry).
pub fn render_cycles(entry: &Entry, out_dir: &Path, version: &str) -> Result<(Record, Record)> {
    let work = scratch_dir(&format!("cy-{}", entry.name))?;
    // The scratch folder goes whether the render succeeds or not.
    let result = render_in(entry, out_dir, version, &work);
    std::fs::remove_dir_all(&work).ok();
    result
}

fn render_in(
    entry: &Entry,
    out_dir: &Path,
    version: &str,
    work: &Path,
) -> Result<(Record, Record)> {
    let (scene, text) = load(entry)?;
    let json = export_text(&scene)?;
    let json_name = format!("{}.json", entry.name);
    std::fs::write(work.join(&json_name), &json)?;
    let script = repo_root().join("scripts/cycles_refs.py");
    let run = |args: &[String]| -> Result<()> {
        let out = Command::new(python())
            .arg(&script)
            .args(args)
            .current_dir(work)
            .output()?;
        if !out.status.success() {
            bail!(
                "cycles failed on {} ({}): {}",
                entry.name,
                args.join(" "),
                String::from_utf8_lossy(&out.stderr)
            );
        }
        Ok(())
    };
    let geo_raw = format!("{}.geom-raw.exr", entry.name);
    run(&[
        "geometry".into(),
        json_name.clone(),
        geo_raw.clone(),
        GEOMETRY_SPP.to_string(),
    ])?;
    run(&[
        "radiance".into(),
        json_name.clone(),
        entry.name.clone(),
        SEED_SPP.to_string(),
        SEEDS.to_string(),
    ])?;
    let mut seeds = Vec::new();
    let mut size = (0, 0);
    for seed in 0..SEEDS {
        let (s, rgb) = read_seed(&work.join(format!("{}.seed{seed}.exr", entry.name)))?;
        size = s;
        seeds.push(rgb);
    }
    let (rgb, est) = combine_seeds(size, &seeds, SEED_SPP)?;
    let geometry = read_geometry_render(
        &work.join(&geo_raw),
        super::export::WORLD,
        scene.camera.eye64,
    )?;
    std::fs::create_dir_all(out_dir)?;
    let (rad_file, geo_file) = (
        format!("{}.exr", entry.name),
        format!("{}.geom.exr", entry.name),
    );
    write_radiance(&out_dir.join(&rad_file), &rgb, &est)?;
    write_geometry(&out_dir.join(&geo_file), &geometry)?;
    let record = |command: String, file: String, spp: Option<u32>| Record {
        tool: "cycles".into(),
        version: version.into(),
        command,
        scene_hash: sha256(text.as_bytes()),
        export_hash: sha256(json.as_bytes()),
        date: today(),
        file,
        spp,
    };
    Ok((
        record(
            format!(
                "python scripts/cycles_refs.py radiance {json_name} {} {SEED_SPP} {SEEDS}, \
                 the seeds combined by conformance::cycles::refs",
                entry.name
            ),
            format!("cycles/{rad_file}"),
            Some(SEEDS * SEED_SPP),
        ),
        record(
            format!("python scripts/cycles_refs.py geometry {json_name} {geo_raw} {GEOMETRY_SPP}"),
            format!("cycles/{geo_file}"),
            None,
        ),
    ))
}

/// Regenerates the Cycles references of `entries` and updates the manifest.
pub fn regenerate(entries: &[Entry]) -> Result<()> {
    let version = cycles_version()?;
    let root = repo_root();
    let manifest_path = crate::manifest::committed_path();
    let mut manifest = Manifest::load(&manifest_path)?;
    for e in entries {
        let t0 = std::time::Instant::now();
        let (rad, geo) = render_cycles(e, &root.join("references/cycles"), &version)?;
        eprintln!("{:<24} {:.1} s", e.name, t0.elapsed().as_secs_f64());
        manifest.reference.insert(format!("cycles/{}", e.name), rad);
        manifest
            .reference
            .insert(format!("cycles-geometry/{}", e.name), geo);
        manifest.save(&manifest_path)?;
    }
    Ok(())
}

/// Re-renders `entries` from scratch and checks the result against the committed files:
/// geometry by the gate's geometric test, radiance by the two-sample statistical test
/// (both sides have a variance), and the manifest records (scene and export hashes,
/// command). Returns the names that differ.
pub fn check(entries: &[Entry]) -> Result<Vec<String>> {
    let tmp = scratch_dir("cy-check")?;
    // The scratch folder goes whether the check succeeds or not.
    let result = check_in(entries, &tmp);
    std::fs::remove_dir_all(&tmp).ok();
    result
}

fn check_in(entries: &[Entry], tmp: &Path) -> Result<Vec<String>> {
    let version = cycles_version()?;
    let root = repo_root();
    let manifest = Manifest::committed()?;
    let mut bad = Vec::new();
    for e in entries {
        let old = manifest
            .reference
            .get(&format!("cycles/{}", e.name))
            .with_context(|| format!("no record cycles/{}", e.name))?;
        let old_geo = manifest
            .reference
            .get(&format!("cycles-geometry/{}", e.name))
            .with_context(|| format!("no record cycles-geometry/{}", e.name))?;
        let (rad, geo) = render_cycles(e, tmp, &version)?;
        let committed = root.join("references/cycles");
        let g = geometry_test(
            &read_geometry(&tmp.join(format!("{}.geom.exr", e.name)))?,
            &read_geometry(&committed.join(format!("{}.geom.exr", e.name)))?,
        );
        let n = old.spp.context("a Cycles radiance record has spp")?;
        let (_, r_new) = super::refs::read_radiance(&tmp.join(format!("{}.exr", e.name)), n)?;
        let (_, r_old) = super::refs::read_radiance(&committed.join(format!("{}.exr", e.name)), n)?;
        let stat = radiance_test(&r_new, &r_old);
        let same_record = old.scene_hash == rad.scene_hash
            && old.export_hash == rad.export_hash
            && old.command == rad.command
            && old_geo.command == geo.command
            && old_geo.export_hash == geo.export_hash;
        eprintln!(
            "{:<24} geometry {} (max distance {:.1e}, normal {:.4}°, edge {}, failing {}) radiance {} (pixel pass {:.2} %, global z {:.2?}) manifest {}",
            e.name,
            if g.passed() { "agrees" } else { "DIFFERS" },
            g.max_rel_distance,
            g.max_normal_degrees,
            g.silhouette,
            g.failing,
            if stat.passed() { "consistent" } else { "INCONSISTENT" },
            stat.pass_fraction * 100.0,
            stat.global_z,
            if same_record { "matches" } else { "DIFFERS" }
        );
        if !(g.passed() && stat.passed() && same_record) {
            bad.push(e.name.clone());
        }
    }
    Ok(bad)
}
