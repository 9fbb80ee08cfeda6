//! Regenerating Mitsuba references: export each scene to XML, render geometry (pixel-centre
//! ray casts) and radiance (the `moment` integrator) with `scripts/mitsuba_refs.py`, and
//! record the manifest entries.

use super::compare::Geometry;
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
    let export = super::xml::export(&scene, spp, true)?;
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
    // A radiance reference rendered by another variant than scalar_rgb says so in its
    // command (the variant is the script's MITSUBA_VARIANT, which the child inherits).
    let variant = match std::env::var("MITSUBA_VARIANT") {
        Ok(v) if !v.is_empty() && v != "scalar_rgb" => format!("MITSUBA_VARIANT={v} "),
        _ => String::new(),
    };
    Ok((
        record(
            format!(
                "{variant}python3 scripts/mitsuba_refs.py radiance {xml_name} {rad_file} {spp}"
            ),
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
    let manifest_path = crate::manifest::committed_path();
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
/// with the same hits and distances and normals within [`GEOMETRY_ULPS`] (Embree rounds by
/// the CPU), radiance by the statistical test against the committed reference (Mitsuba
/// seeds per render block, so its bits depend on the thread count). Returns the names that
/// differ.
pub fn check(entries: &[Entry]) -> Result<Vec<String>> {
    let version = mitsuba_version()?;
    let root = repo_root();
    let manifest = Manifest::committed()?;
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
        let diff = GeometryDiff::new(&g_new, &g_old);
        let same_geometry = diff.within_rounding();
        if !diff.identical() {
            eprintln!("{}", diff.describe());
        }
        let (_, r_new) = read_radiance(&tmp.join(format!("{}.exr", e.name)), spp)?;
        let (_, r_old) = read_radiance(&committed.join(format!("{}.exr", e.name)), spp)?;
        let stat = super::compare::radiance_test(&r_new, &r_old);
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
            if diff.identical() {
                "identical"
            } else if same_geometry {
                "equal up to rounding"
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

/// Ulps of distance, and of a normal component (in units of the ulp of 1), by which a
/// regenerated geometry reference may differ from the committed one. The reference chain
/// rounds by the CPU it runs on: Mitsuba's CPU variants cast rays with Embree, which picks
/// its kernels by the instruction set when it starts, and `scripts/mitsuba_refs.py` takes
/// the distance with numpy, whose BLAS does the same. Measured: all 13 geometry references,
/// regenerated on an AMD EPYC (AVX2, no AVX-512), differ from the committed ones in 41 to
/// 70 of 1,728 pixels, by at most 2 ulps of distance, with the same hit masks and normals
/// (conformance/docs/mitsuba.md). The gate's own geometry tolerance is far looser, so this
/// bound is not what decides a scene.
pub const GEOMETRY_ULPS: u32 = 4;

/// How a regenerated geometry reference differs from the committed one.
struct GeometryDiff {
    /// Both sizes, when they differ (nothing else is compared then).
    sizes: Option<((usize, usize), (usize, usize))>,
    /// Pixels whose hit, distance or normal differ in any bit.
    pixels: usize,
    /// Pixels hit in one and missed in the other.
    hit_flips: usize,
    /// Largest distance difference in f32 ulps, over pixels both hit.
    z_ulps: u32,
    /// Largest normal component difference, in ulps of 1.
    n_ulps: f64,
    /// The first few differing pixels.
    first: Vec<String>,
}

/// Distance in f32 ulps between two values stored as f32 (the EXR channels).
fn ulps(a: f64, b: f64) -> u32 {
    let key = |v: f64| {
        // Sign-magnitude bits to a monotonic integer line (-0 and +0 both at 0).
        let i = i64::from((v as f32).to_bits() as i32);
        if i < 0 {
            i64::from(i32::MIN) - i
        } else {
            i
        }
    };
    u32::try_from((key(a) - key(b)).unsigned_abs()).unwrap_or(u32::MAX)
}

impl GeometryDiff {
    fn new(new: &Geometry, old: &Geometry) -> GeometryDiff {
        let mut d = GeometryDiff {
            sizes: (new.size != old.size).then_some((new.size, old.size)),
            pixels: 0,
            hit_flips: 0,
            z_ulps: 0,
            n_ulps: 0.0,
            first: Vec::new(),
        };
        if d.sizes.is_some() {
            return d;
        }
        let w = new.size.0;
        for i in 0..new.hit.len() {
            let hit_flip = new.hit[i] != old.hit[i];
            let z = ulps(new.z[i], old.z[i]);
            let n = (0..3)
                .map(|c| (new.n[3 * i + c] - old.n[3 * i + c]).abs() / f64::from(f32::EPSILON))
                .fold(0.0, f64::max);
            if !(hit_flip || z > 0 || n > 0.0) {
                continue;
            }
            d.pixels += 1;
            d.hit_flips += hit_flip as usize;
            if new.hit[i] && old.hit[i] {
                d.z_ulps = d.z_ulps.max(z);
                d.n_ulps = d.n_ulps.max(n);
            }
            if d.first.len() < 5 {
                d.first.push(format!(
                    "({}, {}) distance {} now, {} committed ({z} ulps){}",
                    i % w,
                    i / w,
                    new.z[i] as f32,
                    old.z[i] as f32,
                    if hit_flip { ", hit/miss differs" } else { "" }
                ));
            }
        }
        d
    }

    /// The same size and every pixel the same in every bit.
    fn identical(&self) -> bool {
        self.sizes.is_none() && self.pixels == 0
    }

    /// The same hits, and distances and normals within [`GEOMETRY_ULPS`].
    fn within_rounding(&self) -> bool {
        self.sizes.is_none()
            && self.hit_flips == 0
            && self.z_ulps <= GEOMETRY_ULPS
            && self.n_ulps <= f64::from(GEOMETRY_ULPS)
    }

    fn describe(&self) -> String {
        if let Some((a, b)) = self.sizes {
            return format!("  geometry: {a:?} pixels now, {b:?} committed");
        }
        format!(
            "  geometry: {} pixels differ ({} hit/miss), distance by up to {} ulps, normal \
             components by up to {:.1} ulps of 1 (allowed: no hit/miss, {GEOMETRY_ULPS} ulps); \
             first: {}",
            self.pixels,
            self.hit_flips,
            self.z_ulps,
            self.n_ulps,
            self.first.join("; ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry(z: &[f64], hit: &[bool]) -> Geometry {
        Geometry {
            size: (z.len(), 1),
            z: z.to_vec(),
            n: z.iter().flat_map(|_| [0.0, 0.0, 1.0]).collect(),
            hit: hit.to_vec(),
        }
    }

    #[test]
    fn ulps_count_representable_f32_steps_across_zero() {
        assert_eq!(ulps(1.0, 1.0), 0);
        let next = f32::from_bits(1.0f32.to_bits() + 3) as f64;
        assert_eq!(ulps(1.0, next), 3);
        assert_eq!(ulps(next, 1.0), 3);
        let tiny = f32::from_bits(1) as f64;
        assert_eq!(ulps(tiny, -tiny), 2);
    }

    #[test]
    fn rounding_differences_pass_and_real_ones_do_not() {
        let z = 8.382542610168457f64;
        let near = f32::from_bits((z as f32).to_bits() + GEOMETRY_ULPS) as f64;
        let far = f32::from_bits((z as f32).to_bits() + GEOMETRY_ULPS + 1) as f64;
        let old = geometry(&[z, 1.0], &[true, true]);
        let same = GeometryDiff::new(&old, &old);
        assert!(same.identical() && same.within_rounding());
        let rounded = GeometryDiff::new(&geometry(&[near, 1.0], &[true, true]), &old);
        assert_eq!((rounded.pixels, rounded.z_ulps), (1, GEOMETRY_ULPS));
        assert!(rounded.within_rounding(), "{}", rounded.describe());
        let moved = GeometryDiff::new(&geometry(&[far, 1.0], &[true, true]), &old);
        assert!(!moved.within_rounding(), "{}", moved.describe());
        let flipped = GeometryDiff::new(&geometry(&[z, 0.0], &[true, false]), &old);
        assert!(!flipped.within_rounding(), "{}", flipped.describe());
        assert!(
            flipped.describe().contains("1 hit/miss"),
            "{}",
            flipped.describe()
        );
        let mut turned = old.clone();
        turned.n[2] -= 5.0 * f64::from(f32::EPSILON);
        assert!(!GeometryDiff::new(&turned, &old).within_rounding());
        let small = GeometryDiff::new(&geometry(&[z], &[true]), &old);
        assert!(!small.identical() && !small.within_rounding());
    }
}
