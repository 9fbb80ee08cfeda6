//! Every canonical primitive against closed forms (hand-worked cases, one line each) and
//! against an independent `f64` reference intersector (random rays).
//!
//! For each hit the helper checks: t against the closed form, the normalized geometric
//! normal against the analytic outward normal, uv against the mapping documented in the
//! shape's source, that `Hit.p` is the point o + t·d and lies on the surface within its own
//! error bound `Hit.err` (finite, non-negative), that scaling the direction by 3 divides t
//! by 3, that the interval `(t_min, t_max)` is honoured, and that `occluded` agrees.

use glam::{DVec2, DVec3};
use renderer::aggregate::Shape;
use renderer::real::{dvec3, vec3, Vec2};
use renderer::shapes::{Mesh, Triangle};
use renderer::{Hit, Ray, Real, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;

/// Relative tolerance for t, normals, uv and points in the hand-worked cases.
#[cfg(not(feature = "f64"))]
const TOL: f64 = 1e-5;
#[cfg(feature = "f64")]
const TOL: f64 = 1e-12;

/// Machine epsilon of the renderer's precision.
const EPS: f64 = Real::EPSILON as f64;

const INF: Real = Real::INFINITY;

// ---------------------------------------------------------------------------------------
// Shapes under test.

/// The triangle (1,0,0), (0,2,0), (0,0,3): the plane x + y/2 + z/3 = 1, normal ∝ (6,3,2).
fn tri_points() -> [Vec3; 3] {
    [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 0.0, 3.0),
    ]
}

fn triangle() -> Shape {
    Shape::Triangle(Box::new(Triangle {
        p: tri_points(),
        n: None,
        uv: None,
    }))
}

fn triangle_with_uv() -> Shape {
    Shape::Triangle(Box::new(Triangle {
        p: tri_points(),
        n: None,
        uv: Some([
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.5, 1.0),
        ]),
    }))
}

/// The square [−1, 1]² in y = 0 as two triangles sharing the diagonal x = z, normal +y.
/// With `uv`, vertex uvs are ((x+1)/2, (z+1)/2), so the interpolated uv is that map.
fn quad_mesh(uv: bool) -> Shape {
    let pos = vec![
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 1.0),
    ];
    let uvs = uv.then(|| {
        pos.iter()
            .map(|p| Vec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5))
            .collect()
    });
    let m = Mesh::new(pos, None, uvs, vec![[0, 3, 2], [0, 2, 1]]).expect("valid mesh");
    Shape::Mesh(Arc::new(m))
}

fn name(s: &Shape) -> &'static str {
    match s {
        Shape::Sphere => "sphere",
        Shape::Plane => "plane",
        Shape::Cube => "cube",
        Shape::Cylinder { capped: true } => "capped cylinder",
        Shape::Cylinder { capped: false } => "open cylinder",
        Shape::Cone { capped: true } => "capped cone",
        Shape::Cone { capped: false } => "open cone",
        Shape::Disk => "disk",
        Shape::Rectangle => "rectangle",
        Shape::Triangle(_) => "triangle",
        Shape::Mesh(_) => "mesh",
        Shape::Group(_) => "group",
    }
}

// ---------------------------------------------------------------------------------------
// Exact distance from a point to each surface, in f64 (for "p is on the surface").

fn seg_dist2(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let s = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (q - (a + ab * s)).length()
}

fn seg_dist3(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let s = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (q - (a + ab * s)).length()
}

fn tri_dist(q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
    if inside {
        (q - a).dot(n).abs() / n.length()
    } else {
        seg_dist3(q, a, b)
            .min(seg_dist3(q, b, c))
            .min(seg_dist3(q, c, a))
    }
}

/// Distance from `p` to the surface of a surface of revolution about y, given its meridian
/// as segments in the (r, y) half-plane.
fn meridian_dist(p: DVec3, segs: &[([f64; 2], [f64; 2])]) -> f64 {
    let q = DVec2::new((p.x * p.x + p.z * p.z).sqrt(), p.y);
    segs.iter()
        .map(|&(a, b)| seg_dist2(q, DVec2::from(a), DVec2::from(b)))
        .fold(f64::INFINITY, f64::min)
}

