//! Image files shared by the failure output and the report: PNG writing, and wrapping raw
//! RGB as an [`Image`]. What an image shows of a comparison is each reference's
//! ([`crate::checked::Checked::figure`]).

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
