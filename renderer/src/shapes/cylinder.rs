//! The cylinder of radius 1 about the y axis, y ∈ [−1, 1], open or capped. The side uses
//! the same stable quadratic as the sphere, in the xz plane.

use super::{azimuth, local_hit, stable_roots};
use crate::aggregate::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// Closest hit. Side normal (x, 0, z); cap normals ±y. uv: side (azimuth, (y+1)/2), caps
/// ((x+1)/2, (z+1)/2).
#[inline]
pub fn intersect(ray: &Ray, capped: bool, t_min: Real, t_max: Real) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut t_max = t_max;
    let (o, d) = (ray.o, ray.d);
    let a = d.x * d.x + d.z * d.z;
    if a > 0.0 {
        let b = o.x * d.x + o.z * d.z;
        let (lx, lz) = (o.x - d.x * (b / a), o.z - d.z * (b / a));
        let disc = a * (1.0 - (lx * lx + lz * lz));
        if disc >= 0.0 {
            let c = o.x * o.x + o.z * o.z - 1.0;
            let (t0, t1) = stable_roots(a, b, c, disc);
            for t in [t0, t1] {
                if t > t_min && t < t_max {
                    let p = ray.at(t);
                    if (-1.0..=1.0).contains(&p.y) {
                        // Re-project onto radius 1 in xz (pbrt), error γ(3)·|x|, γ(3)·|z|.
                        let r = (p.x * p.x + p.z * p.z).sqrt();
                        let p = Vec3::new(p.x / r, p.y, p.z / r);
                        let err = p.abs() * Vec3::new(gamma(3), gamma(4), gamma(3));
                        let n = Vec3::new(p.x, 0.0, p.z);
                        let uv = Vec2::new(azimuth(p.x, p.z), (p.y + 1.0) * 0.5);
                        best = Some(local_hit(t, p, err, n, uv));
                        t_max = t;
                        break;
                    }
                }
            }
        }
    }
    if capped && d.y != 0.0 {
        for y in [-1.0 as Real, 1.0] {
            let t = (y - o.y) / d.y;
            if t > t_min && t < t_max {
                let mut p = ray.at(t);
                if p.x * p.x + p.z * p.z <= 1.0 {
                    p.y = y;
                    let err = Vec3::new(p.x.abs(), 0.0, p.z.abs()) * gamma(4);
                    let uv = Vec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5);
                    best = Some(local_hit(t, p, err, Vec3::new(0.0, y, 0.0), uv));
                    t_max = t;
                }
            }
        }
    }
    best
}
