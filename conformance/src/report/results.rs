//! `results.json`: the measurements of one run (verdict, time, worst error per scene),
//! written beside the report and plotted from disk, and the UTC time stamp they carry.

use super::table::shown_verdict;
use crate::gate::{error_in_tolerances, Checked, Judged};

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

pub(super) fn results(judged: &[Judged]) -> Results {
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
