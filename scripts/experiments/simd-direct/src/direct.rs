//! The `direct` integrator (one light sample and one BSDF sample at the first hit,
//! combined by the power heuristic, as Mitsuba's `direct` with its defaults) for eight
//! samples of one pixel at once, in the lanes.
use crate::lanes::{uniform, V};
use crate::scene::Scene;
use std::f32::consts::{FRAC_1_PI, TAU};
use wide::*;

/// The one area light: a rectangle at y = `y` over [x0, x0 + size] x [z0, z0 + size],
/// facing down (-y), of radiance `radiance`, and its object's index.
pub struct Light {
    pub y: f32,
    pub x0: f32,
    pub z0: f32,
    pub size: f32,
    pub radiance: f32,
    pub object: usize,
}

/// The camera of a look-at with a horizontal field of view: the eye, and the rotation's
/// up and forward axes' y and z (its x axis is +x).
pub struct Camera {
    pub eye: V,
    pub tan_half_fov: f32,
    pub cos: f32,
    pub sin: f32,
}

fn mis(a: f32x8, b: f32x8) -> f32x8 {
    let (a2, b2) = (a * a, b * b);
    a2 / (a2 + b2)
}

/// A cosine-distributed direction about the unit `n` (Duff et al.'s frame).
fn cosine_dir(n: V, u1: f32x8, u2: f32x8) -> V {
    let r = u1.sqrt();
    let (s, c) = (u2 * f32x8::splat(TAU)).sin_cos();
    let (lx, ly, lz) = (r * c, r * s, (f32x8::ONE - u1).max(f32x8::ZERO).sqrt());
    let sign = n.z.cmp_ge(f32x8::ZERO).blend(f32x8::ONE, f32x8::splat(-1.0));
    let a = f32x8::splat(-1.0) / (sign + n.z);
    let b = n.x * n.y * a;
    let t1 = V { x: f32x8::ONE + sign * n.x * n.x * a, y: sign * b, z: -sign * n.x };
    let t2 = V { x: b, y: sign + n.y * n.y * a, z: -n.y };
    t1.mul(lx).add(t2.mul(ly)).add(n.mul(lz))
}

/// Eight samples of pixel (i, j) of a w x h image, lane l drawing from `key`'s lane l:
/// their summed RGB.
pub fn eight(scene: &Scene, light: &Light, cam: &Camera, (w, h): (usize, usize), (i, j): (usize, usize), key: u32x8) -> [f32x8; 3] {
    let px = (f32x8::splat(i as f32) + uniform(key, 0)) * f32x8::splat(2.0 / w as f32) - f32x8::ONE;
    let py = f32x8::ONE - (f32x8::splat(j as f32) + uniform(key, 1)) * f32x8::splat(2.0 / h as f32);
    let (lx, ly) = (px * f32x8::splat(cam.tan_half_fov), py * f32x8::splat(cam.tan_half_fov));
    let (c, s) = (f32x8::splat(cam.cos), f32x8::splat(cam.sin));
    let d = V { x: lx, y: ly * c - s, z: ly * s + c }.normalize();
    let (t, id, ng) = scene.closest(cam.eye, d, f32x8::ZERO);
    let hit = t.cmp_lt(f32x8::splat(f32::INFINITY));
    if hit.none() {
        return [f32x8::ZERO; 3];
    }
    let p = cam.eye.add(d.mul(t));
    let ng = ng.normalize();
    let front = ng.dot(d).cmp_lt(f32x8::ZERO);
    let ns = V::blend(front, ng, ng.mul(f32x8::splat(-1.0)));
    // Per-lane material: a gather from the object table.
    let ids = id.to_array();
    let (mut albedo, mut le) = ([[0f32; 8]; 3], [0f32; 8]);
    for l in 0..8 {
        if ids[l] >= 0 {
            let o = &scene.objects[ids[l] as usize];
            for k in 0..3 {
                albedo[k][l] = o.albedo[k];
            }
            le[l] = o.radiance;
        }
    }
    let is_light: f32x8 = bytemuck::cast(id.cmp_eq(i32x8::splat(light.object as i32)));
    let seen = (is_light & front & hit).blend(f32x8::from(le), f32x8::ZERO);
    let diffuse = hit & !is_light;
    let area = light.size * light.size;
    let mut grey = f32x8::ZERO;
    if diffuse.any() {
        let offset = |p: V| p.add(ns.mul(f32x8::splat(1e-4)));
        // Light sampling.
        let q = V {
            x: f32x8::splat(light.x0) + uniform(key, 2) * f32x8::splat(light.size),
            y: f32x8::splat(light.y),
            z: f32x8::splat(light.z0) + uniform(key, 3) * f32x8::splat(light.size),
        };
        let to = q.sub(p);
        let d2 = to.dot(to);
        let dist = d2.sqrt();
        let wi = to.mul(f32x8::ONE / dist);
        let (cos_l, cos_s) = (wi.y, ns.dot(wi));
        let ok = diffuse & cos_l.cmp_gt(f32x8::ZERO) & cos_s.cmp_gt(f32x8::ZERO);
        if ok.any() {
            let blocked = scene.occluded(offset(p), wi, f32x8::ZERO, dist * f32x8::splat(1.0 - 1e-4), light.object);
            let pdf_l = d2 / (cos_l * f32x8::splat(area));
            let pdf_b = cos_s * f32x8::splat(FRAC_1_PI);
            let v = f32x8::splat(light.radiance) * cos_s * f32x8::splat(FRAC_1_PI) * mis(pdf_l, pdf_b) / pdf_l;
            grey += (ok & !blocked).blend(v, f32x8::ZERO);
        }
        // BSDF sampling.
        let wi = cosine_dir(ns, uniform(key, 4), uniform(key, 5));
        let (t2, id2, _) = scene.closest(offset(p), wi, f32x8::ZERO);
        let on_light: f32x8 = bytemuck::cast(id2.cmp_eq(i32x8::splat(light.object as i32)));
        let found = diffuse & on_light & wi.y.cmp_gt(f32x8::ZERO);
        if found.any() {
            let pdf_l = t2 * t2 / (wi.y * f32x8::splat(area));
            let pdf_b = ns.dot(wi) * f32x8::splat(FRAC_1_PI);
            grey += found.blend(f32x8::splat(light.radiance) * mis(pdf_b, pdf_l), f32x8::ZERO);
        }
    }
    let a = albedo.map(f32x8::from);
    [seen + grey * a[0], seen + grey * a[1], seen + grey * a[2]]
}