fn surface_distance(s: &Shape, p: DVec3) -> f64 {
    match s {
        Shape::Sphere => (p.length() - 1.0).abs(),
        Shape::Plane => p.y.abs(),
        Shape::Cube => {
            let a = p.abs();
            let m = a.max_element();
            if m <= 1.0 {
                1.0 - m
            } else {
                (a - DVec3::ONE).max(DVec3::ZERO).length()
            }
        }
        Shape::Cylinder { capped } => {
            let mut segs = vec![([1.0, -1.0], [1.0, 1.0])];
            if *capped {
                segs.push(([0.0, -1.0], [1.0, -1.0]));
                segs.push(([0.0, 1.0], [1.0, 1.0]));
            }
            meridian_dist(p, &segs)
        }
        Shape::Cone { capped } => {
            let mut segs = vec![([0.0, 1.0], [1.0, -1.0])];
            if *capped {
                segs.push(([0.0, -1.0], [1.0, -1.0]));
            }
            meridian_dist(p, &segs)
        }
        Shape::Disk => meridian_dist(p, &[([0.0, 0.0], [1.0, 0.0])]),
        Shape::Rectangle => {
            let dx = (p.x.abs() - 1.0).max(0.0);
            let dz = (p.z.abs() - 1.0).max(0.0);
            (dx * dx + p.y * p.y + dz * dz).sqrt()
        }
        Shape::Triangle(t) => tri_dist(p, dvec3(t.p[0]), dvec3(t.p[1]), dvec3(t.p[2])),
        Shape::Mesh(m) => (0..m.triangles.len())
            .map(|i| {
                let [a, b, c] = m.vertices(i);
                tri_dist(p, dvec3(a), dvec3(b), dvec3(c))
            })
            .fold(f64::INFINITY, f64::min),
        Shape::Group(_) => unreachable!(),
    }
}

/// Checks what every hit must satisfy regardless of the expected values: finite fields,
/// a finite non-negative error bound, and a point on the surface within that bound.
#[track_caller]
fn check_record(s: &Shape, r: &Ray, h: &Hit) {
    let what = format!("{} o={:?} d={:?}: {h:?}", name(s), r.o, r.d);
    assert!(h.t.is_finite() && h.t > 0.0, "bad t, {what}");
    assert!(h.p.is_finite(), "non-finite p, {what}");
    assert!(
        h.n_geo.is_finite() && h.n_geo.length_squared() > 0.0,
        "bad normal, {what}"
    );
    assert!(h.uv.is_finite(), "non-finite uv, {what}");
    assert!(
        h.err.is_finite() && h.err.cmpge(Vec3::ZERO).all(),
        "error bound not finite and non-negative, {what}"
    );
    let p = dvec3(h.p);
    let dist = surface_distance(s, p);
    // The true point lies on the surface and within `err` of p, componentwise. The slack
    // only covers the f64 rounding of the distance computation itself.
    let bound = dvec3(h.err).length() + 8.0 * f64::EPSILON * (1.0 + p.length());
    assert!(
        dist <= bound,
        "p is {dist:e} from the surface, more than its error bound {bound:e}, {what}"
    );
}

// ---------------------------------------------------------------------------------------
// The data-driven helper for hand-worked cases.

enum Want {
    Miss,
    Hit {
        t: f64,
        n: [f64; 3],
        uv: Option<[f64; 2]>,
    },
}
use Want::Miss;

mod common;
use common::SplitMix;

fn hit(t: f64, n: [f64; 3], uv: [f64; 2]) -> Want {
    Want::Hit { t, n, uv: Some(uv) }
}

fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
    Ray::new(vec3(DVec3::from(o)), vec3(DVec3::from(d)))
}

