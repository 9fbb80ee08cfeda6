//! Instances: rays mapped into object space by the inverse transform (t unchanged), normals
//! mapped back by M⁻ᵀ, mirrors, nested groups, and transform validation. Every expected
//! value is computed independently in f64, directly in world space.

use glam::{DMat3, DVec3};
use renderer::aggregate::Shape;
use renderer::aggregate::INHERIT;
use renderer::real::{dvec3, vec3, Vec2};
use renderer::shapes::{Mesh, Triangle};
use renderer::transform::TransformError;
use renderer::{Affine64, Aggregate, Hit, Instance, Ray, Real, Transform, Vec3};
use std::sync::Arc;

mod common;
use common::SplitMix;

/// Relative tolerance on t against the f64 closed form.
#[cfg(not(feature = "f64"))]
const T_TOL: f64 = 1e-5;
#[cfg(feature = "f64")]
const T_TOL: f64 = 1e-11;

/// Tolerance on unit normals.
#[cfg(not(feature = "f64"))]
const N_TOL: f64 = 2e-5;
#[cfg(feature = "f64")]
const N_TOL: f64 = 1e-10;

/// Tolerance on unit normals and uv between two roundings of the same transform (a
/// composed matrix against a chain of matrices), relative to the ray's scale.
#[cfg(not(feature = "f64"))]
const G_TOL: f64 = 1e-5;
#[cfg(feature = "f64")]
const G_TOL: f64 = 1e-11;

const INF: Real = Real::INFINITY;

fn affine(m: DMat3, d: DVec3) -> Affine64 {
    Affine64 { m, d }
}

fn transform(a: &Affine64) -> Transform {
    Transform::new(a).expect("a valid transform")
}

fn instance(shape: Shape, a: &Affine64) -> Instance {
    Instance {
        shape,
        xf: Some(transform(a)),
        material: 1,
        object_id: 1,
    }
}

fn rot(axis: [f64; 3], angle: f64) -> DMat3 {
    DMat3::from_axis_angle(DVec3::from(axis).normalize(), angle)
}

fn diag(x: f64, y: f64, z: f64) -> DMat3 {
    DMat3::from_diagonal(DVec3::new(x, y, z))
}

/// A ray in renderer precision, and the same ray exactly, in f64.
fn ray(o: DVec3, d: DVec3) -> (Ray, DVec3, DVec3) {
    let r = Ray::new(vec3(o), vec3(d));
    (r, dvec3(r.o), dvec3(r.d))
}

fn unit(v: Vec3) -> DVec3 {
    dvec3(v).normalize()
}

/// The ellipsoid {x : (x − c)ᵀ A (x − c) = 1} that is the image of the unit sphere under
/// x = M·u + c, with A = (M·Mᵀ)⁻¹, intersected directly in world space: roots of
/// (o − c + t·d)ᵀ A (o − c + t·d) = 1. Returns both roots (ascending).
fn ellipsoid_roots(m: DMat3, c: DVec3, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let a_mat = (m * m.transpose()).inverse();
    let oc = o - c;
    let a = d.dot(a_mat * d);
    let b = d.dot(a_mat * oc);
    let cc = oc.dot(a_mat * oc) - 1.0;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let q = -(b + s.copysign(b));
    let (r0, r1) = (q / a, cc / q);
    Some((r0.min(r1), r0.max(r1)))
}

/// The outward normal of that ellipsoid at x: the gradient A·(x − c).
fn ellipsoid_normal(m: DMat3, c: DVec3, x: DVec3) -> DVec3 {
    ((m * m.transpose()).inverse() * (x - c)).normalize()
}

#[track_caller]
fn check_ellipsoid_hit(m: DMat3, c: DVec3, inst: &Instance, o: DVec3, d: DVec3, inside: bool) {
    let (r, o, d) = ray(o, d);
    let (t0, t1) = ellipsoid_roots(m, c, o, d).expect("the ray is aimed inside");
    let t = if inside { t1 } else { t0 };
    assert!(t > 0.0);
    let what = format!("o={o:?} d={d:?}");
    let h = inst
        .intersect(&r, 0.0, INF)
        .unwrap_or_else(|| panic!("missed the ellipsoid (t = {t}): {what}"));
    assert!(inst.occluded(&r, 0.0, INF), "not occluded: {what}");
    let rel = (h.t as f64 - t).abs() / t;
    assert!(
        rel < T_TOL,
        "t = {}, closed form {t} (rel {rel:e}): {what}",
        h.t
    );
    let x = o + d * t;
    let n = ellipsoid_normal(m, c, x);
    assert!(
        (unit(h.n_geo) - n).length() < N_TOL,
        "normal {:?}, expected {n:?}: {what}",
        unit(h.n_geo)
    );
    assert!(
        (dvec3(h.p) - x).length() < T_TOL * (1.0 + x.length() + o.length()),
        "p = {:?}, expected {x:?}: {what}",
        h.p
    );
    let e = dvec3(h.err);
    assert!(e.is_finite() && e.min_element() >= 0.0, "bad err {e:?}");
    if !inside {
        assert!(
            inst.intersect(&r, 0.0, (t * (1.0 - 1e-3)) as Real)
                .is_none(),
            "a hit before the first root: {what}"
        );
    }
}

