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
