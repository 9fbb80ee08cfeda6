//! The report: for every scene, our image, the reference and a false-colour difference
//! image, plus `index.html` showing them side by side with the metrics, and a text table.

use crate::compare::{diff_image, SILHOUETTE_BUDGET};
use crate::harness::Outcome;
use anyhow::Result;
use renderer::output::{to_rgb8, ToneMap};
use renderer::render::Image;
use std::fmt::Write;
use std::path::Path;

fn save_png(path: &Path, w: u32, h: u32, rgb8: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(w, h, rgb8)
        .ok_or_else(|| anyhow::anyhow!("image size mismatch"))?;
    img.save(path)?;
    Ok(())
}

fn srgb(w: u32, h: u32, rgb: &[f32]) -> Vec<u8> {
    let img = Image {
        width: w,
        height: h,
        rgb: rgb.to_vec(),
        aov: None,
        non_finite: 0,
    };
    to_rgb8(&img, ToneMap::Srgb)
}

/// The text table printed by `conformance run`.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut s = format!(
        "{:<28} {:<8} {:>10} {:>10} {:>10} {:>6} {:>9} {:>8}  verdict\n",
        "scene", "ref", "max abs", "mean abs", "rmse", "fail", "silh/bud", "ours s"
    );
    for o in outcomes {
        match &o.cmp {
            Some(c) => writeln!(
                s,
                "{:<28} {:<8} {:>10.2e} {:>10.2e} {:>10.2e} {:>6} {:>9} {:>8.3}  {}",
                o.scene,
                o.reference,
                c.max_abs,
                c.mean_abs,
                c.rmse,
                c.failing,
                format!("{}/{}", c.silhouette, c.budget()),
                o.seconds,
                o.verdict
            ),
            None => writeln!(
                s,
                "{:<28} {:<8} {:>57} {:>8.3}  {}",
                o.scene, o.reference, "-", o.seconds, o.verdict
            ),
        }
        .unwrap();
    }
    let count = |v| outcomes.iter().filter(|o| o.verdict == v).count();
    use crate::harness::Verdict::*;
    writeln!(
        s,
        "{} scenes: {} pass, {} fail, {} stale, {} missing",
        outcomes.len(),
        count(Pass),
        count(Fail),
        count(Stale),
        count(Missing)
    )
    .unwrap();
    s
}

/// Writes images and `index.html` under `dir`.
pub fn write(dir: &Path, outcomes: &[Outcome]) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut html = String::from(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>Conformance report</title><style>\
body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}td,th{padding:4px 8px;border-bottom:1px solid #ddd;text-align:left}\
img{image-rendering:pixelated;width:192px;border:1px solid #888}.pass{color:#070}.fail{color:#b00;font-weight:bold}</style></head><body>\n",
    );
    writeln!(
        html,
        "<h1>Conformance report</h1><p>Tolerance per channel: 1.05·2<sup>−11</sup>·|ref| + 1e-6 (half-float rounding of the reference). \
Silhouette pixels (orange in the difference image) lie within the range of the reference's 3×3 neighbourhood; budget {:.2} % of pixels. \
Failing pixels are red. See conformance/docs/tolerances.md.</p>",
        SILHOUETTE_BUDGET * 100.0
    )?;
    html.push_str("<table><tr><th>scene</th><th>ours</th><th>reference</th><th>difference</th><th>metrics</th></tr>\n");
    for o in outcomes {
        let sub = dir.join(&o.scene);
        std::fs::create_dir_all(&sub)?;
        let (w, h) = (o.ours.width, o.ours.height);
        save_png(&sub.join("ours.png"), w, h, srgb(w, h, &o.ours.rgb))?;
        let class = if o.verdict == crate::harness::Verdict::Pass {
            "pass"
        } else {
            "fail"
        };
        let mut metrics = format!(
            "<span class=\"{class}\">{}</span> against {}",
            o.verdict, o.reference
        );
        if let (Some(r), Some(c)) = (&o.reference_rgb, &o.cmp) {
            save_png(&sub.join("reference.png"), w, h, srgb(w, h, r))?;
            save_png(&sub.join("diff.png"), w, h, diff_image(c, &o.ours.rgb, r))?;
            write!(
                metrics,
                "<br>max abs {:.2e}<br>mean abs {:.2e}<br>RMSE {:.2e}<br>failing {}<br>silhouette {} (budget {})<br>{w}×{h}, ours {:.3} s",
                c.max_abs,
                c.mean_abs,
                c.rmse,
                c.failing,
                c.silhouette,
                c.budget(),
                o.seconds
            )?;
        }
        let img = |f: &str| {
            if sub.join(f).exists() {
                format!("<img src=\"{}/{f}\" alt=\"{f}\">", o.scene)
            } else {
                "—".into()
            }
        };
        writeln!(
            html,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{metrics}</td></tr>",
            o.scene,
            img("ours.png"),
            img("reference.png"),
            img("diff.png")
        )?;
    }
    html.push_str("</table></body></html>\n");
    std::fs::write(dir.join("index.html"), html)?;
    Ok(())
}
