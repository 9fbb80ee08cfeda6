//! Every canonical primitive against an independent `f64` reference intersector, on random
//! rays.
//!
//! For each hit the helper checks: t against the closed form, the normalized geometric
//! normal against the analytic outward normal, uv against the mapping documented in the
//! shape's source, that `Hit.p` is the point o + t·d and lies on the surface within its own
//! error bound `Hit.err` (finite, non-negative), that scaling the direction by 3 divides t
//! by 3, that the interval `(t_min, t_max)` is honoured, and that `occluded` agrees.

use glam::{DVec2, DVec3};
use renderer::aggregate::Shape;
use renderer::real::{dvec3, vec3};
use renderer::Ray;
use std::f64::consts::PI;

mod common;
use common::primitives::*;
use common::SplitMix;

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
        Shape::Group(_) | Shape::Anchored(_) => unreachable!(),
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
        (Shape::Group(_) | Shape::Anchored(_), _) => unreachable!(),
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
