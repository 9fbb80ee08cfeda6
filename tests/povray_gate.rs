//! The catalog-wide checks against POV-Ray: the catalog covers what it must, a stale
//! reference is never a pass, and the comparison is tight enough to catch a half-pixel
//! shift, a 1 % change in a light and a 1° rotation of one object. Each perturbation test
//! first requires the unperturbed scene to pass, then requires the perturbed one to fail,
//! and says which it was when it does not. (One test per catalog scene is in
//! `catalog.rs`.)

use conformance::catalog::load;
use conformance::catalog::{find, repo_root, scenes, Entry};
use conformance::manifest::Manifest;
use conformance::povray::compare::Comparison;
use conformance::povray::harness::{check, compare_render, read_reference, render_for_conformance};
use conformance::verdict::Verdict;
use glam::DMat3;
use renderer::aggregate::Aggregate;
use renderer::camera::{Camera, Window};
use renderer::scene::Scene;
use renderer::transform::{Affine64, Transform};

fn manifest() -> Manifest {
    Manifest::committed().unwrap()
}

fn entry(name: &str) -> Entry {
    find("povray", name).unwrap()
}

/// Renders a (modified) scene and compares it with the named scene's reference.
fn against_reference(scene: &Scene, name: &str) -> Comparison {
    let img = render_for_conformance(scene);
    let (_, _, rgb) = read_reference(
        &repo_root()
            .join("references/povray")
            .join(format!("{name}.exr")),
    )
    .unwrap();
    compare_render(scene, &Default::default(), &img, &rgb)
}

fn metrics(c: &Comparison) -> String {
    format!(
        "{} failing pixels, {} excused by geometry (budget {}), max abs {:.2e}",
        c.failing,
        c.silhouette,
        c.budget(),
        c.max_abs
    )
}

/// Requires the unperturbed scene to pass, so that a failure of the perturbed one means
/// the comparison saw the perturbation.
fn require_unperturbed_pass(scene: &Scene, name: &str, perturbation: &str) {
    let c = against_reference(scene, name);
    assert!(
        c.passed(),
        "{name}, before the {perturbation}: the unperturbed scene must pass against its reference \
(see `cargo test --test catalog {name}`), but it has {}",
        metrics(&c)
    );
}

/// Requires the perturbed scene to fail.
fn require_failure(c: &Comparison, name: &str, perturbation: &str) {
    eprintln!("{perturbation}, {name}: {}", metrics(c));
    assert!(
        !c.passed(),
        "{name} with a {perturbation}: expected the comparison with the unperturbed scene's \
reference to fail, but it passed ({}). The comparison has become too lenient: see \
conformance/src/povray/compare.rs and conformance/docs/tolerances.md",
        metrics(c)
    );
}

#[test]
fn test02_catalog_covers_the_required_features() {
    let names: Vec<String> = scenes("povray", "")
        .unwrap()
        .into_iter()
        .map(|e| e.name)
        .collect();
    let has = |n: &str| names.iter().any(|x| x == n);
    assert!(names.iter().filter(|n| n.starts_with("cam_")).count() >= 8);
    for p in [
        "sphere",
        "plane",
        "box",
        "cylinder",
        "cylopen",
        "cone",
        "disk",
        "rectangle",
        "triangle",
        "mesh",
    ] {
        for t in [
            "identity",
            "translate",
            "rotate",
            "scale",
            "nonuniform",
            "shear",
            "mirror",
        ] {
            assert!(has(&format!("prim_{p}_{t}")), "prim_{p}_{t} is missing");
        }
    }
    for n in [
        "hier_three_levels",
        "hier_instanced",
        "shade_ambient",
        "shade_diffuse",
        "shade_brilliance",
        "shade_phong",
        "shade_specular",
        "shade_shadows_two_lights",
        "shade_reflection_chain",
        "shade_refract_sphere",
        "shade_refract_slab",
        "shade_total_internal",
    ] {
        assert!(has(n), "{n} is missing");
    }
    // The non-square pixel array really is non-square.
    let (s, _) = load(&entry("cam_nonsquare")).unwrap();
    let w = s.camera.model.window;
    let pixel_aspect = ((w.right - w.left) / s.settings.width as f64)
        / ((w.top - w.bottom) / s.settings.height as f64);
    assert!(
        (pixel_aspect - 0.5).abs() < 1e-12,
        "pixels are 2:1 tall, got aspect {pixel_aspect}"
    );
}

