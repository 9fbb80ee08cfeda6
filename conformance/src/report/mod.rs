//! The report: a text table for the terminal, and `<target>/conformance/index.html` to work
//! in. The page opens on a summary (counts per verdict and catalog), lists the scenes that
//! need attention first (with a switch to show only them), gives each scene a stable
//! anchor (`index.html#prim_cone_shear`), shows our image and the reference in one place
//! (hover or click swaps them), a difference image whose colour encodes the size of the
//! error (with a legend), and plots drawn at report time from the data on disk
//! (`results.json`, written by the same run; instruction counts and the speed/accuracy
//! trade when their scripts have left data in the target directory), each labelled with
//! when and how it was measured.

mod chart;
mod html;
mod plots;
mod results;
mod table;

use crate::gate::{by_scene, Judged};
use crate::registry::Registry;
use crate::verdict::Verdict;
use anyhow::{Context, Result};
use renderer::output::{to_rgb8, ToneMap};
use std::fmt::Write;
use std::path::Path;

pub use crate::images::save_png;
use html::html_escape;
pub use results::{Results, Row};
use table::VERDICTS;
pub use table::{shown_verdict, table};

fn srgb(w: u32, h: u32, rgb: &[f32]) -> Vec<u8> {
    to_rgb8(&crate::images::image_of(w, h, rgb), ToneMap::Srgb)
}

