//! `conformance`: export catalog scenes to the reference renderers' formats, and compare the
//! renderer with the committed references.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "Conformance harness for the verified ray tracer")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Export a scene file to POV-Ray SDL.
    ExportPov {
        /// The scene file.
        scene: PathBuf,
        /// Output .pov file.
        #[arg(short, long)]
        output: PathBuf,
    },
}

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<ExitCode> {
    match Cli::parse().cmd {
        Cmd::ExportPov { scene, output } => {
            let s = renderer::scene::Scene::load(&scene)?;
            let title = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let sdl = conformance::povray::export(&s, &title);
            std::fs::write(&output, sdl).with_context(|| format!("writing {}", output.display()))?;
            Ok(ExitCode::SUCCESS)
        }
    }
}
