//! Render progress on stderr: a bar that redraws itself (indicatif) for a terminal, or one
//! plain line every 10 % for a log or a pipe (`renderer render --progress`,
//! renderer/docs/cli.md).

use std::io::IsTerminal;
use std::sync::Mutex;

/// How a render reports its progress.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Progress {
    /// Nothing.
    #[default]
    None,
    /// The bar when stderr is a terminal, else nothing.
    Auto,
    /// The bar (drawn only when stderr is a terminal: indicatif hides it otherwise).
    Bar,
    /// A line `progress: 10 % (48/480 rows), 1.2 s` at every tenth of the rows.
    Plain,
}

/// A started report: counts rows and shows them as its [`Progress`] says.
pub enum Reporter {
    /// Nothing to show.
    Silent,
    /// The terminal bar.
    Bar(indicatif::ProgressBar),
    /// Plain lines.
    Plain {
        /// Rows in all.
        total: u64,
        /// Rows done; locked while a line is printed, so the lines come in order.
        done: Mutex<u64>,
        /// When the render started.
        start: std::time::Instant,
    },
}

impl Reporter {
    /// A report over `rows` rows.
    pub fn start(mode: Progress, rows: u64) -> Reporter {
        let bar = match mode {
            Progress::None => false,
            Progress::Auto => std::io::stderr().is_terminal(),
            Progress::Bar => true,
            Progress::Plain => {
                return Reporter::Plain {
                    total: rows,
                    done: Mutex::new(0),
                    start: std::time::Instant::now(),
                }
            }
        };
        if !bar {
            return Reporter::Silent;
        }
        let bar = indicatif::ProgressBar::new(rows);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} rows, {elapsed} elapsed, ETA {eta}",
        ) {
            bar.set_style(style);
        }
        Reporter::Bar(bar)
    }

    /// One more row done (from any render thread).
    pub fn row_done(&self) {
        match self {
            Reporter::Silent => {}
            Reporter::Bar(b) => b.inc(1),
            Reporter::Plain { total, done, start } => {
                let mut done = done.lock().unwrap_or_else(|e| e.into_inner());
                *done += 1;
                // The row that reaches a new tenth prints it.
                let tenth = |n: u64| n * 10 / (*total).max(1);
                if tenth(*done) > tenth(*done - 1) {
                    eprintln!(
                        "progress: {} % ({}/{total} rows), {:.1} s",
                        tenth(*done) * 10,
                        *done,
                        start.elapsed().as_secs_f64()
                    );
                }
            }
        }
    }

    /// The render is over: clears the bar.
    pub fn finish(&self) {
        if let Reporter::Bar(b) = self {
            b.finish_and_clear();
        }
    }
}
