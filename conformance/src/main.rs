//! `conformance`: run the catalog against the committed references, export scenes to the
//! reference renderers' formats, and regenerate references.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use conformance::catalog::{repo_root, Entry};
use conformance::gate;
use conformance::manifest::Manifest;
use conformance::reference::{ExportOptions, Reference, RegenOptions};
use conformance::registry::Registry;
use conformance::waivers::Waivers;
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
    /// Render catalog scenes, compare them with their references, print a table (and for
    /// each scene that does not pass, its worst pixels and failure images) and write
    /// $CARGO_TARGET_DIR/conformance/index.html (default target/). Exits 1 unless every
    /// scene passes or is waived, 2 when the filter matches no scene.
    Run {
        /// Which scenes: a scene's name (that scene alone), `povray::NAME` or
        /// `mitsuba::NAME` (one catalog), or a part of names (every scene whose name
        /// contains it). Empty: every scene.
        #[arg(default_value = "")]
        filter: String,
    },
    /// Export a scene file to a reference renderer's input: `export povray` writes
    /// POV-Ray SDL, `export mitsuba` Mitsuba 3 XML (meshes beside it).
    Export {
        /// The reference (povray, mitsuba).
        reference: String,
        /// The scene file.
        scene: PathBuf,
        /// The output file (.pov, .xml).
        #[arg(short, long)]
        output: PathBuf,
        /// Samples per pixel of the exported sampler (sampled references; Mitsuba: 64).
        #[arg(long)]
        spp: Option<u32>,
        /// Wrap the integrator in one that also writes second moments (Mitsuba's `moment`).
        #[arg(long)]
        moment: bool,
    },
    /// Add a scene to a catalog and generate its references: writes
    /// conformance/scenes/CATALOG/NAME.toml (a copy of --from, or a small starting scene),
    /// then renders its references with each reference tool that checks it and records
    /// them in references/manifest.toml.
    NewScene {
        /// The scene's name: lower-case letters, digits and underscores.
        name: String,
        /// The catalog (povray or mitsuba).
        #[arg(long)]
        catalog: String,
        /// Start from this scene file instead of the built-in starting scene.
        #[arg(long)]
        from: Option<PathBuf>,
        /// Only write the scene file; generate its references later with
        /// scripts/regen-REFERENCE.sh NAME.
        #[arg(long)]
        no_references: bool,
        /// Samples per pixel of a sampled reference (Mitsuba radiance: 8192).
        #[arg(long)]
        spp: Option<u32>,
    },
    /// Regenerate a reference renderer's references (needs the tool; see
    /// scripts/regen-REFERENCE.sh, which installs it).
    Regen {
        /// The reference (povray, mitsuba).
        reference: String,
        /// Which scenes, as for `run`.
        #[arg(default_value = "")]
        filter: String,
        /// Samples per pixel of a sampled reference (Mitsuba radiance: 8192).
        #[arg(long, conflicts_with = "check")]
        spp: Option<u32>,
        /// Re-render from scratch into a temporary folder and check the result against the
        /// committed references (bit for bit, or statistically for a sampled reference),
        /// instead of replacing them.
        #[arg(long)]
        check: bool,
    },
}