/// One case: the ray o + t·d against `s`, with t_min = 0 and t_max = ∞.
#[track_caller]
fn check(s: &Shape, o: [f64; 3], d: [f64; 3], want: Want) {
    let r = ray(o, d);
    let got = s.intersect(&r, 0.0, INF);
    let occ = s.occluded(&r, 0.0, INF);
    let what = format!("{} o={o:?} d={d:?}", name(s));
    let (t, n, uv) = match want {
        Miss => {
            assert!(got.is_none(), "expected a miss, got {got:?}: {what}");
            assert!(!occ, "occluded but expected a miss: {what}");
            return;
        }
        Want::Hit { t, n, uv } => (t, n, uv),
    };
    let h = got.unwrap_or_else(|| panic!("expected a hit at t = {t}, got a miss: {what}"));
    assert!(occ, "hit but not occluded: {what}");
    check_record(s, &r, &h);
    let ht = h.t as f64;
    assert!(
        (ht - t).abs() <= TOL * t,
        "t = {ht}, closed form {t}: {what}"
    );
    let n_want = DVec3::from(n).normalize();
    let n_got = dvec3(h.n_geo).normalize();
    assert!(
        (n_got - n_want).length() <= TOL,
        "normal {n_got:?}, expected {n_want:?}: {what}"
    );
    if let Some(uv) = uv {
        let got = DVec2::new(h.uv.x as f64, h.uv.y as f64);
        assert!(
            (got - DVec2::from(uv)).abs().max_element() <= TOL,
            "uv {got:?}, expected {uv:?}: {what}"
        );
    }
    // The point is o + t·d (the closed-form t, evaluated in f64).
    let p_want = DVec3::from(o) + DVec3::from(d) * t;
    let scale = 1.0 + DVec3::from(o).length() + p_want.length();
    assert!(
        (dvec3(h.p) - p_want).length() <= TOL * scale,
        "p = {:?}, expected {p_want:?}: {what}",
        h.p
    );
    // Scaling the direction by 3 divides t by 3 and changes nothing else.
    let r3 = Ray::new(r.o, r.d * 3.0);
    let h3 = s
        .intersect(&r3, 0.0, INF)
        .unwrap_or_else(|| panic!("miss with the direction scaled by 3: {what}"));
    assert!(
        (h3.t as f64 - t / 3.0).abs() <= TOL * t / 3.0,
        "t = {} with 3·d, expected {}: {what}",
        h3.t,
        t / 3.0
    );
    assert!(
        (dvec3(h3.n_geo).normalize() - n_want).length() <= TOL,
        "normal changed with 3·d: {what}"
    );
    assert!(
        (dvec3(h3.p) - p_want).length() <= TOL * scale,
        "point changed with 3·d: {what}"
    );
    // The interval is open and honoured: nothing before the first hit, and a later query
    // only finds later hits.
    let before = (t * (1.0 - 1e-3)) as Real;
    assert!(
        s.intersect(&r, 0.0, before).is_none() && !s.occluded(&r, 0.0, before),
        "a hit before t_max = {before} although the first hit is at {t}: {what}"
    );
    let after = (t * (1.0 + 1e-3)) as Real;
    if let Some(h2) = s.intersect(&r, after, INF) {
        assert!(h2.t > after, "t_min = {after} ignored ({}): {what}", h2.t);
        check_record(s, &r, &h2);
    }
}

/// A tangent or grazing ray: a miss, or a hit at the tangent point (when one is given),
/// never NaN.
#[track_caller]
fn graze(s: &Shape, o: [f64; 3], d: [f64; 3], at: Option<[f64; 3]>) {
    let r = ray(o, d);
    let what = format!("{} o={o:?} d={d:?}", name(s));
    let got = s.intersect(&r, 0.0, INF);
    assert_eq!(
        got.is_some(),
        s.occluded(&r, 0.0, INF),
        "intersect and occluded disagree: {what}"
    );
    let Some(h) = got else { return };
    check_record(s, &r, &h);
    if let Some(at) = at {
        // A tangent t is ill-conditioned (error ~ √ε), so the tolerance is looser here.
        let at = DVec3::from(at);
        assert!(
            (dvec3(h.p) - at).length() <= 1e-3,
            "grazing hit at {:?}, expected the tangent point {at:?}: {what}",
            h.p
        );
        let t = (at - DVec3::from(o)).length() / DVec3::from(d).length();
        assert!(
            (h.t as f64 - t).abs() <= 1e-3 * t,
            "grazing t = {}, expected {t}: {what}",
            h.t
        );
    }
}

/// `azimuth` as documented in shapes/mod.rs: atan2(z, x)/2π in [0, 1).
fn az(x: f64, z: f64) -> f64 {
    let a = z.atan2(x) / (2.0 * PI);
    if a < 0.0 {
        a + 1.0
    } else {
        a
    }
}

