//! A mutation fuzzer on stable Rust: every committed scene (renderer/scenes, the catalogs)
//! is mutated (bytes, lines, number tokens replaced by extreme values) and run through
//! parse, build and, for one input in 16, a tiny render (4 × 3 pixels, 1 sample), under
//! `catch_unwind`. The fuzzing runs in a child process (this test binary run again as the
//! worker), so a stack overflow or an abort, which no `catch_unwind` sees, fails the test
//! too; the input being run is kept on disk, and the failure names it.
//!
//! `FUZZ_SECONDS` sets the duration (default 20; CI runs 60, `scripts/fuzz.sh` longer) and
//! `FUZZ_SEED` the seed, `FUZZ_RENDER_EVERY` how often an input is rendered (default 16;
//! 0 = parse + build only, the fastest mode for long runs). The worker prints how many
//! inputs it ran.

use renderer::scene::build::{build_with, Overrides};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// Every committed scene file, with the folder its meshes resolve against.
fn corpus() -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    for dir in [
        "renderer/scenes",
        "conformance/scenes/povray",
        "conformance/scenes/mitsuba",
        "conformance/scenes/scale",
    ] {
        let d = Path::new(ROOT).join(dir);
        let mut files: Vec<PathBuf> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).unwrap();
            out.push((f, text));
        }
    }
    out
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        renderer::sampler::mix64(self.0)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const EXTREMES: [&str; 20] = [
    "1e39",
    "-1e39",
    "3.4e38",
    "1e308",
    "-1e308",
    "1e-45",
    "1e-320",
    "0",
    "-0.0",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "-1",
    "9223372036854775807",
    "1e20",
    "65536",
    "0.5",
    "1e-7",
    "256",
];

/// One mutation of `text`.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut s = text.to_string();
    for _ in 0..1 + rng.below(4) {
        match rng.below(6) {
            // Replace a number token by an extreme value.
            0 | 1 => {
                let spans: Vec<(usize, usize)> = {
                    let b = s.as_bytes();
                    let mut v = Vec::new();
                    let mut i = 0;
                    while i < b.len() {
                        if b[i].is_ascii_digit()
                            || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit())
                        {
                            let st = i;
                            i += 1;
                            while i < b.len()
                                && (b[i].is_ascii_alphanumeric()
                                    || b[i] == b'.'
                                    || b[i] == b'_'
                                    || ((b[i] == b'-' || b[i] == b'+')
                                        && (b[i - 1] == b'e' || b[i - 1] == b'E')))
                            {
                                i += 1;
                            }
                            v.push((st, i));
                        } else {
                            i += 1;
                        }
                    }
                    v
                };
                if !spans.is_empty() {
                    let (a, b) = spans[rng.below(spans.len())];
                    s.replace_range(a..b, EXTREMES[rng.below(EXTREMES.len())]);
                }
            }
            // Flip a byte (kept valid UTF-8 by working on ASCII only).
            2 => {
                let mut bytes = s.into_bytes();
                if !bytes.is_empty() {
                    let k = rng.below(bytes.len());
                    if bytes[k].is_ascii() {
                        bytes[k] = (rng.next() % 0x7f) as u8;
                    }
                }
                s = String::from_utf8(bytes).unwrap_or_default();
            }
            // Delete, duplicate or swap lines.
            3 | 4 => {
                let mut lines: Vec<&str> = s.lines().collect();
                if lines.len() > 1 {
                    let (i, j) = (rng.below(lines.len()), rng.below(lines.len()));
                    match rng.below(3) {
                        0 => {
                            lines.remove(i);
                        }
                        1 => lines.insert(j, lines[i]),
                        _ => lines.swap(i, j),
                    }
                }
                s = lines.join("\n");
            }
            // Cut or repeat a chunk.
            _ => {
                if !s.is_empty() {
                    let a = rng.below(s.len());
                    let b = (a + 1 + rng.below(40)).min(s.len());
                    if s.is_char_boundary(a) && s.is_char_boundary(b) {
                        if rng.below(2) == 0 {
                            s.replace_range(a..b, "");
                        } else {
                            let chunk = s[a..b].to_string();
                            s.insert_str(b, &chunk);
                        }
                    }
                }
            }
        }
    }
    s
}

