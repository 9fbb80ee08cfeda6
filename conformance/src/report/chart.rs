//! A horizontal bar chart (SVG) of one value per scene, on a log axis.

use super::html::html_escape;
use std::fmt::Write;

/// A horizontal bar chart (SVG) of one value per scene, on a log axis.
pub(super) fn bar_chart(
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
