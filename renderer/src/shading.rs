//! POV-Ray 3.7's classic illumination model, term for term (`#version 3.7`, one texture
//! layer, no radiosity). The formulas and their order follow POV-Ray's
//! source/backend/render/trace.cpp; renderer/docs/shading.md cites the function for each.
//!
//! ```text
//! a   = 1 − filter − transmit                           (ComputeLightedTexture)
//! fil = pigment·filter + transmit
//! C   = P·Ka·ambient_light·a + P·Ke·a
//!     + Σ lights S·Lc·fade · [ Kd·a·P·(N·L)^brilliance    (only if N·L ≥ 1e-10)
//!                             + Kp·(R·L)^phong_size + Ks·(N·Ĥ)^(1/roughness) ]
//!     + fil·Trace(refracted)      or, on total internal reflection, Trace(reflected)
//!     + Kr·Trace(reflected)       (skipped after total internal reflection)
//! ```
//! N is the normal flipped to face the incoming ray; R = D − 2(D·N)N; Ĥ = norm(L − D).
//! `Trace` returns black once the trace level reaches `max_depth` or the ray weight drops
//! below `adc_bailout`, and the background on a miss.

use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{Real, Vec3};
use crate::scene::{Color, Scene};
use crate::spawn::Spawn;

/// POV-Ray's EPSILON for the light-side test (ComputeOneDiffuseLight).
const LIGHT_SIDE_EPSILON: Real = 1e-10;
/// Interiors a ray can be inside at once (nesting depth of transparent objects).
const MAX_INTERIORS: usize = 16;

/// The objects a ray is inside, innermost last (POV-Ray's interior list), each as the
/// surface that was entered ([`Hit::surface`]: the shape and the instance path, so two
/// shapes inside one instanced definition are two objects, as they are in a group).
#[derive(Clone, Copy, Debug)]
pub struct Interiors {
    ids: [(u64, f32); MAX_INTERIORS],
    len: usize,
    /// Surfaces this path has passed straight through (ior the same on both sides).
    passes: u32,
}

impl Default for Interiors {
    fn default() -> Self {
        Interiors::EMPTY
    }
}

/// Surfaces a path may pass straight through (the same ior on both sides) without using up
/// a trace level; past that each one uses a level, as a refraction does. Without it, a ray
/// through thousands of such surfaces recursed once per surface, whatever `max_depth`
/// said, and overflowed the stack (renderer/docs/robustness.md).
pub const MAX_PASS_THROUGH: u32 = 64;

impl Interiors {
    /// Inside nothing: where a camera ray starts (by reference). A path copies its list
    /// only where it enters or leaves something (refraction, pass-through); a reflected
    /// ray shares its parent's list by reference.
    const EMPTY: Interiors = Interiors {
        ids: [(0, 1.0); MAX_INTERIORS],
        len: 0,
        passes: 0,
    };

    fn top(&self) -> Option<(u64, f32)> {
        (self.len > 0).then(|| self.ids[self.len - 1])
    }
    fn outer_ior(&self) -> f32 {
        if self.len >= 2 {
            self.ids[self.len - 2].1
        } else {
            1.0
        }
    }
    fn push(&mut self, id: u64, ior: f32) {
        if self.len < MAX_INTERIORS {
            self.ids[self.len] = (id, ior);
            self.len += 1;
        }
    }
    fn pop(&mut self) {
        self.len = self.len.saturating_sub(1);
    }
}

/// The per-render shading context.
pub struct Shader<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// How secondary rays start.
    pub spawn: Spawn,
    /// POV-Ray's shadow tolerance, applied at the light end of shadow rays.
    pub shadow_tolerance: Real,
    /// Whether every material is opaque: then a shadow ray only asks whether anything
    /// blocks it (any hit, which stops at the first blocker), not what.
    opaque: bool,
}

impl<'a> Shader<'a> {
    /// A shader with the scene's settings.
    pub fn new(scene: &'a Scene, spawn: Spawn) -> Self {
        Shader {
            scene,
            spawn,
            shadow_tolerance: 1e-3,
            opaque: scene
                .materials
                .iter()
                .all(|m| m.filter == 0.0 && m.transmit == 0.0),
        }
    }

