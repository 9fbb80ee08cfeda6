//! A path vertex's questions to the scene, which the camera paths (integrator.rs) and the
//! light paths (light_paths.rs) both ask: the surface at a hit, whether a segment is
//! occluded, whether an emitter is an area light.

use super::bsdf::{dv, rv, Surface};
use crate::hit::Hit;
use crate::real::Real;
use crate::scene::Scene;
use crate::spawn::Spawn;

/// The scene and the spawn strategy a render traces with.
#[derive(Clone, Copy)]
pub(super) struct Tracer<'a> {
    pub(super) scene: &'a Scene,
    pub(super) spawn: Spawn,
}

impl<'a> Tracer<'a> {
    /// The surface at `hit`, oriented for shading.
    #[inline(always)]
    pub(super) fn surface(&self, hit: &Hit) -> Surface<'a> {
        let ng = dv(hit.n_geo).normalize();
        let ns = if hit.flat_shaded() {
            ng
        } else {
            Some(dv(hit.n_shade).normalize())
                .filter(|ns| ns.is_finite())
                .unwrap_or(ng)
        };
        Surface {
            p: hit.p,
            err: hit.err,
            ng,
            ns,
            m: self.scene.material(hit.material),
            object_id: hit.object_id,
            n_world: hit.n_geo,
        }
    }

    /// Whether anything lies between `s` and `dist` along the unit `dir`.
    #[inline(always)]
    pub(super) fn occluded(&self, s: &Surface, dir: glam::DVec3, dist: f64) -> bool {
        let (ray, t_min) = self.spawn.ray(s.p, s.err, rv(s.ng), rv(dir));
        let limit = if dist.is_finite() {
            (dist * (1.0 - 1e-4)) as Real
        } else {
            Real::INFINITY
        };
        self.scene.root.occluded(&ray, t_min, limit)
    }

    /// Whether the emitter at `s` is an area light (what the light paths start from).
    #[inline]
    pub(super) fn is_area_light(&self, s: &Surface) -> bool {
        self.scene
            .area_light_of
            .get(s.object_id as usize)
            .is_some_and(|&k| k != u32::MAX)
    }
}
