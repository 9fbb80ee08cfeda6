//! Localized sensitivity: faults that change only a small part of an image must fail the
//! comparison with failing pixels, not merely by exceeding the silhouette budget. Each test
//! checks that the unchanged scene passes, injects one fault into the built scene or the
//! render options, and requires failing pixels. The figures, and whether each fault would
//! have passed the earlier colour-range classification, are in
//! conformance/docs/tolerances.md.

use conformance::catalog::{load, repo_root, scenes, Entry};
use conformance::mitsuba::compare::{geometry_test, GeometryTest};
use conformance::mitsuba::harness::{our_geometry, read_geometry};
use conformance::povray::compare::Comparison;
use conformance::povray::harness::{compare_render, read_reference, retrace};
use glam::{DMat3, DVec3};
use renderer::aggregate::Shape;
use renderer::aggregate::{Aggregate, Instance};
use renderer::camera::{Camera, Window};
use renderer::render::{render, Options};
use renderer::scene::{Material, Scene};
use renderer::spawn::Spawn;
use renderer::transform::{Affine64, Transform};

fn entry(reference: &str, name: &str) -> Entry {
    scenes(reference, name)
        .unwrap()
        .into_iter()
        .find(|e| e.name == name)
        .unwrap_or_else(|| panic!("no catalog scene {reference}/{name}"))
}

fn scene(name: &str) -> Scene {
    load(&entry("povray", name)).unwrap().0
}

/// Renders `scene` with `opts` and compares it with the named scene's POV-Ray reference.
fn against(scene: &Scene, opts: &Options, name: &str) -> Comparison {
    let (_, _, rgb) = read_reference(
        &repo_root()
            .join("references/povray")
            .join(format!("{name}.exr")),
    )
    .unwrap();
    compare_render(scene, opts, &render(scene, opts), &rgb)
}

fn summary(c: &Comparison) -> String {
    format!(
        "{} failing, {} excused ({}), budget {}",
        c.failing,
        c.silhouette,
        c.excused,
        c.budget()
    )
}

/// Requires the unchanged scene to pass and the faulty one to have failing pixels.
fn assert_caught(fault: &str, name: &str, good: &Comparison, bad: &Comparison) {
    assert!(
        good.passed(),
        "{name} must pass before the fault is injected: {}",
        summary(good)
    );
    eprintln!("{fault}, {name}: {}", summary(bad));
    assert!(
        bad.failing > 0 && !bad.passed(),
        "{name}: {fault} was not caught by failing pixels: {}",
        summary(bad)
    );
}

/// The index of a material by its name in the scene file.
fn material(s: &Scene, name: &str) -> usize {
    s.materials
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| panic!("no material {name}"))
}

#[test]
fn test01_the_retrace_reproduces_every_catalog_pixel() {
    // The comparison excuses a pixel from samples traced again at sub-pixel positions; they
    // must come from the image's own render path, so at the pixel centre they must give
    // the image's bits.
    let mut bad = Vec::new();
    for e in scenes("povray", "").unwrap() {
        let (s, _) = load(&e).unwrap();
        let opts = Options::default();
        let img = render(&s, &opts);
        let trace = retrace(&s, &opts);
        let (w, h) = (img.width as usize, img.height as usize);
        let differ = (0..w * h)
            .filter(|&k| {
                let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
                trace(x, y).rgb != [img.rgb[3 * k], img.rgb[3 * k + 1], img.rgb[3 * k + 2]]
            })
            .count();
        if differ > 0 {
            bad.push(format!("{}: {differ} pixels", e.name));
        }
    }
    assert!(
        bad.is_empty(),
        "the re-trace differs from the render:\n{}",
        bad.join("\n")
    );
}

/// Requires `fault`, applied to the named material of `name`, to be caught.
fn assert_material_fault_caught(
    name: &str,
    material_name: &str,
    fault: &str,
    f: fn(&mut Material),
) {
    let mut s = scene(name);
    let opts = Options::default();
    let good = against(&s, &opts, name);
    let k = material(&s, material_name);
    f(&mut s.materials[k]);
    assert_caught(fault, name, &good, &against(&s, &opts, name));
}

#[test]
fn test02_a_phong_exponent_2_percent_off_on_one_small_sphere_fails() {
    assert_material_fault_caught(
        "loc_small_objects",
        "shiny",
        "phong_size 2 % off on the small sphere",
        |m| m.phong_size *= 1.02,
    );
}

