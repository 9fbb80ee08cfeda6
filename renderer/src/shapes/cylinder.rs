//! The cylinder of radius 1 about the y axis, y ∈ [−1, 1], open or capped. The side uses
//! the same stable quadratic as the sphere, in the xz plane.

use super::{azimuth, local_hit, stable_roots};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// Closest hit. Side normal (x, 0, z); cap normals ±y. uv: side (azimuth, (y+1)/2), caps
/// ((x+1)/2, (z+1)/2).
#[inline]
pub fn intersect(ray: &Ray, capped: bool, t_min: Real, t_max: Real) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut t_max = t_max;
    let (o, d) = (ray.o, ray.d);
    // The slab −1 ≤ y ≤ 1 and the infinite cylinder as intervals of t. A side hit counts
    // when its t lies in the slab's interval, a cap hit when its t lies between the side's
    // roots: the same computed values decide both, so a ray entering exactly at a rim
    // takes the later of the two entries, as in the box's slab test. (Testing the y of one
    // rounded point and the radius of another left a gap: 1.8 % of the rays aimed at a
    // rim from inside the solid's tangent cone missed in f32.)
    let (ty0, ty1) = slab(o.y, d.y);
    // a, b, l and the discriminant in f64, in both builds, as for the sphere: in f32 the
    // products d·(b/a), of size |o|, move l by ε·|o|, so a far cylinder (|o| ≫ 1 in
    // object space) got wrong hits and misses near its silhouette.
    let (ox, oz, dx, dz) = (o.x as f64, o.z as f64, d.x as f64, d.z as f64);
    let a64 = dx * dx + dz * dz;
    let a = a64 as Real;
    let mut roots: Option<(Real, Real)> = None;
    if a > 0.0 {
        let b64 = ox * dx + oz * dz;
        let (lx64, lz64) = (ox - dx * (b64 / a64), oz - dz * (b64 / a64));
        let disc64 = a64 * (1.0 - (lx64 * lx64 + lz64 * lz64));
        let (b, disc) = (b64 as Real, disc64 as Real);
        if disc >= 0.0 {
            let c = o.x * o.x + o.z * o.z - 1.0;
            let (t0, t1) = stable_roots(a, b, c, disc);
            roots = Some((t0, t1));
            for (t, side) in [(t0, -1.0), (t1, 1.0)] {
                if t > t_min && t < t_max && ty0 <= t && t <= ty1 {
                    // The point in xz as l ∓ d·√disc/a (l: the line's closest point to the
                    // axis), not o + t·d, which cancels when |o| ≫ 1 (a far or flattened
                    // instance seen in object space), down to the axis itself and a NaN.
                    let k = side * disc64.sqrt() / a64;
                    let (mut x, mut z) = ((lx64 + dx * k) as Real, (lz64 + dz * k) as Real);
                    let mut r = (x * x + z * z).sqrt();
                    if !(r > 0.0 && r.is_finite()) {
                        // Nothing left of the point: the side facing the ray.
                        (x, z, r) = (-d.x, -d.z, a.sqrt());
                    }
                    // Re-project onto radius 1 in xz (pbrt), error γ(3)·|x|, γ(3)·|z|.
                    let y = (o.y + t * d.y).clamp(-1.0, 1.0);
                    let p = Vec3::new(x / r, y, z / r);
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
    if capped && d.y != 0.0 {
        for y in [-1.0 as Real, 1.0] {
            let t = (y - o.y) / d.y;
            if t > t_min && t < t_max {
                let inside = match roots {
                    Some((t0, t1)) => t0 <= t && t <= t1,
                    // Parallel to the axis: inside everywhere or nowhere.
                    None => a == 0.0 && o.x * o.x + o.z * o.z <= 1.0,
                };
                if inside {
                    let mut p = ray.at(t);
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

/// The interval of t in which `o_y + t·d_y` lies in [−1, 1] (empty when `d_y = 0` and the
/// ray is outside). Its ends are computed exactly as the caps' t.
#[inline]
pub(crate) fn slab(o_y: Real, d_y: Real) -> (Real, Real) {
    if d_y != 0.0 {
        let (a, b) = ((-1.0 - o_y) / d_y, (1.0 - o_y) / d_y);
        (a.min(b), a.max(b))
    } else if (-1.0..=1.0).contains(&o_y) {
        (Real::NEG_INFINITY, Real::INFINITY)
    } else {
        (Real::INFINITY, Real::NEG_INFINITY)
    }
}
