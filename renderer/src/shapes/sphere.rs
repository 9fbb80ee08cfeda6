//! The unit sphere at the origin. The discriminant is computed as
//! `a·(1 − |o − (b/a)·d|²)` and the roots in the stable form of Haines et al. (Ray
//! Tracing Gems, ch. 7), which stays exact far from the sphere.

use super::{azimuth, local_hit, stable_roots};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{dvec3, gamma, vec3, Real, Vec2, Vec3};
use glam::DVec3;

/// The root of a ray's closest hit with `t_min < t < t_max`, and what the hit point is
/// computed from: `(t, side, l, d, disc, a)` in the notation below.
#[inline(always)]
fn solve(ray: &Ray, t_min: Real, t_max: Real) -> Option<(Real, f64, DVec3, DVec3, f64, f64)> {
    // a, b, l and the discriminant in f64, in both builds. In f32 the products d·(b/a),
    // of size |o|, moved l by ε·|o|: rays within ~ε·|o| of the silhouette came out as
    // wrong hits or misses (up to 5e-3 of the radius at |o| = 1e5).
    let (o, d) = (dvec3(ray.o), dvec3(ray.d));
    let a64 = d.length_squared();
    let b64 = o.dot(d);
    let l = o - d * (b64 / a64);
    let disc64 = a64 * (1.0 - l.length_squared());
    let disc = disc64 as Real;
    if !(disc >= 0.0) {
        return None;
    }
    let (a, b) = (a64 as Real, b64 as Real);
    let c = ray.o.length_squared() - 1.0;
    let (t0, t1) = stable_roots(a, b, c, disc);
    if t0 > t_min && t0 < t_max {
        Some((t0, -1.0, l, d, disc64, a64))
    } else if t1 > t_min && t1 < t_max {
        Some((t1, 1.0, l, d, disc64, a64))
    } else {
        None
    }
}

/// Whether the ray hits the unit sphere with `t_min < t < t_max`: exactly when
/// [`intersect`] returns a hit, without building it (shadow rays).
#[inline(always)]
pub fn hits(ray: &Ray, t_min: Real, t_max: Real) -> bool {
    solve(ray, t_min, t_max).is_some()
}

/// [`intersect`] without the uv (left at 0): the search for the closest hit builds this
/// for every candidate, and [`uv`] completes the winner's record, from the same point,
/// so the final record has the same bits (uv costs an `acos` and an `atan2`).
/// Always inlined (as [`hits`]): as a call, it read the ray its caller had just written
/// field by field, a store-forwarding stall on every sphere tested.
#[inline(always)]
pub fn intersect_bare(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let (t, side, l, d, disc64, a64) = solve(ray, t_min, t_max)?;
    // The point as l ∓ d·√disc/a, not o + t·d, which cancels when |o| ≫ 1 (an instance
    // far away or flattened, seen in object space) down to p = 0 and a zero normal.
    // Then re-project onto the surface; the error of the result is γ(5)·|p| (pbrt).
    let p = vec3(l + d * (side * disc64.sqrt() / a64));
    let p = p.normalize_or(p);
    let err = p.abs() * gamma(5);
    Some(local_hit(t, p, err, p, Vec2::ZERO))
}

/// The uv of the object-space point `p` on the unit sphere: azimuth and polar angle.
#[inline]
pub fn uv(p: Vec3) -> Vec2 {
    let v = 1.0 - p.y.clamp(-1.0, 1.0).acos() / (std::f64::consts::PI as Real);
    Vec2::new(azimuth(p.x, p.z), v)
}

/// Closest hit on the unit sphere. The normal is the hit point (outward).
#[inline]
pub fn intersect(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let mut h = intersect_bare(ray, t_min, t_max)?;
    h.uv = uv(h.p);
    Some(h)
}
