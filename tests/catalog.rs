//! The catalog gate: one test per catalog scene, named `<reference>::<scene>`
//! (`povray::prim_cone_shear`, `mitsuba::mi_cornell`), so `cargo test prim_cone` runs a
//! subset and `cargo nextest run --partition count:K/N` shards the catalog. A filter
//! selects scenes as `conformance run` does (`Registry::select`): a scene's whole name
//! runs that scene alone (`shade_phong`, not `shade_phong_size`), a part of names runs every
//! scene whose name contains it; a filter that names no scene is libtest's substring
//! filter over the test names, and `--exact` is libtest's.
//!
//! A scene that does not pass prints its verdict and metrics, its worst pixels, the
//! failure images it wrote under `$CARGO_TARGET_DIR/conformance/failures/<scene>/`, and
//! the commands that show or fix it. A scene whose failing checks are all waived in
//! `conformance/waivers.toml` is reported as ignored with the reason `WAIVED …`, never
//! as a pass; a waiver whose check passes again fails the scene's test until it is
//! removed. The catalog-wide checks (coverage, staleness, perturbations) are in
//! `povray_gate.rs` and `mitsuba_gate.rs`.

use conformance::catalog::repo_root;
use conformance::gate::{check, failure_dir, key};
use conformance::manifest::Manifest;
use conformance::registry::Registry;
use conformance::verdict::Verdict;
use conformance::waivers::Waivers;
use libtest_mimic::{Arguments, Completion, Failed, Trial};
use std::sync::Arc;

fn main() {
    let mut args = Arguments::from_args();
    let manifest = Arc::new(
        Manifest::load(&repo_root().join("references/manifest.toml"))
            .expect("references/manifest.toml must load"),
    );
    let waivers = Arc::new(Waivers::committed().expect("conformance/waivers.toml must load"));
    let registry = Registry::committed();
    let mut trials = Vec::new();
    let mut names = Vec::new();
    for r in registry.iter() {
        let reference = r.name();
        for entry in registry
            .scenes(r)
            .expect("the catalog folders must be readable")
        {
            names.push(format!("{reference}/{}", entry.name));
            let (manifest, waivers) = (manifest.clone(), waivers.clone());
            trials.push(Trial::ignorable_test(
                format!("{reference}::{}", entry.name),
                move || {
                    let j = check(r, &entry, &manifest, &waivers)
                        .map_err(|e| Failed::from(format!("{reference}/{}: {e:#}", entry.name)))?;
                    match (j.accepted(), j.verdict) {
                        (true, Verdict::Pass) => {
                            // Failure images of an earlier run would mislead.
                            let _ = std::fs::remove_dir_all(failure_dir(&key(&*j.checked)));
                            Ok(Completion::Completed)
                        }
                        (true, _) => Ok(Completion::ignored_with(format!(
                            "WAIVED: {}",
                            j.waived
                                .iter()
                                .map(|w| w.to_string())
                                .collect::<Vec<_>>()
                                .join("; ")
                        ))),
                        (false, _) => Err(j.failure_message().into()),
                    }
                },
            ));
        }
    }
    let w = waivers.clone();
    trials.push(Trial::test(
        "catalog::waivers_name_catalog_scenes",
        move || {
            let unknown: Vec<String> = w
                .list
                .iter()
                .filter(|x| !names.contains(&x.scene))
                .map(|x| {
                    format!(
                        "{}:{}: no catalog scene {}",
                        w.path.display(),
                        x.line,
                        x.scene
                    )
                })
                .collect();
            if unknown.is_empty() {
                Ok(())
            } else {
                Err(unknown.join("\n").into())
            }
        },
    ));
    if let Some(filter) = args.filter.clone().filter(|_| !args.exact) {
        if let Ok(chosen) = registry.select(&filter) {
            let names: Vec<String> = chosen
                .iter()
                .map(|(r, e)| format!("{}::{}", r.name(), e.name))
                .collect();
            let scene_test = |n: &str| {
                registry
                    .names()
                    .iter()
                    .any(|r| n.starts_with(&format!("{r}::")))
            };
            trials.retain(|t| {
                let n = t.name();
                names.iter().any(|c| c == n) || (!scene_test(n) && n.contains(&filter))
            });
            args.filter = None;
        }
    }
    libtest_mimic::run(&args, trials).exit();
}
