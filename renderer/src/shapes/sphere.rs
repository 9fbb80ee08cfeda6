//! The unit sphere at the origin. The discriminant is computed as
//! `a·(1 − |o − (b/a)·d|²)` and the roots in the stable form of Haines et al. (Ray
//! Tracing Gems, ch. 7), which stays exact far from the sphere.

use super::{azimuth, local_hit, stable_roots};
use crate::aggregate::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2};

/// Closest hit on the unit sphere. The normal is the hit point (outward).
#[inline]
pub fn intersect(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let a = ray.d.length_squared();
    let b = ray.o.dot(ray.d);
    let l = ray.o - ray.d * (b / a);
    let disc = a * (1.0 - l.length_squared());
    if !(disc >= 0.0) {
        return None;
    }
    let c = ray.o.length_squared() - 1.0;
    let (t0, t1) = stable_roots(a, b, c, disc);
    let t = if t0 > t_min && t0 < t_max {
        t0
    } else if t1 > t_min && t1 < t_max {
        t1
    } else {
        return None;
    };
    // Re-project onto the surface; the error of the result is γ(5)·|p| (pbrt).
    let p = ray.at(t);
    let p = p.normalize_or(p);
    let err = p.abs() * gamma(5);
    let v = 1.0 - p.y.clamp(-1.0, 1.0).acos() / (std::f64::consts::PI as Real);
    Some(local_hit(t, p, err, p, Vec2::new(azimuth(p.x, p.z), v)))
}