fn main() -> ExitCode {
    if let Err(e) = renderer::check_cpu() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<ExitCode> {
    let registry = Registry::committed();
    match Cli::parse().cmd {
        Cmd::Run { filter } => {
            let manifest = Manifest::committed()?;
            let waivers = Waivers::committed()?;
            if let Err(e) = registry.select(&filter) {
                eprintln!("error: {e:#}");
                return Ok(ExitCode::from(2));
            }
            let judged = gate::check_all(&registry, &filter, &manifest, &waivers)?;
            print!("{}", conformance::report::table(&judged));
            for j in judged.iter().filter(|j| !j.accepted()) {
                print!("\n{}", j.failure_message());
            }
            let dir = gate::report_dir();
            conformance::report::write(&dir, &judged, &registry)?;
            println!("report: {}", dir.join("index.html").display());
            Ok(if judged.iter().all(|j| j.accepted()) {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            })
        }
        Cmd::Export {
            reference,
            scene,
            output,
            spp,
            moment,
        } => {
            let r = registry.get(&reference)?;
            let s = renderer::scene::Scene::load(&scene)?;
            let title = scene
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            r.export(&s, &title, &ExportOptions { spp, moment }, &output)?;
            Ok(ExitCode::SUCCESS)
        }
        Cmd::NewScene {
            name,
            catalog,
            from,
            no_references,
            spp,
        } => {
            let references = registry.of_catalog(&catalog);
            anyhow::ensure!(
                !references.is_empty(),
                "--catalog {catalog}: unknown catalog (one of: {})",
                registry.catalogs().join(", ")
            );
            let path = new_scene(&name, &catalog, &references, from.as_deref())?;
            println!("wrote {}", path.display());
            // The references that check the new scene, each with it as its one entry.
            let mut checking: Vec<(&dyn Reference, Vec<Entry>)> = Vec::new();
            for r in references {
                let entries: Vec<Entry> = registry
                    .scenes(r)?
                    .into_iter()
                    .filter(|e| e.name == name)
                    .collect();
                if !entries.is_empty() {
                    checking.push((r, entries));
                }
            }
            let commands: Vec<String> = checking
                .iter()
                .map(|(r, _)| gate::regen_command(r.name(), &name))
                .collect();
            if no_references {
                println!("generate its references with: {}", commands.join("; "));
                return Ok(ExitCode::SUCCESS);
            }
            for (r, entries) in &checking {
                r.regenerate(entries, &RegenOptions { spp }).with_context(|| {
                    format!(
                        "the scene file was written, but its {} references were not: run {} (it installs the tool)",
                        r.title(),
                        gate::regen_command(r.name(), &name)
                    )
                })?;
            }
            println!(
                "references written and recorded in references/manifest.toml; check with: cargo test --test catalog {name}"
            );
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Regen {
            reference,
            filter,
            spp,
            check,
        } => {
            let r = registry.get(&reference)?;
            let entries = registry.select_for(r, &filter)?;
            if !check {
                r.regenerate(&entries, &RegenOptions { spp })?;
                return Ok(ExitCode::SUCCESS);
            }
            let bad = r.check_regenerated(&entries)?;
            if bad.is_empty() {
                println!(
                    "{} {} reference(s) regenerated from scratch and consistent with the committed files",
                    entries.len(),
                    r.title()
                );
                Ok(ExitCode::SUCCESS)
            } else {
                println!(
                    "regenerated {} references differ: {}",
                    r.title(),
                    bad.join(", ")
                );
                Ok(ExitCode::from(1))
            }
        }
    }
}

/// Writes a new catalog scene file and returns its path. Without `from`, the scene starts
/// as a copy of the starting scene of the catalog's `references` ([`Reference::starter`]).
fn new_scene(
    name: &str,
    catalog: &str,
    references: &[&dyn Reference],
    from: Option<&std::path::Path>,
) -> Result<PathBuf> {
    anyhow::ensure!(
        !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'),
        "NAME `{name}`: use lower-case letters, digits and underscores (it names the file and the test)"
    );
    let dir = repo_root().join("conformance/scenes").join(catalog);
    let path = dir.join(format!("{name}.toml"));
    anyhow::ensure!(
        !path.exists(),
        "{} already exists: to regenerate its references run {}",
        path.display(),
        references
            .iter()
            .map(|r| gate::regen_command(r.name(), name))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let source = match from {
        Some(f) => PathBuf::from(f),
        None => {
            let Some(starter) = references.iter().find_map(|r| r.starter()) else {
                anyhow::bail!(
                    "--catalog {catalog}: no reference of it has a starting scene; give one with --from"
                );
            };
            dir.join(format!("{starter}.toml"))
        }
    };
    let body = std::fs::read_to_string(&source)
        .with_context(|| format!("reading {}", source.display()))?;
    // The scene must load before it becomes part of the catalog.
    renderer::scene::Scene::from_str(&body, &path, &dir)
        .with_context(|| format!("{} does not load as a scene", source.display()))?;
    let text = format!(
        "# {name}: added with `conformance new-scene` from {}.\n{body}",
        source
            .file_name()
            .map_or("?".into(), |f| f.to_string_lossy().into_owned())
    );
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}
