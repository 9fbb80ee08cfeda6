//! Scale against view (issue 37): a primitive whose own size (1e6) is huge next to the
//! distances the camera sees (2 units above its surface), with small objects on it. For
//! every pixel's camera ray, the hit of the whole scene is checked against the closed
//! form of the same ray in f64: hit or miss and object id exactly, depth within a
//! relative 1e-5. The scenes are the family of `conformance/scenes/scale/`; the scale
//! check (`renderer::scene::scale_check`) must flag the huge instances that need mixed
//! precision, and leave the rest alone (renderer/docs/precision.md, "Scale against view").

use glam::{DMat3, DVec3};
use renderer::real::dvec3;
use renderer::scene::Scene;
use std::path::Path;

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../conformance/scenes/scale");

/// The depth tolerance of the comparison (relative).
const DEPTH: f64 = 1e-5;

/// The ground's closed form in world coordinates: the nearest t > 0 of `o + t·d`.
#[derive(Clone, Copy, Debug)]
enum Ground {
    /// Sphere of radius 1e6 centred 1e6 below the origin.
    Sphere,
    /// Box [−1e6, 1e6] × [−2e6, 0] × [−1e6, 1e6].
    Box,
    /// Capped cylinder of radius 1e6 about the x axis through (0, −1e6, 0), |x| ≤ 1e6.
    Cylinder,
    /// Disk of radius 1e6 in y = 0.
    Disk,
    /// The icosphere mesh scaled by 1e6 and moved down by 1e6.
    Mesh,
}

const R: f64 = 1e6;

fn sphere_t(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    // Stable roots with f = o − c, Δ = r² − |f − (f·d̂)d̂|² (Haines et al.), in f64.
    let f = o - c;
    let a = d.length_squared();
    let b = f.dot(d);
    let l = f - d * (b / a);
    let disc = a * (r - l.length()) * (r + l.length());
    if disc < 0.0 {
        return None;
    }
    let q = -(b + disc.sqrt().copysign(b));
    // c term in f64 computed as (|f| − r)(|f| + r), exact enough at |f| ≈ r.
    let cc = (f.length() - r) * (f.length() + r);
    let (t0, t1) = ((q / a).min(cc / q), (q / a).max(cc / q));
    [t0, t1].into_iter().find(|&t| t > 1e-9)
}

fn slab_t(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<f64> {
    let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    if near > far {
        return None;
    }
    [near, far].into_iter().find(|&t| t > 1e-9)
}

fn cylinder_x_t(o: DVec3, d: DVec3) -> Option<f64> {
    // Side: (y + R)² + z² = R², in the yz plane, with |x| ≤ R; caps at x = ±R.
    let (fy, fz) = (o.y + R, o.z);
    let a = d.y * d.y + d.z * d.z;
    let mut best: Option<f64> = None;
    if a > 0.0 {
        let b = fy * d.y + fz * d.z;
        let (ly, lz) = (fy - d.y * b / a, fz - d.z * b / a);
        let l = ly.hypot(lz);
        let disc = a * (R - l) * (R + l);
        if disc >= 0.0 {
            let q = -(b + disc.sqrt().copysign(b));
            let f = fy.hypot(fz);
            let c = (f - R) * (f + R);
            for t in [q / a, c / q] {
                if t > 1e-9 && (o.x + t * d.x).abs() <= R && best.is_none_or(|b| t < b) {
                    best = Some(t);
                }
            }
        }
    }
    best
}

fn disk_t(o: DVec3, d: DVec3) -> Option<f64> {
    let t = -o.y / d.y;
    let p = o + d * t;
    (t > 1e-9 && p.x * p.x + p.z * p.z <= R * R).then_some(t)
}

/// Möller–Trumbore in f64.
fn triangle_t(o: DVec3, d: DVec3, v: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - v[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let w = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && w >= 0.0 && u + w <= 1.0 && t > 1e-9).then_some(t)
}

fn icosphere() -> Vec<[DVec3; 3]> {
    let text =
        std::fs::read_to_string(format!("{DIR}/../meshes/icosphere.obj")).expect("icosphere.obj");
    let mut v = Vec::new();
    let mut tris = Vec::new();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            // The vertex as the renderer reads it (f32, as tobj parses), then in f64.
            Some("v") => {
                let c: Vec<f64> = w.map(|x| x.parse::<f32>().unwrap() as f64).collect();
                v.push(DVec3::new(c[0], c[1], c[2]) * R - DVec3::new(0.0, R, 0.0));
            }
            Some("f") => {
                let k: Vec<usize> = w
                    .map(|x| x.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                for i in 1..k.len() - 1 {
                    tris.push([v[k[0]], v[k[i]], v[k[i + 1]]]);
                }
            }
            _ => {}
        }
    }
    tris
}