// ---------------------------------------------------------------------------------------
// Hand-worked cases, one block per primitive.

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
fn plane() {
    let s = Shape::Plane;
    // uv are the hit's x and z.
    check(
        &s,
        [1., 2., 3.],
        [0., -1., 0.],
        hit(2.0, [0., 1., 0.], [1.0, 3.0]),
    );
    check(
        &s,
        [0., 4., 0.],
        [1., -2., 0.5],
        hit(2.0, [0., 1., 0.], [2.0, 1.0]),
    );
    check(&s, [0., 1., 0.], [0., 1., 0.], Miss);
    check(&s, [0., 1., 0.], [1., 0., 0.], Miss);
    // In the plane: parallel, so never a hit (and never NaN).
    graze(&s, [0., 0., 0.], [1., 0., 0.], None);
    check(&s, [0., 0., 0.], [1., 0., 0.], Miss);
    // From below: the normal stays +y.
    check(
        &s,
        [0., -1., 0.],
        [0.5, 1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.0]),
    );
}

#[test]
fn cube() {
    let s = Shape::Cube;
    // uv on the face of axis k: ((p[k+1]+1)/2, (p[k+2]+1)/2).
    check(
        &s,
        [0.2, 0.3, -5.],
        [0., 0., 1.],
        hit(4.0, [0., 0., -1.], [0.6, 0.65]),
    );
    check(
        &s,
        [5., 0., 0.],
        [-2., 0.2, 0.1],
        hit(2.0, [1., 0., 0.], [0.7, 0.6]),
    );
    check(
        &s,
        [0.5, 4., -0.5],
        [0., -1., 0.],
        hit(3.0, [0., 1., 0.], [0.25, 0.75]),
    );
    check(&s, [0., 1.5, -5.], [0., 0., 1.], Miss);
    check(&s, [3., 3., 3.], [1., 0., 0.], Miss);
    check(&s, [2.5, 0., 0.], [-1., 1., 0.], Miss); // passes beside the edge x = y = 1
                                                   // Along an edge and along a face plane: a miss or a hit on the boundary.
    graze(&s, [-5., 1., 1.], [1., 0., 0.], Some([-1., 1., 1.]));
    graze(&s, [-5., 1., 0.], [1., 0., 0.], Some([-1., 1., 0.]));
    check(&s, [-5., 1.001, 0.], [1., 0., 0.], Miss);
    check(
        &s,
        [-5., 0.999, 0.],
        [1., 0., 0.],
        hit(4.0, [-1., 0., 0.], [0.9995, 0.5]),
    );
    // From inside: the exit face, outward normal.
    check(
        &s,
        [0., 0., 0.],
        [0., 0., 1.],
        hit(1.0, [0., 0., 1.], [0.5, 0.5]),
    );
    check(
        &s,
        [0.5, -0.5, 0.25],
        [0., -1., 0.],
        hit(0.5, [0., -1., 0.], [0.625, 0.75]),
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

#[test]
fn disk() {
    let s = Shape::Disk;
    // uv ((x+1)/2, (z+1)/2).
    check(
        &s,
        [0.3, 2., 0.4],
        [0., -1., 0.],
        hit(2.0, [0., 1., 0.], [0.65, 0.7]),
    );
    check(
        &s,
        [0., 1., 0.],
        [0.5, -1., -0.5],
        hit(1.0, [0., 1., 0.], [0.75, 0.25]),
    );
    // Inside the square but outside the unit circle.
    check(&s, [0.8, 1., 0.8], [0., -1., 0.], Miss);
    check(&s, [0., 1., 0.], [0., 1., 0.], Miss);
    // In the plane, and through the rim.
    graze(&s, [-5., 0., 0.], [1., 0., 0.], None);
    check(&s, [-5., 0., 0.], [1., 0., 0.], Miss);
    graze(&s, [1., 1., 0.], [0., -1., 0.], Some([1., 0., 0.]));
    // From the far side: the normal is not flipped.
    check(
        &s,
        [0.2, -1., 0.],
        [0., 1., 0.],
        hit(1.0, [0., 1., 0.], [0.6, 0.5]),
    );
}

#[test]
fn rectangle() {
    let s = Shape::Rectangle;
    check(
        &s,
        [0.8, 1., 0.8],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.9, 0.9]),
    );
    check(
        &s,
        [0., 3., 0.],
        [-0.25, -1.5, 0.25],
        hit(2.0, [0., 1., 0.], [0.25, 0.75]),
    );
    check(&s, [1.2, 1., 0.], [0., -1., 0.], Miss);
    check(&s, [0., 1., -1.01], [0., -1., 0.], Miss);
    graze(&s, [-5., 0., 0.5], [1., 0., 0.], None);
    check(&s, [-5., 0., 0.5], [1., 0., 0.], Miss);
    graze(&s, [1., 1., 1.], [0., -1., 0.], Some([1., 0., 1.]));
    check(
        &s,
        [-0.5, -2., 0.5],
        [0., 2., 0.],
        hit(1.0, [0., 1., 0.], [0.25, 0.75]),
    );
}

