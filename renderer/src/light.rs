//! Lights: point, directional and environment lights, and area lights (emissive spheres and
//! rectangles). Scene data, read by both integrators; area lights also know how to sample
//! themselves.

use crate::aggregate::Instance;
use crate::aggregate::Shape;
use crate::material::Color;
use crate::real::{Real, Vec3};
use crate::sampler::cos_sin_turn;
use crate::transform::Transform;
use glam::DVec3;
use serde::Deserialize;
use std::f64::consts::PI;

/// Kinds of light.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum LightKind {
    /// A point light at `position`.
    #[default]
    Point,
    /// A directional light travelling along `direction`.
    Directional,
    /// A constant environment around the scene.
    Environment,
}

/// A light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Kind.
    pub kind: LightKind,
    /// Position (point lights; zero otherwise).
    pub position: Vec3,
    /// Unit direction the light travels (directional lights; zero otherwise).
    pub direction: Vec3,
    /// Colour.
    pub color: Color,
    /// Fade distance and power, when fading is on.
    pub fade: Option<(Real, Real)>,
}

/// An emissive sphere or rectangle placed by a transform.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// `Sphere` or `Rectangle`.
    pub shape: Shape,
    /// `world_from_object`, if any.
    pub xf: Option<Transform>,
    /// Emitted radiance.
    pub radiance: Color,
    /// |det M| of the transform (1 without one).
    det: Real,
    /// For a sphere placed by a similarity (rotation, uniform scale, translation): its
    /// world centre and radius, so that it is sampled by the cone of directions it
    /// subtends (as Mitsuba 3 samples its `sphere` emitter) instead of by area.
    ball: Option<(DVec3, f64)>,
    /// For a rectangle, what is the same at every point of it: its world normal
    /// (`m⁻ᵀ·y`, as its hits report it) made unit, and its area density
    /// ([`AreaLight::pdf_area`]). [`AreaLight::sample_from`] reads them rather than
    /// computing them per sample (the same bits).
    flat: Option<(DVec3, Real)>,
    /// Bounds in render space (its instance's).
    pub(crate) bounds: crate::aabb::Aabb,
}

/// The density of a sampled light point: per solid angle (a sphere's cone) or per area.
#[derive(Clone, Copy)]
enum Density {
    Cone(f64),
    Area(Real),
}

/// A point sampled on an area light, as seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightSample {
    /// Unit direction from the shading point to the sampled point, and the distance.
    pub wi: DVec3,
    pub dist: f64,
    /// Solid-angle density of having sampled `wi` (0: nothing to sample, such as the
    /// back of the light; the sample is then to be skipped).
    pub pdf: f64,
}

/// Whether the linear part `m` of a transform is a similarity: orthogonal columns of one
/// length, to a relative 1e-5 (a rotation and a uniform scale in f32 are that, to
/// rounding). Returns the scale.
fn similarity_scale(m: &crate::real::Mat3) -> Option<f64> {
    let c = [m.x_axis, m.y_axis, m.z_axis].map(crate::real::dvec3);
    let s2 = c[0].length_squared();
    let tol = 1e-5 * s2;
    let ok = (c[1].length_squared() - s2).abs() <= tol
        && (c[2].length_squared() - s2).abs() <= tol
        && c[0].dot(c[1]).abs() <= tol
        && c[0].dot(c[2]).abs() <= tol
        && c[1].dot(c[2]).abs() <= tol;
    (ok && s2 > 0.0 && s2.is_finite()).then(|| s2.sqrt())
}

/// The world centre and radius of a sphere instance placed by a similarity (rotation,
/// uniform scale, translation); `None` for anything else.
pub(crate) fn sphere_ball(inst: &Instance) -> Option<(DVec3, f64)> {
    match (&inst.shape, &inst.xf) {
        (Shape::Sphere, None) => Some((DVec3::ZERO, 1.0)),
        (Shape::Sphere, Some(x)) => {
            similarity_scale(&x.matrix()).map(|r| (crate::real::dvec3(x.translation()), r))
        }
        _ => None,
    }
}

/// The cone of directions a ball (centre `c`, radius `r`) subtends from `p`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subtended {
    /// Unit axis from `p` towards the centre.
    pub axis: DVec3,
    /// Distance from `p` to the centre.
    pub dist: f64,
    /// sin²θ_max.
    pub sin2: f64,
    /// 1 − cos θ_max, from sin²θ_max without cancellation (> 0).
    pub one_minus_cos: f64,
}

