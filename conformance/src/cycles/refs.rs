//! The Cycles reference files: reading Blender's multilayer EXRs, combining independent
//! seeds into a mean and a variance, and the committed files' layout.
//!
//! Cycles stores no per-sample variance, and its default sampler correlates samples within
//! a render, so the variance comes from K renders with independent seeds of S samples
//! each: the K means x₁…x_K of a pixel-channel have sample variance s², and the variance
//! of their grand mean is s²/K. The committed radiance reference stores the grand mean and
//! the **per-sample equivalent** S·s², with n = K·S in the manifest's `spp`, so that
//! `var / n` is the grand mean's variance and the reference plugs into the same two-sample
//! test as Mitsuba's (`crate::mitsuba::compare`).
//!
//! | file | channels |
//! |---|---|
//! | `references/cycles/<scene>.exr` | R, G, B (mean); mean.X/Y/Z (CIE XYZ mean); var.X/Y/Z (per-sample equivalent variance) |
//! | `references/cycles/<scene>.geom.exr` | Z (distance from the eye), N.X/Y/Z (outward unit normal, our world), mask |

use crate::mitsuba::compare::{Estimate, Geometry, SRGB_TO_XYZ};
use anyhow::{ensure, Context, Result};
use glam::DVec3;
use renderer::output::{read_exr, ExrImage};
use std::path::Path;

/// Blender's name of the first view layer in a multilayer EXR.
const LAYER: &str = "ViewLayer";

