//! The closest hit over the oracle's world, by testing every object (no acceleration
//! structure: the catalog scenes have at most a few hundred primitives).
//!
//! An object maps the ray into its own space by the inverse of `world_from_object`,
//! `o' = M⁻¹(o − T)`, `d' = M⁻¹d` (not renormalised, so t is the world distance), and its
//! normal back out by `M⁻ᵀ` (pbrt-v4's instancing, and POV-Ray's `MInvTransNormal`).

use super::camera::Ray;
use super::world::World;
use glam::DVec3;

/// A surface hit in world space.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the (unit) ray.
    pub t: f64,
    /// The point.
    pub p: DVec3,
    /// Unit geometric normal, any orientation.
    pub n: DVec3,
    /// Index of the object hit.
    pub object: usize,
}

impl World {
    /// The nearest hit with t in (lo, hi).
    pub fn closest(&self, ray: &Ray, lo: f64, hi: f64) -> Option<Hit> {
        let mut best: Option<(f64, DVec3, DVec3, usize)> = None;
        for (k, obj) in self.objects.iter().enumerate() {
            let x = &obj.xf;
            let o = x.inv * (ray.o - x.t);
            let d = x.inv * ray.d;
            let far = best.map_or(hi, |b| b.0);
            if let Some((t, n, local)) = obj.prim.intersect(o, d, lo, far) {
                best = Some((t, n, local, k));
            }
        }
        // The point is mapped out of object space, where the refined root puts it on the
        // surface to an ulp, rather than taken as o + t·d (whose rounding grows with t).
        best.map(|(t, n, local, k)| {
            let x = &self.objects[k].xf;
            Hit {
                t,
                p: x.m * local + x.t,
                n: (x.inv.transpose() * n).normalize(),
                object: k,
            }
        })
    }
}