    /// Radiance along a camera ray.
    pub fn trace_primary(&self, ray: &Ray) -> Color {
        self.trace_primary_hit(
            ray,
            self.scene
                .root
                .intersect_for_shading(ray, 0.0, Real::INFINITY),
        )
    }

    /// [`Shader::trace_primary`] given the ray's closest hit (from
    /// [`crate::aggregate::Aggregate::intersect_many`], which finds many at once).
    /// Always inlined into the render loop: as a call, its colour came back through
    /// memory, written float by float and read as a pair (a store-forwarding stall).
    #[inline(always)]
    pub fn trace_primary_hit(&self, ray: &Ray, hit: Option<Hit>) -> Color {
        if self.cut_off(0, 1.0) {
            return Color::ZERO;
        }
        match hit {
            None => self.scene.settings.background,
            Some(hit) => self.shade(ray, &hit, 0, 1.0, &Interiors::EMPTY),
        }
    }

    /// POV-Ray's TraceRay: black past the trace level or below the bailout weight, the
    /// background on a miss, else the lit surface colour.
    pub fn trace(
        &self,
        ray: &Ray,
        t_min: Real,
        level: u32,
        weight: f32,
        interiors: &Interiors,
    ) -> Color {
        if self.cut_off(level, weight) {
            return Color::ZERO;
        }
        // The record written in place (`intersect_for_shading_into`: one returned is
        // copied out with wide loads of fields just written, a store-forwarding stall).
        let mut hit = Hit::default();
        if self
            .scene
            .root
            .intersect_for_shading_into(ray, t_min, Real::INFINITY, &mut hit)
        {
            self.shade(ray, &hit, level, weight, interiors)
        } else {
            self.scene.settings.background
        }
    }

    /// Whether a ray is past the trace level or below the bailout weight.
    fn cut_off(&self, level: u32, weight: f32) -> bool {
        let s = &self.scene.settings;
        level >= s.max_depth || weight < s.adc_bailout
    }

    fn shade(&self, ray: &Ray, hit: &Hit, level: u32, weight: f32, interiors: &Interiors) -> Color {
        let scene = self.scene;
        let m = scene.material(hit.material);
        let d = ray.d.normalize();
        let (p, err) = (hit.p, hit.err);
        let n_geo = hit.n_geo.normalize();
        let mut n = if hit.flat_shaded() {
            n_geo
        } else {
            hit.n_shade.normalize()
        };
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let pig = m.color;
        let att = 1.0 - m.filter - m.transmit;
        let mut c =
            pig * (m.ambient * att) * scene.settings.ambient_light + pig * (m.emission * att);

        if m.diffuse != 0.0 || m.phong != 0.0 || m.specular != 0.0 {
            for light in &scene.lights {
                let to_light = light.position - p;
                let dist = to_light.length();
                if !(dist > 0.0) {
                    continue;
                }
                let l = to_light / dist;
                let cos = n.dot(l);
                if cos < LIGHT_SIDE_EPSILON {
                    continue;
                }
                let mut lc = light.color;
                if let Some((fd, fp)) = light.fade {
                    lc *= (2.0 / (1.0 + (dist / fd).powf(fp))) as f32;
                }
                lc *= self.shadow(p, err, n_geo, l, dist);
                if lc.max_element() <= 1e-10 {
                    continue;
                }
                let cos = cos as f32;
                let intensity = if m.brilliance != 1.0 {
                    cos.powf(m.brilliance)
                } else {
                    cos
                };
                c += pig * lc * (intensity * m.diffuse * att);
                if m.phong > 0.0 {
                    let r = d - n * (2.0 * d.dot(n));
                    let rl = r.dot(l) as f32;
                    if rl > 0.0 && (m.phong_size < 60.0 || rl > 0.0008) {
                        c += lc * (m.phong * rl.powf(m.phong_size));
                    }
                }
                if m.specular > 0.0 {
                    let h = (l - d) * 0.5;
                    let hn = (h.dot(n) / h.length()) as f32;
                    if hn > 0.0 {
                        c += lc * (m.specular * hn.powf(1.0 / m.roughness));
                    }
                }
            }
        }

        // Transmission (before reflection, as in POV-Ray).
        let fil = pig * m.filter + Color::splat(m.transmit);
        let trans = (0.297 * fil.x + 0.589 * fil.y + 0.114 * fil.z)
            .abs()
            .min(1.0);
        let mut total_internal = false;
        if trans > scene.settings.adc_bailout {
            let w = weight * fil.abs().max_element();
            let id = hit.surface;
            let (entering, eta) = match interiors.top() {
                Some((top, ior)) if top == id => (false, ior / interiors.outer_ior()),
                _ => (true, interiors.top().map_or(1.0, |t| t.1) / m.ior),
            };
            if (eta - 1.0).abs() < 1e-10 {
                // Straight through: the trace level is not used up, for the first
                // MAX_PASS_THROUGH such surfaces of the path.
                let mut inner = *interiors;
                if entering {
                    inner.push(id, m.ior)
                } else {
                    inner.pop()
                }
                let next = if inner.passes < MAX_PASS_THROUGH {
                    inner.passes += 1;
                    level
                } else {
                    level + 1
                };
                let (r, tmin) = self.spawn.ray(p, err, n_geo, ray.d);
                c += fil * self.trace(&r, tmin, next, w, &inner);
            } else {
                let cos_i = -d.dot(n);
                let eta_r = eta as Real;
                let k = 1.0 + eta_r * eta_r * (cos_i * cos_i - 1.0);
                if k < 0.0 {
                    total_internal = true;
                    c += self.reflect(p, err, n_geo, d, n, level, w, interiors);
                } else {
                    let dir = d * eta_r + n * (eta_r * cos_i - k.sqrt());
                    let mut inner = *interiors;
                    if entering {
                        inner.push(id, m.ior)
                    } else {
                        inner.pop()
                    }
                    let (r, tmin) = self.spawn.ray(p, err, n_geo, dir);
                    c += fil * self.trace(&r, tmin, level + 1, w, &inner);
                }
            }
        }
        if m.reflection > 0.0 && !total_internal {
            let w = weight * m.reflection;
            c += self.reflect(p, err, n_geo, d, n, level, w, interiors) * m.reflection;
        }
        c
    }

