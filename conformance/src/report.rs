//! The report: a text table for the terminal, and `<target>/conformance/index.html` to work
//! in. The page opens on a summary (counts per verdict and catalog), lists the scenes that
//! need attention first (with a switch to show only them), gives each scene a stable
//! anchor (`index.html#prim_cone_shear`), shows our image and the reference in one place
//! (hover or click swaps them), a difference image whose colour encodes the size of the
//! error (with a legend), and plots drawn at report time from the data on disk
//! (`results.json`, written by the same run; instruction counts and the speed/accuracy
//! trade when their scripts have left data in the target directory), each labelled with
//! when and how it was measured.

use crate::gate::{error_in_tolerances, Checked, Judged, REFERENCES};
use crate::povray::compare::{diff_image, SILHOUETTE_BUDGET};
use crate::verdict::Verdict;
use anyhow::{Context, Result};
use renderer::output::{to_rgb8, ToneMap};
use std::fmt::Write;
use std::path::Path;

pub use crate::images::{save_png, z_image};

fn srgb(w: u32, h: u32, rgb: &[f32]) -> Vec<u8> {
    to_rgb8(&crate::images::image_of(w, h, rgb), ToneMap::Srgb)
}

/// The verdict shown for a judged scene ("pass", "FAIL", …; a stale waiver is named).
pub fn shown_verdict(j: &Judged) -> String {
    if j.stale_waivers.is_empty() {
        j.verdict.to_string()
    } else {
        format!("{} (STALE WAIVER)", j.verdict)
    }
}

/// The text table printed by `conformance run`.
pub fn table(judged: &[Judged]) -> String {
    let mut s = format!(
        "{:<28} {:<8} {:>8}  {:<22} metrics\n",
        "scene", "ref", "ours s", "verdict"
    );
    for j in judged {
        writeln!(
            s,
            "{:<28} {:<8} {:>8.3}  {:<22} {}",
            j.checked.scene(),
            j.checked.reference(),
            j.checked.seconds(),
            shown_verdict(j),
            j.checked.metrics()
        )
        .unwrap();
    }
    s.push_str(&summary_line(judged));
    s
}

const VERDICTS: [Verdict; 5] = [
    Verdict::Pass,
    Verdict::Fail,
    Verdict::Stale,
    Verdict::Missing,
    Verdict::Waived,
];

fn summary_line(judged: &[Judged]) -> String {
    let counts: Vec<String> = VERDICTS
        .iter()
        .map(|v| {
            let n = judged.iter().filter(|j| j.verdict == *v).count();
            format!("{n} {v}")
        })
        .collect();
    let stale_waivers: usize = judged.iter().map(|j| j.stale_waivers.len()).sum();
    format!(
        "{} scenes: {}, {stale_waivers} stale waiver(s)\n",
        judged.len(),
        counts.join(", ")
    )
}

