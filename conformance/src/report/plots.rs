//! The report's plots, drawn from data on disk: this run's `results.json`, and the
//! instruction counts and the speed/accuracy trade when their scripts have left them.

use super::chart::bar_chart;
use super::html::html_escape;
use super::results::{utc, Results, Row};
use crate::registry::Registry;
use anyhow::Result;
use std::fmt::Write;
use std::path::Path;

/// Plots from data on disk: this run's `results.json`, and (when present) the
/// instruction counts and the speed/accuracy trade their scripts leave in `dir`.
pub(super) fn plots(
    html: &mut String,
    dir: &Path,
    fallback: &Results,
    registry: &Registry,
) -> Result<()> {
    html.push_str("<h2 id=\"plots\">Plots</h2>\n");
    let data: Results = std::fs::read_to_string(dir.join("results.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_else(|| fallback.clone());
    let caption = format!(
        "From results.json: measured {} by {}.",
        data.measured, data.how
    );
    for r in registry.iter() {
        let reference = r.name();
        let rows: Vec<&Row> = data
            .rows
            .iter()
            .filter(|row| row.reference == reference)
            .collect();
        if rows.is_empty() {
            continue;
        }
        let plot = r.worst_plot();
        let (title, label, mark) = (plot.title, plot.label, plot.mark);
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
