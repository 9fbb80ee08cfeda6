//! The speed/accuracy trade: for three Mitsuba catalog scenes, the RMSE against the 8192-spp
//! Mitsuba reference versus render time, for this renderer at 1, 4, 16, 64 and 256 spp with
//! each sampler, and for Mitsuba at the same spp. Both use every core. Writes the table and
//! the plot to `<target>/conformance/tradeoff.md` and `tradeoff.svg` (the HTML report
//! embeds the plot); with `--write-docs`, also into conformance/docs/tradeoff.md (between
//! markers) and conformance/docs/tradeoff.svg. Run by scripts/tradeoff.sh.

use anyhow::{Context, Result};
use conformance::catalog::load;
use conformance::catalog::{repo_root, scenes};
use conformance::manifest::Manifest;
use conformance::mitsuba::harness::read_radiance;
use renderer::render::{render, Options};
use renderer::sampler::SamplerKind;
use std::fmt::Write;
use std::process::Command;

const SCENES: [&str; 3] = ["mi_diffuse_point", "mi_area_soft_shadow", "mi_cornell"];
const SPP: [u32; 5] = [1, 4, 16, 64, 256];

struct Point {
    scene: &'static str,
    series: String,
    spp: u32,
    seconds: f64,
    rmse: f64,
}

fn rmse(a: &[f32], b: &[f32]) -> f64 {
    (a.iter()
        .zip(b)
        .map(|(x, y)| ((x - y) as f64).powi(2))
        .sum::<f64>()
        / a.len() as f64)
        .sqrt()
}

fn main() -> Result<()> {
    let root = repo_root();
    let manifest = Manifest::committed()?;
    let mut points = Vec::new();
    let work = std::env::temp_dir().join(format!("tradeoff-{}", std::process::id()));
    std::fs::create_dir_all(&work)?;
    for name in SCENES {
        let e = scenes("mitsuba", name)?
            .into_iter()
            .find(|e| e.name == name)
            .context("scene")?;
        let (scene, _) = load(&e)?;
        let rec = &manifest.reference[&format!("mitsuba/{name}")];
        let (reference, _) = read_radiance(
            &root.join("references").join(&rec.file),
            rec.spp.context("spp")?,
        )?;
        for (label, kind) in [
            ("ours, independent", SamplerKind::Independent),
            ("ours, stratified", SamplerKind::Stratified),
            ("ours, sobol", SamplerKind::Sobol),
        ] {
            let mut s = load(&e)?.0;
            s.settings.sampler = kind;
            for spp in SPP {
                // Best of three runs: the machine is shared and noisy.
                let mut best = f64::INFINITY;
                let mut img = None;
                for _ in 0..3 {
                    let t0 = std::time::Instant::now();
                    let i = render(
                        &s,
                        &Options {
                            samples: Some(spp),
                            ..Options::default()
                        },
                    );
                    best = best.min(t0.elapsed().as_secs_f64());
                    img = Some(i);
                }
                let img = img.unwrap();
                points.push(Point {
                    scene: name,
                    series: label.into(),
                    spp,
                    seconds: best,
                    rmse: rmse(&img.rgb, &reference),
                });
            }
        }
        let script = root.join("scripts/mitsuba_refs.py");
        for spp in SPP {
            let export = conformance::mitsuba::export(&scene, spp, false)?;
            let xml = work.join(format!("{name}.xml"));
            export.write(&xml)?;
            let mut best = f64::INFINITY;
            for _ in 0..3 {
                let out = Command::new("python3")
                    .arg(&script)
                    .args(["time", xml.to_str().unwrap(), "out.exr", &spp.to_string()])
                    .current_dir(&work)
                    .output()?;
                anyhow::ensure!(
                    out.status.success(),
                    "mitsuba: {}",
                    String::from_utf8_lossy(&out.stderr)
                );
                best = best.min(String::from_utf8_lossy(&out.stdout).trim().parse::<f64>()?);
            }
            let e = renderer::output::read_exr(&work.join("out.exr"))?;
            let (r, g, b) = (
                e.channel("R").unwrap(),
                e.channel("G").unwrap(),
                e.channel("B").unwrap(),
            );
            let rgb: Vec<f32> = (0..r.len()).flat_map(|k| [r[k], g[k], b[k]]).collect();
            points.push(Point {
                scene: name,
                series: "Mitsuba 3 (independent)".into(),
                spp,
                seconds: best,
                rmse: rmse(&rgb, &reference),
            });
        }
        eprintln!("{name}: done");
    }
    std::fs::remove_dir_all(&work).ok();

    // The table.
    let mut md = format!(
        "Measured {} by `scripts/tradeoff.sh` on {} cores, both renderers on every core, best of 3 runs. RMSE is over RGB against the 8192-spp Mitsuba reference; times are render only (no scene loading).\n\n",
        conformance::manifest::today(),
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    );
    for name in SCENES {
        writeln!(
            md,
            "### `{name}`\n\n| series | spp | time (ms) | RMSE |\n|---|---|---|---|"
        )?;
        for p in points.iter().filter(|p| p.scene == name) {
            writeln!(
                md,
                "| {} | {} | {:.2} | {:.3e} |",
                p.series,
                p.spp,
                p.seconds * 1e3,
                p.rmse
            )?;
        }
        md.push('\n');
    }
    let out = conformance::gate::report_dir();
    std::fs::create_dir_all(&out)?;
    std::fs::write(out.join("tradeoff.md"), &md)?;
    std::fs::write(out.join("tradeoff.svg"), svg(&points))?;
    println!("{md}");
    println!(
        "wrote {} and tradeoff.svg",
        out.join("tradeoff.md").display()
    );
    if !std::env::args().any(|a| a == "--write-docs") {
        return Ok(());
    }
    let doc = root.join("conformance/docs/tradeoff.md");
    let text = std::fs::read_to_string(&doc)?;
    let (a, b) = ("<!-- tradeoff:begin -->\n", "<!-- tradeoff:end -->");
    let (i, j) = (
        text.find(a).context("begin marker")? + a.len(),
        text.find(b).context("end marker")?,
    );
    std::fs::write(&doc, format!("{}{md}{}", &text[..i], &text[j..]))?;
    std::fs::write(root.join("conformance/docs/tradeoff.svg"), svg(&points))?;
    println!("updated conformance/docs/tradeoff.md and tradeoff.svg");
    Ok(())
}

