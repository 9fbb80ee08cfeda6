//! The scale-extreme family (`conformance/scenes/scale/`, issue 37) against the f64 build.
//!
//! POV-Ray itself loses precision on a sphere of radius 1e6, so for these scenes the
//! references are our own f64 build's renders (`references/scale/<scene>.exr`, RGB and
//! AOVs at pixel centres) and the closed form (renderer/tests/scale_extremes.rs). This
//! build must match the f64 render with the catalog's comparison: colour within the
//! POV-Ray tolerance, excused only by geometry and within the budget
//! (conformance/docs/tolerances.md), object ids (so hit or miss) exactly, and depth
//! within a relative 1e-5. In the f32 build the huge grounds are intersected in mixed
//! precision (renderer/docs/precision.md, "Scale against view"); without it, every
//! planet pixel is ~1 % off in depth.
//!
//! The references are written by the f64 build: `SCALE_REFS=write cargo test --features
//! f64 --test scale_extremes`.

use conformance::catalog::repo_root;
use conformance::povray::harness::compare_render;
use renderer::output::{read_exr, write_exr};
use renderer::render::{render, Options};
use renderer::scene::Scene;

const DEPTH: f64 = 1e-5;

fn check(name: &str) {
    let root = repo_root();
    let scene_path = root.join(format!("conformance/scenes/scale/{name}.toml"));
    let reference = root.join(format!("references/scale/{name}.exr"));
    let scene = Scene::load(&scene_path).unwrap_or_else(|e| panic!("{e}"));
    let opts = Options {
        aov: true,
        ..Options::default()
    };
    let img = render(&scene, &opts);
    assert_eq!(img.non_finite, 0, "{name}: non-finite pixels");
    if std::env::var("SCALE_REFS").as_deref() == Ok("write") {
        assert_eq!(
            renderer::real::PRECISION,
            "f64",
            "the scale family's references are the f64 build's renders"
        );
        std::fs::create_dir_all(reference.parent().unwrap()).unwrap();
        write_exr(&img, &reference).unwrap();
        println!("wrote {}", reference.display());
        return;
    }
    let exr = read_exr(&reference).unwrap_or_else(|e| {
        panic!(
            "{}: {e:#}; write it with `SCALE_REFS=write cargo test --features f64 --test scale_extremes`",
            reference.display()
        )
    });
    let chan = |n: &str| {
        exr.channel(n)
            .unwrap_or_else(|| panic!("{name}: reference has no {n}"))
            .to_vec()
    };
    let (r, g, b) = (chan("R"), chan("G"), chan("B"));
    let rgb: Vec<f32> = (0..r.len()).flat_map(|k| [r[k], g[k], b[k]]).collect();
    let cmp = compare_render(&scene, &opts, &img, &rgb);
    let aov = img.aov.as_ref().unwrap();
    let (ids, z) = (chan("objectId"), chan("Z"));
    let mut wrong = Vec::new();
    let w = img.width as usize;
    for k in 0..ids.len() {
        let (i, j) = (k % w, k / w);
        if aov.object_id[k] != ids[k] {
            wrong.push(format!(
                "({i}, {j}): object {} where the f64 build has {}",
                aov.object_id[k], ids[k]
            ));
        } else if ids[k] != 0.0 {
            let e = ((aov.z[k] as f64) - z[k] as f64).abs() / z[k] as f64;
            if e > DEPTH {
                wrong.push(format!(
                    "({i}, {j}): depth {} where the f64 build has {} (relative {e:.1e})",
                    aov.z[k], z[k]
                ));
            }
        }
    }
    println!(
        "{name}: colour max abs {:.2e}, {} failing, {} excused; {} id or depth differences",
        cmp.max_abs,
        cmp.failing,
        cmp.silhouette,
        wrong.len()
    );
    assert!(
        cmp.passed() && wrong.is_empty(),
        "{name} differs from the f64 build's render ({}): {} failing and {} excused pixels (budget {}), \
{} id or depth differences (beyond {DEPTH} relative):\n{}\n(renderer/src/shapes/anchored.rs, \
renderer/src/scene/scale_check.rs)",
        reference.display(),
        cmp.failing,
        cmp.silhouette,
        cmp.budget(),
        wrong.len(),
        wrong.iter().take(12).cloned().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn test01_planet_sphere() {
    check("scale_planet_sphere");
}

#[test]
fn test02_ground_box() {
    check("scale_ground_box");
}

#[test]
fn test03_ground_cylinder() {
    check("scale_ground_cylinder");
}

#[test]
fn test04_sea_disk() {
    check("scale_sea_disk");
}

#[test]
fn test05_mesh_planet() {
    check("scale_mesh_planet");
}
