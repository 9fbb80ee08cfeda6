//! Primary-ray throughput (closest hit, no shading) on N = 1, 100, 10 000 and 1 000 000
//! spheres and on a mesh of about one million triangles. Run with
//! `cargo bench -p renderer --bench primary_rays`; results go to renderer/docs/performance.md.
//!
//! The spheres are scattered uniformly in the cube [−1, 1]³ with radius `0.75/√N`, which
//! holds the optical depth of the cloud constant (N·πr²·2/8 ≈ 0.44 along a ray through the
//! cube): every N puts about the same number of spheres along each ray and covers about the
//! same part of the image, so the per-ray cost measures the acceleration structure and not
//! the scene's depth complexity. Each iteration traces the pixel-centre rays of a 128×128
//! camera on one thread.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{DMat3, DVec3};
use renderer::aggregate::{Aggregate, Instance};
use renderer::camera::{Camera, FovAxis, ViewingModel};
use renderer::real::{Real, Vec3};
use renderer::shapes::{Mesh, Shape};
use renderer::transform::{Affine64, Transform};
use std::sync::Arc;

const RES: u32 = 128;

fn camera() -> Camera {
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

/// N spheres in [−1, 1]³ with radius 0.75/√N.
pub fn spheres(n: usize) -> Aggregate {
    let mut s = 7u64;
    let r = 0.75 / (n as f64).sqrt();
    let v: Vec<Instance> = (0..n)
        .map(|k| {
            let c = DVec3::new(rnd(&mut s), rnd(&mut s), rnd(&mut s)) * 2.0 - 1.0;
            let a = Affine64 {
                m: DMat3::from_diagonal(DVec3::splat(r)),
                d: c,
            };
            Instance {
                shape: Shape::Sphere,
                xf: Some(Transform::new(&a).unwrap()),
                material: 0,
                object_id: k as u32 + 1,
            }
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

fn trace_all(cam: &Camera, agg: &Aggregate) -> u32 {
    let mut hits = 0;
    for j in 0..RES {
        for i in 0..RES {
            if agg.intersect(&cam.pixel_ray(i, j), 0.0, Real::INFINITY).is_some() {
                hits += 1;
            }
        }
    }
    hits
}

fn bench(c: &mut Criterion) {
    let cam = camera();
    let mut g = c.benchmark_group("primary_rays");
    g.throughput(Throughput::Elements((RES * RES) as u64));
    g.sample_size(20);
    for n in [1usize, 100, 10_000, 1_000_000] {
        let agg = spheres(n);
        g.bench_with_input(BenchmarkId::new("spheres", n), &agg, |b, agg| b.iter(|| trace_all(&cam, agg)));
    }
    let m = Arc::new(mesh(1000, 500));
    let agg = Aggregate::new(vec![Instance {
        shape: Shape::Mesh(m.clone()),
        xf: None,
        material: 0,
        object_id: 1,
    }]);
    g.bench_with_input(
        BenchmarkId::new("mesh_triangles", m.triangles.len()),
        &agg,
        |b, agg| b.iter(|| trace_all(&cam, agg)),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
