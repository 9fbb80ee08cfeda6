//! The curved primitives (sphere, cylinder, cone; capped and open) against hand-worked
//! closed forms, one `check` line per case.
//!
//! For each hit the helper checks: t against the closed form, the normalized geometric
//! normal against the analytic outward normal, uv against the mapping documented in the
//! shape's source, that `Hit.p` is the point o + t·d and lies on the surface within its own
//! error bound `Hit.err` (finite, non-negative), that scaling the direction by 3 divides t
//! by 3, that the interval `(t_min, t_max)` is honoured, and that `occluded` agrees.

use glam::DVec3;
use renderer::aggregate::Shape;
use std::f64::consts::PI;

mod common;
use common::primitives::*;
use common::SplitMix;

#[test]
fn sphere() {
    let s = Shape::Sphere;
    // Hits from outside; uv = (azimuth, 1 − acos(y)/π).
    check(
        &s,
        [0., 0., -5.],
        [0., 0., 1.],
        hit(4.0, [0., 0., -1.], [0.75, 0.5]),
    );
    check(
        &s,
        [0., 5., 0.],
        [0., -1., 0.],
        hit(4.0, [0., 1., 0.], [0.0, 1.0]),
    );
    let z = -(0.75f64).sqrt();
    check(
        &s,
        [0.3, 0.4, -5.],
        [0., 0., 2.],
        hit(
            (5.0 + z) / 2.0,
            [0.3, 0.4, z],
            [az(0.3, z), 1.0 - 0.4f64.acos() / PI],
        ),
    );
    // A far origin, oblique: |o + t·d|² = 1 solved in closed form.
    let (o, d) = ([30.0, -20.0, 10.0], [-3.0, 2.0, -1.0]);
    let t = {
        let (o, d) = (DVec3::from(o), DVec3::from(d));
        let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) - 1.0);
        (-b - (b * b - a * c).sqrt()) / a
    };
    let p = DVec3::from(o) + DVec3::from(d) * t;
    let uv = [az(p.x, p.z), 1.0 - p.y.acos() / PI];
    check(&s, o, d, hit(t, p.to_array(), uv));
    // Misses: beside, and pointing away.
    check(&s, [0., 1.5, -5.], [0., 0., 1.], Miss);
    check(&s, [0., 0., -5.], [0., 0., -1.], Miss);
    // Tangent at (0, 1, 0); just inside and just outside the silhouette.
    graze(&s, [-5., 1., 0.], [1., 0., 0.], Some([0., 1., 0.]));
    check(&s, [-5., 1.001, 0.], [1., 0., 0.], Miss);
    let x = -(1.0f64 - 0.999 * 0.999).sqrt();
    check(
        &s,
        [-5., 0.999, 0.],
        [1., 0., 0.],
        hit(
            5.0 + x,
            [x, 0.999, 0.],
            [az(x, 0.), 1.0 - 0.999f64.acos() / PI],
        ),
    );
    // From inside: the far side, outward normal.
    check(
        &s,
        [0., 0., 0.],
        [1., 0., 0.],
        hit(1.0, [1., 0., 0.], [0.0, 0.5]),
    );
    check(
        &s,
        [0.5, 0., 0.],
        [-1., 0., 0.],
        hit(1.5, [-1., 0., 0.], [0.5, 0.5]),
    );
}

