//! Measures the precision trade for one build (f32 or f64): throughput on the benchmark
//! scenes and error on the extreme scenes, for each self-intersection strategy. Prints
//! markdown table rows; `scripts/precision.sh` runs it in both builds and writes
//! renderer/docs/precision.md.

use glam::{DMat3, DVec3};
use renderer::aggregate::Shape;
use renderer::aggregate::{Aggregate, Instance};
use renderer::camera::{Camera, FovAxis, ViewingModel};
use renderer::real::{dvec3, Real, PRECISION};
use renderer::render::{render, Options};
use renderer::scene::Scene;
use renderer::spawn::Spawn;
use renderer::transform::{Affine64, Transform};
use std::time::Instant;

fn rnd(state: &mut u64) -> f64 {
    *state = renderer::sampler::mix64(state.wrapping_add(0x9e37_79b9_7f4a_7c15));
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn unit(s: &mut u64) -> DVec3 {
    loop {
        let v = DVec3::new(rnd(s), rnd(s), rnd(s)) * 2.0 - 1.0;
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

fn strategies() -> [(&'static str, Spawn); 3] {
    [
        ("robust", Spawn::Robust),
        ("fixed 1e-3", Spawn::Fixed(1e-3)),
        ("none", Spawn::None),
    ]
}

/// Fraction of spawned rays that hit their own sphere again: a random instance (rotation,
/// log-uniform scale 10^±s, translation up to `shift`), a ray from outside at it, a new ray
/// from the hit into the outward hemisphere.
fn self_hits(spawn: Spawn, shift: f64, scale_exp: f64, n: usize) -> f64 {
    let mut s = 11u64;
    let mut bad = 0;
    let mut tried = 0;
    while tried < n {
        let scale = 10f64.powf((rnd(&mut s) * 2.0 - 1.0) * scale_exp);
        let rot = DMat3::from_axis_angle(unit(&mut s), rnd(&mut s) * 6.28);
        let a = Affine64 {
            m: rot
                * DMat3::from_diagonal(
                    DVec3::new(1.0, 0.5 + rnd(&mut s), 0.5 + rnd(&mut s)) * scale,
                ),
            d: (DVec3::new(rnd(&mut s), rnd(&mut s), rnd(&mut s)) * 2.0 - 1.0) * shift,
        };
        let Ok(x) = Transform::new(&a) else { continue };
        let inst = Instance {
            shape: Shape::Sphere,
            xf: Some(x),
            material: 0,
            object_id: 1,
        };
        let target = a.point(unit(&mut s) * 0.5);
        let origin = target + unit(&mut s) * scale * 5.0;
        let ray = renderer::Ray::new(
            renderer::real::vec3(origin),
            renderer::real::vec3(target - origin),
        );
        let Some(h) = inst.intersect(&ray, 0.0, Real::INFINITY) else {
            continue;
        };
        tried += 1;
        let n_geo = h.n_geo.normalize();
        let mut dir = renderer::real::vec3(unit(&mut s));
        if dir.dot(n_geo) < 0.0 {
            dir = -dir;
        }
        let (r, t_min) = spawn.ray(h.p, h.err, n_geo, dir);
        if inst.intersect(&r, t_min, Real::INFINITY).is_some() {
            bad += 1;
        }
    }
    bad as f64 / n as f64
}

/// Light leaking under a thin plate (a rectangle) held `gap` above a plane: the fraction
/// of shadow rays, from points on the plane under the plate towards a light above it, that
/// are not blocked.
fn leak(spawn: Spawn, gap: f64) -> f64 {
    let sphere = Instance {
        shape: Shape::Rectangle,
        xf: Some(Transform::new(&Affine64::translate(DVec3::new(0.0, gap, 0.0))).unwrap()),
        material: 0,
        object_id: 1,
    };
    let plane = Instance {
        shape: Shape::Plane,
        xf: None,
        material: 0,
        object_id: 2,
    };
    let scene = Aggregate::new(vec![sphere, plane]);
    let light = DVec3::new(0.0, 10.0, 0.0);
    let mut s = 5u64;
    let n = 2000;
    let mut leaked = 0;
    for _ in 0..n {
        // A point on the plane under the plate, found by a ray from below the plane (the
        // plate would hide it from above).
        let p = DVec3::new((rnd(&mut s) - 0.5) * 1.6, 0.0, (rnd(&mut s) - 0.5) * 1.6);
        let eye = p - DVec3::new(0.3, 5.0, -0.2);
        let ray = renderer::Ray::new(renderer::real::vec3(eye), renderer::real::vec3(p - eye));
        let Some(h) = scene.intersect(&ray, 0.0, Real::INFINITY) else {
            continue;
        };
        assert_eq!(h.object_id, 2, "the sample ray hits the plane first");
        let to_light = renderer::real::vec3(light) - h.p;
        let dist = to_light.length();
        let l = to_light / dist;
        let (r, t_min) = spawn.ray(h.p, h.err, h.n_geo.normalize(), l);
        if !scene.occluded(&r, t_min, dist) {
            leaked += 1;
        }
    }
    leaked as f64 / n as f64
}

/// t error in ulps (of the build's precision) of a unit sphere at distance D, against the
/// f64 closed form for the same ray, and wrong hit/miss decisions outside the silhouette
/// band `8·ε·D`.
fn far_sphere(ratio: f64) -> (f64, f64, f64, usize) {
    let mut s = 3u64;
    let c = DVec3::new(ratio, 0.3 * ratio, -0.2 * ratio);
    let inst = Instance {
        shape: Shape::Sphere,
        xf: Some(Transform::new(&Affine64::translate(c)).unwrap()),
        material: 0,
        object_id: 1,
    };
    let mut errs = Vec::new();
    let mut wrong = 0;
    // Rays this close to the silhouette (in 1 − |l|², radius units) have no defined answer
    // at this precision: the ray's own position near the sphere is only known to ε·D.
    let band = 8.0 * Real::EPSILON as f64 * ratio;
    for _ in 0..20_000 {
        // Aim at a random point within 1.2 radii of the centre, as seen from the origin.
        let aim = c + unit(&mut s) * 1.2 * rnd(&mut s).sqrt();
        let d = renderer::real::vec3(aim);
        let (o64, d64) = (DVec3::ZERO, dvec3(d));
        // Closed form in f64 with the stable discriminant.
        let f = o64 - c;
        let a = d64.length_squared();
        let b = f.dot(d64);
        let l = f - d64 * (b / a);
        let disc = a * (1.0 - l.length_squared());
        let margin = (1.0 - l.length_squared()).abs();
        let got = inst.intersect(
            &renderer::Ray::new(renderer::Vec3::ZERO, d),
            0.0,
            Real::INFINITY,
        );
        if margin < band {
            continue;
        }
        match (disc >= 0.0, got) {
            (true, Some(h)) => {
                let q = -(b + disc.sqrt().copysign(b));
                let t = (q / a).min((f.length_squared() - 1.0) / q);
                let ulp = (t as Real).next_up() as f64 - t as Real as f64;
                errs.push(((h.t as f64) - t).abs() / ulp);
            }
            (false, None) => {}
            _ => wrong += 1,
        }
    }
    errs.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let at = |q: f64| {
        errs.get(((errs.len() as f64 * q) as usize).min(errs.len().saturating_sub(1)))
            .copied()
            .unwrap_or(0.0)
    };
    (at(0.5), at(0.99), at(1.0), wrong)
}

/// Fraction of pixels whose object id changes when the whole scene and camera move by
/// `shift` along (1, 1, 1)/√3.
fn translated_scene(shift: f64) -> f64 {
    let text = |d: f64| {
        format!(
            r#"
[camera.look_at]
from = [{a}, {b}, {c}]
at = [{d}, {d}, {d}]
up = [0, 1, 0]
fov = 40
[render]
width = 96
height = 72
[[objects]]
type = "sphere"
transform = [{{ translate = [{d}, {d}, {d}] }}]
[[objects]]
type = "box"
transform = [{{ scale = 0.5 }}, {{ rotate = {{ axis = [1, 1, 0], degrees = 30 }} }}, {{ translate = [{e}, {d}, {d}] }}]
[[objects]]
type = "plane"
transform = [{{ translate = [{d}, {f}, {d}] }}]
"#,
            a = d + 0.5,
            b = d + 1.5,
            c = d - 6.0,
            d = d,
            e = d + 1.6,
            f = d - 1.0
        )
    };
    let opts = Options {
        threads: Some(2),
        aov: true,
        ..Options::default()
    };
    let at = |d: f64| {
        let s = Scene::from_str(
            &text(d),
            std::path::Path::new("shift.toml"),
            std::path::Path::new("."),
        )
        .unwrap();
        render(&s, &opts).aov.unwrap().object_id
    };
    let (a, b) = (at(0.0), at(shift / 3f64.sqrt()));
    a.iter().zip(&b).filter(|(x, y)| x != y).count() as f64 / a.len() as f64
}

/// Depth range inside one view: a rectangle lying `gap` above a plane, both at distance
/// `dist` from the eye (which is the render-space origin, so rebasing cannot help), seen
/// from above. Returns the fraction of the central pixels (all on the rectangle) whose
/// object id is not the rectangle's: where the two surfaces merge in this precision.
fn depth_range(dist: f64, gap: f64) -> f64 {
    let text = format!(
        r#"
[camera.look_at]
from = [0, {h}, 0]
at = [0, 0, {dist}]
up = [0, 1, 0]
fov = 40
[render]
width = 96
height = 72
[[objects]]
type = "plane"
[[objects]]
type = "rectangle"
transform = [{{ scale = {half} }}, {{ translate = [0, {gap}, {dist}] }}]
"#,
        h = dist / 2.0,
        half = dist / 2.0,
    );
    let s = Scene::from_str(
        &text,
        std::path::Path::new("depth.toml"),
        std::path::Path::new("."),
    )
    .unwrap();
    let ids = render(
        &s,
        &Options {
            threads: Some(2),
            aov: true,
            ..Options::default()
        },
    )
    .aov
    .unwrap()
    .object_id;
    let (w, h) = (96, 72);
    let (mut wrong, mut n) = (0, 0);
    for j in h * 3 / 10..h * 7 / 10 {
        for i in w * 3 / 10..w * 7 / 10 {
            n += 1;
            if ids[j * w + i] != 2.0 {
                wrong += 1;
            }
        }
    }
    wrong as f64 / n as f64
}

fn primary_throughput() -> f64 {
    let cam = Camera::new(
        ViewingModel::look_at(
            DVec3::new(0.3, 0.8, -4.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            FovAxis::Horizontal,
            256,
            256,
        )
        .unwrap(),
    )
    .unwrap();
    let mut s = 7u64;
    let n = 10_000;
    let r = 0.35 * (n as f64).powf(-1.0 / 3.0);
    let agg = Aggregate::new(
        (0..n)
            .map(|k| Instance {
                shape: Shape::Sphere,
                xf: Some(
                    Transform::new(&Affine64 {
                        m: DMat3::from_diagonal(DVec3::splat(r)),
                        d: DVec3::new(rnd(&mut s), rnd(&mut s), rnd(&mut s)) * 2.0 - 1.0,
                    })
                    .unwrap(),
                ),
                material: 0,
                object_id: k + 1,
            })
            .collect(),
    );
    let t0 = Instant::now();
    let mut rays = 0u64;
    while t0.elapsed().as_secs_f64() < 1.0 {
        for j in 0..256 {
            for i in 0..256 {
                std::hint::black_box(agg.intersect(&cam.pixel_ray(i, j), 0.0, Real::INFINITY));
            }
        }
        rays += 256 * 256;
    }
    rays as f64 / t0.elapsed().as_secs_f64() / 1e6
}

/// Shaded pixels per second (millions, one thread) on a catalog scene with shadows,
/// reflection and refraction.
fn shaded_throughput(spawn: Spawn) -> f64 {
    let root = conformance::catalog::repo_root();
    let scene =
        Scene::load(&root.join("conformance/scenes/povray/shade_refract_sphere.toml")).unwrap();
    let opts = Options {
        threads: Some(1),
        spawn,
        ..Options::default()
    };
    let t0 = Instant::now();
    let mut frames = 0;
    while t0.elapsed().as_secs_f64() < 1.0 {
        std::hint::black_box(render(&scene, &opts));
        frames += 1;
    }
    (scene.settings.width * scene.settings.height) as f64 * frames as f64
        / t0.elapsed().as_secs_f64()
        / 1e6
}

fn main() {
    println!("THROUGHPUT|{PRECISION}|{:.2}", primary_throughput());
    for ratio in [1e3, 1e4, 1e5] {
        let (med, p99, max, wrong) = far_sphere(ratio);
        println!("FARSPHERE|{PRECISION}|{ratio:e}|{med:.2}|{p99:.1}|{max:.0}|{wrong}");
    }
    for shift in [1e3, 1e5, 1e7] {
        println!(
            "SHIFT|{PRECISION}|{shift:e}|{:.4}",
            translated_scene(shift) * 100.0
        );
    }
    for dist in [1e2, 1e4, 1e6] {
        for rel in [1e-6, 1e-7, 3e-8, 1e-8, 1e-9] {
            println!(
                "DEPTH|{PRECISION}|{dist:e}|{rel:e}|{:.1}",
                depth_range(dist, dist * rel) * 100.0
            );
        }
    }
    for (name, sp) in strategies() {
        let hits: Vec<String> = [(0.0, 0.0), (1e5, 0.0), (1e6, 4.0)]
            .iter()
            .map(|&(shift, sc)| format!("{:.2}", self_hits(sp, shift, sc, 4000) * 100.0))
            .collect();
        let leaks: Vec<String> = [1e-2, 1e-4]
            .iter()
            .map(|&g| format!("{:.1}", leak(sp, g) * 100.0))
            .collect();
        println!(
            "SPAWN|{PRECISION}|{name}|{:.2}|{}|{}",
            shaded_throughput(sp),
            hits.join("|"),
            leaks.join("|")
        );
    }
}
