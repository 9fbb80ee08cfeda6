//! Helpers shared by the tests of extreme inputs (far_from_origin, edges_and_seams,
//! grazing_and_tangent, degenerate_transforms, coplanar_and_refraction).

use glam::{DMat3, DVec3};
use renderer::aggregate::Shape;
use renderer::real::{dvec3, vec3};
use renderer::render::{render, Image, Options};
use renderer::scene::Scene;
use renderer::spawn::Spawn;
use renderer::{Affine64, Hit, Instance, Ray, Real, Transform, Vec3};
use std::path::Path;

/// Machine epsilon of the renderer's precision.
pub const EPS: f64 = Real::EPSILON as f64;
pub const INF: Real = Real::INFINITY;
pub const F64: bool = cfg!(feature = "f64");

pub fn report(what: &str, v: impl std::fmt::Display) {
    eprintln!("measured [{}] {what}: {v}", renderer::real::PRECISION);
}

/// A ray from `o` (rounded to `Real`) aimed at `target`, with direction length `len`
/// times the distance. The direction is computed from the rounded origin.
pub fn aimed(o: DVec3, target: DVec3, len: f64) -> Ray {
    let o = vec3(o);
    Ray::new(o, vec3((target - dvec3(o)) * len))
}

#[track_caller]
pub fn assert_finite(h: &Hit) {
    assert!(
        h.t.is_finite()
            && h.p.is_finite()
            && h.err.is_finite()
            && h.n_geo.is_finite()
            && h.n_shade.is_finite()
            && h.uv.is_finite()
            && h.n_geo != Vec3::ZERO,
        "non-finite hit {h:?}"
    );
}

pub fn rot(axis: DVec3, angle: f64) -> DMat3 {
    DMat3::from_axis_angle(axis.normalize(), angle)
}

pub fn instance(shape: Shape, a: &Affine64) -> Instance {
    Instance {
        shape,
        xf: Some(Transform::new(a).expect("a valid transform")),
        material: 1,
        object_id: 1,
    }
}

pub fn scene(text: &str) -> Scene {
    Scene::from_str(text, Path::new("extremes.toml"), Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
}

pub fn render_with(scene: &Scene, threads: usize, spawn: Spawn) -> Image {
    let img = render(
        scene,
        &Options {
            threads: Some(threads),
            aov: true,
            spawn,
            ..Options::default()
        },
    );
    assert_eq!(img.non_finite, 0, "non-finite pixels");
    assert!(img.rgb.iter().all(|v| v.is_finite()));
    img
}

pub fn ids(img: &Image) -> &[f32] {
    &img.aov.as_ref().unwrap().object_id
}
