//! Closed-form checks of the physically based model: the white furnace, a point light over
//! a diffuse plane, a square area light over a diffuse plane (both strategies of MIS), the
//! samplers' error against independent sampling, glass of ior 1 left invisible, and light
//! paths that leave the image's expectation as it was.

use renderer::render::{render, Image, Options};
use renderer::sampler::SamplerKind;
use renderer::scene::Scene;
use std::path::Path;

fn scene(text: &str) -> Scene {
    Scene::from_str(text, Path::new("physical.toml"), Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn run(s: &Scene, spp: u32) -> Image {
    render(
        s,
        &Options {
            samples: Some(spp),
            moments: true,
            aov: true,
            ..Options::default()
        },
    )
}

/// The mean of channel `c` over `pixels` of a moments render at `spp`, and the standard
/// error of that mean (each pixel's variance of its mean from its second moment).
fn mean_and_error(img: &Image, spp: u32, pixels: &[usize], c: usize) -> (f64, f64) {
    let m = img.moments.as_ref().expect("a render with moments");
    let (mut sum, mut var) = (0.0, 0.0);
    for &k in pixels {
        let mean = img.rgb[3 * k + c] as f64;
        sum += mean;
        var += (m[6 * k + c] as f64 - mean * mean).max(0.0) / spp as f64;
    }
    let n = pixels.len() as f64;
    (sum / n, var.sqrt() / n)
}

const FURNACE: &str = r#"
[camera.look_at]
from = [0, 0, -4]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 30
[render]
width = 16
height = 16
integrator = "INTEGRATOR"
sampler = "SAMPLER"
max_depth = 10
[[lights]]
type = "environment"
color = [0.5, 0.5, 0.5]
[materials.m]
model = "diffuse"
color = [0.8, 0.6, 0.4]
[[objects]]
type = "sphere"
material = "m"
"#;

/// A diffuse sphere of reflectance ρ in a constant environment L has radiance ρ·L
/// everywhere (it is convex, so it never sees itself): pbrt's furnace test.
#[test]
fn test01_white_furnace() {
    for integrator in ["direct", "path"] {
        for sampler in ["independent", "stratified", "sobol"] {
            let s = scene(
                &FURNACE
                    .replace("INTEGRATOR", integrator)
                    .replace("SAMPLER", sampler),
            );
            let spp = 256;
            let img = run(&s, spp);
            let aov = img.aov.as_ref().unwrap();
            // Pixels fully on the sphere: not on the border, and their centre and all eight
            // neighbours' centres hit it (the sphere's outline is convex).
            let (w, h) = (16usize, 16usize);
            let inside = |i: usize, j: usize| {
                i > 0
                    && j > 0
                    && i + 1 < w
                    && j + 1 < h
                    && (j - 1..j + 2)
                        .all(|y| (i - 1..i + 2).all(|x| aov.object_id[y * w + x] == 1.0))
            };
            let pixels: Vec<usize> = (0..w * h).filter(|k| inside(k % w, k / w)).collect();
            let n = pixels.len();
            assert!(n > 40, "{n} interior pixels");
            for (c, want) in [0.4, 0.3, 0.2].into_iter().enumerate() {
                let (mean, se) = mean_and_error(&img, spp, &pixels, c);
                // The environment is sampled by the cosine (physical/integrator.rs, env_pdf), so each
                // sample is ρ·L to rounding: the noise is then the f32 sum's rounding, at
                // most spp ulps of the mean.
                let rounding = want * spp as f64 * f32::EPSILON as f64;
                let z = (mean - want) / se.hypot(rounding);
                assert!(
                    z.abs() < 5.0,
                    "{integrator}/{sampler}, channel {c}: {mean} vs {want} (z = {z:.1})"
                );
            }
            // Background pixels see the environment exactly.
            assert_eq!(&img.rgb[0..3], &[0.5, 0.5, 0.5]);
        }
    }
}

/// A diffuse plane under a point light: radiance ρ/π · I·cosθ/d² (no noise: point lights
/// are sampled exactly). The camera looks straight down from far away with a tiny window,
/// so each pixel covers a patch over which the closed form is nearly constant.
#[test]
fn test02_point_light_over_a_plane() {
    let s = scene(
        r#"
[camera.view]
vrp = [0.7, 100, 0.3]
vpn = [0, -1, 0]
vup = [0, 0, 1]
e = 10
window = { left = -0.0001, right = 0.0001, bottom = -0.0001, top = 0.0001 }
[render]
width = 4
height = 4
integrator = "direct"
[[lights]]
position = [0, 2, 0]
color = [10, 20, 30]
[materials.m]
model = "diffuse"
color = [0.5, 0.5, 0.5]
[[objects]]
type = "plane"
material = "m"
"#,
    );
    let img = run(&s, 64);
    let aov = img.aov.as_ref().unwrap();
    for k in 0..16 {
        // The closed form at the pixel-centre hit. A pixel covers a patch 0.00055 wide, over
        // which the irradiance varies by ±1.3e-4: its jittered average stays within 1e-4.
        let (px, pz) = (aov.p[3 * k] as f64, aov.p[3 * k + 2] as f64);
        assert!(aov.p[3 * k + 1].abs() < 1e-5);
        let d2 = px * px + pz * pz + 4.0;
        let cos = 2.0 / d2.sqrt();
        for (c, intensity) in [10.0, 20.0, 30.0].into_iter().enumerate() {
            let want = 0.5 / std::f64::consts::PI * intensity * cos / d2;
            let got = img.rgb[3 * k + c] as f64;
            assert!(
                ((got - want) / want).abs() < 1e-4,
                "pixel {k}, channel {c}: {got} vs {want}"
            );
        }
    }
}

/// Stratified and Sobol samples reach a lower error than independent ones at the same
/// spp, on soft shadows from an area light (against a 4096-spp render of the same scene).
#[test]
fn test03_better_samplers_have_lower_error() {
    let text = r#"
[camera.look_at]
from = [0, 2, -4]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 40
[render]
width = 24
height = 18
integrator = "direct"
sampler = "SAMPLER"
[materials.floor]
model = "diffuse"
color = [0.7, 0.7, 0.7]
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [5, 5, 5]
[[objects]]
type = "rectangle"
material = "floor"
transform = [{ scale = 4 }, { translate = [0, -1, 0] }]
[[objects]]
type = "rectangle"
material = "light"
transform = [{ scale = 0.7 }, { rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [0, 1.5, 0] }]
[[objects]]
type = "sphere"
material = "floor"
transform = [{ scale = 0.5 }, { translate = [0, -0.5, 0] }]
"#;
    let reference = run(&scene(&text.replace("SAMPLER", "independent")), 4096).rgb;
    let mse = |kind: &str| {
        let img = run(&scene(&text.replace("SAMPLER", kind)), 16).rgb;
        img.iter()
            .zip(&reference)
            .map(|(a, b)| ((a - b) as f64).powi(2))
            .sum::<f64>()
            / img.len() as f64
    };
    let (ind, strat, sobol) = (mse("independent"), mse("stratified"), mse("sobol"));
    eprintln!("MSE at 16 spp: independent {ind:.3e}, stratified {strat:.3e}, sobol {sobol:.3e}");
    assert!(strat < 0.8 * ind, "stratified {strat} vs independent {ind}");
    assert!(sobol < 0.8 * ind, "sobol {sobol} vs independent {ind}");
    let _ = SamplerKind::Sobol;
}

/// A diffuse floor (reflectance 0.5) at y = 0 under an emitter of radiance (4, 2, 1)
/// given by `light` (a TOML object table), seen at the origin from the side through a
/// tiny window (the camera at `from` cannot see the light; the light is black, so `path`
/// has nothing to add to `direct`). Renders it with each integrator at 16,384 spp and
/// checks each channel's mean against `0.5 · radiance · factor` (z < 5), then hands the
/// image to `more` (integrator, image, the expected red). `render` is added to the
/// `[render]` table.
fn light_over_a_plane(
    from: &str,
    render: &str,
    light: &str,
    factor: f64,
    more: impl Fn(&str, &Image, f64),
) {
    let text = format!(
        r#"
[camera.look_at]
from = {from}
at = [0, 0, 0]
up = [0, 1, 0]
fov = 0.001
[render]
width = 2
height = 2
integrator = "INTEGRATOR"
max_depth = 4
{render}
[materials.floor]
model = "diffuse"
color = [0.5, 0.5, 0.5]
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [4, 2, 1]
[[objects]]
type = "plane"
material = "floor"
[[objects]]
material = "light"
{light}
"#
    );
    for integrator in ["direct", "path"] {
        let s = scene(&text.replace("INTEGRATOR", integrator));
        let spp = 16384;
        let img = run(&s, spp);
        for (c, radiance) in [4.0, 2.0, 1.0].into_iter().enumerate() {
            let want = 0.5 * radiance * factor;
            let (mean, se) = mean_and_error(&img, spp, &[0, 1, 2, 3], c);
            let z = (mean - want) / se.max(1e-12);
            assert!(
                z.abs() < 5.0,
                "{integrator}, channel {c}: {mean} vs the closed form {want} (z = {z:.1}, \
                 standard error {se:.2e}); see the area-light sampling (AreaLight::sample_from \
                 and pdf_from in renderer/src/light.rs) and the MIS weights in \
                 renderer/src/physical/integrator.rs"
            );
        }
        more(integrator, &img, 0.5 * 4.0 * factor);
    }
}

/// A diffuse plane (reflectance ρ) under a square light of half-side a and radiance L at
/// height h, facing down: straight below its centre the form factor to the square is four
/// times that to an a × a rectangle seen from below its corner,
/// F = 4 · (1/2π) · 2 · A/√(1+A²) · atan(A/√(1+A²)) with A = a/h, and the plane's radiance
/// there is ρ·L·F. The light subtends a wide cone (a = h), so both strategies of multiple
/// importance sampling, light samples and BSDF samples that hit the light, carry much of
/// the estimate, and a wrong density or weight in either biases it.
#[test]
fn test04_square_light_over_a_plane() {
    let a = 1.0f64 / (1.0f64 + 1.0).sqrt();
    let form_factor = 4.0 / std::f64::consts::PI * a * a.atan();
    light_over_a_plane(
        "[4, 1, 0.5]",
        "",
        r#"type = "rectangle"
transform = [{ rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [0, 1, 0] }]"#,
        form_factor,
        |_, _, _| {},
    );
}

/// A diffuse plane (reflectance ρ) under a sphere light of radius R and radiance L whose
/// centre is at height h: straight below, the sphere subtends a cone of sin²θ_max = R²/h²
/// about the normal, so the irradiance is π·L·R²/h² and the plane's radiance ρ·L·R²/h².
/// The sphere is large and near (R = 0.8, h = 1): sampled uniformly by area, half of its
/// samples fall on its far side and the rest vary strongly in density; sampled by the cone
/// it subtends (as Mitsuba samples its sphere emitter), every sample lands on the visible
/// cap with a density near the integrand's. Checks the mean against the closed form, for
/// both integrators and both MIS strategies, and that the per-sample standard deviation
/// is that of cone sampling (measured 0.24 of the mean with the cone, 0.75 by area).
#[test]
fn test05_sphere_light_over_a_plane() {
    light_over_a_plane(
        "[4, 0.5, 0.5]",
        "",
        r#"type = "sphere"
transform = [{ scale = 0.8 }, { rotate = { axis = [1, 2, 3], degrees = 40 } }, { translate = [0, 1, 0] }]"#,
        0.8 * 0.8,
        |integrator, img, want| {
            // The per-sample standard deviation of pixel 0's red, relative to its mean.
            let m = img.moments.as_ref().expect("moments");
            let sd = (m[0] as f64 - (img.rgb[0] as f64).powi(2)).max(0.0).sqrt() / want;
            eprintln!("measured: {integrator}: per-sample sd {sd:.3} of the mean");
            assert!(
                sd < 0.4,
                "{integrator}: the per-sample standard deviation is {sd:.3} of the mean, \
                 where sampling the sphere by the cone it subtends gives 0.24 (by area: \
                 0.75); is the sphere light sampled by solid angle? \
                 (AreaLight::sample_from, renderer/src/light.rs)"
            );
        },
    );
}

/// The square light of test04 with a point light, a directional light and an
/// environment, each a multiple of its radiance (4, 2, 1): the plane's radiance below the
/// light's centre is ρ·L·(F + e·(1 − F) + (k/h² + m·cos θ)/π), where the light hides the
/// fraction F of the environment (the form factor is the cosine-weighted share of the
/// hemisphere it covers), the point light of intensity k·L is at height h below the square
/// light, and the directional light of irradiance m·L comes in at cos θ = 1/√5 past the
/// square's edge. With `light_sampling = "one"` every estimate takes one of the four
/// lights, chosen uniformly: a weight or density that forgets the choice biases it by a
/// factor of up to four, and so does one that counts it twice.
#[test]
fn test09_one_light_a_vertex_keeps_the_closed_form() {
    let a = 1.0f64 / (1.0f64 + 1.0).sqrt();
    let f = 4.0 / std::f64::consts::PI * a * a.atan();
    let (e, k, h, m) = (0.25, 0.5, 0.5, 0.75);
    let cos = 1.0 / 5f64.sqrt();
    let factor = f + e * (1.0 - f) + (k / (h * h) + m * cos) / std::f64::consts::PI;
    for sampling in ["one", "all"] {
        light_over_a_plane(
            "[4, 1, 0.5]",
            &format!("light_sampling = \"{sampling}\""),
            r#"type = "rectangle"
transform = [{ rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [0, 1, 0] }]
[[lights]]
position = [0, 0.5, 0]
color = [2, 1, 0.5]
[[lights]]
type = "directional"
direction = [2, -1, 0]
color = [3, 1.5, 0.75]
[[lights]]
type = "environment"
color = [1, 0.5, 0.25]"#,
            factor,
            |_, _, _| {},
        );
    }
}

/// Glass of ior 1 (the default) is invisible: through a slanted dielectric rectangle every
/// pixel sees the environment unchanged, exactly. The refraction then crosses η = 1 while
/// the Fresnel reflectance rounds to a tiny positive at these angles (cos θ = 0.32), so a
/// path loop that told the reflection lobe by "η = 1" took every refraction for one and
/// dropped what it met (the first vertex's reflection taken whole, renderer/src/physical/integrator.rs
/// `reflected_emission`): black where the glass is.
#[test]
fn test06_index_matched_glass_is_invisible() {
    for integrator in ["direct", "path"] {
        let s = scene(&format!(
            r#"
[camera.look_at]
from = [0, 1, -3]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 30
[render]
width = 8
height = 8
integrator = "{integrator}"
[[lights]]
type = "environment"
color = [0.5, 0.5, 0.5]
[materials.glass]
model = "dielectric"
[[objects]]
type = "rectangle"
material = "glass"
transform = [{{ scale = 4 }}]
"#
        ));
        let img = run(&s, 8);
        let aov = img.aov.as_ref().unwrap();
        let glass = aov.object_id.iter().filter(|&&id| id == 1.0).count();
        assert!(
            glass > 16,
            "{integrator}: the rectangle covers {glass} pixels"
        );
        for (k, v) in img.rgb.iter().enumerate() {
            assert_eq!(
                *v,
                0.5,
                "{integrator}: pixel {} channel {} is {v}, not the environment's 0.5: \
                 an ior-1 dielectric must change nothing (renderer/src/physical/integrator.rs, \
                 the path loop's reflection test)",
                k / 3,
                k % 3
            );
        }
    }
}

/// A glass and a mirror sphere on a floor under a square light: their caustics on the
/// floor are seen directly (light_paths.rs).
const CAUSTICS: &str = r#"
[camera.look_at]
from = [0, 2.5, -3]
at = [0, -0.6, 0]
up = [0, 1, 0]
fov = 50
[render]
width = 24
height = 24
integrator = "path"
max_depth = 6
sampler = "sobol"
light_paths = LIGHT_PATHS
[materials.floor]
model = "diffuse"
color = [0.7, 0.7, 0.7]
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [6, 6, 6]
[materials.glass]
model = "dielectric"
ior = 1.5
[materials.mirror]
model = "conductor"
color = [0.9, 0.9, 0.9]
[[objects]]
type = "rectangle"
material = "floor"
transform = [{ scale = 4 }, { translate = [0, -1, 0] }]
[[objects]]
type = "rectangle"
material = "light"
transform = [{ scale = 0.5 }, { rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [0, 2, 0] }]
[[objects]]
type = "sphere"
material = "glass"
transform = [{ scale = 0.5 }, { translate = [-0.6, -0.3, 0] }]
[[objects]]
type = "sphere"
material = "mirror"
transform = [{ scale = 0.4 }, { translate = [0.7, -0.5, 0.2] }]
"#;

/// The sum over the image of channel `c`, and its standard error (the pixels' variances
/// of their means from the second moments).
fn image_sum(img: &Image, spp: u32, c: usize) -> (f64, f64) {
    let pixels: Vec<usize> = (0..(img.width * img.height) as usize).collect();
    let (mean, se) = mean_and_error(img, spp, &pixels, c);
    let n = pixels.len() as f64;
    (mean * n, se * n)
}

/// Light paths take the caustics seen directly over from the camera paths: the image's
/// expectation must not change. The image with them (the camera paths' share and the
/// light paths' sums, whose variance `fold` puts into the moments) agrees with the image
/// without them within 5 standard errors; with both counting those caustics
/// (`Fault::CausticsTwice`), it is brighter by their whole share, and the same test fails.
#[test]
fn test07_light_paths_keep_the_expectation() {
    light_paths_keep_the_expectation(CAUSTICS, "a glass and a mirror sphere");
}

/// A single glass interface (a rectangle whose inside, below it, is glass) between a
/// square light and the floor: light paths cross it once, so a wrong refraction weight
/// (η² where power needs 1) shows, where a sphere's two crossings cancel it.
const PANE: &str = r#"
[camera.look_at]
from = [0, 0.2, -2.6]
at = [0, -1, 0]
up = [0, 1, 0]
fov = 60
[render]
width = 24
height = 24
integrator = "path"
max_depth = 4
sampler = "sobol"
light_paths = LIGHT_PATHS
[materials.floor]
model = "diffuse"
color = [0.7, 0.7, 0.7]
[materials.light]
model = "diffuse"
color = [0, 0, 0]
radiance = [6, 6, 6]
[materials.glass]
model = "dielectric"
ior = 1.5
[[objects]]
type = "rectangle"
material = "floor"
transform = [{ scale = 4 }, { translate = [0, -1, 0] }]
[[objects]]
type = "rectangle"
material = "light"
transform = [{ scale = 0.5 }, { rotate = { axis = [1, 0, 0], degrees = 180 } }, { translate = [0, 2, 0] }]
[[objects]]
type = "rectangle"
material = "glass"
transform = [{ scale = 0.8 }, { translate = [0, 0.5, 0] }]
"#;

#[test]
fn test08_light_paths_through_one_interface_keep_the_expectation() {
    light_paths_keep_the_expectation(PANE, "one glass interface");
}

fn light_paths_keep_the_expectation(text: &str, what: &str) {
    let spp = 1024;
    let plain = run(&scene(&text.replace("LIGHT_PATHS", "0")), spp);
    let with = scene(&text.replace("LIGHT_PATHS", "2"));
    let light = run(&with, spp);
    let twice = render(
        &with,
        &Options {
            samples: Some(spp),
            moments: true,
            fault: Some(renderer::physical::Fault::CausticsTwice),
            ..Options::default()
        },
    );
    for c in 0..3 {
        let (a, sa) = image_sum(&plain, spp, c);
        let (b, sb) = image_sum(&light, spp, c);
        let (t, st) = image_sum(&twice, spp, c);
        let z = (b - a) / sa.hypot(sb);
        assert!(
            z.abs() < 5.0,
            "{what}, channel {c}: the image sums {b} with light paths and {a} without (z = {z:.1}): \
the light paths' estimate (renderer/src/physical/light_paths.rs, the factor in its module docs) \
or the camera paths' share (`caustic` in PhysicalIntegrator::path) is wrong"
        );
        // The caustics' share, counted twice: a test that cannot see it is no test.
        let zt = (t - a) / sa.hypot(st);
        assert!(
            zt > 10.0 && t - b > 0.02 * a,
            "{what}, channel {c}: with the caustics counted twice the image sum is {t} against \
{a} (z = {zt:.1}): the scene's caustics seen directly are too faint for this test"
        );
    }
}