#[test]
fn test03_an_ior_1_percent_off_on_one_glass_sphere_fails() {
    assert_material_fault_caught(
        "loc_small_objects",
        "glass",
        "ior 1 % off on the glass sphere",
        |m| m.ior *= 1.01,
    );
}

#[test]
fn test04_a_light_moved_by_1_percent_of_its_distance_fails() {
    // The faded pool light, 0.4 above the floor it lights, moved 0.004 sideways.
    let name = "loc_small_objects";
    let mut s = scene(name);
    let opts = Options::default();
    let good = against(&s, &opts, name);
    let pool = s
        .lights
        .iter()
        .position(|l| l.fade.is_some())
        .expect("the pool light fades");
    let height = s.lights[pool].position.y as f64 + 1.0;
    assert!((height - 0.4).abs() < 1e-6, "the pool light is 0.4 up");
    s.lights[pool].position.x += (0.01 * height) as renderer::Real;
    assert_caught(
        "pool light moved by 1 % of its height",
        name,
        &good,
        &against(&s, &opts, name),
    );
}

#[test]
fn test05_a_shadow_tolerance_ten_times_too_large_fails() {
    // POV-Ray ignores shadow-ray hits closer than 1e-3 to the ray's start. The disk floats
    // 0.005 above the floor, so the floor's shadow rays meet it 0.0075 away: a tolerance
    // of 1e-2 loses the sliver of shadow that shows beside the rim. (The scene has no
    // reflection or refraction, so `Spawn::Fixed` changes only the shadow rays.)
    let name = "loc_contact_shadow";
    let s = scene(name);
    let with = |eps| Options {
        spawn: Spawn::Fixed(eps),
        ..Options::default()
    };
    assert_caught(
        "shadow tolerance 1e-2 instead of 1e-3",
        name,
        &against(&s, &with(1e-3), name),
        &against(&s, &with(1e-2), name),
    );
}

#[test]
fn test06_the_pixel_centre_moved_by_a_fiftieth_of_a_pixel_fails() {
    // Scenes the earlier colour-range classification passed (the box) or failed only by
    // the budget (the cylinder, the rectangle).
    for name in [
        "prim_box_rotate",
        "prim_cylinder_identity",
        "prim_rectangle_identity",
    ] {
        let mut s = scene(name);
        let opts = Options::default();
        let good = against(&s, &opts, name);
        let mut m = s.camera.model;
        let shift = 0.02 * (m.window.right - m.window.left) / m.cols as f64;
        m.window = Window {
            left: m.window.left + shift,
            right: m.window.right + shift,
            ..m.window
        };
        s.camera = Camera::new(m).unwrap();
        assert_caught(
            "pixel centre moved 0.02 px",
            name,
            &good,
            &against(&s, &opts, name),
        );
    }
}

/// `scene` with one instance's `world_from_object` matrix entry (row, column; column 3 is
/// the translation) changed by `delta`.
fn with_entry_changed(s: &Scene, object_id: u32, row: usize, col: usize, delta: f64) -> Aggregate {
    let mut instances: Vec<Instance> = s.root.in_scene_order().cloned().collect();
    let inst = instances
        .iter_mut()
        .find(|i| i.object_id == object_id)
        .expect("the instance");
    let xf = inst.xf.as_ref().expect("a placed instance");
    let m = xf.matrix();
    let mut a = Affine64 {
        m: DMat3::from_cols_array(&m.to_cols_array().map(|v| v as f64)),
        d: renderer::real::dvec3(xf.translation()),
    };
    if col == 3 {
        a.d[row] += delta;
    } else {
        let mut c = a.m.col(col);
        c[row] += delta;
        a.m = DMat3::from_cols(
            if col == 0 { c } else { a.m.col(0) },
            if col == 1 { c } else { a.m.col(1) },
            if col == 2 { c } else { a.m.col(2) },
        );
    }
    inst.xf = Some(Transform::new(&a).unwrap());
    Aggregate::new(instances)
}

#[test]
fn test07_one_instance_transform_entry_off_by_1e3_fails() {
    // One of the 60 posts of hier_instanced (the fifth of the front row), each of the 12
    // entries of its world_from_object matrix in turn (column 3 is the translation).
    let name = "hier_instanced";
    let s = scene(name);
    let opts = Options::default();
    let post = 6;
    let mut t = scene(name);
    t.root = with_entry_changed(&s, post, 0, 0, 0.0);
    let good = against(&t, &opts, name);
    for row in 0..3 {
        for col in 0..4 {
            t.root = with_entry_changed(&s, post, row, col, 1e-3);
            assert_caught(
                &format!("entry ({row}, {col}) of one instance's matrix off by 1e-3"),
                name,
                &good,
                &against(&t, &opts, name),
            );
        }
    }
}

