//! `conformance`: run the catalog against the committed references, export scenes to the
//! reference renderers' formats, and regenerate references.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use conformance::catalog::{repo_root, select, select_in};
use conformance::gate::{self, REFERENCES};
use conformance::manifest::Manifest;
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
    /// Add a scene to a catalog and generate its references: writes
    /// conformance/scenes/CATALOG/NAME.toml (a copy of --from, or a small starting scene),
    /// then renders its references with the reference tool and records them in
    /// references/manifest.toml.
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
        /// scripts/regen-CATALOG.sh NAME.
        #[arg(long)]
        no_references: bool,
        /// Samples per pixel of a Mitsuba radiance reference.
        #[arg(long, default_value_t = 8192)]
        spp: u32,
    },
    /// Regenerate Mitsuba references (needs `pip install mitsuba`; see scripts/regen-mitsuba.sh).
    RegenMitsuba {
        /// Which scenes, as for `run`.
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
    /// Regenerate Blender Cycles references (needs `bpy`; see scripts/regen-cycles.sh).
    RegenCycles {
        /// Which scenes of the physical catalog, as for `run`.
        #[arg(default_value = "")]
        filter: String,
        /// Re-render from scratch into a temporary folder and check the result against the
        /// committed references, instead of replacing them.
        #[arg(long)]
        check: bool,
    },
    /// Regenerate POV-Ray references (needs povray; see scripts/regen-povray.sh).
    RegenPovray {
        /// Which scenes, as for `run`.
        #[arg(default_value = "")]
        filter: String,
        /// Render into a temporary folder and check that the result equals the committed
        /// references bit for bit, instead of replacing them.
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
    match Cli::parse().cmd {
        Cmd::Run { filter } => {
            let root = repo_root();
            let manifest = Manifest::load(&root.join("references/manifest.toml"))?;
            let waivers = Waivers::committed()?;
            let chosen = match select_in(&REFERENCES, &filter) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    return Ok(ExitCode::from(2));
                }
            };
            let mut judged = Vec::new();
            for (reference, e) in &chosen {
                judged.push(
                    gate::check(reference, e, &manifest, &waivers)
                        .with_context(|| format!("{reference}/{}", e.name))?,
                );
            }
            print!("{}", conformance::report::table(&judged));
            for j in judged.iter().filter(|j| !j.accepted()) {
                print!("\n{}", j.failure_message());
            }
            let dir = gate::report_dir();
            conformance::report::write(&dir, &judged)?;
            println!("report: {}", dir.join("index.html").display());
            Ok(if judged.iter().all(|j| j.accepted()) {
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
        Cmd::NewScene {
            name,
            catalog,
            from,
            no_references,
            spp,
        } => {
            let path = new_scene(&name, &catalog, from.as_deref())?;
            println!("wrote {}", path.display());
            let entries = select(&catalog, &name)?;
            if no_references {
                println!(
                    "generate its references with: {}",
                    gate::regen_command(&catalog, &name)
                );
                return Ok(ExitCode::SUCCESS);
            }
            let made = match catalog.as_str() {
                "povray" => conformance::povray::refgen::regenerate(&entries),
                _ => conformance::mitsuba::refgen::regenerate(&entries, spp),
            };
            made.with_context(|| {
                format!(
                    "the scene file was written, but its references were not: run {} (it installs the tool)",
                    gate::regen_command(&catalog, &name)
                )
            })?;
            println!(
                "references written and recorded in references/manifest.toml; check with: cargo test --test catalog {catalog}::{name}"
            );
            Ok(ExitCode::SUCCESS)
        }
        Cmd::RegenMitsuba { filter, spp, check } => {
            let entries = select("mitsuba", &filter)?;
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
        Cmd::RegenCycles { filter, check } => {
            let entries = select("mitsuba", &filter)?;
            if check {
                let bad = conformance::cycles::refgen::check(&entries)?;
                if bad.is_empty() {
                    println!("{} Cycles reference(s) regenerated from scratch and consistent with the committed files", entries.len());
                    Ok(ExitCode::SUCCESS)
                } else {
                    println!("regenerated Cycles references differ: {}", bad.join(", "));
                    Ok(ExitCode::from(1))
                }
            } else {
                conformance::cycles::refgen::regenerate(&entries)?;
                Ok(ExitCode::SUCCESS)
            }
        }
        Cmd::RegenPovray { filter, check } => {
            let entries = select("povray", &filter)?;
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

/// The built-in starting scenes of `new-scene`, per catalog.
const STARTERS: [(&str, &str); 2] = [
    ("povray", "prim_sphere_identity"),
    ("mitsuba", "mi_diffuse_point"),
];

/// Writes a new catalog scene file and returns its path.
fn new_scene(name: &str, catalog: &str, from: Option<&std::path::Path>) -> Result<PathBuf> {
    let Some((_, starter)) = STARTERS.iter().find(|(c, _)| *c == catalog) else {
        anyhow::bail!("--catalog {catalog}: unknown catalog (one of: povray, mitsuba)");
    };
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
        gate::regen_command(catalog, name)
    );
    let source = from
        .map(PathBuf::from)
        .unwrap_or_else(|| dir.join(format!("{starter}.toml")));
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