/// The cone the ball (`c`, `r`) subtends from `p`, when `p` lies farther than `outside`
/// from the centre (and the cone is not empty to rounding).
#[inline]
pub(crate) fn subtended(c: DVec3, r: f64, p: DVec3, outside: f64) -> Option<Subtended> {
    let to = c - p;
    let d2 = to.length_squared();
    if !(d2 > outside.powi(2)) {
        return None;
    }
    let d = d2.sqrt();
    let sin2 = (r * r / d2).min(1.0);
    let one_minus_cos = sin2 / (1.0 + (1.0 - sin2).sqrt());
    (one_minus_cos > 0.0).then_some(Subtended {
        axis: to / d,
        dist: d,
        sin2,
        one_minus_cos,
    })
}

/// An orthonormal frame `(t, b)` completing unit `n` (Duff et al. 2017).
pub(crate) fn frame(n: DVec3) -> (DVec3, DVec3) {
    let s = if n.z < 0.0 { -1.0 } else { 1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        DVec3::new(b, s + n.y * n.y * a, -n.y),
    )
}

impl AreaLight {
    /// The area light of an emissive instance (a sphere or a rectangle).
    pub fn new(inst: &Instance, radiance: Color) -> Self {
        let det = inst.xf.map_or(1.0, |x| x.matrix().determinant().abs());
        let ball = sphere_ball(inst);
        let mut light = AreaLight {
            shape: inst.shape.clone(),
            xf: inst.xf,
            radiance,
            det,
            ball,
            flat: None,
            bounds: inst.bounds(),
        };
        if !matches!(light.shape, Shape::Sphere) {
            let n_world = light.sample((0.5, 0.5)).1;
            light.flat = Some((
                crate::real::dvec3(n_world).normalize(),
                light.pdf_area(n_world),
            ));
        }
        light
    }

    /// The cone of directions the sphere subtends from `p`, when it is sampled by solid
    /// angle and `p` lies outside it: the unit axis from `p` towards the centre, the
    /// distance to the centre, and 1 − cos θ_max (from sin²θ_max without cancellation).
    #[inline]
    fn cone(&self, p: DVec3) -> Option<(DVec3, f64, f64)> {
        let (c, r) = self.ball?;
        // Outside, with Mitsuba's margin (a point on the light itself is inside).
        subtended(c, r, p, r * (1.0 - 1e-4)).map(|s| (s.axis, s.dist, s.one_minus_cos))
    }

    /// Samples a point of the light as seen from `p`: a sphere placed by a similarity,
    /// with `p` outside it, by the cone of directions it subtends (uniform in that solid
    /// angle; Mitsuba 3's `sphere::sample_direction`, after Akalin's "Sampling the visible
    /// sphere"); anything else uniformly by area ([`AreaLight::sample`]), with the density
    /// converted to solid angle. Uses one 2D sample either way.
    pub(crate) fn sample_from(&self, p: DVec3, u: (f64, f64)) -> LightSample {
        // The point on the light, its unit world normal, and the density: the cone's (per
        // solid angle) or the area's.
        let (q, unit_n, pdf) = match self.cone(p) {
            Some((axis, d, one_minus_cos_max)) => {
                let (c, r) = self.ball.expect("a cone comes from a ball");
                // cos θ uniform in [cos θ_max, 1]; sin²θ from 1 − cos θ without
                // cancellation.
                let omc = u.0 * one_minus_cos_max;
                let sin2 = (omc * (2.0 - omc)).max(0.0);
                let cos_t = 1.0 - omc;
                // The angle at the centre between the axis (towards p) and the point
                // where the sampled direction first meets the sphere.
                let cos_a = sin2 * d / r + cos_t * (1.0 - sin2 * d * d / (r * r)).max(0.0).sqrt();
                let cos_a = cos_a.clamp(-1.0, 1.0);
                let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                let (cos_phi, sin_phi) = cos_sin_turn(u.1);
                let (t, b) = frame(-axis);
                let n = (t * cos_phi + b * sin_phi) * sin_a - axis * cos_a;
                // The normal's direction (hits report m⁻ᵀ·n_obj, which for a similarity
                // of scale r is this over r; only its direction is used).
                (
                    c + n * r,
                    crate::real::dvec3(crate::real::vec3(n)).normalize(),
                    Density::Cone(1.0 / (2.0 * PI * one_minus_cos_max)),
                )
            }
            None => match self.flat {
                Some((unit_n, pdf_area)) => (
                    crate::real::dvec3(self.sample_point(u)),
                    unit_n,
                    Density::Area(pdf_area),
                ),
                None => {
                    let (q, n_world) = self.sample(u);
                    (
                        crate::real::dvec3(q),
                        crate::real::dvec3(n_world).normalize(),
                        Density::Area(self.pdf_area(n_world)),
                    )
                }
            },
        };
        let to = q - p;
        let d2 = to.length_squared();
        let dist = d2.sqrt();
        let wi = to / dist;
        // Nothing to sample on the back of the light, nor where the shading point lies on
        // the light itself (its own surface counts as outside, by Mitsuba's margin) and
        // draws the point it stands on (distance 0: the cosine is NaN).
        let cos_l = unit_n.dot(-wi);
        let pdf = match pdf {
            _ if !(cos_l > 0.0) => 0.0,
            Density::Cone(pdf) => pdf,
            Density::Area(pdf_area) => pdf_area as f64 * d2 / cos_l,
        };
        LightSample { wi, dist, pdf }
    }