#[test]
fn triangle_cases() {
    let s = triangle();
    // The plane x + y/2 + z/3 = 1 meets the diagonal at (6/11)(1,1,1); barycentrics
    // (6/11, 3/11, 2/11); default uv = (b1, b2).
    let uv = [3.0 / 11.0, 2.0 / 11.0];
    check(
        &s,
        [2., 2., 2.],
        [-1., -1., -1.],
        hit(2.0 - 6.0 / 11.0, [6., 3., 2.], uv),
    );
    // From behind: same t formula, normal still (p1 − p0) × (p2 − p0).
    check(
        &s,
        [0., 0., 0.],
        [1., 1., 1.],
        hit(6.0 / 11.0, [6., 3., 2.], uv),
    );
    check(
        &s,
        [0., 0., 0.],
        [3., 3., 3.],
        hit(2.0 / 11.0, [6., 3., 2.], uv),
    );
    // Vertex uvs are interpolated: (0,0)·b0 + (1,0)·b1 + (0.5,1)·b2.
    let s_uv = triangle_with_uv();
    check(
        &s_uv,
        [0., 0., 0.],
        [1., 1., 1.],
        hit(6.0 / 11.0, [6., 3., 2.], [4.0 / 11.0, 2.0 / 11.0]),
    );
    // Misses: away, and through the plane outside the triangle (y < 0).
    check(&s, [0., 0., 0.], [-1., -1., -1.], Miss);
    check(&s, [0., 0., 0.], [1., -0.1, 1.], Miss);
    // In the plane along an edge (parallel), and exactly through an edge's midpoint.
    graze(&s, [2., -2., 0.], [-1., 2., 0.], None);
    check(&s, [2., -2., 0.], [-1., 2., 0.], Miss);
    graze(&s, [6.5, 4., 2.], [-6., -3., -2.], Some([0.5, 1., 0.]));
}

#[test]
fn mesh_quad() {
    let s = quad_mesh(true);
    check(
        &s,
        [0.2, 1., -0.4],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.6, 0.3]),
    );
    check(
        &s,
        [0., 2., 0.],
        [0.25, -1., -0.25],
        hit(2.0, [0., 1., 0.], [0.75, 0.25]),
    );
    // Exactly on the shared diagonal: watertight, so it must hit.
    check(
        &s,
        [0.3, 1., 0.3],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.65, 0.65]),
    );
    check(
        &s,
        [0., 1., 0.],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.5]),
    );
    check(
        &s,
        [-0.9, 1., 0.9],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.05, 0.95]),
    );
    check(&s, [1.5, 1., 0.], [0., -1., 0.], Miss);
    check(&s, [0., 1., 0.], [0., 1., 0.], Miss);
    graze(&s, [-5., 0., 0.3], [1., 0., 0.], None);
    graze(&s, [1., 1., 0.2], [0., -1., 0.], Some([1., 0., 0.2]));
    // From the far side.
    check(
        &s,
        [-0.5, -1., 0.5],
        [0., 1., 0.],
        hit(1.0, [0., 1., 0.], [0.25, 0.75]),
    );
    // Without vertex uvs, uv = (b1, b2) of the triangle hit: (−0.5, 0, 0.5) in triangle
    // (−1,0,−1), (−1,0,1), (1,0,1) has b = (0.25, 0.5, 0.25).
    let s = quad_mesh(false);
    check(
        &s,
        [-0.5, 1., 0.5],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.25]),
    );
}