/// Sort key: scenes that need attention first, then waived, then passing; by catalog and
/// name.
fn order(j: &Judged) -> (u8, u8, String) {
    let rank = match (j.accepted(), j.verdict) {
        (false, _) => 0,
        (true, Verdict::Waived) => 1,
        _ => 2,
    };
    let catalog = REFERENCES
        .iter()
        .position(|r| *r == j.checked.reference())
        .unwrap_or(REFERENCES.len()) as u8;
    (rank, catalog, j.checked.scene().to_string())
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// One scene's measurements, as `results.json` holds them.
#[derive(serde::Serialize, serde::Deserialize, Clone, Debug)]
pub struct Row {
    /// The reference (povray, mitsuba).
    pub reference: String,
    /// The scene.
    pub scene: String,
    /// The verdict as shown.
    pub verdict: String,
    /// Seconds our render took.
    pub seconds: f64,
    /// Largest pixel error in units of the tolerance (POV-Ray), or largest per-pixel z
    /// (Mitsuba).
    pub worst: f64,
}

/// The data of one run, written beside the report and plotted from disk.
#[derive(serde::Serialize, serde::Deserialize, Clone, Debug)]
pub struct Results {
    /// When the run ended (UTC, RFC 3339).
    pub measured: String,
    /// How: command, precision, threads.
    pub how: String,
    /// One row per scene.
    pub rows: Vec<Row>,
}

/// A time as `YYYY-MM-DD HH:MM:SS UTC` (the proleptic Gregorian calendar from days since
/// 1970-01-01).
fn utc(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86400), secs.rem_euclid(86400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

fn now_utc() -> String {
    utc(std::time::SystemTime::now())
}

fn results(judged: &[Judged]) -> Results {
    let rows = judged
        .iter()
        .map(|j| {
            let worst = match &j.checked {
                Checked::Povray(o) => o.reference_rgb.as_ref().map_or(0.0, |r| {
                    (0..r.len() / 3)
                        .map(|k| error_in_tolerances(&o.ours.rgb, r, k))
                        .fold(0.0, f64::max)
                }),
                Checked::Mitsuba(o) => o
                    .radiance
                    .as_ref()
                    .map_or(0.0, |r| r.z_max.iter().copied().fold(0.0, f64::max)),
            };
            Row {
                reference: j.checked.reference().into(),
                scene: j.checked.scene().into(),
                verdict: shown_verdict(j),
                seconds: j.checked.seconds(),
                worst,
            }
        })
        .collect();
    Results {
        measured: now_utc(),
        how: format!(
            "`conformance run`, {} build, {} threads, pixel centres (POV-Ray) / {} spp (Mitsuba)",
            if cfg!(feature = "f64") { "f64" } else { "f32" },
            std::thread::available_parallelism().map_or(1, |n| n.get()),
            crate::mitsuba::harness::GATE_SPP
        ),
        rows,
    }
}

/// A horizontal bar chart (SVG) of one value per scene, on a log axis.
fn bar_chart(
    title: &str,
    label: &str,
    rows: &[(String, f64)],
    mark: Option<(f64, &str)>,
) -> String {
    let (lw, pw, bh) = (230.0, 420.0, 9.0);
    let height = rows.len() as f64 * bh + 50.0;
    let max = rows
        .iter()
        .map(|r| r.1)
        .chain(mark.map(|m| m.0))
        .fold(1e-9, f64::max);
    let min = rows
        .iter()
        .map(|r| r.1)
        .filter(|v| *v > 0.0)
        .fold(max, f64::min)
        .min(max / 10.0);
    let (lo, hi) = (
        min.log10().floor(),
        max.log10().ceil().max(min.log10().floor() + 1.0),
    );
    let x = |v: f64| lw + pw * ((v.max(10f64.powf(lo)).log10() - lo) / (hi - lo));
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{height}\" font-family=\"sans-serif\" font-size=\"8\" role=\"img\" aria-label=\"{title}\">\n<text x=\"0\" y=\"12\" font-size=\"12\">{title}</text>\n",
        lw + pw + 20.0
    );
    for d in lo as i32..=hi as i32 {
        let xv = x(10f64.powi(d));
        writeln!(
            s,
            "<line x1=\"{xv}\" x2=\"{xv}\" y1=\"20\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{xv}\" y=\"{}\" text-anchor=\"middle\">1e{d}</text>",
            height - 22.0,
            height - 12.0
        )
        .unwrap();
    }
    for (i, (name, v)) in rows.iter().enumerate() {
        let y = 22.0 + i as f64 * bh;
        writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text><rect x=\"{lw}\" y=\"{y}\" width=\"{:.1}\" height=\"{}\" fill=\"#4a7ab0\"><title>{} {v:.3e}</title></rect>",
            lw - 4.0,
            y + bh - 2.0,
            html_escape(name),
            (x(*v) - lw).max(0.5),
            bh - 2.0,
            html_escape(name)
        )
        .unwrap();
    }
    if let Some((m, what)) = mark {
        let xm = x(m);
        writeln!(
            s,
            "<line x1=\"{xm}\" x2=\"{xm}\" y1=\"20\" y2=\"{}\" stroke=\"#b00\"/><text x=\"{xm}\" y=\"{}\" fill=\"#b00\">{what}</text>",
            height - 22.0,
            height - 2.0
        )
        .unwrap();
    }
    writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{label}</text></svg>",
        lw + pw / 2.0,
        height - 2.0
    )
    .unwrap();
    s
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em;max-width:1400px}\
table{border-collapse:collapse}td,th{padding:4px 8px;border-bottom:1px solid #ddd;text-align:left;vertical-align:top}\
img{image-rendering:pixelated;width:192px;border:1px solid #888;display:block}\
.pass{color:#070}.fail{color:#b00;font-weight:bold}.waived{color:#a60;font-weight:bold}\
.swap{position:relative;cursor:pointer}.swap .ref{position:absolute;top:0;left:0;visibility:hidden}\
.swap:hover .ref,.swap.flip .ref{visibility:visible}\
body.only-attention tr.ok{display:none}\
.legend{display:inline-block;width:300px;height:12px;vertical-align:middle;\
background:linear-gradient(to right,rgb(255,255,0),rgb(255,90,0),rgb(200,0,200))}\
.sw{display:inline-block;width:12px;height:12px;vertical-align:middle;border:1px solid #888}\
#broken{color:#b00;font-weight:bold}";

const SCRIPT: &str = "<script>\
document.querySelectorAll('.swap').forEach(function(e){e.addEventListener('click',function(){e.classList.toggle('flip')})});\
document.getElementById('attention').addEventListener('change',function(ev){document.body.classList.toggle('only-attention',ev.target.checked)});\
window.addEventListener('load',function(){\
var imgs=document.images,bad=[];\
for(var i=0;i<imgs.length;i++){if(!imgs[i].complete||imgs[i].naturalWidth===0){bad.push(imgs[i].getAttribute('src'))}}\
document.body.dataset.images=imgs.length;document.body.dataset.brokenImages=bad.length;\
if(bad.length){document.getElementById('broken').textContent=bad.length+' image(s) failed to load: '+bad.join(', ')}});\
</script>";

/// Writes the images, `results.json`, and `index.html` under `dir`.
pub fn write(dir: &Path, judged: &[Judged]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let data = results(judged);
    let json_path = dir.join("results.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&data)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    let mut sorted: Vec<&Judged> = judged.iter().collect();
    sorted.sort_by_key(|j| order(j));

    let mut html = format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>Conformance report</title><style>{STYLE}</style></head><body>\n<h1>Conformance report</h1>\n<p>Measured {} by {}.</p><p id=\"broken\"></p>\n",
        data.measured, data.how
    );
    // Summary.
    html.push_str("<h2 id=\"summary\">Summary</h2>\n<table><tr><th>catalog</th>");
    for v in VERDICTS {
        write!(html, "<th>{v}</th>")?;
    }
    html.push_str("<th>stale waivers</th><th>scenes</th></tr>\n");
    for reference in REFERENCES {
        let of: Vec<&Judged> = judged
            .iter()
            .filter(|j| j.checked.reference() == reference)
            .collect();
        write!(html, "<tr><td>{reference}</td>")?;
        for v in VERDICTS {
            let n = of.iter().filter(|j| j.verdict == v).count();
            let class = match v {
                Verdict::Pass => "pass",
                Verdict::Waived if n > 0 => "waived",
                Verdict::Waived => "",
                _ if n > 0 => "fail",
                _ => "",
            };
            write!(html, "<td class=\"{class}\">{n}</td>")?;
        }
        let stale: usize = of.iter().map(|j| j.stale_waivers.len()).sum();
        writeln!(html, "<td>{stale}</td><td>{}</td></tr>", of.len())?;
    }
    html.push_str("</table>\n");
    let attention = judged.iter().filter(|j| !j.accepted()).count();
    writeln!(
        html,
        "<p><label><input type=\"checkbox\" id=\"attention\"> show only the {attention} scene(s) that need attention (failing, stale, missing, or with a stale waiver)</label></p>"
    )?;
    // Legend.
    writeln!(
        html,
        "<h2>How to read it</h2><p>Hover over (or click) our image to see the reference in its place. \
POV-Ray scenes: the difference image shows agreeing pixels as dimmed grey, pixels excused by geometry \
<span class=\"sw\" style=\"background:rgb(0,160,255)\"></span> blue, and failing pixels by the size of the error \
relative to the per-pixel tolerance (1.05·2<sup>−11</sup>·|ref| + 1e-6): 1× <span class=\"legend\"></span> ≥ 1000× (log scale). \
A pixel is excused only when our own renderer, traced again within 1e-3 pixel of the centre (or 1e-2 across a discontinuity), takes \
the reference's value; at most {:.2} % of pixels may be excused. Mitsuba scenes: the z image shows per-pixel z of the two-sample \
test, grey up to 2, <span class=\"sw\" style=\"background:rgb(255,160,0)\"></span> orange above, \
<span class=\"sw\" style=\"background:rgb(230,0,0)\"></span> red past the Šidák threshold. \
See conformance/docs/tolerances.md, mitsuba.md and workflows.md.</p>",
        SILHOUETTE_BUDGET * 100.0
    )?;
    // Scenes.
    html.push_str("<h2>Scenes</h2>\n<table><tr><th>scene</th><th>ours (hover: reference)</th><th>difference / z</th><th>verdict and metrics</th></tr>\n");
    for j in &sorted {
        scene_row(&mut html, dir, j)?;
    }
    html.push_str("</table>\n");
    plots(&mut html, dir, &data)?;
    html.push_str(SCRIPT);
    html.push_str("</body></html>\n");
    let index = dir.join("index.html");
    std::fs::write(&index, html).with_context(|| format!("writing {}", index.display()))?;
    Ok(())
}

fn scene_row(html: &mut String, dir: &Path, j: &Judged) -> Result<()> {
    let (scene, reference) = (j.checked.scene(), j.checked.reference());
    let sub = dir.join(scene);
    std::fs::create_dir_all(&sub)?;
    let ours = j.checked.ours();
    let (w, h) = (ours.width, ours.height);
    save_png(&sub.join("ours.png"), w, h, srgb(w, h, &ours.rgb))?;
    let mut third = None;
    if let Some(r) = j.checked.reference_rgb() {
        save_png(&sub.join("reference.png"), w, h, srgb(w, h, r))?;
        match &j.checked {
            Checked::Povray(o) => {
                if let Some(c) = &o.cmp {
                    save_png(&sub.join("diff.png"), w, h, diff_image(c, &ours.rgb, r))?;
                    third = Some("diff.png");
                }
            }
            Checked::Mitsuba(o) => {
                if let Some(rad) = &o.radiance {
                    let alpha = crate::mitsuba::stats::sidak_alpha((w * h) as usize);
                    save_png(&sub.join("z.png"), w, h, z_image(&rad.z_max, alpha))?;
                    third = Some("z.png");
                }
            }
        }
    }
    let class = match (j.accepted(), j.verdict) {
        (false, _) => "fail",
        (true, Verdict::Waived) => "waived",
        _ => "pass",
    };
    let row_class = if j.accepted() { "ok" } else { "attention" };
    let images = if j.checked.reference_rgb().is_some() {
        format!(
            "<div class=\"swap\" title=\"hover or click: the reference\"><img src=\"{scene}/ours.png\" alt=\"ours\"><img class=\"ref\" src=\"{scene}/reference.png\" alt=\"reference\"></div>"
        )
    } else {
        format!("<img src=\"{scene}/ours.png\" alt=\"ours\">")
    };
    let third = third.map_or("—".to_string(), |f| {
        format!("<img src=\"{scene}/{f}\" alt=\"{f}\">")
    });
    let mut notes = String::new();
    for wv in &j.waived {
        write!(notes, "<br>WAIVED: {}", html_escape(&wv.to_string()))?;
    }
    for wv in &j.stale_waivers {
        write!(
            notes,
            "<br><span class=\"fail\">STALE WAIVER</span> (conformance/waivers.toml:{}): the {} check passes again; remove it",
            wv.line, wv.check
        )?;
    }
    let fix = match j.verdict {
        Verdict::Missing | Verdict::Stale => format!(
            "<br>fix: <code>{}</code>",
            crate::gate::regen_command(reference, scene)
        ),
        _ => String::new(),
    };
    writeln!(
        html,
        "<tr id=\"{scene}\" class=\"{row_class}\"><td><a href=\"#{scene}\">{scene}</a><br>{reference}<br>{w}×{h}, ours {:.3} s</td><td>{images}</td><td>{third}</td><td><span class=\"{class}\">{}</span> against {reference}{fix}{notes}<br>{}</td></tr>",
        j.checked.seconds(),
        html_escape(&shown_verdict(j)),
        html_escape(&j.checked.metrics()).replace("; ", "<br>")
    )?;
    Ok(())
}

/// Plots from data on disk: this run's `results.json`, and (when present) the
/// instruction counts and the speed/accuracy trade their scripts leave in `dir`.
fn plots(html: &mut String, dir: &Path, fallback: &Results) -> Result<()> {
    html.push_str("<h2 id=\"plots\">Plots</h2>\n");
    let data: Results = std::fs::read_to_string(dir.join("results.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_else(|| fallback.clone());
    let caption = format!(
        "From results.json: measured {} by {}.",
        data.measured, data.how
    );
    for reference in REFERENCES {
        let rows: Vec<&Row> = data
            .rows
            .iter()
            .filter(|r| r.reference == reference)
            .collect();
        if rows.is_empty() {
            continue;
        }
        let (title, label, mark) = if reference == "povray" {
            (
                "Largest pixel error per scene, in tolerances (POV-Ray)",
                "largest |ours − reference| / tolerance (log)",
                Some((1.0, "tolerance")),
            )
        } else {
            (
                "Largest per-pixel z per scene (Mitsuba)",
                "largest z over pixels and channels (log)",
                None,
            )
        };
        let worst: Vec<(String, f64)> = rows.iter().map(|r| (r.scene.clone(), r.worst)).collect();
        let time: Vec<(String, f64)> = rows.iter().map(|r| (r.scene.clone(), r.seconds)).collect();
        writeln!(
            html,
            "<figure>{}<figcaption>{caption}</figcaption></figure>",
            bar_chart(title, label, &worst, mark)
        )?;
        writeln!(
            html,
            "<figure>{}<figcaption>{caption} Wall-clock time moves by up to 2× with the machine's other tenants.</figcaption></figure>",
            bar_chart(
                &format!("Our render time per scene ({reference})"),
                "seconds (log)",
                &time,
                None
            )
        )?;
    }
    for (file, what) in [
        (
            "bench.md",
            "Instruction counts against the committed baseline (scripts/bench-counts.sh)",
        ),
        (
            "tradeoff.svg",
            "Speed against accuracy (scripts/tradeoff.sh)",
        ),
    ] {
        let path = dir.join(file);
        if let Ok(text) = std::fs::read_to_string(&path) {
            let when = std::fs::metadata(&path)
                .and_then(|m| m.modified())
                .ok()
                .map(|t| format!("written {}", utc(t)))
                .unwrap_or_default();
            let body = if file.ends_with(".svg") {
                text
            } else {
                format!("<pre>{}</pre>", html_escape(&text))
            };
            writeln!(
                html,
                "<figure><h3>{what}</h3>{body}<figcaption>From {} ({when}).</figcaption></figure>",
                path.display()
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, UNIX_EPOCH};

    #[test]
    fn test01_utc_dates() {
        let at = |s: u64| utc(UNIX_EPOCH + Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(at(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(at(1_795_510_861), "2026-11-24 09:01:01 UTC");
    }
}