/// The worker: fuzzes until the deadline, writing each input to `current` before running
/// it; exits 1 on a caught panic (the input stays in `current`).
fn work(seconds: f64, seed: u64, render_every: usize, current: &Path) {
    let corpus = corpus();
    let mut rng = Rng(seed);
    let deadline = Instant::now() + Duration::from_secs_f64(seconds);
    let tiny = Overrides {
        size: Some((4, 3)),
        samples: Some(1),
        adaptive: false,
    };
    let mut runs = 0u64;
    std::panic::set_hook(Box::new(|_| {}));
    while Instant::now() < deadline {
        for _ in 0..64 {
            let (path, text) = &corpus[rng.below(corpus.len())];
            let input = mutate(text, &mut rng);
            std::fs::write(current, format!("# from {}\n{input}", path.display())).unwrap();
            let render = render_every > 0 && rng.below(render_every) == 0;
            let base = path.parent().unwrap();
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
                if let Ok(scene) = build_with(&input, path, base, &tiny) {
                    if render {
                        let img = renderer::render::render(
                            &scene,
                            &renderer::render::Options {
                                threads: Some(1),
                                ..Default::default()
                            },
                        );
                        std::hint::black_box(img.non_finite);
                    }
                }
            }));
            runs += 1;
            if r.is_err() {
                println!("FUZZ-PANIC after {runs} inputs");
                std::process::exit(1);
            }
        }
    }
    println!("FUZZ-RUNS {runs}");
}

#[test]
fn fuzz_worker() {
    // Only the child process fuzzes; in a plain test run this test does nothing.
    if let (Ok(secs), Ok(seed), Ok(current)) = (
        std::env::var("FUZZ_WORKER_SECONDS"),
        std::env::var("FUZZ_WORKER_SEED"),
        std::env::var("FUZZ_WORKER_INPUT"),
    ) {
        let render_every = std::env::var("FUZZ_WORKER_RENDER_EVERY")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(16);
        work(
            secs.parse().unwrap(),
            seed.parse().unwrap(),
            render_every,
            Path::new(&current),
        );
    }
}

#[test]
fn test01_no_mutated_scene_panics_aborts_or_hangs() {
    let seconds: f64 = std::env::var("FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20.0);
    let seed: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    // One input in FUZZ_RENDER_EVERY is rendered (default 16); 0 renders none, the fastest
    // mode (parse + build only) for long runs.
    let render_every: usize = std::env::var("FUZZ_RENDER_EVERY")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(16);
    let dir = std::env::temp_dir().join(format!("renderer-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let current = dir.join("current.toml");
    let t0 = Instant::now();
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "fuzz_worker", "--nocapture", "--test-threads=1"])
        .env("FUZZ_WORKER_SECONDS", seconds.to_string())
        .env("FUZZ_WORKER_SEED", seed.to_string())
        .env("FUZZ_WORKER_RENDER_EVERY", render_every.to_string())
        .env("FUZZ_WORKER_INPUT", &current)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // A hang: no input may take more than a minute past the deadline.
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed().as_secs_f64() > seconds + 60.0 {
            child.kill().unwrap();
            panic!(
                "an input hangs (no progress for 60 s past the deadline); it is {}",
                current.display()
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let runs = stdout
        .lines()
        .find_map(|l| l.split("FUZZ-RUNS ").nth(1))
        .and_then(|n| n.parse::<u64>().ok());
    assert!(
        out.status.success() && runs.is_some(),
        "the fuzzer (seed {seed}) crashed, aborted or panicked ({:?}) on the input kept at {}:\n{}\n{}",
        out.status,
        current.display(),
        stdout.lines().filter(|l| l.contains("FUZZ")).collect::<Vec<_>>().join("\n"),
        String::from_utf8_lossy(&out.stderr).lines().rev().take(10).collect::<Vec<_>>().join("\n")
    );
    let runs = runs.unwrap();
    eprintln!(
        "fuzz: {runs} inputs in {:.1} s ({:.0}/s), seed {seed}, one in {render_every} rendered",
        t0.elapsed().as_secs_f64(),
        runs as f64 / t0.elapsed().as_secs_f64()
    );
    assert!(runs > 100, "the fuzzer ran only {runs} inputs");
    std::fs::remove_dir_all(&dir).unwrap();
}