/// Log-log plots of RMSE against time, one panel per scene.
fn svg(points: &[Point]) -> String {
    let (pw, ph, m) = (340.0, 260.0, 48.0);
    let width = pw * SCENES.len() as f64;
    let colors = ["#1f77b4", "#2ca02c", "#9467bd", "#d62728"];
    let series: Vec<String> = {
        let mut v: Vec<String> = points.iter().map(|p| p.series.clone()).collect();
        v.dedup();
        v.sort();
        v.dedup();
        v
    };
    let mut s = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{}\" font-family=\"sans-serif\" font-size=\"11\">\n", ph + 70.0);
    for (k, name) in SCENES.iter().enumerate() {
        let pts: Vec<&Point> = points.iter().filter(|p| p.scene == *name).collect();
        let lx = |v: f64| v.max(1e-9).log10();
        let (x0, x1) = (
            pts.iter()
                .map(|p| lx(p.seconds))
                .fold(f64::INFINITY, f64::min)
                .floor(),
            pts.iter()
                .map(|p| lx(p.seconds))
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil(),
        );
        let (y0, y1) = (
            pts.iter()
                .map(|p| lx(p.rmse))
                .fold(f64::INFINITY, f64::min)
                .floor(),
            pts.iter()
                .map(|p| lx(p.rmse))
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil(),
        );
        let ox = k as f64 * pw;
        let px = |v: f64| ox + m + (lx(v) - x0) / (x1 - x0).max(1e-9) * (pw - 2.0 * m);
        let py = |v: f64| 20.0 + (1.0 - (lx(v) - y0) / (y1 - y0).max(1e-9)) * (ph - m);
        s += &format!(
            "<text x=\"{}\" y=\"14\" text-anchor=\"middle\" font-weight=\"bold\">{name}</text>\n",
            ox + pw / 2.0
        );
        s += &format!(
            "<rect x=\"{}\" y=\"20\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>\n",
            ox + m,
            pw - 2.0 * m,
            ph - m
        );
        for d in (x0 as i32)..=(x1 as i32) {
            let x = ox + m + (d as f64 - x0) / (x1 - x0).max(1e-9) * (pw - 2.0 * m);
            s += &format!(
                "<text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">1e{d} s</text>\n",
                ph - m + 36.0
            );
        }
        for d in (y0 as i32)..=(y1 as i32) {
            let y = 20.0 + (1.0 - (d as f64 - y0) / (y1 - y0).max(1e-9)) * (ph - m);
            s += &format!(
                "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{d}</text>\n",
                ox + m - 4.0,
                y + 4.0
            );
        }
        for (c, ser) in series.iter().enumerate() {
            let line: Vec<String> = pts
                .iter()
                .filter(|p| &p.series == ser)
                .map(|p| format!("{:.1},{:.1}", px(p.seconds), py(p.rmse)))
                .collect();
            s += &format!(
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\"/>\n",
                line.join(" "),
                colors[c % colors.len()]
            );
            for p in pts.iter().filter(|p| &p.series == ser) {
                s += &format!("<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"{}\"><title>{} spp: {:.2} ms, RMSE {:.2e}</title></circle>\n", px(p.seconds), py(p.rmse), colors[c % colors.len()], p.spp, p.seconds * 1e3, p.rmse);
            }
        }
    }
    for (c, ser) in series.iter().enumerate() {
        let x = 10.0 + c as f64 * 200.0;
        s += &format!("<rect x=\"{x}\" y=\"{}\" width=\"12\" height=\"12\" fill=\"{}\"/><text x=\"{}\" y=\"{}\">{ser}</text>\n", ph + 44.0, colors[c % colors.len()], x + 16.0, ph + 54.0);
    }
    s += &format!("<text x=\"10\" y=\"{}\">RMSE against the 8192-spp Mitsuba reference (vertical) versus render time (horizontal), log-log.</text>\n", ph + 68.0);
    s + "</svg>\n"
}