#[test]
fn cylinder_capped() {
    let s = Shape::Cylinder { capped: true };
    // Side uv (azimuth, (y+1)/2); cap uv ((x+1)/2, (z+1)/2).
    check(
        &s,
        [-5., 0.5, 0.],
        [1., 0., 0.],
        hit(4.0, [-1., 0., 0.], [0.5, 0.75]),
    );
    check(
        &s,
        [0.6, 0., -5.],
        [0., 0., 1.],
        hit(4.2, [0.6, 0., -0.8], [az(0.6, -0.8), 0.5]),
    );
    check(
        &s,
        [0.3, 5., -0.2],
        [0., -1., 0.],
        hit(4.0, [0., 1., 0.], [0.65, 0.4]),
    );
    check(
        &s,
        [0., -3., 0.],
        [0.1, 1., 0.2],
        hit(2.0, [0., -1., 0.], [0.6, 0.7]),
    );
    check(&s, [-5., 1.5, 0.], [1., 0., 0.], Miss);
    check(&s, [2., 5., 0.], [0., -1., 0.], Miss);
    // Tangent to the side at (1, 0, 0).
    graze(&s, [1., 0., -5.], [0., 0., 1.], Some([1., 0., 0.]));
    check(&s, [1.001, 0., -5.], [0., 0., 1.], Miss);
    let z = -(1.0f64 - 0.999 * 0.999).sqrt();
    check(
        &s,
        [0.999, 0., -5.],
        [0., 0., 1.],
        hit(5.0 + z, [0.999, 0., z], [az(0.999, z), 0.5]),
    );
    // Through the rim of the top cap.
    graze(&s, [1., 5., 0.], [0., -1., 0.], None);
    // From inside: cap and side, outward normals.
    check(
        &s,
        [0., 0., 0.],
        [0., 1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.5]),
    );
    check(
        &s,
        [0., 0., 0.],
        [0., 0., 1.],
        hit(1.0, [0., 0., 1.], [0.25, 0.5]),
    );
    check(
        &s,
        [0.2, 0.5, 0.],
        [0., -1., 0.],
        hit(1.5, [0., -1., 0.], [0.6, 0.5]),
    );
}

#[test]
fn cylinder_open() {
    let s = Shape::Cylinder { capped: false };
    check(
        &s,
        [-5., 0.5, 0.],
        [1., 0., 0.],
        hit(4.0, [-1., 0., 0.], [0.5, 0.75]),
    );
    check(
        &s,
        [0.6, 0., -5.],
        [0., 0., 1.],
        hit(4.2, [0.6, 0., -0.8], [az(0.6, -0.8), 0.5]),
    );
    // Down the axis: no caps, so nothing to hit.
    check(&s, [0.3, 5., 0.], [0., -1., 0.], Miss);
    check(&s, [-5., 1.5, 0.], [1., 0., 0.], Miss);
    // In through the open top, onto the inside of the wall: the normal is still outward.
    check(
        &s,
        [0., 2., 0.],
        [0.5, -1., 0.],
        hit(2.0, [1., 0., 0.], [0.0, 0.5]),
    );
    graze(&s, [1., 0., -5.], [0., 0., 1.], Some([1., 0., 0.]));
    check(&s, [1.001, 0., -5.], [0., 0., 1.], Miss);
    // From inside.
    check(
        &s,
        [0., 0., 0.],
        [0., 0., -1.],
        hit(1.0, [0., 0., -1.], [0.75, 0.5]),
    );
    check(&s, [0., 0., 0.], [0., 1., 0.], Miss);
}

/// Rays aimed at points of the cylinder's rims from anywhere (4,096 of them, capped and
/// open): `occluded` agrees with `intersect`, every hit is a point of the surface within
/// its error bound, and a side point lies in the slab −1 ≤ y ≤ 1 exactly (`o.y + t·d.y`
/// rounds across a rim, and the side's y is clamped back). And a ray down the line of the
/// wall, x² + z² = 1 exactly, meets the cap at its rim: the radius test is closed, as the
/// side's interval is.
#[test]
fn cylinder_rims() {
    let mut rng = SplitMix(1);
    for capped in [true, false] {
        let s = Shape::Cylinder { capped };
        let mut side = 0;
        for _ in 0..4096 {
            let (o, d) = rng.toward_cylinder_rim();
            let (o, d) = (o.to_array(), d.to_array());
            let r = ray(o, d);
            let got = s.intersect(&r, 0.0, INF);
            assert_eq!(
                got.is_some(),
                s.occluded(&r, 0.0, INF),
                "{} o={o:?} d={d:?}: intersect and occluded disagree \
                 (renderer/src/shapes/cylinder.rs intersect, hits)",
                name(&s)
            );
            let Some(h) = got else {
                continue;
            };
            check_record(&s, &r, &h);
            assert!(
                (-1.0..=1.0).contains(&h.p.y),
                "{} o={o:?} d={d:?}: the hit's y {} is outside the slab \
                 (renderer/src/shapes/cylinder.rs Crossing::record)",
                name(&s),
                h.p.y
            );
            side += (h.n_geo.y == 0.0) as usize;
        }
        assert!(side > 1000, "only {side} side hits");
    }
    let s = Shape::Cylinder { capped: true };
    check(
        &s,
        [1., 5., 0.],
        [0., -1., 0.],
        hit(4.0, [0., 1., 0.], [1.0, 0.5]),
    );
    check(
        &s,
        [0., -5., -1.],
        [0., 1., 0.],
        hit(4.0, [0., -1., 0.], [0.5, 0.0]),
    );
}

