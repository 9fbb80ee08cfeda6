//! The text table that `conformance run` prints: one line per scene and a summary.

use crate::gate::Judged;
use crate::verdict::Verdict;
use std::fmt::Write;

/// The verdict shown for a judged scene ("pass", "FAIL", …; a stale waiver is named).
pub fn shown_verdict(j: &Judged) -> String {
    if j.stale_waivers.is_empty() {
        j.verdict.to_string()
    } else {
        format!("{} (STALE WAIVER)", j.verdict)
    }
}

/// The width the table's metric lines are wrapped to.
pub const WIDTH: usize = 100;

/// The text table printed by `conformance run`: a line per scene, and under it the
/// scene's metrics, indented and wrapped to [`WIDTH`] columns.
pub fn table(judged: &[Judged]) -> String {
    let mut s = format!(
        "{:<28} {:<8} {:>15}  verdict\n",
        "scene", "ref", "render time (s)"
    );
    for j in judged {
        writeln!(
            s,
            "{:<28} {:<8} {:>15.3}  {}",
            j.checked.scene(),
            j.checked.reference(),
            j.checked.seconds(),
            shown_verdict(j),
        )
        .unwrap();
        for part in metric_parts(&j.checked.metrics()) {
            for line in wrap(part, WIDTH - 4) {
                writeln!(s, "    {line}").unwrap();
            }
        }
    }
    s.push_str(&summary_line(judged));
    s
}

/// A metrics string cut at its top-level `; ` (one part per measurement, e.g. radiance;
/// geometry), never inside parentheses, where `; ` separates the items of one measurement.
pub fn metric_parts(metrics: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in metrics.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ';' if depth == 0 && metrics[i + 1..].starts_with(' ') => {
                parts.push(&metrics[start..i]);
                start = i + 2;
            }
            _ => {}
        }
    }
    parts.push(&metrics[start..]);
    parts
}

/// `text` in lines of at most `width` characters, broken at spaces (a longer word stays
/// whole on its own line).
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

pub(super) const VERDICTS: [Verdict; 5] = [
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test01_metrics_split_at_top_level_semicolons_only() {
        let povray =
            "0 failing pixels, 2 excused by geometry (2 outline, 0 seen; budget 40), RMSE 1e-4";
        assert_eq!(
            metric_parts(povray),
            [povray],
            "a `; ` inside parentheses split"
        );
        let mitsuba = "radiance: 99.9 % pass (need 99 %); geometry: distance error 1e-6";
        assert_eq!(
            metric_parts(mitsuba),
            [
                "radiance: 99.9 % pass (need 99 %)",
                "geometry: distance error 1e-6"
            ]
        );
    }

    #[test]
    fn test02_lines_wrap_at_spaces_within_the_width() {
        let text = "radiance: 99.988 % of pixel-channels pass (need 99.00 %), global z -0.31 0.12 0.56 (need |z| < 4), RMSE 1.234e-3";
        let lines = wrap(text, 40);
        assert!(lines.len() > 1, "{lines:?}");
        for l in &lines {
            assert!(
                l.chars().count() <= 40,
                "a line of {} characters: {l}",
                l.chars().count()
            );
        }
        assert_eq!(lines.join(" "), text, "wrapping lost or moved words");
        assert_eq!(wrap("one", 40), ["one"]);
        assert_eq!(wrap("a-very-long-word b", 5), ["a-very-long-word", "b"]);
    }
}