    #[allow(clippy::too_many_arguments)]
    fn reflect(
        &self,
        p: Vec3,
        err: Vec3,
        n_geo: Vec3,
        d: Vec3,
        n: Vec3,
        level: u32,
        w: f32,
        interiors: &Interiors,
    ) -> Color {
        let r = (d - n * (2.0 * d.dot(n))).normalize();
        let (ray, tmin) = self.spawn.ray(p, err, n_geo, r);
        self.trace(&ray, tmin, level + 1, w, interiors)
    }

    /// Light reaching `p` from a light at distance `dist` along unit `l`: 0 behind an
    /// opaque blocker, filtered by `pigment·filter + transmit` through transparent ones.
    fn shadow(&self, p: Vec3, err: Vec3, n_geo: Vec3, l: Vec3, dist: Real) -> Color {
        let (mut ray, t_min) = self.spawn.ray(p, err, n_geo, l);
        let mut remaining = dist - self.shadow_tolerance;
        if self.opaque {
            // The first blocker decides, and any blocker is opaque: the same answer as
            // the loop below gives, found sooner.
            return if self.scene.root.occluded(&ray, t_min, remaining) {
                Color::ZERO
            } else {
                Color::ONE
            };
        }
        let mut t_min = t_min;
        let mut filter = Color::ONE;
        // Follow the shadow ray through transparent blockers (bounded, allocation-free).
        let mut hit = Hit::default();
        for _ in 0..64 {
            if !self
                .scene
                .root
                .intersect_for_shading_into(&ray, t_min, remaining, &mut hit)
            {
                return filter;
            }
            let m = self.scene.material(hit.material);
            if m.filter == 0.0 && m.transmit == 0.0 {
                return Color::ZERO;
            }
            filter *= m.color * m.filter + Color::splat(m.transmit);
            if filter.max_element() <= 1e-10 {
                return Color::ZERO;
            }
            remaining -= hit.t;
            let ng = hit.n_geo.normalize();
            let (r, tm) = self.spawn.ray(hit.p, hit.err, ng, l);
            ray = r;
            t_min = tm;
        }
        filter
    }
}