fn channel<'a>(e: &'a ExrImage, path: &Path, name: &str) -> Result<&'a [f32]> {
    e.channel(name).with_context(|| {
        format!(
            "{}: no channel {name} (channels: {})",
            path.display(),
            e.channels
                .iter()
                .map(|(n, _)| n.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

/// Reads every part of a multipart EXR (Blender writes each pass of a multilayer EXR as
/// its own part) as one image whose channels are named `<part>.<channel>`, the names
/// Blender gives them (`ViewLayer.Combined.R`).
pub fn read_blender_exr(path: &Path) -> Result<ExrImage> {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let mut out = ExrImage {
        width: 0,
        height: 0,
        channels: Vec::new(),
    };
    for layer in &img.layer_data {
        let size = layer.size;
        if out.channels.is_empty() {
            (out.width, out.height) = (size.0, size.1);
        }
        ensure!(
            (size.0, size.1) == (out.width, out.height),
            "{}: its parts differ in size",
            path.display()
        );
        let part = layer
            .attributes
            .layer_name
            .as_ref()
            .map(|n| n.to_string())
            .unwrap_or_default();
        for c in &layer.channel_data.list {
            let name = c.name.to_string();
            let full = if part.is_empty() || name.starts_with(&format!("{part}.")) {
                name
            } else {
                format!("{part}.{name}")
            };
            out.channels
                .push((full, c.sample_data.values_as_f32().collect()));
        }
    }
    Ok(out)
}

/// One seed's radiance render: its RGB mean per pixel (3 per pixel).
pub fn read_seed(path: &Path) -> Result<((usize, usize), Vec<f64>)> {
    let e = read_blender_exr(path)?;
    let c = ["R", "G", "B"].map(|k| format!("{LAYER}.Combined.{k}"));
    let (r, g, b) = (
        channel(&e, path, &c[0])?,
        channel(&e, path, &c[1])?,
        channel(&e, path, &c[2])?,
    );
    let rgb = (0..e.width * e.height)
        .flat_map(|k| [r[k] as f64, g[k] as f64, b[k] as f64])
        .collect();
    Ok(((e.width, e.height), rgb))
}

/// RGB of one pixel to XYZ.
fn xyz(c: &[f64]) -> [f64; 3] {
    SRGB_TO_XYZ.map(|row| row[0] * c[0] + row[1] * c[1] + row[2] * c[2])
}

/// The radiance reference from K ≥ 2 seeds of `spp` samples each: (RGB mean, XYZ estimate
/// with the per-sample equivalent variance, n = K · spp).
pub fn combine_seeds(
    size: (usize, usize),
    seeds: &[Vec<f64>],
    spp: u32,
) -> Result<(Vec<f64>, Estimate)> {
    let k = seeds.len();
    ensure!(k >= 2, "a variance needs at least two seeds (got {k})");
    let px = size.0 * size.1;
    ensure!(
        seeds.iter().all(|s| s.len() == 3 * px),
        "the seeds' images differ in size"
    );
    let mut rgb = vec![0.0; 3 * px];
    let (mut mean, mut var) = (vec![0.0; 3 * px], vec![0.0; 3 * px]);
    for p in 0..px {
        let xs: Vec<[f64; 3]> = seeds.iter().map(|s| xyz(&s[3 * p..3 * p + 3])).collect();
        for c in 0..3 {
            rgb[3 * p + c] = seeds.iter().map(|s| s[3 * p + c]).sum::<f64>() / k as f64;
            let m = xs.iter().map(|x| x[c]).sum::<f64>() / k as f64;
            let s2 = xs.iter().map(|x| (x[c] - m).powi(2)).sum::<f64>() / (k - 1) as f64;
            mean[3 * p + c] = m;
            var[3 * p + c] = s2 * spp as f64;
        }
    }
    Ok((
        rgb,
        Estimate {
            size,
            mean,
            var,
            n: (k as u64 * spp as u64) as f64,
        },
    ))
}

/// The geometry render: outward normal and position AOVs (means over the samples, all
/// within 0.005 px of the pixel centre) and the object index of the first sample, mapped
/// back to our world by `world` (its own inverse). The distance is `|p − eye|`.
pub fn read_geometry_render(path: &Path, world: glam::DMat3, eye: DVec3) -> Result<Geometry> {
    let e = read_blender_exr(path)?;
    let get = |n: &str| channel(&e, path, &format!("{LAYER}.{n}"));
    let (nx, ny, nz) = (get("ng.R")?, get("ng.G")?, get("ng.B")?);
    let (px_, py, pz) = (get("pos.R")?, get("pos.G")?, get("pos.B")?);
    let index = get("Object Index.X")?;
    let px = e.width * e.height;
    let mut g = Geometry {
        size: (e.width, e.height),
        z: vec![0.0; px],
        n: vec![0.0; 3 * px],
        hit: vec![false; px],
    };
    for k in 0..px {
        if index[k] < 0.5 {
            continue;
        }
        let n = world * DVec3::new(nx[k] as f64, ny[k] as f64, nz[k] as f64);
        let p = world * DVec3::new(px_[k] as f64, py[k] as f64, pz[k] as f64);
        let n = n.normalize_or_zero();
        g.hit[k] = true;
        g.z[k] = (p - eye).length();
        g.n[3 * k..3 * k + 3].copy_from_slice(&[n.x, n.y, n.z]);
    }
    Ok(g)
}

/// Writes float channels (each `size.0 × size.1`, top row first) to an EXR, through a
/// temporary file so that an existing file is only replaced by a complete one.
pub fn write_channels(
    path: &Path,
    size: (usize, usize),
    channels: Vec<(String, Vec<f32>)>,
) -> Result<()> {
    use exr::prelude::*;
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .into_iter()
        .map(|(n, v)| AnyChannel::new(n.as_str(), FlatSamples::F32(v)))
        .collect();
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let tmp = path.with_extension("exr.tmp");
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(&tmp)
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes a radiance reference.
pub fn write_radiance(path: &Path, rgb: &[f64], est: &Estimate) -> Result<()> {
    let plane = |v: &[f64], c: usize| v.iter().skip(c).step_by(3).map(|x| *x as f32).collect();
    let mut ch = Vec::new();
    for (c, k) in ["R", "G", "B"].iter().enumerate() {
        ch.push((k.to_string(), plane(rgb, c)));
    }
    for (c, k) in ["X", "Y", "Z"].iter().enumerate() {
        ch.push((format!("mean.{k}"), plane(&est.mean, c)));
        ch.push((format!("var.{k}"), plane(&est.var, c)));
    }
    write_channels(path, est.size, ch)
}

/// Writes a geometry reference (the channels `crate::mitsuba::harness::read_geometry`
/// reads).
pub fn write_geometry(path: &Path, g: &Geometry) -> Result<()> {
    let plane = |c: usize| g.n.iter().skip(c).step_by(3).map(|x| *x as f32).collect();
    let ch = vec![
        ("Z".to_string(), g.z.iter().map(|x| *x as f32).collect()),
        ("N.X".to_string(), plane(0)),
        ("N.Y".to_string(), plane(1)),
        ("N.Z".to_string(), plane(2)),
        (
            "mask".to_string(),
            g.hit.iter().map(|h| if *h { 1.0 } else { 0.0 }).collect(),
        ),
    ];
    write_channels(path, g.size, ch)
}

/// Reads a radiance reference: the RGB mean and the XYZ estimate with n = `n` samples.
pub fn read_radiance(path: &Path, n: u32) -> Result<(Vec<f32>, Estimate)> {
    let e = read_exr(path)?;
    let get = |k: &str| channel(&e, path, k);
    let px = e.width * e.height;
    let (r, g, b) = (get("R")?, get("G")?, get("B")?);
    let m = [get("mean.X")?, get("mean.Y")?, get("mean.Z")?];
    let v = [get("var.X")?, get("var.Y")?, get("var.Z")?];
    let mut rgb = Vec::with_capacity(3 * px);
    let (mut mean, mut var) = (Vec::with_capacity(3 * px), Vec::with_capacity(3 * px));
    for k in 0..px {
        rgb.extend_from_slice(&[r[k], g[k], b[k]]);
        for c in 0..3 {
            mean.push(m[c][k] as f64);
            var.push(v[c][k] as f64);
        }
    }
    Ok((
        rgb,
        Estimate {
            size: (e.width, e.height),
            mean,
            var,
            n: n as f64,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_combine_into_the_mean_and_the_per_sample_variance() {
        // One pixel, grey (R = G = B, so X, Y and Z are the row sums times it); seeds
        // 0.1, 0.3: mean 0.2, s² = 0.02, per-sample equivalent at S = 4: 0.08.
        let seeds = vec![vec![0.1; 3], vec![0.3; 3]];
        let (rgb, e) = combine_seeds((1, 1), &seeds, 4).unwrap();
        assert!((rgb[0] - 0.2).abs() < 1e-12);
        assert_eq!(e.n, 8.0);
        for (c, row) in SRGB_TO_XYZ.iter().enumerate() {
            let s: f64 = row.iter().sum();
            assert!((e.mean[c] - 0.2 * s).abs() < 1e-12);
            assert!(
                (e.var[c] - 0.08 * s * s).abs() < 1e-12,
                "{} vs {}",
                e.var[c],
                0.08 * s * s
            );
        }
        assert!(combine_seeds((1, 1), &seeds[..1], 4).is_err());
    }
}
