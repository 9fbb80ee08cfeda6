//! Grazing and tangent rays: rays nearly parallel to a plane, disk or box face, and rays
//! tangent to curved surfaces, either miss or hit where the closed form says.
//!
//! Each test states its bound with the figure measured for it (the worst case seen, in
//! this build's precision; run with `--nocapture` to see the figures). Where f32 breaks
//! down the test says so and states the range it supports.

use common::SplitMix;
use glam::DVec3;
use renderer::aggregate::Shape;
use renderer::real::{dvec3, vec3};
use renderer::{Ray, Real, Vec3};
use std::f64::consts::TAU;

mod common;
use common::extremes::{aimed, assert_finite, report, EPS, INF};

// ---------------------------------------------------------------------------------------
// Grazing rays.

/// The f64 slab test of [−1, 1]³ for the ray exactly as given, with the renderer's
/// conventions (closed slabs; from inside, the exit): (t, axis) of the first crossing
/// with t > 0, and the margin (far − near)·|d| by which the ray's line meets the box.
fn box_reference(o: DVec3, d: DVec3) -> (Option<(f64, usize)>, f64) {
    let (mut near, mut far, mut near_axis, mut far_axis) = (f64::NEG_INFINITY, f64::INFINITY, 0, 0);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k].abs() > 1.0 {
                return (None, f64::NEG_INFINITY);
            }
            continue;
        }
        let (a, b) = ((-1.0 - o[k]) / d[k], (1.0 - o[k]) / d[k]);
        let (a, b) = (a.min(b), a.max(b));
        if a > near {
            near = a;
            near_axis = k;
        }
        if b < far {
            far = b;
            far_axis = k;
        }
    }
    let margin = (far - near) * d.length();
    let hit = if near > far {
        None
    } else if near > 0.0 {
        Some((near, near_axis))
    } else if far > 0.0 {
        Some((far, far_axis))
    } else {
        None
    };
    (hit, margin)
}

