//! Precision is a property of the scene, not of where it sits: every POV-Ray catalog scene,
//! moved with its camera and lights by 10⁵, 10⁶ and 10⁷, still passes the gate's comparison
//! against the scene's own (unmoved) reference, in the f32 build too. The renderer moves
//! such a scene's origin to the eye before converting to its precision
//! (renderer/src/scene/build.rs, `render_origin`); without that, f32 loses the scene at
//! 10⁶ (renderer/docs/precision.md). The f64 build also renders the scene moved by 10⁷
//! like the unmoved one, to the last bits the comparison can see.

use conformance::catalog::{repo_root, scenes, Entry};
use conformance::povray::compare::Comparison;
use conformance::povray::harness::{compare_render, read_reference, render_for_conformance};
use renderer::render::Image;
use renderer::render::Options;
use renderer::scene::Scene;
use toml::Value;

/// The direction every scene is moved along (a generic one: no coordinate stays 0).
const DIRECTION: [f64; 3] = [1.0, 0.5, -0.75];

fn shift_point(v: &mut Value, off: [f64; 3]) {
    let arr = v.as_array_mut().expect("a point is an array of 3 numbers");
    for (x, o) in arr.iter_mut().zip(off) {
        let f = x
            .as_float()
            .or_else(|| x.as_integer().map(|i| i as f64))
            .unwrap();
        *x = Value::Float(f + o);
    }
}

/// The scene text moved by `off`: the camera's points, every point light, and every
/// top-level object (by one more translation after its own transform).
fn translated(text: &str, off: [f64; 3]) -> String {
    let mut doc: Value = toml::from_str(text).unwrap();
    let t = doc.as_table_mut().unwrap();
    let camera = t["camera"].as_table_mut().unwrap();
    for (form, fields) in camera.iter_mut() {
        let fields = fields.as_table_mut().unwrap();
        let points: &[&str] = match form.as_str() {
            "look_at" => &["from", "at"],
            "view" => &["vrp"],
            "povray" => &["location"],
            other => panic!("unknown camera form {other}"),
        };
        for p in points {
            shift_point(fields.get_mut(*p).unwrap(), off);
        }
    }
    if let Some(lights) = t.get_mut("lights").and_then(Value::as_array_mut) {
        for l in lights {
            if let Some(p) = l.get_mut("position") {
                shift_point(p, off);
            }
        }
    }
    for o in t["objects"].as_array_mut().unwrap() {
        let o = o.as_table_mut().unwrap();
        let mut op = toml::map::Map::new();
        op.insert(
            "translate".into(),
            Value::Array(off.iter().map(|&x| Value::Float(x)).collect()),
        );
        let ops = o
            .entry("transform")
            .or_insert_with(|| Value::Array(Vec::new()))
            .as_array_mut()
            .unwrap();
        ops.push(Value::Table(op));
    }
    toml::to_string(&doc).unwrap()
}

fn render_moved(e: &Entry, by: f64) -> (Scene, Image) {
    let text = std::fs::read_to_string(&e.path).unwrap();
    let off = DIRECTION.map(|x| x * by);
    let moved = translated(&text, off);
    let base = e.path.parent().unwrap();
    let scene = Scene::from_str(&moved, &e.path, base)
        .unwrap_or_else(|err| panic!("{} moved by {by:e}: {err}", e.name));
    let img = render_for_conformance(&scene);
    (scene, img)
}

fn describe(c: &Comparison) -> String {
    format!(
        "{} failing, {} silhouette (budget {}), max abs {:.2e}",
        c.failing,
        c.silhouette,
        c.budget(),
        c.max_abs
    )
}

#[test]
fn every_catalog_scene_moved_far_away_passes_against_its_reference() {
    let all = scenes("povray", "").unwrap();
    assert!(all.len() >= 90, "only {} catalog scenes", all.len());
    let mut bad = Vec::new();
    for by in [1e5, 1e6, 1e7] {
        // Against the unmoved render: the largest channel difference and the pixels that
        // differ by more than the comparison's tolerance (for renderer/docs/precision.md).
        let (mut worst, mut moved_pixels) = (0.0f64, 0);
        for e in &all {
            let (scene, img) = render_moved(e, by);
            let (_, near) = render_moved(e, 0.0);
            let vs_near = compare_render(&scene, &Options::default(), &img, &near.rgb);
            worst = worst.max(vs_near.max_abs);
            moved_pixels += vs_near.failing + vs_near.silhouette;
            assert!(
                scene.origin().length() > 0.5 * by,
                "{} moved by {by:e} was not rebased (origin {:?})",
                e.name,
                scene.origin()
            );
            let (_, _, reference) = read_reference(
                &repo_root()
                    .join("references/povray")
                    .join(format!("{}.exr", e.name)),
            )
            .unwrap();
            let c = compare_render(&scene, &Options::default(), &img, &reference);
            if !c.passed() {
                bad.push(format!("{} moved by {by:e}: {}", e.name, describe(&c)));
            }
        }
        eprintln!(
            "measured [{}] catalog moved by {by:e} against unmoved: {moved_pixels} pixels \
             outside tolerance in {} scenes, max abs difference {worst:.2e}",
            renderer::real::PRECISION,
            all.len()
        );
    }
    assert!(
        bad.is_empty(),
        "{} moved scenes no longer match their references (the render-space origin in \
         renderer/src/scene/build.rs, or a shape's precision far from its object origin):\n{}",
        bad.len(),
        bad.join("\n")
    );
}

/// In f64 the scene moved by 10⁷ renders as the unmoved one: the same object at every
/// pixel, and colours within the comparison's tolerance everywhere.
#[cfg(feature = "f64")]
#[test]
fn f64_renders_the_scene_moved_by_1e7_like_the_unmoved_one() {
    let mut bad = Vec::new();
    let mut worst = 0.0f64;
    for e in &scenes("povray", "").unwrap() {
        let (scene, far) = render_moved(e, 1e7);
        let (_, near) = render_moved(e, 0.0);
        let c = compare_render(&scene, &Options::default(), &far, &near.rgb);
        worst = worst.max(c.max_abs);
        if c.failing + c.silhouette > 0 {
            bad.push(format!("{}: {}", e.name, describe(&c)));
        }
    }
    eprintln!(
        "measured [f64] catalog moved by 1e7 against unmoved: max abs difference {worst:.2e}"
    );
    assert!(
        bad.is_empty(),
        "moved by 1e7, the f64 build renders differently:\n{}",
        bad.join("\n")
    );
}
