//! The gate against POV-Ray: every catalog scene agrees with its committed reference, a
//! stale reference is never a pass, and the comparison is tight enough to catch a
//! half-pixel shift, a 1 % change in a light and a 1° rotation of one object.

use conformance::catalog::load;
use conformance::catalog::{repo_root, scenes, Entry};
use conformance::manifest::Manifest;
use conformance::povray::compare::Comparison;
use conformance::povray::harness::{
    check_povray, compare_render, read_reference, render_for_conformance,
};
use conformance::verdict::Verdict;
use glam::DMat3;
use renderer::aggregate::Aggregate;
use renderer::camera::{Camera, Window};
use renderer::scene::Scene;
use renderer::transform::{Affine64, Transform};

fn manifest() -> Manifest {
    Manifest::load(&repo_root().join("references/manifest.toml")).unwrap()
}

fn entry(name: &str) -> Entry {
    scenes("povray", name)
        .unwrap()
        .into_iter()
        .find(|e| e.name == name)
        .unwrap()
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

#[test]
fn test01_every_catalog_scene_passes_against_povray() {
    let m = manifest();
    let all = scenes("povray", "").unwrap();
    let mut bad = Vec::new();
    for e in &all {
        let o = check_povray(e, &m).unwrap();
        if o.verdict != Verdict::Pass {
            let detail = o
                .cmp
                .map(|c| {
                    format!(
                        "{} failing, {} silhouette (budget {}), max abs {:.2e}",
                        c.failing,
                        c.silhouette,
                        c.budget(),
                        c.max_abs
                    )
                })
                .unwrap_or_default();
            bad.push(format!("{}: {} {detail}", e.name, o.verdict));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {} scenes do not pass:\n{}",
        bad.len(),
        all.len(),
        bad.join("\n")
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
    let o = check_povray(
        &Entry {
            name: e.name.clone(),
            path,
        },
        &manifest(),
    )
    .unwrap();
    assert!(o.cmp.as_ref().unwrap().passed(), "the pixels still agree");
    assert_eq!(o.verdict, Verdict::Stale);
    // And a scene with no record is missing, not passing.
    let mut m = manifest();
    m.reference.remove("povray/prim_sphere_identity");
    assert_eq!(check_povray(&e, &m).unwrap().verdict, Verdict::Missing);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test04_a_half_pixel_shift_of_the_window_fails() {
    for name in ["hier_three_levels", "shade_diffuse", "cam_oblique_roll"] {
        let (mut s, _) = load(&entry(name)).unwrap();
        assert!(
            against_reference(&s, name).passed(),
            "{name} passes unshifted"
        );
        let mut m = s.camera.model;
        let half = 0.5 * (m.window.right - m.window.left) / m.cols as f64;
        m.window = Window {
            left: m.window.left + half,
            right: m.window.right + half,
            ..m.window
        };
        s.camera = Camera::new(m).unwrap();
        let c = against_reference(&s, name);
        eprintln!(
            "half-pixel shift, {name}: {} failing, {} silhouette (budget {})",
            c.failing,
            c.silhouette,
            c.budget()
        );
        assert!(
            !c.passed(),
            "{name}: a half-pixel shift passed ({} failing, {} silhouette)",
            c.failing,
            c.silhouette
        );
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
        s.lights[0].color *= 1.01;
        let c = against_reference(&s, name);
        eprintln!(
            "1 % light, {name}: {} failing, {} silhouette (budget {})",
            c.failing,
            c.silhouette,
            c.budget()
        );
        assert!(!c.passed(), "{name}: a 1 % brighter light passed");
        assert!(c.failing > 100, "{name}: only {} failing pixels", c.failing);
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
        let c = against_reference(&s, name);
        eprintln!(
            "1° rotation, {name}: {} failing, {} silhouette (budget {})",
            c.failing,
            c.silhouette,
            c.budget()
        );
        assert!(
            !c.passed(),
            "{name}: a 1° rotation passed ({} failing, {} silhouette)",
            c.failing,
            c.silhouette
        );
    }
}