#[test]
fn test03_a_stale_reference_is_never_a_pass() {
    let e = entry("prim_sphere_identity");
    // The same scene with one more comment: the image is unchanged, the hash is not.
    let text = std::fs::read_to_string(&e.path).unwrap() + "\n# edited\n";
    let dir = std::env::temp_dir().join(format!("gate-stale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("prim_sphere_identity.toml");
    std::fs::write(&path, text).unwrap();
    let o = check(&Entry { path, ..e.clone() }, &manifest()).unwrap();
    let c = o.cmp.as_ref().unwrap();
    assert!(
        c.passed(),
        "prim_sphere_identity with a comment appended to its scene file (same image, new hash): \
expected its pixels to still agree with the reference, but the comparison has {}",
        metrics(c)
    );
    assert_eq!(
        o.verdict,
        Verdict::Stale,
        "prim_sphere_identity with a comment appended to its scene file: the scene's hash no \
longer matches references/manifest.toml, so the verdict must be STALE, never a pass"
    );
    // And a scene with no record is missing, not passing.
    let mut m = manifest();
    m.reference.remove("povray/prim_sphere_identity");
    assert_eq!(
        check(&e, &m).unwrap().verdict,
        Verdict::Missing,
        "prim_sphere_identity with its manifest record removed must be MISSING"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test04_a_half_pixel_shift_of_the_window_fails() {
    for name in ["hier_three_levels", "shade_diffuse", "cam_oblique_roll"] {
        let (mut s, _) = load(&entry(name)).unwrap();
        let what = "window shifted right by half a pixel";
        require_unperturbed_pass(&s, name, what);
        let mut m = s.camera.model;
        let half = 0.5 * (m.window.right - m.window.left) / m.cols as f64;
        m.window = Window {
            left: m.window.left + half,
            right: m.window.right + half,
            ..m.window
        };
        s.camera = Camera::new(m).unwrap();
        require_failure(&against_reference(&s, name), name, what);
    }
}

#[test]
fn test05_a_one_percent_change_in_a_light_fails() {
    for name in [
        "shade_shadows_two_lights",
        "prim_cone_rotate",
        "hier_instanced",
    ] {
        let (mut s, _) = load(&entry(name)).unwrap();
        let what = "first light 1 % brighter";
        require_unperturbed_pass(&s, name, what);
        s.lights[0].color *= 1.01;
        let c = against_reference(&s, name);
        require_failure(&c, name, what);
        assert!(
            c.failing > 100,
            "{name} with the {what}: expected more than 100 failing pixels (the light \
changes most of the image), got {}",
            metrics(&c)
        );
    }
}

#[test]
fn test06_a_one_degree_rotation_of_one_object_fails() {
    // (scene, object id): a box, the table top of the hierarchy, a faceted mesh. (A sphere
    // turned about its own centre would not change, so it is not a fair case.)
    for (name, id) in [
        ("prim_box_identity", 1),
        ("hier_three_levels", 2),
        ("prim_mesh_rotate", 1),
    ] {
        let (mut s, _) = load(&entry(name)).unwrap();
        let what = format!("1° rotation of object {id} about its vertical axis");
        require_unperturbed_pass(&s, name, &what);
        // Rotate the object by 1° about the vertical axis through its own origin.
        let mut instances = s.root.instances.clone();
        let inst = instances.iter_mut().find(|i| i.object_id == id).unwrap();
        let (m, d) = match &inst.xf {
            Some(x) => (x.matrix(), x.translation()),
            None => (renderer::real::Mat3::IDENTITY, renderer::Vec3::ZERO),
        };
        let m64 = DMat3::from_cols_array(&m.to_cols_array().map(|v| v as f64));
        let d64 = renderer::real::dvec3(d);
        let rot = Affine64::linear(DMat3::from_rotation_y(1f64.to_radians()));
        let placed = Affine64 { m: m64, d: d64 }.compose(&rot);
        inst.xf = Some(Transform::new(&placed).unwrap());
        s.root = Aggregate::new(instances);
        require_failure(&against_reference(&s, name), name, &what);
    }
}
