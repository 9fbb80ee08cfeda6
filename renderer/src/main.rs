//! The `renderer` command line: `renderer render SCENE -o OUT [--aov]`.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use renderer::output::{self, ToneMap};
use renderer::render::{self, Options, Progress};
use renderer::scene::build::Overrides;
use renderer::scene::Scene;
use renderer::spawn::Spawn;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(version, about = "A verified classic ray tracer")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Render a scene file to PNG (8-bit sRGB) or EXR (32-bit float, linear).
    Render {
        /// The scene file (TOML; see renderer/docs/scene-format.md).
        scene: PathBuf,
        /// Output file; the format follows the extension (.png or .exr).
        #[arg(short, long)]
        output: PathBuf,
        /// Add geometry channels to the EXR: Z, N.X/Y/Z, P.X/Y/Z, objectId.
        #[arg(long)]
        aov: bool,
        /// Worker threads; 0 (the default) uses every core. At most 1024.
        #[arg(long, value_name = "N", default_value_t = 0, value_parser = parse_threads)]
        threads: usize,
        /// Progress on stderr: a bar when stderr is a terminal (auto), always the bar, a
        /// plain line every 10 % (for logs and pipes), or none.
        #[arg(long, value_enum, default_value_t = Progress::Auto)]
        progress: Progress,
        /// How PNG output maps intensities to 8 bits.
        #[arg(long, value_enum, default_value_t = ToneMap::Srgb)]
        map: ToneMap,
        /// Self-intersection strategy for secondary rays: robust, or fixed=EPS (POV-Ray's 1e-3), or none.
        #[arg(long, default_value = "robust", value_parser = parse_spawn)]
        spawn: Spawn,
        /// Samples per pixel, replacing the scene's render.samples (validated like it).
        #[arg(long, value_name = "N")]
        spp: Option<u32>,
        /// Image size, replacing the scene's render.width and render.height (validated like
        /// them). The camera's window stays as the scene gives it, so the pixels cover the
        /// same view; with a look-at camera the field of view follows the new aspect ratio
        /// as it would in the scene file.
        #[arg(long, value_name = "WxH", value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// Adaptive sampling: spend the samples (an average of --spp or render.samples a
        /// pixel) where the noise is, as render.adaptive = true does.
        #[arg(long)]
        adaptive: bool,
    },
}

fn parse_spawn(s: &str) -> Result<Spawn, String> {
    match s {
        "robust" => Ok(Spawn::Robust),
        "none" => Ok(Spawn::None),
        _ => s
            .strip_prefix("fixed=")
            .and_then(|e| e.parse::<f64>().ok())
            .filter(|e| e.is_finite() && *e >= 0.0)
            .map(Spawn::Fixed)
            .ok_or_else(|| format!("'{s}': expected robust, none or fixed=EPS")),
    }
}

/// The most render threads `--threads` accepts: rendering gains nothing from more threads
/// than cores, and each thread reserves 64 MiB of address space for its stack.
const MAX_THREADS: usize = 1024;

fn parse_threads(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|e| format!("'{s}' is not a whole number of threads ({e})"))?;
    if n > MAX_THREADS {
        return Err(format!(
            "{n} threads is more than the limit of {MAX_THREADS} (this machine has {} cores; 0 uses them all)",
            std::thread::available_parallelism().map_or(1, |c| c.get())
        ));
    }
    Ok(n)
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 640x480"))?;
    let side = |v: &str, name: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|e| format!("'{s}': the {name} '{v}' is not a whole number of pixels ({e})"))
    };
    let size = (side(w, "width")?, side(h, "height")?);
    renderer::scene::build::check_size(size.0, size.1)
        .map_err(|(which, m)| format!("'{s}': {which}: {m}"))?;
    Ok(size)
}

fn main() -> ExitCode {
    if let Err(e) = renderer::check_cpu() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    // SIGINT and SIGTERM: remove any temp file an interrupted write left, then exit with
    // the shell's code for an interrupt. An existing output is never touched.
    let _ = ctrlc::set_handler(|| {
        output::remove_temp_files();
        eprintln!("interrupted: no output written");
        std::process::exit(130);
    });
    if let Some(ms) = std::env::var("RENDERER_FAULT_SLOW_WRITE_MS")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        output::SLOW_WRITE_MS.store(ms, std::sync::atomic::Ordering::Relaxed);
    }
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<()> {
    match Cli::parse().cmd {
        Cmd::Render {
            scene,
            output: out,
            aov,
            threads,
            progress,
            map,
            spawn,
            spp,
            size,
            adaptive,
        } => {
            let ext = out
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            anyhow::ensure!(
                ext == "png" || ext == "exr",
                "{}: unknown output format (use .png or .exr)",
                out.display()
            );
            anyhow::ensure!(!aov || ext == "exr", "--aov needs an .exr output");
            // Before the render, not after it.
            output::check_folder(&out)?;
            let overrides = Overrides {
                size,
                samples: spp,
                adaptive,
            };
            overrides.check().map_err(anyhow::Error::msg)?;
            let s = Scene::load_with(&scene, &overrides)?;
            for note in &s.scale_notes {
                eprintln!("{note}");
            }
            let t0 = std::time::Instant::now();
            let opts = Options {
                aov,
                progress,
                spawn,
                ..Options::default()
            };
            // Render threads with stacks deep enough for the deepest scene the build accepts.
            let mut pool = rayon::ThreadPoolBuilder::new().stack_size(render::STACK_SIZE);
            // rayon reads 0 as every core.
            pool = pool.num_threads(threads);
            let img = pool
                .build()
                .map_err(|e| match threads {
                    0 => anyhow::anyhow!("cannot start the render threads ({e})"),
                    n => anyhow::anyhow!("--threads {n}: cannot start {n} threads ({e})"),
                })?
                .install(|| render::render(&s, &opts));
            let secs = t0.elapsed().as_secs_f64();
            anyhow::ensure!(
                img.non_finite == 0,
                "{}: {} pixel(s) came out non-finite (NaN or infinite); no output written. \
Check the scene's numbers (renderer/docs/robustness.md)",
                scene.display(),
                img.non_finite
            );
            output::write(&img, &out, map).with_context(|| format!("writing {}", out.display()))?;
            // With adaptive sampling the count is the average the pixels took.
            let spp =
                if s.settings.adaptive && renderer::adaptive::pilot(s.settings.samples).is_some() {
                    let px = (img.width as u64 * img.height as u64).max(1);
                    format!("adaptive, {:.3} spp", img.samples as f64 / px as f64)
                } else {
                    format!("{} spp", s.settings.samples)
                };
            eprintln!(
                "{}: {}x{} px, {spp}, {:.3} s -> {}",
                scene.display(),
                img.width,
                img.height,
                secs,
                out.display()
            );
            Ok(())
        }
    }
}