/// The cylinder's interval is open at both ends, as every shape's: a root exactly at
/// `t_min` (a ray leaving the side from a point on it, where the root is −0) or exactly
/// at `t_max` is not a hit, for the side and for a cap.
#[test]
fn cylinder_interval_is_open() {
    for capped in [true, false] {
        let s = Shape::Cylinder { capped };
        let what = name(&s);
        let leaving = ray([1., 0., 0.], [1., 0., 0.]);
        assert!(
            s.intersect(&leaving, 0.0, INF).is_none() && !s.occluded(&leaving, 0.0, INF),
            "{what}: a ray leaving the side from a point on it hits its own root at t = 0 \
             (renderer/src/shapes/cylinder.rs Crossing::pick, t > t_min)"
        );
        let toward = ray([-5., 0., 0.], [1., 0., 0.]);
        assert_eq!(s.intersect(&toward, 0.0, INF).map(|h| h.t), Some(4.0));
        assert!(
            s.intersect(&toward, 0.0, 4.0).is_none() && !s.occluded(&toward, 0.0, 4.0),
            "{what}: the side's root at exactly t_max = 4 counts as a hit \
             (renderer/src/shapes/cylinder.rs Crossing::pick, t < t_max)"
        );
    }
    let s = Shape::Cylinder { capped: true };
    let down = ray([0.5, 5., 0.], [0., -1., 0.]);
    assert_eq!(s.intersect(&down, 0.0, INF).map(|h| h.t), Some(4.0));
    assert!(
        s.intersect(&down, 0.0, 4.0).is_none() && s.intersect(&down, 4.0, 5.0).is_none(),
        "the cap at exactly t_max or t_min counts as a hit \
         (renderer/src/shapes/cylinder.rs Crossing::pick)"
    );
}

#[test]
fn cone_capped() {
    let s = Shape::Cone { capped: true };
    // x² + z² = ¼(1 − y)²; side normal (x, ¼(1 − y), z), uv (azimuth, (y+1)/2); cap −y.
    check(
        &s,
        [-5., 0., 0.],
        [1., 0., 0.],
        hit(4.5, [-2., 1., 0.], [0.5, 0.5]),
    );
    check(
        &s,
        [0.2, 5., 0.],
        [0., -1., 0.],
        hit(4.4, [2., 1., 0.], [0.0, 0.8]),
    );
    check(
        &s,
        [0.3, -4., 0.4],
        [0., 1., 0.],
        hit(3.0, [0., -1., 0.], [0.65, 0.7]),
    );
    // Parallel to the generator on the +x side (the linear branch): F = 0.25 − 0.5·t.
    check(
        &s,
        [-0.5, 1., 0.],
        [0.5, -1., 0.],
        hit(0.5, [-2., 1., 0.], [0.5, 0.75]),
    );
    // Through the apex along the axis: hits the apex, normal +y by definition.
    check(
        &s,
        [0., 5., 0.],
        [0., -1., 0.],
        hit(4.0, [0., 1., 0.], [0.0, 1.0]),
    );
    // Misses: beside the tip, and through the upper nappe of the double cone (y > 1).
    check(&s, [-5., 0.9, 0.2], [1., 0., 0.], Miss);
    check(&s, [-5., 2., 0.], [1., 0., 0.], Miss);
    check(&s, [0., -1.5, -5.], [0., 0., 1.], Miss);
    // Tangent at (0.5, 0, 0), with rays just outside and inside it.
    graze(&s, [0.5, 0., -5.], [0., 0., 1.], Some([0.5, 0., 0.]));
    check(&s, [0.501, 0., -5.], [0., 0., 1.], Miss);
    let z = -(0.25f64 - 0.499 * 0.499).sqrt();
    check(
        &s,
        [0.499, 0., -5.],
        [0., 0., 1.],
        hit(5.0 + z, [0.499, 0.25, z], [az(0.499, z), 0.5]),
    );
    // From inside: the side and the base, outward normals.
    check(
        &s,
        [0., 0., 0.],
        [1., 0., 0.],
        hit(0.5, [2., 1., 0.], [0.0, 0.5]),
    );
    check(
        &s,
        [0., -0.5, 0.],
        [0., -1., 0.],
        hit(0.5, [0., -1., 0.], [0.5, 0.5]),
    );
}

