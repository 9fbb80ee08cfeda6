//! The `direct` and `path` integrators (Mitsuba 3's), MIS weights and the environment's
//! density, and the specular guides' spheres; the module docs of `physical` say what they
//! compute.

use super::bsdf::{cosine_dir, dv, mirror, rgb, rv, BsdfSample, Surface};
use super::guide::{specular_balls, AtVertex, Ball, Pick, MAX_GUIDES};
use super::light_paths::{LightImage, LightPaths};
use super::vertex::Tracer;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::Real;
use crate::sampler::PixelSampler;
use crate::scene::settings::LightSampling;
use crate::scene::{Color, Integrator, LightKind, MaterialModel, Scene};
use crate::spawn::Spawn;
use std::f64::consts::PI;

/// A deliberate error, injected only by tests that show the conformance gate catches it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// Light sampling forgets the cosine at the shading point.
    MissingCosine,
    /// The camera paths count the caustics seen directly although light paths count them
    /// too (light_paths.rs).
    CausticsTwice,
}

/// The environment's light-sampling density of `dir` at a vertex whose facing normal is
/// `n`: cosine-weighted about it. (Mitsuba samples its constant environment uniformly
/// over the sphere, 1/4π: half of those directions lie below a surface, and the cosine
/// varies over the rest; cosine-weighted, a diffuse vertex's unshadowed environment light
/// is the same for every sample. The same expectation.)
///
/// Either side of `n` counts: a continuation sampled at a diffuse vertex lies on the side
/// the path came from, so the path loop keeps the shading normal as it is.
#[inline]
fn env_pdf(n: glam::DVec3, dir: glam::DVec3) -> f64 {
    n.dot(dir).abs() / PI
}

/// Power heuristic weight of strategy a against b (Veach; Mitsuba's `mis_weight`).
#[inline]
fn mis(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// The previous vertex's density when the emission the next hit would add was already
/// counted there ([`PhysicalIntegrator::reflected_emission`]): that emission then weighs 0.
const TAKEN: f64 = -1.0;

/// The MIS weight of emission reached from a vertex without a density (a delta lobe: 1,
/// or [`TAKEN`]: 0).
#[inline(always)]
fn taken_or_one(prev_pdf: f64) -> f64 {
    if prev_pdf == TAKEN {
        0.0
    } else {
        1.0
    }
}

/// The physically based integrators.
pub struct PhysicalIntegrator<'a> {
    scene: &'a Scene,
    spawn: Spawn,
    env: Option<glam::DVec3>,
    /// Spheres around the specular objects, when `render.guides` is on (guide.rs).
    guides: Vec<Ball>,
    /// Whether a top-level object is a dielectric: the path loop then takes a camera
    /// ray's reflection on it whole ([`PhysicalIntegrator::reflected_emission`]; a loop
    /// without that code is 2 % fewer instructions). Glass only inside a definition placed
    /// by `type = "instance"` takes the loop without it: the same expectation, without the
    /// gain.
    glass: bool,
    /// The light paths for the caustics seen directly, when on (light_paths.rs).
    light: Option<LightPaths>,
    /// The chance that next-event estimation picks a given light: 1 when it takes every
    /// light (`render.light_sampling = "all"`, or a single light), else 1 / their number.
    select: f64,
    /// A deliberate fault (tests only).
    pub fault: Option<Fault>,
}

impl<'a> PhysicalIntegrator<'a> {
    /// An integrator for `scene`.
    pub fn new(scene: &'a Scene, spawn: Spawn) -> Self {
        let env = scene
            .lights
            .iter()
            .filter(|l| l.kind == LightKind::Environment)
            .map(|l| rgb(l.color))
            .reduce(|a, b| a + b);
        PhysicalIntegrator {
            scene,
            spawn,
            env,
            glass: scene
                .root
                .in_scene_order()
                .any(|inst| scene.material(inst.material).model == MaterialModel::Dielectric),
            guides: if scene.settings.guides {
                guide_balls(scene)
            } else {
                Vec::new()
            },
            light: LightPaths::new(scene),
            select: match scene.settings.light_sampling {
                LightSampling::One => {
                    1.0 / (scene.lights.len() + scene.area_lights.len()).max(1) as f64
                }
                LightSampling::All => 1.0,
            },
            fault: None,
        }
    }

