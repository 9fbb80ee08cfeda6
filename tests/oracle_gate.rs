//! The catalog-wide checks of the closed-form oracle (conformance/docs/oracle.md): it
//! covers every classic scene but those it cannot model, and on each it covers, our
//! renderer, POV-Ray and the oracle agree pairwise. A failure names the scene, the pair
//! that disagrees and its worst pixels with all three values.

use conformance::catalog::{load, repo_root, scenes};
use conformance::oracle::vote::vote;
use conformance::oracle::Oracle;

/// The scenes the oracle declines, and why: POV-Ray's smooth meshes.
const DECLINED: [&str; 7] = [
    "prim_mesh_identity",
    "prim_mesh_mirror",
    "prim_mesh_nonuniform",
    "prim_mesh_rotate",
    "prim_mesh_scale",
    "prim_mesh_shear",
    "prim_mesh_translate",
];

#[test]
fn test01_the_oracle_covers_every_classic_scene_but_the_smooth_meshes() {
    let mut declined = Vec::new();
    for e in scenes("povray", "").unwrap() {
        let (scene, _) = load(&e).unwrap();
        if let Err(why) = Oracle::new(&scene) {
            declined.push(format!("{}: {why}", e.name));
        }
    }
    let names: Vec<&str> = declined.iter().map(|d| d.split(':').next().unwrap()).collect();
    assert_eq!(
        names, DECLINED,
        "the oracle's coverage changed; it declines:\n{}",
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
        if !v.passed() || !v.ours_povray.passed() {
            failures += &v.failure_message(5);
        }
    }
    assert_eq!(covered, 92, "covered scenes");
    assert!(failures.is_empty(), "three-way disagreements:\n{failures}");
}
