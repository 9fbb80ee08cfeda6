//! The catalog-wide checks of the closed-form oracle (conformance/docs/oracle.md): it
//! covers every classic scene, and on each our renderer, POV-Ray and the oracle agree
//! pairwise; on the scale family, which has no POV-Ray reference, ours agrees with it. A
//! failure names the scene, the pair that disagrees and its worst pixels with all three
//! values.

use conformance::catalog::{load, repo_root, scenes};
use conformance::oracle::vote::vote;
use conformance::oracle::Oracle;

#[test]
fn test01_the_oracle_covers_every_classic_scene() {
    let mut declined = Vec::new();
    for e in scenes("povray", "").unwrap() {
        let (scene, _) = load(&e).unwrap();
        if let Err(why) = Oracle::new(&scene) {
            declined.push(format!("{}: {why}", e.name));
        }
    }
    assert!(
        declined.is_empty(),
        "the oracle's coverage shrank; it declines:\n{}",
        declined.join("\n")
    );
}

#[test]
fn test02_ours_povray_and_the_oracle_agree_on_every_covered_scene() {
    let mut failures = String::new();
    let mut covered = 0;
    for e in scenes("povray", "").unwrap() {
        let reference = repo_root()
            .join("references/povray")
            .join(format!("{}.exr", e.name));
        let Ok(v) = vote(&e, &reference).unwrap() else {
            continue;
        };
        covered += 1;
        if !v.passed() || !v.ours_povray.as_ref().is_some_and(|c| c.passed()) {
            failures += &v.failure_message(5);
        }
    }
    assert_eq!(covered, 99, "covered scenes");
    assert!(failures.is_empty(), "three-way disagreements:\n{failures}");
}

/// The scale-extreme family (grounds of size 1e6, renderer/docs/precision.md) has no
/// POV-Ray reference, because POV-Ray loses precision there: the oracle, exact at that
/// scale, is the independent check of its shading, beside the closed-form depths of
/// `renderer/tests/scale_extremes.rs` and the f64 build's renders of `scale_extremes.rs`.
#[test]
fn test03_ours_agrees_with_the_oracle_on_the_scale_family() {
    use conformance::povray::harness::{compare_render, render_for_conformance};
    let dir = repo_root().join("conformance/scenes/scale");
    let mut failures = String::new();
    let mut covered = Vec::new();
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    for path in names {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let text = std::fs::read_to_string(&path).unwrap();
        let scene = renderer::scene::Scene::from_str(&text, &path, &dir).unwrap();
        let Ok(oracle) = Oracle::new(&scene) else {
            continue;
        };
        covered.push(name.clone());
        let ours = render_for_conformance(&scene);
        let exact = oracle.render();
        let c = compare_render(&scene, &Default::default(), &ours, &exact);
        if !c.passed() {
            let w = c.size.0;
            let k = c.class.iter().position(|&k| k == 2).unwrap_or(0);
            failures += &format!(
                "{name}: ours~oracle DISAGREE: {} failing, {} excused (budget {}); first failing pixel ({}, {}): ours {:?}, oracle {:?}\n",
                c.failing,
                c.silhouette,
                c.budget(),
                k % w,
                k / w,
                &ours.rgb[3 * k..3 * k + 3],
                &exact[3 * k..3 * k + 3]
            );
        }
    }
    assert_eq!(
        covered,
        [
            "scale_ground_box",
            "scale_ground_cylinder",
            "scale_mesh_planet",
            "scale_planet_sphere",
            "scale_sea_disk"
        ],
        "the scale scenes the oracle covers"
    );
    assert!(failures.is_empty(), "{failures}");
}
