//! Scenes shared by the benchmarks (see primary_rays.rs for what each family measures).

#![allow(dead_code)]

use glam::{DMat3, DVec3};
use renderer::aggregate::Shape;
use renderer::aggregate::{Aggregate, Instance};
use renderer::camera::{Camera, FovAxis, ViewingModel};
use renderer::ray::Ray;
use renderer::real::{Real, Vec3};
use renderer::shapes::Mesh;
use renderer::transform::{Affine64, Transform};

/// Image side: every iteration traces RES × RES pixel-centre rays.
pub const RES: u32 = 128;

/// The camera every benchmark uses.
pub fn camera() -> Camera {
    let m = ViewingModel::look_at(
        DVec3::new(0.3, 0.8, -4.0),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        FovAxis::Horizontal,
        RES,
        RES,
    )
    .unwrap();
    Camera::new(m).unwrap()
}

/// A deterministic uniform number in [0, 1).
fn rnd(state: &mut u64) -> f64 {
    *state = renderer::sampler::mix64(state.wrapping_add(0x9e37_79b9_7f4a_7c15));
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn sphere_at(c: DVec3, r: f64, id: usize) -> Instance {
    let a = Affine64 {
        m: DMat3::from_diagonal(DVec3::splat(r)),
        d: c,
    };
    Instance {
        shape: Shape::Sphere,
        xf: Some(Transform::new(&a).unwrap()),
        material: 0,
        object_id: id as u32 + 1,
    }
}

/// N spheres in [−1, 1]³ with radius 0.35·N^(−1/3).
pub fn cloud(n: usize) -> Aggregate {
    let mut s = 7u64;
    let r = 0.35 * (n as f64).powf(-1.0 / 3.0);
    let v = (0..n)
        .map(|k| {
            sphere_at(
                DVec3::new(rnd(&mut s), rnd(&mut s), rnd(&mut s)) * 2.0 - 1.0,
                r,
                k,
            )
        })
        .collect();
    Aggregate::new(v)
}

/// N spheres of radius 1/√N on a jittered grid in a layer facing the camera.
pub fn front(n: usize) -> Aggregate {
    let mut s = 7u64;
    let side = (n as f64).sqrt();
    let r = 1.0 / side;
    let v = (0..n)
        .map(|k| {
            let (gx, gy) = ((k as f64 / side).floor(), k as f64 % side);
            let c = DVec3::new(
                (gx + 0.5) / side * 2.0 - 1.0 + (rnd(&mut s) - 0.5) * r,
                (gy + 0.5) / side * 2.0 - 1.0 + (rnd(&mut s) - 0.5) * r,
                (rnd(&mut s) - 0.5) * 2.0 * r,
            );
            sphere_at(c, r, k)
        })
        .collect();
    Aggregate::new(v)
}

/// A UV sphere of radius 1 with `2·nu·nv` triangles and a bumpy radius.
pub fn mesh(nu: usize, nv: usize) -> Mesh {
    let mut pos = Vec::with_capacity((nu + 1) * (nv + 1));
    for j in 0..=nv {
        let th = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..=nu {
            let ph = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            let r = 1.0 + 0.03 * (7.0 * ph).sin() * (5.0 * th).sin();
            pos.push(Vec3::new(
                (r * th.sin() * ph.cos()) as Real,
                (r * th.cos()) as Real,
                (r * th.sin() * ph.sin()) as Real,
            ));
        }
    }
    let mut tris = Vec::with_capacity(2 * nu * nv);
    let idx = |i: usize, j: usize| (j * (nu + 1) + i) as u32;
    for j in 0..nv {
        for i in 0..nu {
            tris.push([idx(i, j), idx(i + 1, j), idx(i, j + 1)]);
            tris.push([idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]);
        }
    }
    Mesh::new(pos, None, None, tris).unwrap()
}

/// An aggregate whose only instance is `mesh`, unplaced (what every mesh benchmark
/// traces).
pub fn one_mesh(mesh: std::sync::Arc<Mesh>) -> Aggregate {
    Aggregate::new(vec![Instance {
        shape: Shape::Mesh(mesh),
        xf: None,
        material: 0,
        object_id: 1,
    }])
}

/// Traces every pixel-centre ray on this thread, a row at a time through
/// `Aggregate::intersect_many` as the renderer traces camera rays; returns the number of
/// hits.
pub fn trace_all(cam: &Camera, agg: &Aggregate) -> u32 {
    let mut rays = [Ray::new(Vec3::ZERO, Vec3::ONE); RES as usize];
    let mut hits = [None; RES as usize];
    let mut count = 0;
    for j in 0..RES {
        for (i, ray) in rays.iter_mut().enumerate() {
            *ray = cam.pixel_ray(i as u32, j);
        }
        agg.intersect_many(&rays, 0.0, Real::INFINITY, &mut hits);
        count += hits.iter().filter(|h| h.is_some()).count() as u32;
    }
    count
}