#[test]
fn grazing_rays_on_plane_disk_and_box() {
    // Rays meeting a plane, a disk and a box face at angles from 1e-1 down to 1e-7 rad,
    // aimed at points on them (and, for the disk and the box, just beyond their edge).
    // The f64 answer for the ray as given is the reference. No NaN; the same hit/miss
    // answer (measured 0 disagreements); t within 8 EPS relative (measured 1.04 EPS in
    // f32, 1.0 in f64). Rays whose line passes within 64·EPS·(1 + |o|) of the disk's rim
    // or a box edge have no defined answer at this precision and are skipped (32 of
    // 420,000 in f32, none in f64).
    let mut rng = SplitMix(23);
    let mut worst = 0.0f64;
    let (mut n_hits, mut skipped) = (0, 0);
    for e in 1..=7 {
        let theta = 10f64.powi(-e);
        for _ in 0..20_000 {
            let phi = rng.range(0.0, TAU);
            let h = DVec3::new(phi.cos(), 0.0, phi.sin());
            let len = rng.range(0.5, 10.0);
            // Plane and disk in y = 0, from above or below.
            let side = if rng.f() < 0.5 { 1.0 } else { -1.0 };
            let dir = h * theta.cos() - DVec3::Y * (side * theta.sin());
            for (shape, radius) in [(Shape::Plane, 5.0), (Shape::Disk, 1.0)] {
                let rr = radius * rng.range(0.0, 1.1).sqrt();
                let a = rng.range(0.0, TAU);
                let target = DVec3::new(rr * a.cos(), 0.0, rr * a.sin());
                let r = aimed(target - dir * len, target, rng.range(0.5, 2.0));
                let (o, d) = (dvec3(r.o), dvec3(r.d));
                let t_ref = -o.y / d.y;
                let p = o + d * t_ref;
                let rim = (p.x * p.x + p.z * p.z).sqrt() - 1.0;
                if matches!(shape, Shape::Disk) && rim.abs() < 64.0 * EPS * (1.0 + o.length()) {
                    skipped += 1;
                    continue;
                }
                let inside = matches!(shape, Shape::Plane) || rim <= 0.0;
                let want = t_ref > 0.0 && inside;
                let got = shape.intersect(&r, 0.0, INF);
                assert_eq!(got.is_some(), want, "{shape:?} θ = {theta:e}: {r:?}");
                if let Some(hit) = got {
                    assert_finite(&hit);
                    assert_eq!(hit.p.y, 0.0);
                    worst = worst.max((hit.t as f64 - t_ref).abs() / t_ref);
                    n_hits += 1;
                }
            }
            // A box face: target on a random face, within 0.9 of its centre or 1.02–1.2
            // beyond it along one axis.
            let axis = rng.below_scaled(3);
            let sgn = if rng.f() < 0.5 { -1.0 } else { 1.0 };
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut target = DVec3::ZERO;
            target[axis] = sgn;
            target[u] = rng.range(-0.9, 0.9);
            target[v] = rng.range(-0.9, 0.9);
            if rng.f() < 0.3 {
                target[u] = rng.range(1.02, 1.2) * if rng.f() < 0.5 { -1.0 } else { 1.0 };
            }
            // Along the face (a random direction in it), descending onto it at θ.
            let mut along = DVec3::ZERO;
            along[u] = phi.cos();
            along[v] = phi.sin();
            let mut normal = DVec3::ZERO;
            normal[axis] = sgn;
            let dir = along * theta.cos() - normal * theta.sin();
            let r = aimed(target - dir * len, target, rng.range(0.5, 2.0));
            let (want, margin) = box_reference(dvec3(r.o), dvec3(r.d));
            // Rays whose line passes within rounding of an edge (the box's silhouette) have
            // no defined answer at this precision: skipped.
            if margin.abs() < 64.0 * EPS * (1.0 + dvec3(r.o).length()) {
                skipped += 1;
                continue;
            }
            let got = Shape::Cube.intersect(&r, 0.0, INF);
            assert_eq!(
                got.is_some(),
                want.is_some(),
                "box θ = {theta:e}: {r:?} {want:?}"
            );
            if let (Some(hit), Some((t, k))) = (got, want) {
                assert_finite(&hit);
                worst = worst.max((hit.t as f64 - t).abs() / t);
                assert!(
                    hit.n_geo[k] != 0.0,
                    "box θ = {theta:e}: crossed at axis {k}, normal {:?}",
                    hit.n_geo
                );
                n_hits += 1;
            }
        }
    }
    report(
        "grazing: worst relative t error",
        format!("{worst:e} over {n_hits} hits ({skipped} rays within rounding of a disk's rim or a box's edge skipped)"),
    );
    assert!(worst <= 8.0 * EPS, "t error {worst:e}");

    // Exactly parallel: the documented answers. A ray parallel to the plane y = 0 never
    // hits the plane or the disk, even lying in it. A ray lying in a box face's plane is
    // inside that (closed) slab, so it hits the side face it enters through.
    for y in [0.0, 1e-30, -1e-7, 0.5] {
        let r = Ray::new(Vec3::new(-3.0, y as Real, 0.25), Vec3::new(1.0, 0.0, 0.1));
        assert!(Shape::Plane.intersect(&r, 0.0, INF).is_none());
        assert!(Shape::Disk.intersect(&r, 0.0, INF).is_none());
        assert!(Shape::Rectangle.intersect(&r, 0.0, INF).is_none());
    }
    let r = Ray::new(Vec3::new(-3.0, 1.0, 0.25), Vec3::new(1.0, 0.0, 0.1));
    let h = Shape::Cube
        .intersect(&r, 0.0, INF)
        .expect("the face plane is part of the slab");
    assert_eq!((h.t, h.n_geo), (2.0, Vec3::new(-1.0, 0.0, 0.0)));
}

// ---------------------------------------------------------------------------------------
// Tangent rays.