// ---------------------------------------------------------------------------------------
// Random rays against an independent f64 reference.

/// The roots of Q(o + t·d) = k for the diagonal quadratic form Q(v) = Σ wᵢ·vᵢ² (all of
/// them; the leading coefficient may be ~0). The discriminant b² − a·c is computed as
/// −a·(Q(l) − k) with l = o − d·(b/a), which does not cancel when the origin is far away:
/// in f64 mode the reference must be at least as accurate as the renderer.
fn quadric_roots(w: DVec3, k: f64, o: DVec3, d: DVec3) -> Vec<f64> {
    let q = |u: DVec3, v: DVec3| (w * u * v).element_sum();
    let (a, b, c) = (q(d, d), q(o, d), q(o, o) - k);
    if a.abs() <= 1e-12 * d.length_squared() {
        return if b != 0.0 {
            vec![-c / (2.0 * b)]
        } else {
            vec![]
        };
    }
    let l = o - d * (b / a);
    let disc = -a * (q(l, l) - k);
    if disc < 0.0 {
        return vec![];
    }
    let s = disc.sqrt();
    let q = -(b + s.copysign(b));
    if q == 0.0 {
        return vec![0.0];
    }
    vec![q / a, c / q]
}

fn mt(o: DVec3, d: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return None;
    }
    let tv = o - a;
    let u = tv.dot(pv) / det;
    let qv = tv.cross(e1);
    let v = d.dot(qv) / det;
    if u < 0.0 || v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(qv) / det)
}

/// Every intersection with t > 0 as (t, face id).
fn candidates(s: &Shape, o: DVec3, d: DVec3) -> Vec<(f64, u32)> {
    let at = |t: f64| o + d * t;
    let mut out = Vec::new();
    let plane_y = |face: u32, y: f64, inside: &dyn Fn(DVec3) -> bool, out: &mut Vec<(f64, u32)>| {
        if d.y != 0.0 {
            let t = (y - o.y) / d.y;
            if inside(at(t)) {
                out.push((t, face));
            }
        }
    };
    match s {
        Shape::Sphere => {
            for t in quadric_roots(DVec3::ONE, 1.0, o, d) {
                out.push((t, 0));
            }
        }
        Shape::Plane => plane_y(0, 0.0, &|_| true, &mut out),
        Shape::Cube => {
            for k in 0..3 {
                if d[k] == 0.0 {
                    continue;
                }
                for (j, side) in [-1.0, 1.0].into_iter().enumerate() {
                    let t = (side - o[k]) / d[k];
                    let p = at(t);
                    if (0..3).all(|i| i == k || p[i].abs() <= 1.0) {
                        out.push((t, 2 * k as u32 + j as u32));
                    }
                }
            }
        }
        Shape::Cylinder { capped } => {
            if d.x != 0.0 || d.z != 0.0 {
                for t in quadric_roots(DVec3::new(1.0, 0.0, 1.0), 1.0, o, d) {
                    if at(t).y.abs() <= 1.0 {
                        out.push((t, 0));
                    }
                }
            }
            if *capped {
                let disk = |p: DVec3| p.x * p.x + p.z * p.z <= 1.0;
                plane_y(1, -1.0, &disk, &mut out);
                plane_y(2, 1.0, &disk, &mut out);
            }
        }
        Shape::Cone { capped } => {
            // In (x, w = 1 − y, z): x² + z² − ¼·w² = 0.
            let (ow, dw) = (DVec3::new(o.x, 1.0 - o.y, o.z), DVec3::new(d.x, -d.y, d.z));
            for t in quadric_roots(DVec3::new(1.0, -0.25, 1.0), 0.0, ow, dw) {
                if at(t).y.abs() <= 1.0 {
                    out.push((t, 0));
                }
            }
            if *capped {
                plane_y(1, -1.0, &|p| p.x * p.x + p.z * p.z <= 1.0, &mut out);
            }
        }
        Shape::Disk => plane_y(0, 0.0, &|p| p.x * p.x + p.z * p.z <= 1.0, &mut out),
        Shape::Rectangle => plane_y(0, 0.0, &|p| p.x.abs() <= 1.0 && p.z.abs() <= 1.0, &mut out),
        Shape::Triangle(tri) => {
            if let Some(t) = mt(o, d, dvec3(tri.p[0]), dvec3(tri.p[1]), dvec3(tri.p[2])) {
                out.push((t, 0));
            }
        }
        Shape::Mesh(m) => {
            // Only used with coplanar meshes: one face id.
            for i in 0..m.triangles.len() {
                let [a, b, c] = m.vertices(i);
                if let Some(t) = mt(o, d, dvec3(a), dvec3(b), dvec3(c)) {
                    out.push((t, 0));
                }
            }
        }
        Shape::Group(_) => unreachable!(),
    }
    out.retain(|&(t, _)| t > 0.0 && t.is_finite());
    out
}

