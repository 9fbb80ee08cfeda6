//! The cube [−1, 1]³, by the slab method. The normal is that of the slab the ray enters
//! through (or leaves through, when it starts inside).

use super::local_hit;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// The cube's first crossing with `t_min < t < t_max`: `t`, the axis of the face, and
/// whether the ray enters there (else it leaves).
#[inline]
fn crossing(ray: &Ray, t_min: Real, t_max: Real) -> Option<(Real, usize, bool)> {
    let mut near = Real::NEG_INFINITY;
    let mut far = Real::INFINITY;
    let (mut near_axis, mut far_axis) = (0usize, 0usize);
    for k in 0..3 {
        let (o, d) = (ray.o[k], ray.d[k]);
        if d == 0.0 {
            if !(-1.0..=1.0).contains(&o) {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d;
        let (mut a, mut b) = ((-1.0 - o) * inv, (1.0 - o) * inv);
        if a > b {
            std::mem::swap(&mut a, &mut b);
        }
        if a > near {
            near = a;
            near_axis = k;
        }
        if b < far {
            far = b;
            far_axis = k;
        }
    }
    if near > far {
        return None;
    }
    if near > t_min && near < t_max {
        Some((near, near_axis, true))
    } else if far > t_min && far < t_max {
        Some((far, far_axis, false))
    } else {
        None
    }
}

/// Whether the ray hits the cube with `t_min < t < t_max`: exactly when [`intersect`]
/// returns a hit.
#[inline]
pub fn hits(ray: &Ray, t_min: Real, t_max: Real) -> bool {
    crossing(ray, t_min, t_max).is_some()
}

/// Closest hit on the cube.
#[inline]
pub fn intersect(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let (t, axis, entering) = crossing(ray, t_min, t_max)?;
    let mut n = Vec3::ZERO;
    let s = if entering {
        -ray.d[axis].signum()
    } else {
        ray.d[axis].signum()
    };
    n[axis] = s;
    // Snap the hit coordinate onto the face; the other two carry rounding error.
    let mut p = ray.at(t);
    p[axis] = s;
    let mut err = p.abs() * gamma(4);
    err[axis] = 0.0;
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let uv = Vec2::new((p[a] + 1.0) * 0.5, (p[b] + 1.0) * 0.5);
    Some(local_hit(t, p, err, n, uv))
}
