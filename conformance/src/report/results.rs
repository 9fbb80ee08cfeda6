//! `results.json`: the measurements of one run (verdict, time, worst error per scene),
//! written beside the report and plotted from disk, and the UTC time stamp they carry.

use super::table::shown_verdict;
use crate::gate::Judged;
use crate::registry::Registry;

/// One scene's measurements, as `results.json` holds them.
#[derive(serde::Serialize, serde::Deserialize, Clone, Debug)]
pub struct Row {
    /// The reference (povray, mitsuba).
    pub reference: String,
    /// The scene.
    pub scene: String,
    /// Its row's anchor in `index.html` ([`Judged::key`]).
    #[serde(default)]
    pub anchor: String,
    /// The verdict as shown.
    pub verdict: String,
    /// Seconds our render took.
    pub seconds: f64,
    /// The comparison's worst score ([`crate::checked::Checked::worst_score`]): largest
    /// pixel error in units of the tolerance (POV-Ray), or largest per-pixel z (Mitsuba).
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
pub(super) fn utc(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86400), secs.rem_euclid(86400));
    let (y, m, d) = crate::manifest::civil_from_days(days);
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

pub(super) fn results(judged: &[Judged], registry: &Registry) -> Results {
    let rows = judged
        .iter()
        .map(|j| Row {
            reference: j.checked.reference().into(),
            scene: j.checked.scene().into(),
            anchor: j.key(),
            verdict: shown_verdict(j),
            seconds: j.checked.seconds(),
            worst: j.checked.worst_score(),
        })
        .collect();
    let how: Vec<String> = registry.iter().map(|r| r.how()).collect();
    Results {
        measured: now_utc(),
        how: format!(
            "`conformance run`, {} build, {} threads, {}",
            if cfg!(feature = "f64") { "f64" } else { "f32" },
            std::thread::available_parallelism().map_or(1, |n| n.get()),
            how.join(" / ")
        ),
        rows,
    }
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
