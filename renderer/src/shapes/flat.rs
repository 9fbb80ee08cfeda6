//! The flat primitives in the plane y = 0 with normal +y: the infinite plane, the unit
//! disk and the rectangle [−1, 1]². A ray parallel to the plane never hits it.

use super::local_hit;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// The ray's point `p` at a hit snapped exactly onto y = 0; only x and z carry rounding
/// error.
#[inline]
fn on_plane(mut p: Vec3) -> (Vec3, Vec3) {
    p.y = 0.0;
    (p, Vec3::new(p.x.abs(), 0.0, p.z.abs()) * gamma(4))
}

#[inline]
fn plane_t(ray: &Ray, t_min: Real, t_max: Real) -> Option<Real> {
    if ray.d.y == 0.0 {
        return None;
    }
    let t = -ray.o.y / ray.d.y;
    (t > t_min && t < t_max).then_some(t)
}

/// Whether the ray hits the plane y = 0 with `t_min < t < t_max`: exactly when
/// [`plane`] returns a hit.
#[inline]
pub fn plane_hits(ray: &Ray, t_min: Real, t_max: Real) -> bool {
    plane_t(ray, t_min, t_max).is_some()
}

/// The plane y = 0; uv are the hit's x and z.
#[inline]
pub fn plane(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let t = plane_t(ray, t_min, t_max)?;
    let (p, err) = on_plane(ray.at(t));
    Some(local_hit(t, p, err, Vec3::Y, Vec2::new(p.x, p.z)))
}

/// Whether the ray's point `p` in the plane y = 0 lies off the unit disk.
#[inline]
fn off_disk(p: Vec3) -> bool {
    p.x * p.x + p.z * p.z > 1.0
}

/// Whether the ray's point `p` in the plane y = 0 lies off the rectangle [−1, 1]².
#[inline]
fn off_rectangle(p: Vec3) -> bool {
    p.x.abs() > 1.0 || p.z.abs() > 1.0
}

/// Whether the ray hits the unit disk with `t_min < t < t_max`: exactly when [`disk`]
/// returns a hit (the same test on the same values, without the record).
#[inline]
pub fn disk_hits(ray: &Ray, t_min: Real, t_max: Real) -> bool {
    plane_t(ray, t_min, t_max).is_some_and(|t| !off_disk(ray.at(t)))
}

/// Whether the ray hits the rectangle [−1, 1]² with `t_min < t < t_max`: exactly when
/// [`rectangle`] returns a hit.
#[inline]
pub fn rectangle_hits(ray: &Ray, t_min: Real, t_max: Real) -> bool {
    plane_t(ray, t_min, t_max).is_some_and(|t| !off_rectangle(ray.at(t)))
}

/// The unit disk; uv map [−1, 1]² to [0, 1]².
#[inline]
pub fn disk(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let t = plane_t(ray, t_min, t_max)?;
    let at = ray.at(t);
    if off_disk(at) {
        return None;
    }
    let (p, err) = on_plane(at);
    Some(local_hit(
        t,
        p,
        err,
        Vec3::Y,
        Vec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5),
    ))
}

/// The rectangle [−1, 1]²; uv map it to [0, 1]².
#[inline]
pub fn rectangle(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let t = plane_t(ray, t_min, t_max)?;
    let at = ray.at(t);
    if off_rectangle(at) {
        return None;
    }
    let (p, err) = on_plane(at);
    Some(local_hit(
        t,
        p,
        err,
        Vec3::Y,
        Vec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5),
    ))
}