#[test]
fn cone_open() {
    let s = Shape::Cone { capped: false };
    check(
        &s,
        [-5., 0., 0.],
        [1., 0., 0.],
        hit(4.5, [-2., 1., 0.], [0.5, 0.5]),
    );
    // Up through the open base onto the inside of the side: normal still outward.
    check(
        &s,
        [0., -5., 0.],
        [0., 1., 0.],
        hit(6.0, [0., 1., 0.], [0.0, 1.0]),
    );
    check(
        &s,
        [0.3, -4., 0.],
        [0., 1., 0.],
        hit(4.4, [2., 1., 0.], [0.0, 0.7]),
    );
    check(&s, [0., -1.5, -5.], [0., 0., 1.], Miss);
}

/// Rays parallel to one of the cone's generator lines (the quadratic's leading coefficient
/// vanishes, and the cone has a single root): from o = q − g with q inside the solid and g
/// a generator direction, F(o + t·g) is linear in t. The hit must lie at that root, against
/// an f64 solution of the ray as rounded to the render precision.
#[test]
fn cone_rays_parallel_to_a_generator_line() {
    let cone = Shape::Cone { capped: false };
    for k in 0..64 {
        let phi = 2.0 * PI * k as f64 / 64.0 + 0.1;
        let psi = 1.7 * k as f64;
        let (r, y) = (0.2 * (k % 5) as f64 / 5.0, -0.5 + (k % 7) as f64 / 7.0);
        let q = DVec3::new(
            r * psi.cos() * 0.5 * (1.0 - y),
            y,
            r * psi.sin() * 0.5 * (1.0 - y),
        );
        let g = DVec3::new(phi.cos(), -2.0, phi.sin());
        let ray = ray((q - g).to_array(), g.to_array());
        // The root of the rounded ray, in f64: a·t² + 2b·t + c = 0 with a ≈ 0.
        let (o, d) = (renderer::real::dvec3(ray.o), renderer::real::dvec3(ray.d));
        let (ow, dw) = (1.0 - o.y, -d.y);
        let a = d.x * d.x + d.z * d.z - 0.25 * dw * dw;
        let b = o.x * d.x + o.z * d.z - 0.25 * ow * dw;
        let c = o.x * o.x + o.z * o.z - 0.25 * ow * ow;
        let want = if a.abs() < 1e-12 {
            -c / (2.0 * b)
        } else {
            let q = -(b + (b * b - a * c).sqrt().copysign(b));
            let (t0, t1) = (q / a, c / q);
            [t0, t1]
                .into_iter()
                .filter(|t| *t > 0.0 && (o.y + t * d.y).abs() <= 1.0)
                .fold(f64::INFINITY, f64::min)
        };
        let h = cone.intersect(&ray, 0.0, INF).unwrap_or_else(|| {
            panic!("ray {k} parallel to a generator line missed (want t = {want})")
        });
        assert!(
            ((h.t as f64 - want) / want).abs() < 1e-5,
            "ray {k} parallel to a generator line: t {} vs {want} (the one-root case of \
             renderer/src/shapes/cone.rs)",
            h.t
        );
        check_record(&cone, &ray, &h);
    }
}

/// `t_min` is exclusive: a ray that starts exactly on a sphere and leaves it has its root
/// at t = 0 = t_min, which is not a hit (a spawned ray must not re-hit its own surface
/// there); with t_min just below 0 it is.
#[test]
fn a_root_at_t_min_is_not_a_hit() {
    let leaving = ray([1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    assert!(
        Shape::Sphere.intersect(&leaving, 0.0, INF).is_none(),
        "a sphere hit at t = t_min = 0 (renderer/src/shapes/sphere.rs: t_min < t < t_max)"
    );
    let h = Shape::Sphere
        .intersect(&leaving, -1e-3, INF)
        .expect("the root at t = 0");
    assert_eq!(h.t, 0.0);
}