struct Ref {
    t: f64,
    face: u32,
    p: DVec3,
    n: DVec3,
    /// uv, and whether u is an azimuth (periodic).
    uv: DVec2,
    azimuthal: bool,
}

fn reference(s: &Shape, o: DVec3, d: DVec3) -> Option<Ref> {
    let (t, face) = candidates(s, o, d)
        .into_iter()
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    let p = o + d * t;
    let flat_uv = DVec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5);
    let (n, uv, azimuthal) = match (s, face) {
        (Shape::Sphere, _) => (
            p,
            DVec2::new(az(p.x, p.z), 1.0 - p.y.clamp(-1.0, 1.0).acos() / PI),
            true,
        ),
        (Shape::Plane, _) => (DVec3::Y, DVec2::new(p.x, p.z), false),
        (Shape::Cube, f) => {
            let k = (f / 2) as usize;
            let mut n = DVec3::ZERO;
            n[k] = if f % 2 == 1 { 1.0 } else { -1.0 };
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            (n, DVec2::new((p[a] + 1.0) * 0.5, (p[b] + 1.0) * 0.5), false)
        }
        (Shape::Cylinder { .. }, 0) => (
            DVec3::new(p.x, 0.0, p.z),
            DVec2::new(az(p.x, p.z), (p.y + 1.0) * 0.5),
            true,
        ),
        (Shape::Cylinder { .. }, f) => (
            DVec3::new(0.0, if f == 1 { -1.0 } else { 1.0 }, 0.0),
            flat_uv,
            false,
        ),
        (Shape::Cone { .. }, 0) => (
            DVec3::new(p.x, 0.25 * (1.0 - p.y), p.z),
            DVec2::new(az(p.x, p.z), (p.y + 1.0) * 0.5),
            true,
        ),
        (Shape::Cone { .. }, _) => (-DVec3::Y, flat_uv, false),
        (Shape::Disk | Shape::Rectangle, _) => (DVec3::Y, flat_uv, false),
        (Shape::Triangle(tri), _) => {
            let [a, b, c] = tri.p.map(dvec3);
            let n = (b - a).cross(c - a);
            // Barycentrics of p.
            let area = n.length_squared();
            let b1 = (p - a).cross(c - a).dot(n) / area;
            let b2 = (b - a).cross(p - a).dot(n) / area;
            (n, DVec2::new(b1, b2), false)
        }
        (Shape::Mesh(_), _) => (DVec3::Y, flat_uv, false),
        (Shape::Group(_), _) => unreachable!(),
    };
    Some(Ref {
        t,
        face,
        p,
        n: n.normalize(),
        uv,
        azimuthal,
    })
}

/// Whether the reference answer changes qualitatively (hit/miss, face) or t jumps under a
/// small perturbation of the ray: near silhouettes, edges and grazing angles the renderer's
/// rounding may legitimately decide either way.
fn ambiguous(s: &Shape, o: DVec3, d: DVec3, r: &Option<Ref>) -> bool {
    let dl = 1e-4 * (1.0 + o.length());
    let dd = 1e-4 * d.length();
    let mut jitters = Vec::new();
    for k in 0..3 {
        for sgn in [-1.0, 1.0] {
            let mut e = DVec3::ZERO;
            e[k] = sgn;
            jitters.push((o + e * dl, d));
            jitters.push((o, d + e * dd));
        }
    }
    jitters.into_iter().any(|(oj, dj)| {
        let rj = reference(s, oj, dj);
        match (r, &rj) {
            (None, None) => false,
            (Some(a), Some(b)) => {
                a.face != b.face
                    || (a.t - b.t).abs() * d.length() > 20.0 * (dl + 1e-4 * a.t * d.length())
            }
            _ => true,
        }
    })
}