    /// Samples the continuation at a diffuse vertex with guides facing it: the cosine
    /// lobe or a guide's cone (guide.rs), weighted by the mixture's density.
    fn sample_guided(
        &self,
        s: &Surface,
        wo: glam::DVec3,
        smp: &mut PixelSampler,
        g: &AtVertex,
    ) -> Option<BsdfSample> {
        let u = smp.next_2d();
        let (dir, own) = match g.pick(u) {
            Pick::Cosine(u1) => (cosine_dir(s.facing(wo), (u1, u.1)), None),
            Pick::Cone(k, dir) => (dir, Some(k)),
        };
        let (f, cos_pdf) = s.eval_diffuse(wo, dir);
        if cos_pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample::diffuse(dir, f, g.pdf(cos_pdf, dir, own)))
    }

    /// What both path directions ask of the scene at a vertex (vertex.rs).
    #[inline(always)]
    fn tracer(&self) -> Tracer<'a> {
        Tracer {
            scene: self.scene,
            spawn: self.spawn,
        }
    }

    #[inline(always)]
    fn surface(&self, hit: &Hit) -> Surface<'a> {
        self.tracer().surface(hit)
    }

    #[inline(always)]
    fn occluded(&self, s: &Surface, dir: glam::DVec3, dist: f64) -> bool {
        self.tracer().occluded(s, dir, dist)
    }

    #[inline]
    fn is_area_light(&self, s: &Surface) -> bool {
        self.tracer().is_area_light(s)
    }

    /// Traces the render's light paths (none when they are off): `spp` camera samples a
    /// pixel; `moments`: also the sums of the contributions' products (light_paths.rs).
    pub(crate) fn light_image(&self, spp: u32, moments: bool) -> Option<LightImage> {
        let lp = self.light.as_ref()?;
        Some(lp.image(self.tracer(), spp, moments))
    }

    /// Radiance emitted by the surface towards `wo` (area lights emit on the normal side).
    fn emitted(&self, s: &Surface, wo: glam::DVec3) -> glam::DVec3 {
        if s.m.radiance == Color::ZERO || s.ng.dot(wo) <= 0.0 {
            return glam::DVec3::ZERO;
        }
        rgb(s.m.radiance)
    }

    /// Solid-angle density of light sampling having produced the emitter hit `s`, seen
    /// from `from` along the unit `dir` at distance `dist` (with the chance of picking its
    /// light, `select`).
    fn light_pdf_at(&self, s: &Surface, from: glam::DVec3, dir: glam::DVec3, dist: f64) -> f64 {
        let Some(&k) = self.scene.area_light_of.get(s.object_id as usize) else {
            return 0.0;
        };
        if k == u32::MAX {
            return 0.0;
        }
        let light = &self.scene.area_lights[k as usize];
        light.pdf_from(from, dir, dist, s.n_world) * self.select
    }

    /// The diffuse BSDF times cosine for light sampling (with the test-only fault applied).
    fn eval_light(&self, s: &Surface, wo: glam::DVec3, wi: glam::DVec3) -> (glam::DVec3, f64) {
        let (f, pdf) = s.eval_diffuse(wo, wi);
        if self.fault == Some(Fault::MissingCosine) && pdf > 0.0 {
            let cos = s.ns.dot(wi).abs();
            return (f / cos, pdf);
        }
        (f, pdf)
    }

    /// Next-event estimation at a non-delta surface: every light once, or with
    /// `render.light_sampling = "one"` one light chosen uniformly (weighted by the number
    /// of lights, as Mitsuba's emitter sampling); area lights and the environment weighted
    /// by MIS against BSDF sampling.
    #[inline(always)]
    fn direct_light(
        &self,
        s: &Surface,
        wo: glam::DVec3,
        smp: &mut PixelSampler,
        g: Option<&AtVertex>,
    ) -> glam::DVec3 {
        let n = self.scene.lights.len() + self.scene.area_lights.len();
        if self.select < 1.0 {
            // One light, picked with probability `select` = 1/n.
            let k = ((smp.next_1d() * n as f64) as usize).min(n - 1);
            return self.light_term(k, s, wo, smp, g, self.select);
        }
        let mut sum = glam::DVec3::ZERO;
        for k in 0..n {
            sum += self.light_term(k, s, wo, smp, g, 1.0);
        }
        sum
    }

    /// Next-event estimation of light `k` (the scene's lights, then its area lights),
    /// picked with probability `sel` (1 when every light is taken): its contribution over
    /// `sel`, and for area lights and the environment `sel` times the light's density in
    /// the MIS weight, as `light_pdf_at` and the path's escape count it. With `sel` = 1
    /// every operation on it is exact, so taking every light gives the bits it gave
    /// before the choice existed.
    #[inline(always)]
    fn light_term(
        &self,
        k: usize,
        s: &Surface,
        wo: glam::DVec3,
        smp: &mut PixelSampler,
        g: Option<&AtVertex>,
        sel: f64,
    ) -> glam::DVec3 {
        let p = dv(s.p);
        let Some(light) = self.scene.lights.get(k) else {
            let light = &self.scene.area_lights[k - self.scene.lights.len()];
            let ls = light.sample_from(p, smp.next_2d());
            // Nothing to sample (the back of the light does not emit).
            if !(ls.pdf > 0.0 && ls.pdf.is_finite()) {
                return glam::DVec3::ZERO;
            }
            let (f, pdf_b) = self.eval_light(s, wo, ls.wi);
            if f == glam::DVec3::ZERO || self.occluded(s, ls.wi, ls.dist) {
                return glam::DVec3::ZERO;
            }
            // The BSDF strategy's density of a light direction: the guided mixture's when
            // guides face the vertex.
            let pdf_b = match g {
                Some(g) => g.pdf(pdf_b, ls.wi, None),
                None => pdf_b,
            };
            let pdf_l = ls.pdf * sel;
            return f * rgb(light.radiance) * (mis(pdf_l, pdf_b) / pdf_l);
        };
        match light.kind {
            LightKind::Point => {
                let to = dv(light.position) - p;
                let d2 = to.length_squared();
                let dist = d2.sqrt();
                let wi = to / dist;
                let (f, _) = self.eval_light(s, wo, wi);
                if f != glam::DVec3::ZERO && !self.occluded(s, wi, dist) {
                    return f * rgb(light.color) / d2 / sel;
                }
            }
            LightKind::Directional => {
                let wi = -dv(light.direction);
                let (f, _) = self.eval_light(s, wo, wi);
                if f != glam::DVec3::ZERO && !self.occluded(s, wi, f64::INFINITY) {
                    return f * rgb(light.color) / sel;
                }
            }
            LightKind::Environment => {
                return self.environment_light(s, wo, smp, g, rgb(light.color), sel);
            }
        }
        glam::DVec3::ZERO
    }

    /// Next-event estimation of a constant environment of radiance `color`, picked with
    /// probability `sel`: one direction, cosine-weighted about the facing normal (env_pdf;
    /// times `sel`, the density of this strategy), weighted by MIS against the BSDF
    /// strategy (the guided mixture's density when guides face the vertex). Out of line:
    /// inlined into `direct_light`, the frames of scenes without an environment ran 1.6 %
    /// more instructions.
    #[inline(never)]
    fn environment_light(
        &self,
        s: &Surface,
        wo: glam::DVec3,
        smp: &mut PixelSampler,
        g: Option<&AtVertex>,
        color: glam::DVec3,
        sel: f64,
    ) -> glam::DVec3 {
        let n = s.facing(wo);
        let wi = cosine_dir(n, smp.next_2d());
        let pdf_l = env_pdf(n, wi) * sel;
        if !(pdf_l > 0.0) {
            return glam::DVec3::ZERO;
        }
        let (f, pdf_b) = self.eval_light(s, wo, wi);
        if f == glam::DVec3::ZERO || self.occluded(s, wi, f64::INFINITY) {
            return glam::DVec3::ZERO;
        }
        let pdf_b = match g {
            Some(g) => g.pdf(pdf_b, wi, None),
            None => pdf_b,
        };
        f * color * (mis(pdf_l, pdf_b) / pdf_l)
    }

    /// The emission along a dielectric's mirror direction times its reflectance F, when
    /// both lobes are possible (0 < F < 1): one more ray. A camera ray's path otherwise
    /// finds the light's highlight on glass only when it draws the reflection, with
    /// probability F (a few per cent), at weight 1: noise where the reflected light is
    /// much brighter than what the glass lets through. Taken whole, and left out of the
    /// path when the sampled lobe is the reflection (`TAKEN`), the expectation is the
    /// same: F·(Le + L_scattered) + (1 − F)·L_t. Measured on `mi_glass_sphere` (128²,
    /// `sobol` adaptive): 3 % less error for 1 % more time at the first vertex; at every
    /// dielectric vertex the extra rays cost what they saved (renderer/docs/physical.md).
    #[inline(never)]
    fn reflected_emission(&self, s: &Surface, wo: glam::DVec3) -> Option<glam::DVec3> {
        let n = s.facing(wo);
        let (cos_i, _, f, _) = s.dielectric(n, wo);
        if !(f > 0.0 && f < 1.0) {
            return None;
        }
        let dir = mirror(n, cos_i, wo);
        let (ray, t_min) = self.spawn.ray(s.p, s.err, rv(s.ng), rv(dir));
        let le = match self
            .scene
            .root
            .intersect_for_shading(&ray, t_min, Real::INFINITY)
        {
            Some(hit) => self.emitted(&self.surface(&hit), -dv(ray.d).normalize()),
            None => self.env.unwrap_or(glam::DVec3::ZERO),
        };
        Some(le * f)
    }

    /// Radiance along a camera ray. With light paths on (`render.light_paths`), the
    /// caustics seen directly are left out: [`crate::render::render`] adds them from the
    /// light paths. (Always inlined, with the path loops and what they
    /// call, into the render loop: each out-of-line call there cost a `direct` frame 1–3 %
    /// more instructions.)
    /// `first` is what the camera ray hits (`Aggregate::intersect_for_shading`), which the
    /// render loop finds for many camera rays at once (`intersect_many_for_shading`).
    #[inline(always)]
    pub fn li(&self, ray: &Ray, first: Option<Hit>, smp: &mut PixelSampler) -> Color {
        let s = &self.scene.settings;
        let v = match s.integrator {
            // A path with guides is its own loop, so that one without them is compiled
            // without their code (guide.rs; the `direct` integrator never guides).
            // So is one through a scene with glass (`reflected_emission`).
            // So is one whose caustics seen directly are the light paths' (light_paths.rs).
            Integrator::Path if self.light.is_some() => {
                match (!self.guides.is_empty(), self.glass) {
                    (true, true) => {
                        self.path::<true, true, true>(ray, first, smp, s.max_depth, s.rr_depth)
                    }
                    (true, false) => {
                        self.path::<true, false, true>(ray, first, smp, s.max_depth, s.rr_depth)
                    }
                    (false, true) => {
                        self.path::<false, true, true>(ray, first, smp, s.max_depth, s.rr_depth)
                    }
                    (false, false) => {
                        self.path::<false, false, true>(ray, first, smp, s.max_depth, s.rr_depth)
                    }
                }
            }
            Integrator::Path => match (!self.guides.is_empty(), self.glass) {
                (true, true) => {
                    self.path::<true, true, false>(ray, first, smp, s.max_depth, s.rr_depth)
                }
                (true, false) => {
                    self.path::<true, false, false>(ray, first, smp, s.max_depth, s.rr_depth)
                }
                (false, true) => {
                    self.path::<false, true, false>(ray, first, smp, s.max_depth, s.rr_depth)
                }
                (false, false) => {
                    self.path::<false, false, false>(ray, first, smp, s.max_depth, s.rr_depth)
                }
            },
            _ if self.glass => self.path::<false, true, false>(ray, first, smp, 2, u32::MAX),
            _ => self.path::<false, false, false>(ray, first, smp, 2, u32::MAX),
        };
        Color::new(v.x as f32, v.y as f32, v.z as f32)
    }

    /// Path tracing with next-event estimation. `max_depth` counts path vertices after the
    /// camera, as Mitsuba does: 1 shows emitters only, 2 adds direct light; `direct` is this
    /// with `max_depth = 2`, where a delta lobe's sampled ray still sees emitters.
    /// (Inlined into the render loop, its one caller there: out of line, a `direct` frame
    /// takes 3 % more instructions.)
    #[inline(always)]
    fn path<const GUIDED: bool, const GLASS: bool, const LIGHT: bool>(
        &self,
        ray: &Ray,
        first: Option<Hit>,
        smp: &mut PixelSampler,
        max_depth: u32,
        rr_depth: u32,
    ) -> glam::DVec3 {
        let mut l = glam::DVec3::ZERO;
        let mut beta = glam::DVec3::ONE;
        // The current ray's origin and direction, kept apart: a copy of the whole `Ray`
        // (24 bytes, moved as 16 + 8) read back as its direction (12 bytes from offset 12)
        // spans both moves, which the processor cannot forward from its store buffer.
        let (mut origin, mut d) = (ray.o, ray.d);
        let mut prev_pdf = 0.0; // 0: the previous vertex was the camera or a delta lobe.
        let mut eta_scale = 1.0;
        let mut depth = 0u32;
        // The path so far is camera → diffuse → one or more specular vertices: an area
        // light it meets now is the light paths' (light_paths.rs).
        let mut caustic = false;
        // The shading normal of the previous vertex, when it had a density (env_pdf).
        let mut prev_n = glam::DVec3::ZERO;
        // The camera ray's hit is given; each vertex finds the next one's, written in
        // place (`intersect_for_shading_into`).
        let mut found = first.is_some();
        let mut hit = first.unwrap_or_default();
        loop {
            let dir = dv(d).normalize();
            if !found {
                if let Some(env) = self.env {
                    let w = if prev_pdf > 0.0 {
                        mis(prev_pdf, env_pdf(prev_n, dir) * self.select)
                    } else {
                        taken_or_one(prev_pdf)
                    };
                    l += beta * env * w;
                }
                break;
            }
            let s = self.surface(&hit);
            let wo = -dir;
            let le = self.emitted(&s, wo);
            if le != glam::DVec3::ZERO {
                let dist = (dv(hit.p) - dv(origin)).length();
                let w = if prev_pdf > 0.0 {
                    mis(prev_pdf, self.light_pdf_at(&s, dv(origin), dir, dist))
                } else if LIGHT
                    && caustic
                    && self.fault != Some(Fault::CausticsTwice)
                    && self.is_area_light(&s)
                {
                    0.0
                } else {
                    taken_or_one(prev_pdf)
                };
                l += beta * le * w;
            }
            depth += 1;
            if LIGHT {
                // Diffuse first, then specular only (caustic is false at depth 1).
                caustic = if depth == 1 {
                    !s.is_delta()
                } else {
                    caustic && s.is_delta()
                };
            }
            if depth >= max_depth {
                break;
            }
            // Guides pay only when the path goes on after the specular object it meets
            // next: a vertex two or more before the last.
            // (Built only in a scene with guides: a vertex of any other pays one test.)
            // Not at the first vertex when light paths are on: what a guided continuation
            // from there finds through a specular object is theirs (light_paths.rs).
            let g = if GUIDED && !s.is_delta() && depth + 1 < max_depth && !(LIGHT && depth == 1) {
                Some(AtVertex::new(&self.guides, dv(s.p), s.facing(wo))).filter(|g| g.active())
            } else {
                None
            };
            if !s.is_delta() {
                l += beta * self.direct_light(&s, wo, smp, g.as_ref());
            }
            let bs = match &g {
                Some(g) => self.sample_guided(&s, wo, smp, g),
                None => s.sample(wo, smp),
            };
            // A dielectric seen from the camera: its reflection's emission (the light's
            // highlight) taken whole.
            let whole = if GLASS && depth == 1 && s.m.model == MaterialModel::Dielectric {
                self.reflected_emission(&s, wo)
            } else {
                None
            };
            if let Some(e) = whole {
                l += beta * e;
            }
            let Some(bs) = bs else { break };
            prev_n = s.ns;
            beta *= bs.weight;
            // The sampled lobe is the reflection (weight 1 with probability F): what it
            // meets goes on, its emission is already counted (`TAKEN`).
            prev_pdf = if whole.is_some() && bs.reflected {
                TAKEN
            } else {
                bs.pdf
            };
            eta_scale *= bs.eta * bs.eta;
            if depth >= rr_depth {
                let q = (beta.max_element() * eta_scale).min(0.95);
                if smp.next_1d() >= q {
                    break;
                }
                beta /= q;
            }
            if beta == glam::DVec3::ZERO {
                break;
            }
            let (ray, t_min) = self.spawn.ray(s.p, s.err, rv(s.ng), rv(bs.dir));
            (origin, d) = (ray.o, ray.d);
            let root = &self.scene.root;
            if depth + 1 >= max_depth {
                // The next vertex is the last: it adds its emission and nothing else, so a
                // hit on a material that emits nothing ends the path here.
                let emits = |m: u32| self.scene.material(m).radiance != Color::ZERO;
                match root.intersect_for_shading_if(&ray, t_min, Real::INFINITY, &mut hit, emits) {
                    Some(false) => break,
                    reached => found = reached.is_some(),
                }
            } else {
                found = root.intersect_for_shading_into(&ray, t_min, Real::INFINITY, &mut hit);
            }
        }
        l
    }
}

/// Spheres around the scene's specular (conductor and dielectric) objects, for guide.rs:
/// a sphere placed by a similarity is its own, any other bounded object has the sphere
/// around its bounding box. None when there are more than [`MAX_GUIDES`].
fn guide_balls(scene: &Scene) -> Vec<Ball> {
    let (mut balls, _) = specular_balls(scene);
    if balls.len() > MAX_GUIDES {
        balls.clear();
    }
    balls
}