#[test]
fn tangent_rays_miss_or_touch_the_tangent_point() {
    // Rays tangent (in f64) to a sphere, a cylinder (capped and open) and a cone, rounded to
    // Real: never NaN, and either a miss or a hit near the tangent point q. Rounding puts
    // the ray up to δ ≈ EPS·(1 + |o|) off tangency, and a chord of half-length √(2δ/κ)
    // follows (κ: the surface's normal curvature along the ray), so the bound is
    // |p − q| ≤ 4·√(EPS·(1 + |o|)/κ) (measured 1.26 in f32, 1.34 in f64; before the fix
    // in cone.rs, a tangent ray's Newton step could jump along the ray and report a hit
    // 0.46 away from q).
    let mut rng = SplitMix(29);
    let mut worst = 0.0f64;
    let (mut hits, mut total) = (0, 0);
    let shapes = [
        Shape::Sphere,
        Shape::Cylinder { capped: true },
        Shape::Cylinder { capped: false },
        Shape::Cone { capped: true },
    ];
    for (k, shape) in shapes.iter().enumerate() {
        for _ in 0..50_000 {
            let phi = rng.range(0.0, TAU);
            let radial = DVec3::new(phi.cos(), 0.0, phi.sin());
            let around = DVec3::new(-phi.sin(), 0.0, phi.cos());
            // Not along the surface's straight lines: at least 10° off them.
            let alpha = rng.range(-80.0, 80.0f64).to_radians();
            // The tangent point, the direction, and the surface's normal curvature along it.
            let (q, dir, kappa) = match k {
                0 => {
                    let q = rng.unit();
                    let (b1, b2) = q.any_orthonormal_pair();
                    (q, b1 * alpha.cos() + b2 * alpha.sin(), 1.0)
                }
                1 | 2 => (
                    radial + DVec3::Y * rng.range(-0.9, 0.9),
                    around * alpha.cos() + DVec3::Y * alpha.sin(),
                    alpha.cos().powi(2),
                ),
                _ => {
                    let y = rng.range(-0.9, 0.9);
                    let r = 0.5 * (1.0 - y);
                    let q = radial * r + DVec3::Y * y;
                    let g = (DVec3::Y - q).normalize();
                    // Along the circle: cos β / r with cos β = 1/√1.25 (the normal's tilt).
                    (
                        q,
                        around * alpha.cos() + g * alpha.sin(),
                        alpha.cos().powi(2) / (1.25f64.sqrt() * r),
                    )
                }
            };
            let len = rng.range(0.1, 10.0);
            let o = q - dir * len;
            let r = Ray::new(vec3(o), vec3(dir * rng.range(0.2, 5.0)));
            total += 1;
            if let Some(h) = shape.intersect(&r, 0.0, INF) {
                assert_finite(&h);
                hits += 1;
                let e = (dvec3(h.p) - q).length() * (kappa / (EPS * (1.0 + o.length()))).sqrt();
                worst = worst.max(e);
                assert!(e <= 4.0, "{shape:?}: hit {:?}, tangent point {q}", h.p);
            }
        }
    }
    report(
        "tangent rays: worst |p − q| / √(EPS·(1 + |o|))",
        format!("{worst:.3} ({hits} hits of {total})"),
    );

    // Along a straight line of the surface (a cylinder generator, a cone generator through
    // the apex): the documented answer is a miss, or a hit on that line (the cap's rim, or
    // the cone's generator), never NaN.
    let (mut line_hits, mut line_total) = (0, 0);
    for _ in 0..20_000 {
        let phi = rng.range(0.0, TAU);
        let radial = DVec3::new(phi.cos(), 0.0, phi.sin());
        let up = if rng.f() < 0.5 { 1.0 } else { -1.0 };
        for capped in [true, false] {
            let o = radial + DVec3::Y * (-3.0 * up);
            let r = Ray::new(vec3(o), vec3(DVec3::Y * up));
            line_total += 1;
            if let Some(h) = (Shape::Cylinder { capped }).intersect(&r, 0.0, INF) {
                assert_finite(&h);
                line_hits += 1;
                let p = dvec3(h.p);
                assert!(p.y.abs() <= 1.0, "{p}");
                assert!(
                    ((p.x * p.x + p.z * p.z).sqrt() - 1.0).abs() < 8.0 * EPS,
                    "{p}"
                );
            }
        }
        let q = radial * 1.0 - DVec3::Y; // on the base rim
        let g = DVec3::Y - q;
        let o = q - g * rng.range(0.1, 3.0);
        let r = Ray::new(vec3(o), vec3(g));
        line_total += 1;
        if let Some(h) = (Shape::Cone { capped: false }).intersect(&r, 0.0, INF) {
            assert_finite(&h);
            line_hits += 1;
            let p = dvec3(h.p);
            // On the generator: distance from the line q + s·g.
            let off = (p - q).cross(g.normalize()).length();
            assert!(
                off < 1e3 * EPS,
                "cone generator hit {p} is {off} off the line"
            );
        }
    }
    report(
        "rays along surface lines",
        format!("{line_hits} hits of {line_total}"),
    );
}
