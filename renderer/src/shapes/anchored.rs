//! The sphere, the cube and the cylinder about an anchor: mixed precision for an instance
//! whose scale is huge next to the distances the camera sees (renderer/docs/precision.md,
//! "Scale against view").
//!
//! A planet of radius 1e6 seen from 2 units above its surface has, in object space, its
//! eye 2e-6 above the unit sphere: an f32 object-space origin near 1 keeps that height
//! only to about 3 %, and the quadratic's constant term |o|² − 1 cancels. Here the object
//! space is moved so that its origin is the anchor `A`, a point of the surface near the
//! eye, chosen at build time in f64 (the instance's transform takes the shift, so the ray
//! arrives relative to `A`, small where the camera looks, and precise in f32). The shape
//! then lies about −A: the terms that cancel (a sphere's |o + A|² − 1, a face's ±1 − A,
//! a cylinder's radius term) are computed in f64 from the small origin and the f64 anchor;
//! the hit point is returned relative to `A` as well. The rest (the transform of the ray,
//! the mapping of the hit back, shading) stays in the build's precision.

use super::{azimuth, local_hit};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{dvec3, gamma, vec3, Real, Vec2, Vec3};
use glam::DVec3;

/// The canonical shapes that can be anchored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// The unit sphere.
    Sphere,
    /// The cube [−1, 1]³.
    Cube,
    /// The cylinder of radius 1 about y, y ∈ [−1, 1].
    Cylinder {
        /// Whether the end disks are part of the surface.
        capped: bool,
    },
}

/// A canonical shape seen from its anchor `a` (in the shape's own object space).
#[derive(Clone, Debug, PartialEq)]
pub struct Anchored {
    /// The shape.
    pub kind: Kind,
    /// The anchor, in the shape's object space.
    pub a: DVec3,
}

/// The error bound of a point rounded from f64 to the build's precision: half an ulp of
/// each component, plus the f64 computation's own (a few ε₆₄ of the unit shape).
#[inline]
fn rounded_err(p: DVec3) -> Vec3 {
    vec3(p.abs() * gamma(2) as f64 + DVec3::splat(16.0 * f64::EPSILON))
}

/// Roots of `a·t² + 2·b·t + c = 0` in f64, ascending (Haines et al.'s stable form, as
/// [`super::stable_roots`]).
#[inline]
fn roots64(a: f64, b: f64, c: f64, disc: f64) -> (f64, f64) {
    let q = -(b + disc.sqrt().copysign(b));
    if q == 0.0 {
        return (0.0, 0.0);
    }
    let (r0, r1) = (q / a, c / q);
    if r0 <= r1 {
        (r0, r1)
    } else {
        (r1, r0)
    }
}