#[test]
fn ellipsoid_matches_world_space_closed_form() {
    let cases = [
        // Non-uniform scale, rotation, translation.
        (
            rot([1.0, 2.0, 3.0], 0.7) * diag(2.0, 0.5, 1.3),
            DVec3::new(3.0, -1.0, 2.0),
        ),
        // The same with a shear, and a larger translation.
        (
            rot([-0.3, 1.0, 0.2], 2.1)
                * DMat3::from_cols(
                    DVec3::new(1.5, 0.0, 0.0),
                    DVec3::new(0.6, 0.8, 0.0),
                    DVec3::new(-0.4, 0.3, 2.5),
                ),
            DVec3::new(-20.0, 7.5, 11.0),
        ),
    ];
    let mut rng = SplitMix(42);
    for (m, c) in cases {
        let a = affine(m, c);
        let inst = instance(Shape::Sphere, &a);
        for _ in 0..2000 {
            // From outside, aimed at a point well inside (no grazing rays).
            let target = c + m * (rng.ball() * 0.7);
            let o = c + rng.unit() * rng.range(4.0, 15.0);
            let d = (target - o) * rng.range(0.05, 5.0);
            check_ellipsoid_hit(m, c, &inst, o, d, false);
            // From inside: the far root, outward normal.
            let o = c + m * (rng.ball() * 0.6);
            let d = rng.unit() * rng.range(0.05, 5.0);
            check_ellipsoid_hit(m, c, &inst, o, d, true);
        }
        // Rays aimed away from the ellipsoid miss.
        for _ in 0..200 {
            let dir = rng.unit();
            let o = c + dir * 10.0;
            let (r, _, _) = ray(o, dir * rng.range(0.1, 3.0));
            assert!(inst.intersect(&r, 0.0, INF).is_none());
            assert!(!inst.occluded(&r, 0.0, INF));
        }
    }
}

#[test]
fn scaled_sphere_normal_is_inverse_transpose() {
    // Object point (1/√2, 1/√2, 0) maps to (√2, 1/√2, 0); M⁻ᵀ·n = (1/(2√2), 1/√2, 0) ∝ (1, 2, 0).
    let inst = instance(Shape::Sphere, &Affine64::linear(diag(2.0, 1.0, 1.0)));
    let s2 = 2f64.sqrt();
    let p = DVec3::new(s2, 1.0 / s2, 0.0);
    let n = DVec3::new(1.0, 2.0, 0.0) / 5f64.sqrt();
    // Along −n from outside (t = 2), and along −x at height 1/√2 (t = 5 − √2).
    for (o, d, t) in [
        (
            p + DVec3::new(2.0, 4.0, 0.0),
            DVec3::new(-1.0, -2.0, 0.0),
            2.0,
        ),
        (
            DVec3::new(5.0, 1.0 / s2, 0.0),
            DVec3::new(-1.0, 0.0, 0.0),
            5.0 - s2,
        ),
    ] {
        let (r, _, _) = ray(o, d);
        let h = inst.intersect(&r, 0.0, INF).expect("hit");
        assert!((h.t as f64 - t).abs() < T_TOL * t, "t = {}, want {t}", h.t);
        assert!((dvec3(h.p) - p).length() < T_TOL * 4.0, "p = {:?}", h.p);
        let got = unit(h.n_geo);
        assert!((got - n).length() < N_TOL, "normal {got:?}, want {n:?}");
        // The shading normal of a sphere is the geometric one.
        assert!((unit(h.n_shade) - n).length() < N_TOL);
        // Material and object id come from the instance.
        assert_eq!((h.material, h.object_id), (1, 1));
    }
}