fn random_cross_check(s: &Shape, seed: u64, n: usize) {
    let mut rng = SplitMix(seed);
    let tol = 256.0 * EPS;
    let (mut hits, mut skipped) = (0, 0);
    for i in 0..n {
        // Origins inside and around the unit box, and far away; targets in and around it.
        let o = match i % 3 {
            0 => rng.vec(-1.5, 1.5),
            1 => rng.unit() * 4.0,
            _ => rng.unit() * 40.0,
        };
        let target = rng.vec(-1.3, 1.3);
        let d = (target - o) * rng.range(0.1, 10.0);
        let r = Ray::new(vec3(o), vec3(d));
        // The reference sees exactly the ray the renderer sees.
        let (o, d) = (dvec3(r.o), dvec3(r.d));
        let want = reference(s, o, d);
        if ambiguous(s, o, d, &want) {
            skipped += 1;
            continue;
        }
        let got = s.intersect(&r, 0.0, INF);
        let what = format!("{} ray #{i} o={o:?} d={d:?}", name(s));
        assert_eq!(
            got.is_some(),
            s.occluded(&r, 0.0, INF),
            "intersect and occluded disagree: {what}"
        );
        let (h, w) = match (got, &want) {
            (None, None) => continue,
            (Some(h), Some(w)) => (h, w),
            (got, want) => panic!(
                "renderer {:?}, reference {:?}: {what}",
                got.map(|h| h.t),
                want.as_ref().map(|w| (w.t, w.p))
            ),
        };
        hits += 1;
        check_record(s, &r, &h);
        let scale = 1.0 + o.length() + w.t * d.length();
        assert!(
            (h.t as f64 - w.t).abs() * d.length() <= tol * scale,
            "t = {}, reference {}: {what}",
            h.t,
            w.t
        );
        assert!(
            (dvec3(h.p) - w.p).length() <= tol * scale,
            "p = {:?}, reference {:?}: {what}",
            h.p,
            w.p
        );
        let ng = dvec3(h.n_geo).normalize();
        assert!(
            (ng - w.n).length() <= tol * scale,
            "normal {ng:?}, reference {:?}: {what}",
            w.n
        );
        // uv: the azimuth is periodic, and ill-conditioned near the axis; the sphere's v is
        // ill-conditioned at the poles.
        let uv = DVec2::new(h.uv.x as f64, h.uv.y as f64);
        let near_axis = w.p.x.hypot(w.p.z) < 1e-2;
        let mut du = (uv.x - w.uv.x).abs();
        if w.azimuthal {
            du = du.min(1.0 - du);
        }
        if !(w.azimuthal && near_axis) {
            assert!(
                du <= tol * scale * 10.0,
                "u = {}, reference {}: {what}",
                uv.x,
                w.uv.x
            );
        }
        if !(matches!(s, Shape::Sphere) && near_axis) {
            let dv = (uv.y - w.uv.y).abs();
            assert!(
                dv <= tol * scale * 10.0,
                "v = {}, reference {}: {what}",
                uv.y,
                w.uv.y
            );
        }
    }
    // The test must have tested something.
    assert!(
        skipped * 10 < n,
        "{}: {skipped} of {n} rays were ambiguous",
        name(s)
    );
    assert!(hits * 10 > n, "{}: only {hits} of {n} rays hit", name(s));
}

#[test]
fn random_rays_against_f64_reference() {
    let shapes = [
        Shape::Sphere,
        Shape::Plane,
        Shape::Cube,
        Shape::Cylinder { capped: true },
        Shape::Cylinder { capped: false },
        Shape::Cone { capped: true },
        Shape::Cone { capped: false },
        Shape::Disk,
        Shape::Rectangle,
        triangle(),
        quad_mesh(true),
    ];
    for (k, s) in shapes.iter().enumerate() {
        random_cross_check(s, 0x5EED_0000 + k as u64, 20_000);
    }
}
