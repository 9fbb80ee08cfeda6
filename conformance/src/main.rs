//! `conformance`: run the catalog against the committed references, export scenes to the
//! reference renderers' formats, and regenerate references.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use conformance::catalog::{repo_root, scenes};
use conformance::manifest::Manifest;
use conformance::povray::harness::check_povray;
use conformance::verdict::Verdict;
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
    /// Render catalog scenes, compare them with their references, print a table and write
    /// target/conformance/index.html. Exits 1 unless every scene passes.
    Run {
        /// Only scenes whose name contains this.
        #[arg(default_value = "")]
        filter: String,
    },
    /// Export a scene file to POV-Ray SDL.
    ExportPov {
        /// The scene file.
        scene: PathBuf,
        /// Output .pov file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Export a scene file to Mitsuba 3 XML (meshes are written beside it).
    ExportMitsuba {
        /// The scene file.
        scene: PathBuf,
        /// Output .xml file.
        #[arg(short, long)]
        output: PathBuf,
        /// Samples per pixel for the sampler.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Wrap the integrator in Mitsuba's `moment` integrator.
        #[arg(long)]
        moment: bool,
    },
    /// Regenerate Mitsuba references (needs `pip install mitsuba`; see scripts/regen-mitsuba.sh).
    RegenMitsuba {
        /// Only scenes whose name contains this.
        #[arg(default_value = "")]
        filter: String,
        /// Samples per pixel of the radiance references.
        #[arg(long, default_value_t = 8192)]
        spp: u32,
        /// Re-render from scratch into a temporary folder and check the result against the
        /// committed references, instead of replacing them.
        #[arg(long)]
        check: bool,
    },
    /// Regenerate POV-Ray references (needs povray; see scripts/regen-povray.sh).
    RegenPovray {
        /// Only scenes whose name contains this.
        #[arg(default_value = "")]
        filter: String,
        /// Render into a temporary folder and check that the result equals the committed
        /// references bit for bit, instead of replacing them.
        #[arg(long)]
        check: bool,
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
        Cmd::Run { filter } => {
            let root = repo_root();
            let manifest = Manifest::load(&root.join("references/manifest.toml"))?;
            let mut outcomes = Vec::new();
            for e in scenes("povray", &filter)? {
                outcomes.push(check_povray(&e, &manifest).with_context(|| e.name.clone())?);
            }
            print!("{}", conformance::report::table(&outcomes));
            let mut mi = Vec::new();
            for e in scenes("mitsuba", &filter)? {
                mi.push(
                    conformance::mitsuba::harness::check_mitsuba(
                        &e,
                        &manifest,
                        conformance::mitsuba::harness::GATE_SPP,
                        None,
                    )
                    .with_context(|| e.name.clone())?,
                );
            }
            if !mi.is_empty() {
                print!("{}", conformance::report::mitsuba_table(&mi));
            }
            let dir = root.join("target/conformance");
            conformance::report::write(&dir, &outcomes, &mi)?;
            println!("report: {}", dir.join("index.html").display());
            let ok = outcomes.iter().all(|o| o.verdict == Verdict::Pass)
                && mi.iter().all(|o| o.verdict == Verdict::Pass);
            Ok(if ok {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            })
        }
        Cmd::ExportPov { scene, output } => {
            let s = renderer::scene::Scene::load(&scene)?;
            let title = scene
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let sdl = conformance::povray::export(&s, &title);
            std::fs::write(&output, sdl)
                .with_context(|| format!("writing {}", output.display()))?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::ExportMitsuba {
            scene,
            output,
            spp,
            moment,
        } => {
            let s = renderer::scene::Scene::load(&scene)?;
            let e = conformance::mitsuba::export(&s, spp, moment)?;
            e.write(&output)
                .with_context(|| format!("writing {}", output.display()))?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::RegenMitsuba { filter, spp, check } => {
            let entries = scenes("mitsuba", &filter)?;
            anyhow::ensure!(!entries.is_empty(), "no catalog scene matches '{filter}'");
            if check {
                let bad = conformance::mitsuba::refgen::check(&entries)?;
                if bad.is_empty() {
                    println!("{} Mitsuba reference(s) regenerated from scratch and consistent with the committed files", entries.len());
                    Ok(ExitCode::SUCCESS)
                } else {
                    println!("regenerated Mitsuba references differ: {}", bad.join(", "));
                    Ok(ExitCode::from(1))
                }
            } else {
                conformance::mitsuba::refgen::regenerate(&entries, spp)?;
                Ok(ExitCode::SUCCESS)
            }
        }
        Cmd::RegenPovray { filter, check } => {
            let entries = scenes("povray", &filter)?;
            anyhow::ensure!(!entries.is_empty(), "no catalog scene matches '{filter}'");
            if check {
                let bad = conformance::povray::refgen::check(&entries)?;
                if bad.is_empty() {
                    println!("{} reference(s) regenerated from scratch and identical to the committed files", entries.len());
                    Ok(ExitCode::SUCCESS)
                } else {
                    println!("regenerated references differ: {}", bad.join(", "));
                    Ok(ExitCode::from(1))
                }
            } else {
                conformance::povray::refgen::regenerate(&entries)?;
                Ok(ExitCode::SUCCESS)
            }
        }
    }
}
