//! Writing images: 8-bit sRGB PNG (or another device mapping) and 32-bit float linear EXR
//! with optional geometry channels. Files are written to a temporary name beside the
//! target and renamed into place, so a failure never leaves a half-written output.

use crate::render::Image;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// How linear intensities map to the 8-bit device range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ToneMap {
    /// Clamp to [0, 1], then the sRGB transfer curve.
    #[default]
    Srgb,
    /// Clamp to [0, 1], linear.
    Clamp,
    /// Rescale the image's min..max to [0, 1], linear.
    #[value(alias = "minmax")]
    MinMax,
}

/// The sRGB transfer curve (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The 8-bit sRGB code of a linear value in [0, 1]: the code k whose encoded value k/255
/// is nearest to the exact sRGB encoding of `x`. It is found by comparing `x` with the
/// 255 linear values at which the nearest code changes (the decoded half-codes, computed
/// once in f64), so it costs a few comparisons instead of a `powf` per channel.
pub fn srgb8(x: f32) -> u8 {
    static STEPS: std::sync::LazyLock<[f32; 255]> = std::sync::LazyLock::new(|| {
        std::array::from_fn(|k| {
            let e = (k as f64 + 0.5) / 255.0;
            let linear = if e <= 0.04045 {
                e / 12.92
            } else {
                ((e + 0.055) / 1.055).powf(2.4)
            };
            linear as f32
        })
    });
    STEPS.partition_point(|&t| t <= x) as u8
}

/// 8-bit RGB pixels of `img` under a device mapping.
pub fn to_rgb8(img: &Image, map: ToneMap) -> Vec<u8> {
    use rayon::prelude::*;
    let (lo, hi) = match map {
        ToneMap::MinMax => img
            .rgb
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            }),
        _ => (0.0, 1.0),
    };
    let span = if hi > lo { hi - lo } else { 1.0 };
    img.rgb
        .par_iter()
        .map(|&v| {
            let x = ((v - lo) / span).clamp(0.0, 1.0);
            if map == ToneMap::Srgb {
                srgb8(x)
            } else {
                (x * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
            }
        })
        .collect()
}

/// Writes a PNG or EXR, by the file's extension.
pub fn write(img: &Image, path: &Path, map: ToneMap) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let tmp = temp_path(path);
    let result = match ext.as_str() {
        "png" => write_png(img, &tmp, map),
        "exr" => write_exr(img, &tmp),
        _ => bail!(
            "{}: unknown output format (use .png or .exr)",
            path.display()
        ),
    };
    match result {
        Ok(()) => std::fs::rename(&tmp, path)
            .with_context(|| format!("cannot move the output into {}", path.display())),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

fn temp_path(path: &Path) -> std::path::PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

fn write_png(img: &Image, path: &Path, map: ToneMap) -> Result<()> {
    let buf = image::RgbImage::from_raw(img.width, img.height, to_rgb8(img, map))
        .context("image size mismatch")?;
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let enc = image::codecs::png::PngEncoder::new(std::io::BufWriter::new(file));
    buf.write_with_encoder(enc)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes a 32-bit float, linear EXR; with AOVs adds Z, N.X/Y/Z, P.X/Y/Z and objectId.
pub fn write_exr(img: &Image, path: &Path) -> Result<()> {
    use exr::prelude::*;
    let (w, h) = (img.width as usize, img.height as usize);
    let chan = |name: &str, data: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(data));
    let plane = |src: &[f32], stride: usize, k: usize| -> Vec<f32> {
        src.iter().skip(k).step_by(stride).copied().collect()
    };
    let mut channels = vec![
        chan("R", plane(&img.rgb, 3, 0)),
        chan("G", plane(&img.rgb, 3, 1)),
        chan("B", plane(&img.rgb, 3, 2)),
    ];
    if let Some(a) = &img.aov {
        channels.push(chan("Z", a.z.clone()));
        for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
            channels.push(chan(&format!("N.{axis}"), plane(&a.n, 3, k)));
            channels.push(chan(&format!("P.{axis}"), plane(&a.p, 3, k)));
        }
        channels.push(chan("objectId", a.object_id.clone()));
    }
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(path)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// A float image read from an EXR: channels by name, each `width × height`, top row first.
#[derive(Clone, Debug)]
pub struct ExrImage {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Channel name and samples (half and uint channels converted to f32).
    pub channels: Vec<(String, Vec<f32>)>,
}

impl ExrImage {
    /// The samples of a channel.
    pub fn channel(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Reads the first layer of an EXR file, every channel as f32.
pub fn read_exr(path: &Path) -> Result<ExrImage> {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let size = img.layer_data.size;
    let channels = img
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| {
            let v: Vec<f32> = c.sample_data.values_as_f32().collect();
            (c.name.to_string(), v)
        })
        .collect();
    Ok(ExrImage {
        width: size.0,
        height: size.1,
        channels,
    })
}
