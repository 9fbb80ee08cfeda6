//! The report: for every scene, our image, the reference and a false-colour difference
//! image, plus `index.html` showing them side by side with the metrics, and a text table.

use crate::mitsuba::harness::MiOutcome;
use crate::povray::compare::{diff_image, SILHOUETTE_BUDGET};
use crate::povray::harness::Outcome;
use anyhow::Result;
use renderer::output::{to_rgb8, ToneMap};
use renderer::render::Image;
use std::fmt::Write;
use std::path::Path;

pub fn save_png(path: &Path, w: u32, h: u32, rgb8: Vec<u8>) -> Result<()> {
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
        moments: None,
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
    use crate::verdict::Verdict::*;
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

/// The text table of the Mitsuba comparisons.
pub fn mitsuba_table(outcomes: &[MiOutcome]) -> String {
    let mut s = format!(
        "{:<24} {:>9} {:>8} {:>8} {:>9} {:>10} {:>9} {:>7}  verdict\n",
        "scene (mitsuba)",
        "rel dist",
        "normal°",
        "silh/bud",
        "px pass",
        "|global z|",
        "rmse",
        "ours s"
    );
    for o in outcomes {
        match (&o.geometry, &o.radiance) {
            (Some(g), Some(r)) => writeln!(
                s,
                "{:<24} {:>9.1e} {:>8.4} {:>8} {:>8.2}% {:>10.2} {:>9.2e} {:>7.2}  {}",
                o.scene,
                g.max_rel_distance,
                g.max_normal_degrees,
                format!("{}/{}", g.silhouette + g.failing, g.budget),
                r.pass_fraction * 100.0,
                r.global_z.iter().fold(0f64, |a, z| a.max(z.abs())),
                r.rmse,
                o.seconds,
                o.verdict
            ),
            _ => writeln!(
                s,
                "{:<24} {:>66} {:>7.2}  {}",
                o.scene, "-", o.seconds, o.verdict
            ),
        }
        .unwrap();
    }
    let pass = outcomes
        .iter()
        .filter(|o| o.verdict == crate::verdict::Verdict::Pass)
        .count();
    writeln!(
        s,
        "{} Mitsuba scenes: {pass} pass, {} not",
        outcomes.len(),
        outcomes.len() - pass
    )
    .unwrap();
    s
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

/// Starts a scene's row: writes our image into the scene's folder and returns the folder
/// and the verdict line of the metrics.
fn begin_row(
    dir: &Path,
    scene: &str,
    ours: &Image,
    verdict: crate::verdict::Verdict,
    reference: &str,
) -> Result<(std::path::PathBuf, String)> {
    let sub = dir.join(scene);
    std::fs::create_dir_all(&sub)?;
    save_png(
        &sub.join("ours.png"),
        ours.width,
        ours.height,
        srgb(ours.width, ours.height, &ours.rgb),
    )?;
    let class = if verdict == crate::verdict::Verdict::Pass {
        "pass"
    } else {
        "fail"
    };
    Ok((
        sub,
        format!("<span class=\"{class}\">{verdict}</span> against {reference}"),
    ))
}

/// One table row: the scene, our image, the reference, the third image (difference or z),
/// and the metrics. Images that were not written show as a dash.
fn row(html: &mut String, dir: &Path, scene: &str, third: &str, metrics: &str) {
    let img = |f: &str| {
        if dir.join(scene).join(f).exists() {
            format!("<img src=\"{scene}/{f}\" alt=\"{f}\">")
        } else {
            "—".into()
        }
    };
    writeln!(
        html,
        "<tr><td>{scene}</td><td>{}</td><td>{}</td><td>{}</td><td>{metrics}</td></tr>",
        img("ours.png"),
        img("reference.png"),
        img(third)
    )
    .unwrap();
}

/// Writes images and `index.html` under `dir`.
pub fn write(dir: &Path, outcomes: &[Outcome], mitsuba: &[MiOutcome]) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut html = String::from(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>Conformance report</title><style>\
body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}td,th{padding:4px 8px;border-bottom:1px solid #ddd;text-align:left}\
img{image-rendering:pixelated;width:192px;border:1px solid #888}.pass{color:#070}.fail{color:#b00;font-weight:bold}</style></head><body>\n",
    );
    writeln!(
        html,
        "<h1>Conformance report</h1><p>Tolerance per channel: 1.05·2<sup>−11</sup>·|ref| + 1e-6 (half-float rounding of the reference). \
Silhouette pixels (orange in the difference image) are excused by geometry: our own image takes the reference's value within 1e-3 pixel of the centre, or across an edge within 1e-2 pixel; budget {:.2} % of pixels. \
Failing pixels are red. See conformance/docs/tolerances.md.</p>",
        SILHOUETTE_BUDGET * 100.0
    )?;
    html.push_str("<table><tr><th>scene</th><th>ours</th><th>reference</th><th>difference</th><th>metrics</th></tr>\n");
    for o in outcomes {
        let (sub, mut metrics) = begin_row(dir, &o.scene, &o.ours, o.verdict, &o.reference)?;
        let (w, h) = (o.ours.width, o.ours.height);
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
        row(&mut html, dir, &o.scene, "diff.png", &metrics);
    }
    html.push_str("</table>\n");
    if !mitsuba.is_empty() {
        html.push_str(
            "<h2>Against Mitsuba 3</h2><p>Radiance: per-pixel two-sample z-test in XYZ with Šidák correction (≥ 99.75 % of pixel-channels must pass) \
and a global test of the mean difference (|z| < 4.5). The z image shows per-pixel z: grey up to 2, orange above, red past the Šidák threshold. \
Geometry: pixel-centre distance and normal against Mitsuba's ray_intersect. See conformance/docs/mitsuba.md.</p>\n\
<table><tr><th>scene</th><th>ours</th><th>Mitsuba</th><th>z</th><th>metrics</th></tr>\n",
        );
        for o in mitsuba {
            let (sub, mut metrics) = begin_row(dir, &o.scene, &o.ours, o.verdict, "mitsuba")?;
            let (w, h) = (o.ours.width, o.ours.height);
            if let (Some(r), Some(g), Some(rgb)) = (&o.radiance, &o.geometry, &o.reference_rgb) {
                save_png(&sub.join("reference.png"), w, h, srgb(w, h, rgb))?;
                let alpha = crate::mitsuba::stats::sidak_alpha((w * h) as usize);
                save_png(&sub.join("z.png"), w, h, z_image(&r.z_max, alpha))?;
                write!(
                    metrics,
                    "<br>pixel-channels passing {:.2} %<br>global z {:.2} {:.2} {:.2}<br>RMSE {:.2e}<br>distance error ≤ {:.1e}<br>normal ≤ {:.4}°<br>edge pixels {} (budget {})<br>ours {:.2} s",
                    r.pass_fraction * 100.0,
                    r.global_z[0],
                    r.global_z[1],
                    r.global_z[2],
                    r.rmse,
                    g.max_rel_distance,
                    g.max_normal_degrees,
                    g.silhouette + g.failing,
                    g.budget,
                    o.seconds
                )?;
            }
            row(&mut html, dir, &o.scene, "z.png", &metrics);
        }
        html.push_str("</table>\n");
    }
    if let Ok(svg) =
        std::fs::read_to_string(crate::catalog::repo_root().join("conformance/docs/tradeoff.svg"))
    {
        html.push_str("<h2>Speed against accuracy</h2>\n");
        html.push_str(&svg);
    }
    html.push_str("</body></html>\n");
    std::fs::write(dir.join("index.html"), html)?;
    Ok(())
}