/// A regular tetrahedron about the origin, wound so that (p1 − p0) × (p2 − p0) is outward.
fn tetrahedron() -> Mesh {
    let v = [
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
    ];
    let mut tris = Vec::new();
    for skip in 0..4u32 {
        let mut t: Vec<u32> = (0..4).filter(|&k| k != skip).collect();
        let (a, b, c) = (v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
        // Outward: away from the omitted vertex.
        if (b - a).cross(c - a).dot(a - v[skip as usize]) < 0.0 {
            t.swap(1, 2);
        }
        tris.push([t[0], t[1], t[2]]);
    }
    Mesh::new(v.to_vec(), None, None, tris).unwrap()
}

#[test]
fn mirror_keeps_normals_outward() {
    let mirror = affine(
        diag(-1.0, 1.0, 1.0) * rot([0.2, 1.0, -0.5], 0.9) * diag(1.5, 0.7, 1.1),
        DVec3::new(0.5, -2.0, 4.0),
    );
    assert!(mirror.m.determinant() < 0.0);
    let tet = Arc::new(tetrahedron());
    let solids = [
        Shape::Sphere,
        Shape::Cube,
        Shape::Cylinder { capped: true },
        Shape::Cone { capped: true },
        Shape::Mesh(tet.clone()),
    ];
    let mut rng = SplitMix(7);
    for shape in solids {
        // Sanity: the same rays in object space (identity) see outward normals too.
        for a in [Affine64::IDENTITY, mirror] {
            let inst = instance(shape.clone(), &a);
            // The object-space origin is inside every one of these convex solids.
            let c = a.d;
            for _ in 0..1000 {
                let target = a.point(rng.ball() * 0.25);
                let o = c + rng.unit() * 8.0;
                let d = (target - o) * rng.range(0.1, 3.0);
                let (r, o, d) = ray(o, d);
                let h = inst.intersect(&r, 0.0, INF).expect("aimed at the inside");
                let n = unit(h.n_geo);
                let p = o + d * h.t as f64;
                assert!(
                    n.dot(d) < 0.0 && n.dot(p - c) > 0.0,
                    "{shape:?} det {}: entering normal {n:?} not outward",
                    a.m.determinant()
                );
                // From inside, out through the far side: still outward.
                let o_in = a.point(rng.ball() * 0.25);
                let (r, o_in, d) = ray(o_in, rng.unit());
                let h = inst.intersect(&r, 0.0, INF).expect("from inside");
                let n = unit(h.n_geo);
                let p = o_in + d * h.t as f64;
                assert!(
                    n.dot(d) > 0.0 && n.dot(p - c) > 0.0,
                    "{shape:?} det {}: exiting normal {n:?} not outward",
                    a.m.determinant()
                );
            }
        }
    }
    // A lone triangle under the mirror: its world normal is M⁻ᵀ·((p1 − p0) × (p2 − p0)),
    // not the cross product of the mirrored vertices (which points the other way).
    let tri = Triangle {
        p: [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        n: None,
        uv: None,
    };
    let inst = instance(Shape::Triangle(Box::new(tri.clone())), &mirror);
    let n_obj = dvec3(tri.normal());
    let want = (mirror.m.inverse().transpose() * n_obj).normalize();
    let q = mirror.point(DVec3::new(0.2, 0.3, 0.0));
    for side in [1.0, -1.0] {
        let o = q + want * (3.0 * side) + DVec3::new(0.1, -0.2, 0.05);
        let (r, _, _) = ray(o, q - o);
        let h = inst.intersect(&r, 0.0, INF).expect("hits the triangle");
        assert!((h.t as f64 - 1.0).abs() < T_TOL, "t = {}", h.t);
        let got = unit(h.n_geo);
        assert!(
            (got - want).length() < N_TOL,
            "normal {got:?}, want {want:?}"
        );
        let corners = [0, 1, 2].map(|k| mirror.point(dvec3(tri.p[k])));
        let naive = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        assert!(
            naive.dot(want) < 0.0,
            "the mirror must flip the vertex winding"
        );
    }
}

/// Whether small perturbations of the ray's origin change `inst`'s answer qualitatively
/// (hit against miss) or make t jump: silhouettes, rims and grazing angles, where two
/// roundings of the same transform may legitimately disagree.
fn ambiguous(inst: &Instance, r: &Ray) -> bool {
    let h = inst.intersect(r, 0.0, INF);
    let o = dvec3(r.o);
    let dl = 1e-4 * (1.0 + o.length());
    let dlen = dvec3(r.d).length();
    (0..6).any(|k| {
        let mut e = DVec3::ZERO;
        e[k / 2] = if k % 2 == 0 { dl } else { -dl };
        let rj = Ray::new(vec3(o + e), r.d);
        match (h, inst.intersect(&rj, 0.0, INF)) {
            (None, None) => false,
            (Some(a), Some(b)) => ((a.t - b.t) as f64).abs() * dlen > 20.0 * dl,
            _ => true,
        }
    })
}

/// The hits of two instances agree (t, point, unit normal, uv, material, object id). Two
/// roundings of the same map differ by about ε·|o| in object space, which a hit at an angle
/// θ to the surface turns into (ε·|o|)/cos θ along it.
#[track_caller]
fn same_hit(r: &Ray, a: Option<Hit>, b: Option<Hit>, what: &str) {
    let (a, b) = match (a, b) {
        (None, None) => return,
        (Some(a), Some(b)) => (a, b),
        (a, b) => panic!("{:?} vs {:?}: {what}", a.map(|h| h.t), b.map(|h| h.t)),
    };
    let d = dvec3(r.d);
    let (na, nb) = (unit(a.n_geo), unit(b.n_geo));
    let cos = nb.dot(d.normalize()).abs().max(0.05);
    let scale = (dvec3(r.o).length() + b.t as f64 * d.length()) / cos;
    let dt = (a.t as f64 - b.t as f64).abs() * d.length();
    assert!(dt < T_TOL * scale, "t {} vs {}: {what}", a.t, b.t);
    let dp = (dvec3(a.p) - dvec3(b.p)).length();
    assert!(dp < T_TOL * scale, "p {:?} vs {:?}: {what}", a.p, b.p);
    assert!(
        (na - nb).length() < G_TOL * scale,
        "normal {na:?} vs {nb:?}: {what}"
    );
    assert!(
        (a.uv - b.uv).abs().max_element() as f64 <= G_TOL * scale,
        "uv {:?} vs {:?}: {what}",
        a.uv,
        b.uv
    );
    assert_eq!(
        (a.material, a.object_id),
        (b.material, b.object_id),
        "ids: {what}"
    );
}

#[test]
fn group_transforms_compose() {
    let t_in = affine(
        rot([0.3, -1.0, 0.4], 1.1) * diag(0.5, 1.7, 0.9),
        DVec3::new(1.0, -0.5, 2.0),
    );
    let t_mid = affine(
        DMat3::from_cols(
            DVec3::new(1.0, 0.2, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.3, 0.0, 0.8),
        ),
        DVec3::new(-2.0, 0.0, 1.0),
    );
    let t_out = affine(
        rot([1.0, 1.0, 0.0], -0.6) * diag(1.3, 1.3, 0.6),
        DVec3::new(4.0, 3.0, -5.0),
    );
    let mut rng = SplitMix(99);
    for shape in [
        Shape::Cone { capped: true },
        Shape::Cube,
        Shape::Cylinder { capped: false },
        Shape::Triangle(Box::new(Triangle {
            p: [
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -0.5, 0.2),
                Vec3::new(0.0, 1.0, -0.3),
            ],
            n: None,
            uv: Some([Vec2::ZERO, Vec2::X, Vec2::Y]),
        })),
    ] {
        // Inner instance inherits material and object id from the group's instance.
        let inner = Instance {
            shape: shape.clone(),
            xf: Some(transform(&t_in)),
            material: INHERIT,
            object_id: 0,
        };
        let group = Shape::Group(Arc::new(Aggregate::new(vec![inner])));
        let nested = Instance {
            shape: group.clone(),
            xf: Some(transform(&t_out)),
            material: 3,
            object_id: 9,
        };
        let flat = Instance {
            shape: shape.clone(),
            xf: Some(transform(&t_out.compose(&t_in))),
            material: 3,
            object_id: 9,
        };
        // Three levels: out ∘ mid ∘ in.
        let mid = Instance {
            shape: group,
            xf: Some(transform(&t_mid)),
            material: INHERIT,
            object_id: 0,
        };
        let deep = Instance {
            shape: Shape::Group(Arc::new(Aggregate::new(vec![mid]))),
            xf: Some(transform(&t_out)),
            material: 3,
            object_id: 9,
        };
        let deep_flat = Instance {
            shape: shape.clone(),
            xf: Some(transform(&t_out.compose(&t_mid).compose(&t_in))),
            material: 3,
            object_id: 9,
        };
        // And the nested one inside a top-level aggregate (exercising the group's bounds).
        let scene = Aggregate::new(vec![nested.clone()]);
        let full_in = t_out.compose(&t_in);
        let full_deep = t_out.compose(&t_mid).compose(&t_in);
        let (mut hits, mut skipped) = (0, 0);
        for i in 0..3000 {
            let (full, a, b) = if i % 2 == 0 {
                (&full_in, &nested, &flat)
            } else {
                (&full_deep, &deep, &deep_flat)
            };
            // Aimed at the shape's interior (object points near the origin), or anywhere.
            let target = if i % 3 == 0 {
                full.point(rng.vec(-3.0, 3.0))
            } else {
                full.point(rng.ball() * 0.3)
            };
            let o = full.point(DVec3::ZERO) + rng.unit() * 20.0;
            let (r, _, _) = ray(o, (target - o) * rng.range(0.1, 3.0));
            let what = format!("{shape:?} ray {i}");
            let (ha, hb) = (a.intersect(&r, 0.0, INF), b.intersect(&r, 0.0, INF));
            if i % 3 != 0 {
                // A ray through the inside of a closed solid must hit it, both ways.
                assert!(
                    (ha.is_some() && hb.is_some()) || !shape.is_convex_solid(),
                    "aimed at the interior but missed: {what}"
                );
            }
            assert_eq!(a.occluded(&r, 0.0, INF), ha.is_some(), "occluded: {what}");
            if let Some(x) = ha {
                assert_eq!((x.material, x.object_id), (3, 9), "inherited ids: {what}");
            }
            if ambiguous(b, &r) {
                skipped += 1;
                continue;
            }
            hits += hb.is_some() as usize;
            same_hit(&r, ha, hb, &what);
            if i % 2 == 0 {
                same_hit(
                    &r,
                    scene.intersect(&r, 0.0, INF),
                    hb,
                    &format!("scene, {what}"),
                );
                assert_eq!(scene.occluded(&r, 0.0, INF), hb.is_some(), "{what}");
            }
        }
        assert!(skipped < 300, "{shape:?}: {skipped} ambiguous rays");
        assert!(hits > 500, "{shape:?}: only {hits} hits");
    }
    // An inner instance's own ids are kept.
    let inner = Instance {
        shape: Shape::Sphere,
        xf: None,
        material: 5,
        object_id: 6,
    };
    let outer = Instance {
        shape: Shape::Group(Arc::new(Aggregate::new(vec![inner]))),
        xf: Some(transform(&t_out)),
        material: 3,
        object_id: 9,
    };
    let (r, _, _) = ray(t_out.d + DVec3::new(0.0, 0.0, -10.0), DVec3::Z);
    let h = outer.intersect(&r, 0.0, INF).expect("hit");
    assert_eq!((h.material, h.object_id), (5, 6));
}

#[test]
fn invalid_transforms_are_rejected() {
    let singular = [
        diag(1.0, 0.0, 1.0),
        diag(0.0, 0.0, 0.0),
        // Rank 2: the second column is twice the first.
        DMat3::from_cols(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(2.0, 4.0, 6.0),
            DVec3::new(0.0, 0.0, 1.0),
        ),
        // Rotated, then flattened along one axis.
        diag(2.0, 0.0, 3.0) * rot([1.0, 1.0, 1.0], 0.5),
        // Invertible in exact arithmetic, but hopelessly ill-conditioned.
        diag(1.0, 1e-16, 1.0),
    ];
    for m in singular {
        let a = affine(m, DVec3::new(1.0, 2.0, 3.0));
        assert!(
            matches!(Transform::new(&a), Err(TransformError::Singular { .. })),
            "accepted singular {m:?}"
        );
        assert!(a.inverse().is_err());
    }
    let non_finite = [
        affine(diag(1.0, f64::NAN, 1.0), DVec3::ZERO),
        affine(diag(1.0, 1.0, f64::INFINITY), DVec3::ZERO),
        affine(
            DMat3::from_cols(DVec3::X, DVec3::new(f64::NEG_INFINITY, 1.0, 0.0), DVec3::Z),
            DVec3::ZERO,
        ),
        affine(DMat3::IDENTITY, DVec3::new(0.0, f64::NAN, 0.0)),
        affine(DMat3::IDENTITY, DVec3::new(f64::INFINITY, 0.0, 0.0)),
    ];
    for a in non_finite {
        assert_eq!(
            Transform::new(&a),
            Err(TransformError::NonFinite),
            "accepted non-finite {a:?}"
        );
    }
    // Valid ones, including a mirror, are accepted and invert correctly.
    for m in [
        diag(-1.0, 1.0, 1.0),
        rot([1.0, 2.0, 3.0], 0.7) * diag(2.0, 0.5, 1.3),
        diag(1e-3, 1e3, 1.0),
    ] {
        let x = Transform::new(&affine(m, DVec3::new(1.0, -2.0, 3.0))).expect("valid");
        let id = dmat(x.inverse_matrix() * x.matrix());
        assert!(
            (id - DMat3::IDENTITY)
                .to_cols_array()
                .iter()
                .all(|e| e.abs() < 1e-5),
            "inverse of {m:?}: {id:?}"
        );
        let p = Vec3::new(0.3, -0.7, 2.0);
        assert!((dvec3(x.inv_point(x.point(p))) - dvec3(p)).length() < 1e-4);
    }
}

fn dmat(m: renderer::real::Mat3) -> DMat3 {
    DMat3::from_cols_array(&m.to_cols_array().map(|x| x as f64))
}

/// Every surface under every instance path has its own [`Hit::surface`]: a definition of
/// two shapes instanced twice gives four surfaces, and a definition instanced inside
/// another keeps the copies apart too. Shading keys its interior list by it, so the shapes
/// inside one instance are separate objects, as they are in a group.
#[test]
fn each_surface_under_each_instance_path_has_its_own_number() {
    // A definition: a box with a sphere inside, along x.
    let def = Arc::new(Aggregate::new(vec![
        Instance {
            shape: Shape::Cube,
            xf: None,
            material: INHERIT,
            object_id: 0,
        },
        instance(Shape::Sphere, &affine(diag(0.5, 0.5, 0.5), DVec3::ZERO)),
    ]));
    assert_eq!(def.surface_count(), Some(2));
    // Two copies of it, side by side, and a plane.
    let copies = |dx: f64| {
        let mut i = instance(
            Shape::Group(def.clone()),
            &affine(DMat3::IDENTITY, DVec3::new(dx, 0.0, 0.0)),
        );
        i.object_id = 1;
        i
    };
    let outer = Arc::new(Aggregate::new(vec![copies(-3.0), copies(3.0)]));
    assert_eq!(outer.surface_count(), Some(4));
    // And the pair instanced twice again, above a plane: 8 + 1 surfaces.
    let root = Aggregate::new(vec![
        instance(
            Shape::Plane,
            &affine(DMat3::IDENTITY, DVec3::new(0.0, -5.0, 0.0)),
        ),
        instance(
            Shape::Group(outer.clone()),
            &affine(DMat3::IDENTITY, DVec3::new(0.0, 0.0, -10.0)),
        ),
        instance(
            Shape::Group(outer),
            &affine(DMat3::IDENTITY, DVec3::new(0.0, 0.0, 10.0)),
        ),
    ]);
    assert_eq!(root.surface_count(), Some(9));
    let mut seen = std::collections::BTreeSet::new();
    for z in [-10.0, 10.0] {
        for x in [-3.0, 3.0] {
            // A ray along +y from below each copy's centre: it enters the box first
            // (from inside the plane's half-space, above y = -5), then the sphere.
            let o = DVec3::new(x, -4.0, z);
            let (r, _, _) = ray(o, DVec3::Y);
            let outer_hit = root.intersect(&r, 0.0, INF).unwrap();
            let inner_hit = root.intersect(&r, outer_hit.t * 1.0001, INF).unwrap();
            assert_eq!(outer_hit, root.intersect_brute_force(&r, 0.0, INF).unwrap());
            assert!(
                seen.insert(outer_hit.surface),
                "box at ({x}, {z}) shares a number"
            );
            assert!(
                seen.insert(inner_hit.surface),
                "sphere at ({x}, {z}) shares a number"
            );
            assert_eq!(
                outer_hit.object_id, inner_hit.object_id,
                "one object id per copy"
            );
        }
    }
    let (down, _, _) = ray(DVec3::new(0.0, 0.0, 0.0), -DVec3::Y);
    assert!(seen.insert(root.intersect(&down, 0.0, INF).unwrap().surface));
    assert!(seen.iter().all(|&s| s < 9), "numbers are dense: {seen:?}");
}