/// Sort key: scenes that need attention first, then waived, then passing; by catalog and
/// name.
fn order(j: &Judged, registry: &Registry) -> (u8, usize, String) {
    let rank = match (j.accepted(), j.verdict) {
        (false, _) => 0,
        (true, Verdict::Waived) => 1,
        _ => 2,
    };
    let reference = registry.position(j.checked.reference());
    (rank, reference, j.checked.scene().to_string())
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

/// Writes the images, `results.json`, and `index.html` under `dir`, with a part for each
/// reference of `registry`.
pub fn write(dir: &Path, judged: &[Judged], registry: &Registry) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let data = results::results(judged, registry);
    let json_path = dir.join("results.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&data)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    let mut sorted: Vec<&Judged> = judged.iter().collect();
    sorted.sort_by_key(|j| order(j, registry));

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
    for reference in registry.names() {
        let of: Vec<&Judged> = judged
            .iter()
            .filter(|j| j.checked.reference() == reference)
            .collect();
        write!(html, "<tr><td>{reference}</td>")?;
        for v in VERDICTS {
            let n = of.iter().filter(|j| j.verdict == v).count();
            write!(html, "<td class=\"{}\">{n}</td>", count_class(v, n))?;
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
    // The scenes more than one reference checks: each one's verdict, and where they
    // disagree.
    several(&mut html, judged, registry)?;
    // Legend.
    html.push_str(
        "<h2>How to read it</h2><p>Hover over (or click) our image to see the reference in its place. \
Workflows (regenerate, review, waive): conformance/docs/workflows.md.</p>\n",
    );
    for r in registry.iter() {
        writeln!(html, "<p>{}</p>", r.legend())?;
    }
    // Scenes.
    html.push_str("<h2>Scenes</h2>\n<table><tr><th>scene</th><th>ours (hover: reference)</th><th>difference / z</th><th>verdict and metrics</th></tr>\n");
    for j in &sorted {
        scene_row(&mut html, dir, j)?;
    }
    html.push_str("</table>\n");
    plots::plots(&mut html, dir, &data, registry)?;
    html.push_str(SCRIPT);
    html.push_str("</body></html>\n");
    let index = dir.join("index.html");
    std::fs::write(&index, html).with_context(|| format!("writing {}", index.display()))?;
    Ok(())
}

/// The colour of a summary count: green for scenes that pass, amber for waived ones, red
/// for any other verdict; none for a count of 0 (no scene of a catalog run is no pass).
fn count_class(v: Verdict, n: usize) -> &'static str {
    match v {
        _ if n == 0 => "",
        Verdict::Pass => "pass",
        Verdict::Waived => "waived",
        _ => "fail",
    }
}

/// A scene's metrics for its table cell: one line per measurement ([`table::metric_parts`]).
fn metrics_html(metrics: &str) -> String {
    table::metric_parts(metrics)
        .iter()
        .map(|p| html_escape(p))
        .collect::<Vec<_>>()
        .join("<br>")
}

/// The section of the scenes that more than one reference checks: a column per
/// reference, and the pairs that disagree (one passes where another fails).
fn several(html: &mut String, judged: &[Judged], registry: &Registry) -> Result<()> {
    let scenes: Vec<_> = by_scene(judged)
        .into_iter()
        .filter(|s| s.verdicts.len() > 1)
        .collect();
    html.push_str("<h2 id=\"by-scene\">Verdicts by scene</h2>\n");
    if scenes.is_empty() {
        html.push_str("<p>No scene of this run is checked by more than one reference.</p>\n");
        return Ok(());
    }
    let names = registry.names();
    html.push_str("<table><tr><th>scene</th>");
    for n in &names {
        write!(html, "<th>{n}</th>")?;
    }
    html.push_str("<th>agreement</th></tr>\n");
    for s in &scenes {
        write!(html, "<tr><td>{}/{}</td>", s.catalog, s.scene)?;
        for n in &names {
            match s.verdicts.iter().find(|(r, _)| r == n) {
                Some((_, v)) => write!(html, "<td class=\"{}\">{v}</td>", count_class(*v, 1))?,
                None => html.push_str("<td>—</td>"),
            }
        }
        let d = s.disagreements();
        if d.is_empty() {
            html.push_str("<td>agree</td></tr>\n");
        } else {
            let pairs: Vec<String> = d
                .iter()
                .map(|(a, b)| format!("{a} and {b} disagree"))
                .collect();
            writeln!(
                html,
                "<td class=\"fail\">{}</td></tr>",
                html_escape(&pairs.join("; "))
            )?;
        }
    }
    html.push_str("</table>\n");
    Ok(())
}

fn scene_row(html: &mut String, dir: &Path, j: &Judged) -> Result<()> {
    let (scene, reference) = (j.checked.scene(), j.checked.reference());
    let key = j.key();
    let sub = dir.join(&key);
    std::fs::create_dir_all(&sub)?;
    let ours = j.checked.ours();
    let (w, h) = (ours.width, ours.height);
    save_png(&sub.join("ours.png"), w, h, srgb(w, h, &ours.rgb))?;
    let mut third = None;
    if let Some(r) = j.checked.reference_rgb() {
        save_png(&sub.join("reference.png"), w, h, srgb(w, h, r))?;
        if let Some(f) = j.checked.figure() {
            let file = format!("{}.png", f.name);
            save_png(&sub.join(&file), w, h, f.png)?;
            third = Some(file);
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
            "<div class=\"swap\" title=\"hover or click: the reference\"><img src=\"{key}/ours.png\" alt=\"ours\"><img class=\"ref\" src=\"{key}/reference.png\" alt=\"reference\"></div>"
        )
    } else {
        format!("<img src=\"{key}/ours.png\" alt=\"ours\">")
    };
    let third = third.map_or("—".to_string(), |f| {
        format!("<img src=\"{key}/{f}\" alt=\"{f}\">")
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
        "<tr id=\"{key}\" class=\"{row_class}\"><td><a href=\"#{key}\">{scene}</a><br>{reference}<br>{w}×{h}, rendered in {:.3} s</td><td>{images}</td><td>{third}</td><td><span class=\"{class}\">{}</span> against {reference}{fix}{notes}<br>{}</td></tr>",
        j.checked.seconds(),
        html_escape(&shown_verdict(j)),
        metrics_html(&j.checked.metrics())
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test01_a_count_of_zero_is_not_green() {
        assert_eq!(
            count_class(Verdict::Pass, 0),
            "",
            "0 scenes shown as a pass"
        );
        assert_eq!(count_class(Verdict::Pass, 3), "pass");
        assert_eq!(count_class(Verdict::Fail, 0), "");
        assert_eq!(count_class(Verdict::Fail, 1), "fail");
        assert_eq!(count_class(Verdict::Waived, 2), "waived");
    }

    #[test]
    fn test02_a_semicolon_inside_parentheses_is_no_line_break() {
        assert_eq!(
            metrics_html("1 failing, 2 excused (2 outline; budget 40); geometry: <ok>"),
            "1 failing, 2 excused (2 outline; budget 40)<br>geometry: &lt;ok&gt;"
        );
    }
}
