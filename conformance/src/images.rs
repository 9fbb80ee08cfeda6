//! Image files shared by the failure output and the report: PNG writing, false-colour z
//! images, and wrapping raw RGB as an [`Image`].

use anyhow::{Context, Result};
use renderer::render::Image;
use std::path::Path;

/// Writes 8-bit RGB pixels as a PNG.
pub fn save_png(path: &Path, w: u32, h: u32, rgb8: Vec<u8>) -> Result<()> {
    let write = || -> Result<()> {
        let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
        renderer::output::encode_png_rgb8(&mut f, w, h, &rgb8)?;
        std::io::Write::flush(&mut f)?;
        Ok(())
    };
    write().with_context(|| format!("writing {}", path.display()))
}

/// An image holding `rgb` (no AOVs).
pub fn image_of(w: u32, h: u32, rgb: &[f32]) -> Image {
    Image {
        width: w,
        height: h,
        rgb: rgb.to_vec(),
        aov: None,
        non_finite: 0,
        moments: None,
        samples: 0,
    }
}

/// A false-colour image of per-pixel z: black to white up to z = 2, orange up to the
/// Šidák threshold, red beyond it.
pub fn z_image(z: &[f64], alpha: f64) -> Vec<u8> {
    let mut out = Vec::with_capacity(z.len() * 3);
    for &v in z {
        if crate::mitsuba::stats::p_value(v) <= alpha {
            out.extend_from_slice(&[230, 0, 0]);
        } else if v > 2.0 {
            out.extend_from_slice(&[255, 160, 0]);
        } else {
            let g = (v / 2.0 * 200.0) as u8;
            out.extend_from_slice(&[g, g, g]);
        }
    }
    out
}