/// `scene` with every box replaced by its six faces as rectangles, with the outward
/// normal of the face `flip` (0..6: +x, −x, +y, −y, +z, −z), if any, pointing inward.
fn boxes_as_faces(s: &Scene, flip: Option<usize>) -> Aggregate {
    let quarter = std::f64::consts::FRAC_PI_2;
    // Each face: the rotation taking the rectangle's normal +y to the face normal, and the
    // face's centre.
    let faces = [
        (DMat3::from_rotation_z(-quarter), DVec3::X),
        (DMat3::from_rotation_z(quarter), -DVec3::X),
        (DMat3::IDENTITY, DVec3::Y),
        (DMat3::from_rotation_x(2.0 * quarter), -DVec3::Y),
        (DMat3::from_rotation_x(quarter), DVec3::Z),
        (DMat3::from_rotation_x(-quarter), -DVec3::Z),
    ];
    let mut out = Vec::new();
    for inst in s.root.in_scene_order() {
        if !matches!(inst.shape, Shape::Cube) {
            out.push(inst.clone());
            continue;
        }
        let world = inst.xf.as_ref().map_or(Affine64::IDENTITY, |x| Affine64 {
            m: DMat3::from_cols_array(&x.matrix().to_cols_array().map(|v| v as f64)),
            d: renderer::real::dvec3(x.translation()),
        });
        for (k, (rot, centre)) in faces.iter().enumerate() {
            // Mirroring y first keeps the rectangle in place and turns its normal over.
            let m = if flip == Some(k) {
                *rot * DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0))
            } else {
                *rot
            };
            let face = world.compose(&Affine64 { m, d: *centre });
            out.push(Instance {
                shape: Shape::Rectangle,
                xf: Some(Transform::new(&face).unwrap()),
                ..inst.clone()
            });
        }
    }
    Aggregate::new(out)
}

/// Our pixel-centre geometry of `scene` against the named Mitsuba geometry reference.
fn geometry_against(scene: &Scene, name: &str) -> GeometryTest {
    let m = conformance::manifest::Manifest::load(&repo_root().join("references/manifest.toml"))
        .unwrap();
    let rec = &m.reference[&format!("mitsuba-geometry/{name}")];
    let reference = read_geometry(&repo_root().join("references").join(&rec.file)).unwrap();
    let opts = Options {
        aov: true,
        samples: Some(1),
        ..Options::default()
    };
    geometry_test(&our_geometry(&render(scene, &opts)), &reference)
}

#[test]
fn test08_one_box_face_normal_flipped_fails() {
    // POV-Ray's classic model turns every normal towards the incoming ray, and so do the
    // classic shader, its shadow rays and its ray offsets: a flipped normal cannot change a
    // classic image, which this checks bit for bit. The physical model and its geometry
    // channels do depend on orientation, so the fault is caught against Mitsuba's
    // pixel-centre normals, on the sheared box of mi_transformed (its top face, +y).
    let name = "prim_box_rotate";
    let mut s = scene(name);
    s.root = boxes_as_faces(&s, None);
    let straight = render(&s, &Options::default());
    s.root = boxes_as_faces(&s, Some(2));
    assert_eq!(
        straight.rgb,
        render(&s, &Options::default()).rgb,
        "a flipped normal changed a classic image"
    );

    let name = "mi_transformed";
    let mut s = load(&entry("mitsuba", name)).unwrap().0;
    let original = s.root.in_scene_order().cloned().collect::<Vec<_>>();
    let g = geometry_against(&s, name);
    assert!(g.passed(), "{name} geometry passes: {g:?}");
    s.root = boxes_as_faces(&s, None);
    let faces = geometry_against(&s, name);
    assert!(
        faces.passed(),
        "{name} with the box as six faces passes: {faces:?}"
    );
    s.root = Aggregate::new(original);
    s.root = boxes_as_faces(&s, Some(2));
    let bad = geometry_against(&s, name);
    eprintln!("box face normal flipped, {name}: {bad:?}");
    assert!(
        bad.failing > 0 && !bad.passed(),
        "{name}: a flipped box face normal passed the geometry test: {bad:?}"
    );
}