impl Anchored {
    /// Object-space bounds, relative to the anchor (rounded outward).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let out = |x: f64, up: bool| {
            let r = x as Real;
            match (up, (r as f64) < x, (r as f64) > x) {
                (true, true, _) => r.next_up(),
                (false, _, true) => r.next_down(),
                _ => r,
            }
        };
        let lo = DVec3::splat(-1.0) - self.a;
        let hi = DVec3::splat(1.0) - self.a;
        (
            Vec3::new(out(lo.x, false), out(lo.y, false), out(lo.z, false)),
            Vec3::new(out(hi.x, true), out(hi.y, true), out(hi.z, true)),
        )
    }

    /// Closest hit with `t_min < t < t_max`; the point relative to the anchor.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut h = self.intersect_bare(ray, t_min, t_max)?;
        h.uv = self.uv(&h);
        Some(h)
    }

    /// [`Anchored::intersect`] without a sphere's uv (left at 0), as the search for a
    /// closest hit and shadow rays ask for it ([`super::sphere::intersect_bare`]);
    /// [`Anchored::uv`] completes the winner's record to the same bits.
    /// Never inlined: only the few instances the scale check flags come here, and
    /// inlined into the instance walk it made the walk of every other scene larger (a
    /// million plain spheres took 23 % more instructions).
    #[inline(never)]
    pub fn intersect_bare(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        match self.kind {
            Kind::Sphere => self.sphere(ray, t_min, t_max),
            Kind::Cube => self.cube(ray, t_min, t_max),
            Kind::Cylinder { capped } => self.cylinder(ray, capped, t_min, t_max),
        }
    }

    /// The sphere about −a: the sphere's own solve (renderer/src/shapes/sphere.rs) with the
    /// origin o + a in f64 and c = |o|² + 2a·o + (|a|² − 1), which does not cancel.
    fn sphere(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let (o, d) = (dvec3(ray.o), dvec3(ray.d));
        let oc = o + self.a;
        let a = d.length_squared();
        let b = oc.dot(d);
        let l = oc - d * (b / a);
        let disc = a * (1.0 - l.length_squared());
        if !(disc >= 0.0) {
            return None;
        }
        let c = o.length_squared() + 2.0 * self.a.dot(o) + (self.a.length_squared() - 1.0);
        let (t0, t1) = roots64(a, b, c, disc);
        let (t, side) = [(t0, -1.0), (t1, 1.0)]
            .into_iter()
            .map(|(t, s)| (t as Real, s))
            .find(|&(t, _)| t > t_min && t < t_max)?;
        let n = (l + d * (side * disc.sqrt() / a)).normalize();
        let p = n - self.a;
        let nr = vec3(n);
        Some(local_hit(t, vec3(p), rounded_err(p), nr, Vec2::ZERO))
    }

    /// The uv of a hit of [`Anchored::intersect_bare`]: a sphere's from its normal (the
    /// point on the unit sphere about its centre); the others' are already in the record.
    #[inline(never)]
    pub fn uv(&self, h: &Hit) -> Vec2 {
        match self.kind {
            Kind::Sphere => super::sphere::uv(h.n_geo),
            _ => h.uv,
        }
    }

    /// The cube's slab test (renderer/src/shapes/cube.rs) with the faces at ±1 − a in f64.
    fn cube(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let (o, d) = (dvec3(ray.o), dvec3(ray.d));
        let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut near_axis, mut far_axis) = (0usize, 0usize);
        for k in 0..3 {
            let (lo, hi) = (-1.0 - self.a[k], 1.0 - self.a[k]);
            if d[k] == 0.0 {
                if !(lo <= o[k] && o[k] <= hi) {
                    return None;
                }
                continue;
            }
            let (mut s0, mut s1) = ((lo - o[k]) / d[k], (hi - o[k]) / d[k]);
            if s0 > s1 {
                std::mem::swap(&mut s0, &mut s1);
            }
            if s0 > near {
                (near, near_axis) = (s0, k);
            }
            if s1 < far {
                (far, far_axis) = (s1, k);
            }
        }
        if near > far {
            return None;
        }
        let (t, axis, entering) = [(near, near_axis, true), (far, far_axis, false)]
            .into_iter()
            .find(|&(t, _, _)| (t as Real) > t_min && (t as Real) < t_max)?;
        let s = if entering == (d[axis] < 0.0) {
            1.0
        } else {
            -1.0
        };
        let mut n = Vec3::ZERO;
        n[axis] = s as Real;
        let mut p = o + d * t;
        p[axis] = s - self.a[axis];
        let mut err = rounded_err(p) + vec3((o.abs() + (d * t).abs()) * (4.0 * f64::EPSILON));
        err[axis] = 0.0;
        let q = p + self.a;
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let uv = Vec2::new(((q[u] + 1.0) * 0.5) as Real, ((q[v] + 1.0) * 0.5) as Real);
        Some(local_hit(t as Real, vec3(p), err, n, uv))
    }

    /// The cylinder (renderer/src/shapes/cylinder.rs) with its axis at −a and its caps at
    /// ±1 − a_y, in f64: the side's c = |o_xz|² + 2a_xz·o_xz + (|a_xz|² − 1).
    fn cylinder(&self, ray: &Ray, capped: bool, t_min: Real, t_max: Real) -> Option<Hit> {
        let (o, d) = (dvec3(ray.o), dvec3(ray.d));
        let a = self.a;
        let (lo, hi) = (-1.0 - a.y, 1.0 - a.y);
        let (ty0, ty1) = if d.y != 0.0 {
            let (s0, s1) = ((lo - o.y) / d.y, (hi - o.y) / d.y);
            (s0.min(s1), s0.max(s1))
        } else if lo <= o.y && o.y <= hi {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        };
        let (ox, oz) = (o.x + a.x, o.z + a.z);
        let qa = d.x * d.x + d.z * d.z;
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        let mut roots = None;
        if qa > 0.0 {
            let b = ox * d.x + oz * d.z;
            let (lx, lz) = (ox - d.x * (b / qa), oz - d.z * (b / qa));
            let disc = qa * (1.0 - (lx * lx + lz * lz));
            if disc >= 0.0 {
                let c = o.x * o.x
                    + o.z * o.z
                    + 2.0 * (a.x * o.x + a.z * o.z)
                    + (a.x * a.x + a.z * a.z - 1.0);
                let (t0, t1) = roots64(qa, b, c, disc);
                roots = Some((t0, t1));
                for (t, side) in [(t0, -1.0), (t1, 1.0)] {
                    let tr = t as Real;
                    if tr > t_min && tr < t_max && ty0 <= t && t <= ty1 {
                        let k = side * disc.sqrt() / qa;
                        let (x, z) = (lx + d.x * k, lz + d.z * k);
                        let r = (x * x + z * z).sqrt();
                        let (x, z) = if r > 0.0 && r.is_finite() {
                            (x / r, z / r)
                        } else {
                            let r = qa.sqrt();
                            (-d.x / r, -d.z / r)
                        };
                        let y = (o.y + t * d.y).clamp(lo, hi);
                        let p = DVec3::new(x - a.x, y, z - a.z);
                        let err = rounded_err(p)
                            + Vec3::new(
                                0.0,
                                ((o.y.abs() + (t * d.y).abs()) * 4.0 * f64::EPSILON) as Real,
                                0.0,
                            );
                        let n = Vec3::new(x as Real, 0.0, z as Real);
                        let uv = Vec2::new(
                            azimuth(x as Real, z as Real),
                            ((y + a.y + 1.0) * 0.5) as Real,
                        );
                        best = Some(local_hit(tr, vec3(p), err, n, uv));
                        t_max = tr;
                        break;
                    }
                }
            }
        }
        if capped && d.y != 0.0 {
            for (cap, y) in [(-1.0, lo), (1.0, hi)] {
                let t = (y - o.y) / d.y;
                let tr = t as Real;
                if tr > t_min && tr < t_max {
                    let inside = match roots {
                        Some((t0, t1)) => t0 <= t && t <= t1,
                        None => qa == 0.0 && ox * ox + oz * oz <= 1.0,
                    };
                    if inside {
                        let p = DVec3::new(o.x + t * d.x, y, o.z + t * d.z);
                        let mut err =
                            rounded_err(p) + vec3((o.abs() + (d * t).abs()) * (4.0 * f64::EPSILON));
                        err.y = 0.0;
                        let uv = Vec2::new(
                            ((p.x + a.x + 1.0) * 0.5) as Real,
                            ((p.z + a.z + 1.0) * 0.5) as Real,
                        );
                        best = Some(local_hit(tr, vec3(p), err, Vec3::new(0.0, cap, 0.0), uv));
                        t_max = tr;
                    }
                }
            }
        }
        best
    }
}
