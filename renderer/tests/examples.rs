//! Every example scene in renderer/scenes renders: with the object in view, no NaN or
//! infinity, AOVs that round-trip through EXR, and the same bits for any thread count.

use renderer::output::{self, read_exr, ToneMap};
use renderer::render::{render, Image, Options};
use renderer::scene::Scene;
use std::path::{Path, PathBuf};

fn scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

fn opts(threads: usize) -> Options {
    Options {
        threads: Some(threads),
        aov: true,
        ..Options::default()
    }
}

#[test]
fn test01_one_example_per_primitive() {
    let names: Vec<String> = scenes()
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    for want in [
        "sphere",
        "plane",
        "box",
        "cylinder",
        "cone",
        "disk",
        "rectangle",
        "triangle",
        "mesh",
        "hierarchy",
    ] {
        assert!(
            names.iter().any(|n| n == want),
            "renderer/scenes/{want}.toml is missing"
        );
    }
}

#[test]
fn test02_examples_render_sanely() {
    for path in scenes() {
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let img = render(&scene, &opts(2));
        let name = path.display();
        assert_eq!(img.non_finite, 0, "{name}: non-finite pixels");
        assert!(img.rgb.iter().all(|v| v.is_finite() && *v >= 0.0), "{name}");
        let aov = img.aov.as_ref().unwrap();
        // Every object of the scene is visible somewhere.
        for id in 1..=scene.objects.len() {
            assert!(
                aov.object_id.iter().any(|&v| v == id as f32),
                "{name}: object {id} ({}) is not visible",
                scene.objects[id - 1]
            );
        }
        // Geometry channels are consistent: unit normals where hit, Z = |P − eye|.
        // P is in world coordinates (the scene may render in a space moved to the eye).
        let eye = scene.camera.eye64;
        for k in 0..aov.z.len() {
            if aov.object_id[k] == 0.0 {
                assert_eq!(
                    (aov.z[k], aov.n[3 * k]),
                    (0.0, 0.0),
                    "{name}: misses are written as 0"
                );
                continue;
            }
            let n = glam::Vec3::from_slice(&aov.n[3 * k..3 * k + 3]);
            assert!(
                (n.length() - 1.0).abs() < 1e-5,
                "{name}: |N| = {}",
                n.length()
            );
            let p = glam::DVec3::new(
                aov.p[3 * k] as f64,
                aov.p[3 * k + 1] as f64,
                aov.p[3 * k + 2] as f64,
            );
            let z = (p - eye).length();
            assert!(
                (z - aov.z[k] as f64).abs() < 1e-4 * z.max(1.0),
                "{name}: Z = {} vs |P - eye| = {z}",
                aov.z[k]
            );
        }
    }
}

#[test]
fn test03_same_bits_for_any_thread_count() {
    for path in scenes() {
        let scene = Scene::load(&path).unwrap();
        let one = render(&scene, &opts(1));
        for t in [2, 8] {
            let other: Image = render(&scene, &opts(t));
            assert!(
                one == other,
                "{}: {t} threads differ from 1",
                path.display()
            );
        }
    }
}

#[test]
fn test04_png_and_exr_outputs() {
    let path = scenes()
        .into_iter()
        .find(|p| p.ends_with("sphere.toml"))
        .unwrap();
    let scene = Scene::load(&path).unwrap();
    let img = render(&scene, &opts(2));
    let dir = std::env::temp_dir().join(format!("renderer-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (png, exr) = (dir.join("a.png"), dir.join("a.exr"));
    output::write(&img, &png, ToneMap::Srgb).unwrap();
    output::write(&img, &exr, ToneMap::Srgb).unwrap();

    let file = std::io::BufReader::new(std::fs::File::open(&png).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut decoded = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut decoded).unwrap();
    assert_eq!((info.width, info.height), (img.width, img.height));
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Rgb, png::BitDepth::Eight)
    );
    assert_eq!(
        &decoded[..info.buffer_size()],
        &output::to_rgb8(&img, ToneMap::Srgb)
    );

    let e = read_exr(&exr).unwrap();
    assert_eq!(
        (e.width, e.height),
        (img.width as usize, img.height as usize)
    );
    let aov = img.aov.as_ref().unwrap();
    let mut names: Vec<&str> = e.channels.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    assert_eq!(
        names,
        ["B", "G", "N.X", "N.Y", "N.Z", "P.X", "P.Y", "P.Z", "R", "Z", "objectId"]
    );
    // 32-bit float and linear: the values come back bit for bit.
    let r: Vec<f32> = img.rgb.iter().step_by(3).copied().collect();
    assert_eq!(e.channel("R").unwrap(), r.as_slice());
    assert_eq!(e.channel("Z").unwrap(), aov.z.as_slice());
    assert_eq!(e.channel("objectId").unwrap(), aov.object_id.as_slice());
    let ny: Vec<f32> = aov.n.iter().skip(1).step_by(3).copied().collect();
    assert_eq!(e.channel("N.Y").unwrap(), ny.as_slice());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test05_srgb_mapping() {
    use renderer::output::srgb_encode;
    assert_eq!(srgb_encode(0.0), 0.0);
    assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
    assert!((srgb_encode(0.18) - 0.4614).abs() < 1e-3);
    // The 8-bit code is the one nearest the exact encoding (computed here in f64), at every
    // step of a fine sweep and at both ends.
    use renderer::output::srgb8;
    assert_eq!(
        (srgb8(0.0), srgb8(1.0), srgb8(-0.5), srgb8(7.0)),
        (0, 255, 0, 255)
    );
    for i in 0..=200_000 {
        let x = (i as f64 / 200_000.0).powi(2) as f32;
        let e = x as f64;
        let exact = if e <= 0.0031308 {
            12.92 * e
        } else {
            1.055 * e.powf(1.0 / 2.4) - 0.055
        } * 255.0;
        let got = srgb8(x) as f64;
        assert!(
            (got - exact).abs() <= 0.5 + 1e-4,
            "srgb8({x}) = {got}, exact encoding {exact}"
        );
    }
    let img = Image {
        width: 2,
        height: 1,
        rgb: vec![0.0, 0.5, 2.0, -1.0, 0.25, 1.0],
        aov: None,
        non_finite: 0,
        moments: None,
        samples: 0,
    };
    assert_eq!(
        output::to_rgb8(&img, ToneMap::Clamp),
        [0, 128, 255, 0, 64, 255]
    );
    assert_eq!(
        output::to_rgb8(&img, ToneMap::MinMax),
        [85, 128, 255, 0, 106, 170]
    );
    assert_eq!(
        output::to_rgb8(&img, ToneMap::Srgb),
        [0, 188, 255, 0, 137, 255]
    );
}

#[test]
fn test06_documented_example_builds() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md"))
            .unwrap();
    let start = doc.find("```toml\n").expect("the doc has a TOML example") + 8;
    let end = start + doc[start..].find("```").unwrap();
    let scene = Scene::from_str(
        &doc[start..end],
        Path::new("scene-format.md"),
        Path::new("."),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.objects.len(), 2);
    let img = render(&scene, &opts(2));
    assert!(img.aov.unwrap().object_id.iter().any(|&v| v == 2.0));
}
