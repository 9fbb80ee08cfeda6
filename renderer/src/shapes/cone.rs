//! The cone with apex (0, 1, 0) and base radius 1 at y = −1: `x² + z² = k²(1 − y)²` with
//! k = ½, for y ∈ [−1, 1], and an optional base cap.

use super::{azimuth, local_hit};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{dvec3, gamma, Real, Vec2, Vec3};
use glam::DVec3;

const K2: Real = 0.25;

/// Closest hit. Side normal is the gradient `(x, k²(1 − y), z)`, and +y at the apex
/// itself, where the gradient vanishes. Cap normal −y.
#[inline]
pub fn intersect(ray: &Ray, capped: bool, t_min: Real, t_max: Real) -> Option<Hit> {
    let (o, d) = (ray.o, ray.d);
    let mut best: Option<Hit> = None;
    let mut t_max = t_max;
    // The quadratic's coefficients, its discriminant and its roots in f64, in both builds,
    // as for the sphere and the cylinder: in f32 the products d·(b/a), of size |o|, move l
    // by ε·|o|, so a far cone (|o| ≫ 1 in object space) got wrong hits and misses near
    // its silhouette. w = 1 − y.
    let (o64, d64) = (dvec3(o), dvec3(d));
    let k2 = K2 as f64;
    let (ow, dw) = (1.0 - o64.y, -d64.y);
    let a = d64.x * d64.x + d64.z * d64.z - k2 * dw * dw;
    let b = o64.x * d64.x + o64.z * d64.z - k2 * ow * dw;
    let c = o64.x * o64.x + o64.z * o64.z - k2 * ow * ow;
    let mut roots = [f64::NAN; 2];
    // Which t lie inside the double cone x² + z² ≤ k²(1 − y)²: [lo, hi], or outside (lo, hi)
    // when the flag is set. The base cap is hit only inside, and a side root counts only
    // inside the slab −1 ≤ y ≤ 1 (whose ends are computed exactly as the cap's t): the
    // same computed values decide both, so a ray entering at the base rim cannot slip
    // between the cap and the side (as in the cylinder).
    let mut inside = (f64::INFINITY, f64::NEG_INFINITY, false);
    let scale = d64.length_squared();
    // Parallel to a generator line when `a` vanishes up to the rounding of the render
    // precision's direction (the same test in both builds' terms).
    if a.abs() <= scale * Real::EPSILON as f64 {
        // The ray is parallel to a generator line: one root.
        if b != 0.0 {
            roots[0] = -c / (2.0 * b);
            inside = if b > 0.0 {
                (f64::NEG_INFINITY, roots[0], false)
            } else {
                (roots[0], f64::INFINITY, false)
            };
        } else if c <= 0.0 {
            inside = (f64::NEG_INFINITY, f64::INFINITY, false);
        }
    } else {
        // b² − a·c cancels catastrophically when the roots are close relative to the
        // origin's distance (a ray passing near the apex from afar). As for the sphere,
        // use b² − a·c = −a·Q(l) with l = o − d·(b/a) and Q(v) = x² + z² − k²·w².
        let s = b / a;
        let (lx, lw, lz) = (o64.x - d64.x * s, ow - dw * s, o64.z - d64.z * s);
        let disc = -a * (lx * lx + lz * lz - k2 * lw * lw);
        if disc >= 0.0 {
            let s = disc.sqrt();
            let q = -(b + s.copysign(b));
            if q != 0.0 {
                roots = [q / a, c / q];
            } else {
                roots = [0.0, 0.0];
            }
            if roots[0] > roots[1] {
                roots.swap(0, 1);
            }
            inside = (roots[0], roots[1], a < 0.0);
        } else if a < 0.0 {
            // The whole line is inside the double cone: it passes through the apex, where
            // rounding lost the double root (see the apex below).
            inside = (f64::NEG_INFINITY, f64::INFINITY, false);
        }
    }
    // In the render precision from here on (the roots keep their f64 values for the
    // Newton step).
    let roots64 = roots;
    let roots = roots.map(|t| t as Real);
    let inside = (inside.0 as Real, inside.1 as Real, inside.2);
    let in_cone = |t: Real| {
        let (lo, hi, outside) = inside;
        if outside {
            t <= lo || t >= hi
        } else {
            lo <= t && t <= hi
        }
    };
    let (ty0, ty1) = super::cylinder::slab(o.y, d.y);
    for (t, t64) in roots.into_iter().zip(roots64) {
        if t > t_min && t < t_max && ty0 <= t && t <= ty1 {
            // One Newton step on the f64 root, in f64, rounded once: t within 0.5 ulp in
            // f32 (measured). The step was taken in the render precision before, which in
            // f32 only added its own rounding (t within 3.4 ulps), as mutation testing
            // showed (conformance/docs/mutation.md); in f64 it is the same step as before.
            let t = refine(o64, d64, t64) as Real;
            if !(t > t_min && t < t_max) {
                continue;
            }
            let p = ray.at(t);
            // Re-project radially onto r = ½(1 − y), as the cylinder does: near a double
            // root, or far from the cone, o + t·d can lie off the surface by much more than
            // `err`; the re-projected point is on it up to the rounding of these few
            // operations, well within γ(8).
            let y = p.y.clamp(-1.0, 1.0);
            let r = (p.x * p.x + p.z * p.z).sqrt();
            let p = if r > 0.0 {
                let s = 0.5 * (1.0 - y) / r;
                Vec3::new(p.x * s, y, p.z * s)
            } else {
                Vec3::new(p.x, y, p.z)
            };
            let mut n = Vec3::new(p.x, K2 * (1.0 - p.y), p.z);
            if n == Vec3::ZERO {
                n = Vec3::Y;
            }
            // On the surface up to the rounding of the projection and of F itself.
            let err = (p.abs() + Vec3::ONE) * gamma(8);
            let uv = Vec2::new(azimuth(p.x, p.z), (p.y + 1.0) * 0.5);
            best = Some(local_hit(t, p, err, n, uv));
            t_max = t;
            break;
        }
    }
    // The apex, as the solid's degenerate face y = 1: a ray that crosses that plane inside
    // the double cone passes through the apex. There the two roots are nearly double, and
    // rounding loses them or moves them past y = 1: half of the rays aimed exactly at the
    // apex from inside the solid's tangent cone missed in f32 without this.
    if d.y != 0.0 {
        let t = (1.0 - o.y) / d.y;
        if t > t_min && t < t_max && in_cone(t) {
            let err = (Vec3::Y + Vec3::ONE) * gamma(8);
            best = Some(local_hit(t, Vec3::Y, err, Vec3::Y, Vec2::new(0.0, 1.0)));
            t_max = t;
        }
    }
    if capped && d.y != 0.0 {
        let t = (-1.0 - o.y) / d.y;
        if t > t_min && t < t_max && in_cone(t) {
            let mut p = ray.at(t);
            p.y = -1.0;
            let err = Vec3::new(p.x.abs(), 0.0, p.z.abs()) * gamma(4);
            best = Some(local_hit(
                t,
                p,
                err,
                -Vec3::Y,
                Vec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5),
            ));
        }
    }
    best
}

/// One Newton step on `F(o + t·d) = 0` in f64, evaluated at the point (not through the
/// quadratic's coefficients, whose cancellation is what the step removes).
#[inline]
fn refine(o: DVec3, d: DVec3, t: f64) -> f64 {
    let k2 = K2 as f64;
    let residual = |p: DVec3| {
        let w = 1.0 - p.y;
        p.x * p.x + p.z * p.z - k2 * w * w
    };
    let p = o + d * t;
    let f = residual(p);
    let df = 2.0 * (p.x * d.x + p.z * d.z + k2 * (1.0 - p.y) * d.y);
    if df != 0.0 && df.is_finite() {
        let t2 = t - f / df;
        // Keep the step only if it reduces the residual. At a tangent ray the root is
        // double and F' vanishes there, so the step can jump far along the ray (and the
        // radial re-projection then put the hit on the cone far from the ray).
        if t2.is_finite() && residual(o + d * t2).abs() < f.abs() {
            return t2;
        }
    }
    t
}