    /// The solid-angle density with which [`AreaLight::sample_from`] at `p` would give
    /// the direction `wi` that meets the light at distance `dist`, where its world normal
    /// is `n_world` (unnormalized).
    pub(crate) fn pdf_from(&self, p: DVec3, wi: DVec3, dist: f64, n_world: Vec3) -> f64 {
        if let Some((_, _, one_minus_cos_max)) = self.cone(p) {
            return 1.0 / (2.0 * PI * one_minus_cos_max);
        }
        let cos = crate::real::dvec3(n_world).normalize().dot(-wi).abs();
        if cos <= 0.0 {
            return 0.0;
        }
        self.pdf_area(n_world) as f64 * dist * dist / cos
    }

    /// Surface area of the canonical shape.
    fn object_area(&self) -> Real {
        match self.shape {
            Shape::Sphere => (4.0 * PI) as Real,
            _ => 4.0,
        }
    }

    /// Density (per world area) of [`AreaLight::sample`] at a point whose unnormalized
    /// world normal is `m⁻ᵀ·n_obj` (`n_world`, as every hit reports it). Uniform in object
    /// space, so the world density is `1 / (A_obj · |det M| · |m⁻ᵀ n_obj|)`.
    #[inline]
    pub fn pdf_area(&self, n_world: Vec3) -> Real {
        let stretch = if self.xf.is_some() {
            n_world.length()
        } else {
            1.0
        };
        1.0 / (self.object_area() * self.det * stretch)
    }

    /// A point uniform (in object space) on the light: world point and unnormalized world
    /// normal.
    pub(crate) fn sample(&self, u: (f64, f64)) -> (Vec3, Vec3) {
        let (p, n) = self.canonical(u);
        match &self.xf {
            Some(x) => (x.point(p), x.normal(n)),
            None => (p, n),
        }
    }

    /// The canonical shape's point for `u` and its normal (object space).
    #[inline]
    fn canonical(&self, u: (f64, f64)) -> (Vec3, Vec3) {
        match self.shape {
            Shape::Sphere => {
                let z = 1.0 - 2.0 * u.0;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (cos_phi, sin_phi) = cos_sin_turn(u.1);
                let v = Vec3::new((r * cos_phi) as Real, z as Real, (r * sin_phi) as Real);
                (v, v)
            }
            _ => (Self::rectangle_point(u), Vec3::Y),
        }
    }

    /// [`AreaLight::sample`] with the sampled point's rounding-error bound (a light path
    /// leaves the light from it, and must not meet the light itself again): a few ulps
    /// of the canonical point, mapped by the transform with pbrt's rule.
    pub(crate) fn sample_with_error(&self, u: (f64, f64)) -> (Vec3, Vec3, Vec3) {
        let (p, n) = self.canonical(u);
        let err = p.abs() * (4.0 * Real::EPSILON);
        match &self.xf {
            Some(x) => {
                let (q, e) = x.point_with_error(p, err);
                (q, x.normal(n), e)
            }
            None => (p, n, err),
        }
    }

    /// The world point of [`AreaLight::sample`] on a rectangle, without its normal.
    #[inline]
    fn sample_point(&self, u: (f64, f64)) -> Vec3 {
        let p = Self::rectangle_point(u);
        match &self.xf {
            Some(x) => x.point(p),
            None => p,
        }
    }

    /// The canonical rectangle's point for `u`: [-1, 1]² in the plane y = 0.
    #[inline]
    fn rectangle_point(u: (f64, f64)) -> Vec3 {
        Vec3::new((2.0 * u.0 - 1.0) as Real, 0.0, (2.0 * u.1 - 1.0) as Real)
    }
}