/// The closest hit of the scene's four objects in f64: (t, object id).
fn closed_form(ground: Ground, mesh: &[[DVec3; 3]], o: DVec3, d: DVec3) -> Option<(f64, u32)> {
    let g = match ground {
        Ground::Sphere => sphere_t(o, d, DVec3::new(0.0, -R, 0.0), R),
        Ground::Box => slab_t(o, d, DVec3::new(-R, -2.0 * R, -R), DVec3::new(R, 0.0, R)),
        Ground::Cylinder => cylinder_x_t(o, d),
        Ground::Disk => disk_t(o, d),
        Ground::Mesh => mesh
            .iter()
            .filter_map(|&v| triangle_t(o, d, v))
            .min_by(f64::total_cmp),
    };
    // The block: scaled 0.35, rotated 30° about y, moved to (−1.3, 0.35, 0.5).
    let rot = DMat3::from_axis_angle(DVec3::Y, 30f64.to_radians());
    let (bo, bd) = (
        rot.transpose() * (o - DVec3::new(-1.3, 0.35, 0.5)),
        rot.transpose() * d,
    );
    let block = slab_t(bo, bd, DVec3::splat(-0.35), DVec3::splat(0.35));
    [
        (g, 1),
        (sphere_t(o, d, DVec3::new(0.0, 0.5, 0.0), 0.5), 2),
        (sphere_t(o, d, DVec3::new(1.2, 0.3, 0.8), 0.3), 3),
        (block, 4),
    ]
    .into_iter()
    .filter_map(|(t, id)| t.map(|t| (t, id)))
    .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// Checks every pixel of `name` against the closed form and returns the worst relative
/// depth error; `mixed`: whether the huge instance must be flagged by the scale check
/// (and so intersected in mixed precision in the f32 build).
fn check(name: &str, ground: Ground, flagged: bool) -> f64 {
    let path = format!("{DIR}/{name}.toml");
    let scene = Scene::load(Path::new(&path)).unwrap_or_else(|e| panic!("{e}"));
    let notes: Vec<String> = scene.scale_notes.iter().map(|n| n.to_string()).collect();
    let need_mixed = flagged && renderer::real::PRECISION == "f32";
    assert_eq!(
        notes.iter().any(|n| n.contains("objects[0]")),
        need_mixed,
        "{name}: the scale check should {}flag the huge ground (renderer/src/scene/scale_check.rs); notes: {notes:?}",
        if need_mixed { "" } else { "not " }
    );
    assert!(
        notes.iter().all(|n| n.contains("objects[0]") && n.contains("mixed precision")),
        "{name}: only the ground may be flagged, and it must be resolved in mixed precision: {notes:?}"
    );
    let mesh = if matches!(ground, Ground::Mesh) {
        icosphere()
    } else {
        Vec::new()
    };
    let origin = scene.origin();
    let (w, h) = (scene.settings.width, scene.settings.height);
    let mut wrong = Vec::new();
    let mut worst: f64 = 0.0;
    for j in 0..h {
        for i in 0..w {
            let ray = scene.camera.pixel_ray(i, j);
            let got = scene
                .root
                .intersect(&ray, 0.0, renderer::real::Real::INFINITY);
            let want = closed_form(ground, &mesh, dvec3(ray.o) + origin, dvec3(ray.d));
            match (got, want) {
                (None, None) => {}
                (Some(g), Some((t, id))) if g.object_id == id => {
                    let e = ((g.t as f64) - t).abs() / t;
                    worst = worst.max(e);
                    if e > DEPTH {
                        wrong.push(format!(
                            "({i}, {j}) id {id}: t {} against {t} (relative {e:.1e})",
                            g.t
                        ));
                    }
                }
                (g, w) => wrong.push(format!(
                    "({i}, {j}): got {:?}, closed form {w:?}",
                    g.map(|g| (g.t, g.object_id))
                )),
            }
        }
    }
    println!(
        "{name}: worst relative depth {worst:.2e}, {} wrong pixels",
        wrong.len()
    );
    assert!(
        wrong.is_empty(),
        "{name}: {} of {} pixels differ from the f64 closed form (hit/miss, id, or depth beyond {DEPTH}); \
see renderer/src/shapes/anchored.rs and renderer/src/scene/scale_check.rs:\n{}",
        wrong.len(),
        w * h,
        wrong.iter().take(12).cloned().collect::<Vec<_>>().join("\n")
    );
    worst
}

#[test]
fn test01_planet_sphere() {
    check("scale_planet_sphere", Ground::Sphere, true);
}

#[test]
fn test02_ground_box() {
    check("scale_ground_box", Ground::Box, true);
}

#[test]
fn test03_ground_cylinder() {
    check("scale_ground_cylinder", Ground::Cylinder, true);
}

#[test]
fn test04_sea_disk_needs_nothing() {
    // Its plane passes through its own origin: nothing cancels, f32 resolves it as is.
    check("scale_sea_disk", Ground::Disk, false);
}

#[test]
fn test05_mesh_planet() {
    check("scale_mesh_planet", Ground::Mesh, true);
}

#[test]
fn test06_quiet_on_the_catalog_and_the_examples() {
    // No catalog scene (conformance/scenes/**) nor example (renderer/scenes/) has an
    // instance the scale check flags: their results and instructions stay as they were.
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut flagged = Vec::new();
    let mut count = 0;
    for dir in [
        "conformance/scenes/povray",
        "conformance/scenes/mitsuba",
        "renderer/scenes",
    ] {
        let mut files: Vec<_> = std::fs::read_dir(format!("{root}/{dir}"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        for f in files {
            let scene = Scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
            count += 1;
            flagged.extend(scene.scale_notes.iter().map(|n| n.to_string()));
        }
    }
    assert!(count > 100, "only {count} scenes found under {root}");
    assert!(
        flagged.is_empty(),
        "the scale check flags catalog or example scenes (renderer/src/scene/scale_check.rs):\n{}",
        flagged.join("\n")
    );
}

#[test]
fn test07_render_names_the_object_and_the_way_out() {
    // `renderer render` prints the note (or, with mixed precision off, the warning) at
    // the object's line in the scene file, with its field and what resolves it.
    let planet = format!("{DIR}/scale_planet_sphere.toml");
    let text = std::fs::read_to_string(&planet).unwrap();
    let line = 1 + text.lines().position(|l| l == "[[objects]]").unwrap();
    let dir = std::env::temp_dir().join(format!("scale_extremes_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let off = dir.join("planet_off.toml");
    std::fs::write(
        &off,
        text.replace("[render]\n", "[render]\nmixed_precision = false\n"),
    )
    .unwrap();
    for (scene, line, want) in [
        (
            planet.clone(),
            line,
            ["note:", "mixed precision", "objects[0]"],
        ),
        (
            off.display().to_string(),
            line + 1,
            ["warning:", "render.mixed_precision = true", "objects[0]"],
        ),
    ] {
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_renderer"))
            .args(["render", &scene, "-o"])
            .arg(dir.join("out.png"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{scene}: {err}");
        let at = format!("{scene}:{line}:");
        if renderer::real::PRECISION == "f64" {
            assert!(!err.contains(&at), "the f64 build needs no note: {err}");
            continue;
        }
        assert!(
            err.contains(&at) && want.iter().all(|w| err.contains(w)),
            "{scene}: stderr should name {at} with {want:?} (renderer/src/scene/scale_check.rs):\n{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn test08_where_the_estimate_is_quiet_the_build_holds() {
    // The planet at radii 10 to 1e6 (the eye 2 above it), in the build's own precision
    // (mixed precision off) and with it on: where the scale check is quiet, the build's
    // precision alone must hold the depth to 1e-5 on every pixel; with mixed precision
    // on, every radius must.
    let text = std::fs::read_to_string(format!("{DIR}/scale_planet_sphere.toml")).unwrap();
    let huge = "[{ scale = 1e6 }, { translate = [0, -1e6, 0] }]";
    assert!(text.contains(huge), "the planet's transform moved");
    for r in [1e1, 1e2, 3e2, 1e3, 3e3, 1e4, 1e5, 1e6] {
        for mixed in [false, true] {
            let t = text
                .replace(
                    huge,
                    &format!("[{{ scale = {r:?} }}, {{ translate = [0, {:?}, 0] }}]", -r),
                )
                .replace(
                    "[render]\n",
                    &format!("[render]\nmixed_precision = {mixed}\n"),
                );
            let scene = Scene::from_str(&t, Path::new("planet.toml"), Path::new(DIR)).unwrap();
            let flagged = scene.scale_notes.first().map(|n| n.bits);
            let mut worst: f64 = 0.0;
            for j in 0..scene.settings.height {
                for i in 0..scene.settings.width {
                    let ray = scene.camera.pixel_ray(i, j);
                    let (o, d) = (dvec3(ray.o) + scene.origin(), dvec3(ray.d));
                    let got = scene
                        .root
                        .intersect(&ray, 0.0, renderer::real::Real::INFINITY);
                    if let (Some(g), Some(t)) = (got, sphere_t(o, d, DVec3::new(0.0, -r, 0.0), r)) {
                        if g.object_id == 1 {
                            worst = worst.max(((g.t as f64) - t).abs() / t);
                        }
                    }
                }
            }
            println!("radius {r:e}, mixed {mixed}: flagged {flagged:?}, worst relative depth {worst:.1e}");
            assert!(
                worst <= DEPTH || (flagged.is_some() && !mixed),
                "radius {r:e}, mixed precision {mixed}: the ground's depth is off by {worst:.1e} \
(beyond {DEPTH}) though {} (renderer/src/scene/scale_check.rs's estimate, or shapes/anchored.rs)",
                if mixed {
                    "mixed precision is on"
                } else {
                    "the scale check was quiet"
                }
            );
        }
    }
}

#[test]
fn test09_an_anchored_shape_is_the_shape_moved() {
    // The same rays (exactly: coordinates on a 1/1024 grid, anchors of few bits) against
    // the canonical shape and against it anchored: the same hit or miss, the same t to a
    // few of the build's ulps, the same normal, and the same point once the anchor is
    // added back; from outside and from inside (exit faces).
    use renderer::aggregate::Shape;
    use renderer::ray::Ray;
    use renderer::real::{vec3, Real};
    use renderer::shapes::anchored::{Anchored, Kind};
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move |k: i64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % (2 * k as u64 + 1)) as i64 - k
    };
    let cases = [
        (Kind::Sphere, Shape::Sphere, DVec3::new(0.0, 1.0, 0.0)),
        (Kind::Sphere, Shape::Sphere, DVec3::new(-1.0, 0.0, 0.0)),
        (Kind::Cube, Shape::Cube, DVec3::new(1.0, 0.5, -0.25)),
        (Kind::Cube, Shape::Cube, DVec3::new(0.25, -1.0, 0.75)),
        (
            Kind::Cylinder { capped: true },
            Shape::Cylinder { capped: true },
            DVec3::new(1.0, 0.5, 0.0),
        ),
        (
            Kind::Cylinder { capped: true },
            Shape::Cylinder { capped: true },
            DVec3::new(0.5, 1.0, 0.25),
        ),
        (
            Kind::Cylinder { capped: false },
            Shape::Cylinder { capped: false },
            DVec3::new(0.0, -0.25, -1.0),
        ),
    ];
    let eps = Real::EPSILON as f64;
    let mut wrong = Vec::new();
    for (kind, canonical, a) in cases {
        let anchored = Shape::Anchored(Box::new(Anchored { kind, a }));
        let (mut hits, mut inside) = (0, 0);
        for _ in 0..20_000 {
            let oa = DVec3::new(next(3072) as f64, next(3072) as f64, next(3072) as f64) / 1024.0;
            // Aimed at a point of the shape's box (most rays hit), on the same grid.
            let aim = DVec3::new(next(1024) as f64, next(1024) as f64, next(1024) as f64) / 1024.0;
            let d = aim - (oa + a);
            if d == DVec3::ZERO {
                continue;
            }
            let near = Ray::new(vec3(oa), vec3(d));
            let far = Ray::new(vec3(oa + a), vec3(d));
            let (got, want) = (
                anchored.intersect(&near, 0.0, Real::INFINITY),
                canonical.intersect(&far, 0.0, Real::INFINITY),
            );
            match (got, want) {
                (None, None) => {}
                (Some(g), Some(w)) => {
                    hits += 1;
                    let (gt, wt) = (g.t as f64, w.t as f64);
                    let (gn, wn) = (dvec3(g.n_geo).normalize(), dvec3(w.n_geo).normalize());
                    let (gp, wp) = (dvec3(g.p) + a, dvec3(w.p));
                    inside += (wn.dot(d) > 0.0) as u32;
                    if (gt - wt).abs() > 16.0 * eps * wt
                        || gn.dot(wn) < 1.0 - 1e-6
                        || (gp - wp).length() > 16.0 * eps * (1.0 + wp.length())
                    {
                        wrong.push(format!(
                            "{kind:?} about {a}: ray {oa} + t·{d}: t {gt} n {gn} p {gp}, canonical t {wt} n {wn} p {wp}"
                        ));
                    }
                }
                (g, w) => wrong.push(format!(
                    "{kind:?} about {a}: ray {oa} + t·{d}: anchored {:?}, canonical {:?}",
                    g.map(|h| h.t),
                    w.map(|h| h.t)
                )),
            }
        }
        assert!(
            hits > 2000 && inside > 200,
            "{kind:?}: too few hits ({hits}) or exits ({inside}) to test"
        );
    }
    assert!(
        wrong.is_empty(),
        "{} rays differ between the anchored shapes (renderer/src/shapes/anchored.rs) and the canonical ones:\n{}",
        wrong.len(),
        wrong.iter().take(12).cloned().collect::<Vec<_>>().join("\n")
    );
}
