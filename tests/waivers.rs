//! Waivers and failure output, end to end on a real comparison: a deliberate divergence is
//! WAIVED (never a pass), a waiver whose check passes again is stale and rejected, a stale
//! reference is never waived, and a failing scene's message names pixels and failure
//! images that exist.

use conformance::catalog::{load, repo_root, scenes};
use conformance::gate::{judge, Judged};
use conformance::povray::harness::{compare_render, read_reference};
use conformance::povray::outcome::Outcome;
use conformance::verdict::Verdict;
use conformance::waivers::Waivers;
use renderer::render::{render, Options};
use std::path::Path;

const SCENE: &str = "shade_phong";

/// `shade_phong` against its reference, with its light's colour scaled by `light`.
fn outcome(light: f32, verdict_if_fails: Verdict) -> Outcome {
    let e = scenes("povray", SCENE)
        .unwrap()
        .into_iter()
        .find(|e| e.name == SCENE)
        .unwrap();
    let (mut s, _) = load(&e).unwrap();
    s.lights[0].color *= light;
    let ours = render(&s, &Options::default());
    let (_, _, rgb) =
        read_reference(&repo_root().join(format!("references/povray/{SCENE}.exr"))).unwrap();
    let cmp = compare_render(&s, &Options::default(), &ours, &rgb);
    Outcome {
        scene: SCENE.into(),
        verdict: if cmp.passed() {
            Verdict::Pass
        } else {
            verdict_if_fails
        },
        cmp: Some(cmp),
        ours,
        reference_rgb: Some(rgb),
        seconds: 0.0,
    }
}

fn waivers(check: &str) -> Waivers {
    Waivers::parse(
        &format!(
            "# test\n[[waiver]]\nscene = \"povray/{SCENE}\"\ncheck = \"{check}\"\nreason = \"a test of waivers\"\ndate = \"2026-11-24\"\n"
        ),
        Path::new("conformance/waivers.toml"),
    )
    .unwrap()
}

/// A folder for failure images the test does not look at.
fn scratch() -> std::path::PathBuf {
    std::env::temp_dir().join(format!("waivers-scratch-{}", std::process::id()))
}

fn judged(light: f32, w: &Waivers) -> Judged {
    judge(Box::new(outcome(light, Verdict::Fail)), w)
}

#[test]
fn test01_a_waived_failure_is_waived_never_a_pass() {
    let j = judged(1.05, &waivers("pixels"));
    assert_eq!(j.verdict, Verdict::Waived, "{}", j.checked.metrics());
    assert!(j.accepted(), "a waived failure is accepted by the gate");
    assert!(j.stale_waivers.is_empty());
    let m = j.failure_message_to(&scratch());
    assert!(
        m.contains("WAIVED (conformance/waivers.toml:2): pixels check waived since 2026-11-24: a test of waivers"),
        "{m}"
    );
}

#[test]
fn test02_without_a_waiver_the_failure_names_pixels_and_images_that_exist() {
    let j = judged(1.05, &Waivers::default());
    assert_eq!(j.verdict, Verdict::Fail);
    assert!(!j.accepted());
    // Not the gate's own folder, which the catalog test clears when the scene passes.
    let dir = std::env::temp_dir().join(format!("waivers-test-{}", std::process::id()));
    let m = j.failure_message_to(&dir);
    assert!(m.starts_with("povray/shade_phong: FAIL\n"), "{m}");
    let pixels = m
        .lines()
        .filter(|l| l.trim_start().starts_with('(') && l.contains("FAILING"))
        .count();
    assert!(
        pixels >= 5,
        "at least 5 worst pixels with coordinates:\n{m}"
    );
    assert!(
        m.contains("cargo run --release -p conformance -- run shade_phong"),
        "{m}"
    );
    let images: Vec<&str> = m
        .lines()
        .map(str::trim)
        .filter(|l| l.ends_with(".png") || l.ends_with(".exr"))
        .collect();
    for name in ["ours", "reference", "difference"] {
        for ext in ["exr", "png"] {
            let f = images
                .iter()
                .find(|p| p.ends_with(&format!("/{name}.{ext}")))
                .unwrap_or_else(|| panic!("no {name}.{ext} in the message:\n{m}"));
            assert!(Path::new(f).is_file(), "{f} is named but does not exist");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test03_a_waiver_of_a_passing_check_is_stale_and_rejected() {
    let j = judged(1.0, &waivers("pixels"));
    assert_eq!(j.verdict, Verdict::Pass);
    assert_eq!(j.stale_waivers.len(), 1);
    assert!(
        !j.accepted(),
        "a stale waiver must fail the gate until it is removed"
    );
    let m = j.failure_message_to(&scratch());
    assert!(
        m.contains("STALE WAIVER: the `pixels` check passes again; remove the entry at conformance/waivers.toml:2"),
        "{m}"
    );
}

#[test]
fn test04_a_stale_reference_is_never_waived() {
    let j = judge(Box::new(outcome(1.05, Verdict::Stale)), &waivers("pixels"));
    assert_eq!(j.verdict, Verdict::Stale);
    assert!(!j.accepted());
    assert!(j
        .failure_message_to(&scratch())
        .contains("scripts/regen-povray.sh shade_phong"));
}

#[test]
fn test05_the_committed_waivers_load() {
    Waivers::committed().expect("conformance/waivers.toml must parse");
}
