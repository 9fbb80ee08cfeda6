//! Helpers shared by the primitive tests (quadrics, flat_shapes, triangles, random_rays):
//! the shapes under test, the data-driven `check` for hand-worked cases, and the checks
//! every hit record must pass.

use glam::{DVec2, DVec3};
use renderer::aggregate::Shape;
use renderer::real::{dvec3, vec3, Vec2};
use renderer::shapes::{Mesh, Triangle};
use renderer::{Hit, Ray, Real, Vec3};
use std::f64::consts::PI;
use std::sync::Arc;
/// Relative tolerance for t, normals, uv and points in the hand-worked cases.
#[cfg(not(feature = "f64"))]
pub const TOL: f64 = 1e-5;
#[cfg(feature = "f64")]
pub const TOL: f64 = 1e-12;

/// Machine epsilon of the renderer's precision.
pub const EPS: f64 = Real::EPSILON as f64;

pub const INF: Real = Real::INFINITY;

// ---------------------------------------------------------------------------------------
// Shapes under test.

/// The triangle (1,0,0), (0,2,0), (0,0,3): the plane x + y/2 + z/3 = 1, normal ∝ (6,3,2).
pub fn tri_points() -> [Vec3; 3] {
    [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 0.0, 3.0),
    ]
}

pub fn triangle() -> Shape {
    Shape::Triangle(Box::new(Triangle {
        p: tri_points(),
        n: None,
        uv: None,
    }))
}

pub fn triangle_with_uv() -> Shape {
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
pub fn quad_mesh(uv: bool) -> Shape {
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

pub fn name(s: &Shape) -> &'static str {
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
        Shape::Anchored(_) => "anchored",
    }
}

// ---------------------------------------------------------------------------------------
// Exact distance from a point to each surface, in f64 (for "p is on the surface").

pub fn seg_dist2(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let s = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (q - (a + ab * s)).length()
}

pub fn seg_dist3(q: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let s = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (q - (a + ab * s)).length()
}

pub fn tri_dist(q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
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
pub fn meridian_dist(p: DVec3, segs: &[([f64; 2], [f64; 2])]) -> f64 {
    let q = DVec2::new((p.x * p.x + p.z * p.z).sqrt(), p.y);
    segs.iter()
        .map(|&(a, b)| seg_dist2(q, DVec2::from(a), DVec2::from(b)))
        .fold(f64::INFINITY, f64::min)
}

pub fn surface_distance(s: &Shape, p: DVec3) -> f64 {
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
        // The canonical shape, about its anchor.
        Shape::Anchored(a) => {
            use renderer::shapes::anchored::Kind;
            let canonical = match a.kind {
                Kind::Sphere => Shape::Sphere,
                Kind::Cube => Shape::Cube,
                Kind::Cylinder { capped } => Shape::Cylinder { capped },
            };
            surface_distance(&canonical, p + a.a)
        }
    }
}

/// Checks what every hit must satisfy regardless of the expected values: finite fields,
/// a finite non-negative error bound, and a point on the surface within that bound.
#[track_caller]
pub fn check_record(s: &Shape, r: &Ray, h: &Hit) {
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
    // The bound is a rounding bound, not a licence: a few dozen ulps of the point's size,
    // never a fraction of the object (a loose bound moves spawned rays off the surface).
    let loose = 1e-4 * (1.0 + p.abs().max_element());
    assert!(
        dvec3(h.err).max_element() <= loose,
        "error bound {:?} is far looser than rounding (limit {loose:e}), {what}",
        h.err
    );
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

pub enum Want {
    Miss,
    Hit {
        t: f64,
        n: [f64; 3],
        uv: Option<[f64; 2]>,
    },
}
pub use Want::Miss;

pub fn hit(t: f64, n: [f64; 3], uv: [f64; 2]) -> Want {
    Want::Hit { t, n, uv: Some(uv) }
}

pub fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
    Ray::new(vec3(DVec3::from(o)), vec3(DVec3::from(d)))
}

/// One case: the ray o + t·d against `s`, with t_min = 0 and t_max = ∞.
#[track_caller]
pub fn check(s: &Shape, o: [f64; 3], d: [f64; 3], want: Want) {
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
pub fn graze(s: &Shape, o: [f64; 3], d: [f64; 3], at: Option<[f64; 3]>) {
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
pub fn az(x: f64, z: f64) -> f64 {
    let a = z.atan2(x) / (2.0 * PI);
    if a < 0.0 {
        a + 1.0
    } else {
        a
    }
}
