//! Specular guides: at a diffuse path vertex, some of the directions that continue the
//! path are aimed at the mirror and glass objects of the scene, not only cosine-weighted.
//!
//! A diffuse surface lit through a mirror or a lens (a caustic) gets that light only from
//! a path that leaves it in a direction that meets the specular object and then, by
//! reflection or refraction, the light. Light sampling cannot build such a path (the
//! specular bounce is a delta), so only the cosine-weighted continuation finds it, as
//! often as that direction meets the object: the caustic is the noisiest part of such an
//! image. With `render.guides` on, a vertex also samples the cone of directions that a
//! sphere bounding each specular object subtends (uniform in its solid angle, as a
//! sphere light is sampled), with probability [`SHARE`] shared among the objects whose
//! cones face the surface, and the continuation's density is the mixture's:
//!
//! `p(ω) = (1 − SHARE)·cos θ/π + SHARE/G · Σ_g [ω in cone g] / (2π(1 − cos θ_g))`
//!
//! That is one-sample multiple importance sampling with the balance heuristic: the
//! estimate is unbiased for any share, and the cosine part alone still covers the whole
//! hemisphere. The emitter a guided direction meets is weighted against light sampling
//! with this density, and light sampling with it in turn, so the two strategies' weights
//! still sum to one. The uniform number that picks the cosine part or a cone is also the
//! first coordinate of the direction (rescaled), so a vertex draws the same sampler
//! dimensions as without guides.
//!
//! The guides are bounding spheres: a sphere placed by a similarity is its own, any other
//! bounded object with a conductor or dielectric material has the sphere around its
//! world bounding box. A scene with more than [`MAX_GUIDES`] such objects gets none (the
//! density sums over all of them at every vertex).

use crate::aggregate::Shape;
use crate::light::subtended;
use crate::real::dvec3;
use crate::scene::{MaterialModel, Scene};
use glam::DVec3;
use std::f64::consts::PI;

/// Most specular objects that are guided towards.
pub const MAX_GUIDES: usize = 4;

/// The share of the continuation directions aimed at the guides (when any faces the
/// surface).
pub const SHARE: f64 = 0.5;

/// A sphere bounding a specular object, in render space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    /// Centre.
    pub centre: DVec3,
    /// Radius.
    pub radius: f64,
}

/// The cone of directions a guide subtends from a vertex.
#[derive(Clone, Copy, Debug, Default)]
struct Cone {
    /// Unit axis towards the ball's centre.
    axis: DVec3,
    /// 1 − cos θ_max.
    one_minus_cos: f64,
    /// Its density, 1 / (2π(1 − cos θ_max)).
    pdf: f64,
}

/// What a sampled continuation is to use: the cosine lobe with its first coordinate
/// rescaled, or a cone's direction.
pub enum Pick {
    /// Cosine-weighted, with this first coordinate.
    Cosine(f64),
    /// Into cone `k`, this direction.
    Cone(usize, DVec3),
}

/// The guides' cones at one vertex.
#[derive(Clone, Copy, Debug, Default)]
pub struct AtVertex {
    cones: [Cone; MAX_GUIDES],
    n: usize,
}

impl AtVertex {
    /// The cones of `balls` seen from `p` on the side of unit normal `n`: those with `p`
    /// outside the ball and some direction above the surface.
    pub fn new(balls: &[Ball], p: DVec3, n: DVec3) -> Self {
        let mut v = AtVertex::default();
        for b in balls.iter().take(MAX_GUIDES) {
            let Some(cone) = subtended(b.centre, b.radius, p, b.radius) else {
                continue;
            };
            let (axis, one_minus_cos) = (cone.axis, cone.one_minus_cos);
            // Wholly below the horizon: cos(angle to n) < −sin θ_max.
            if axis.dot(n) < -cone.sin2.sqrt() {
                continue;
            }
            v.cones[v.n] = Cone {
                axis,
                one_minus_cos,
                pdf: 1.0 / (2.0 * PI * one_minus_cos),
            };
            v.n += 1;
        }
        v
    }

    /// Whether any guide faces the vertex.
    #[inline]
    pub fn active(&self) -> bool {
        self.n > 0
    }

    /// Picks the cosine lobe or a cone from the 2D sample `u` (the cone's direction is
    /// drawn from what is left of `u.0` and from `u.1`).
    pub fn pick(&self, u: (f64, f64)) -> Pick {
        if u.0 >= SHARE || self.n == 0 {
            return Pick::Cosine(
                ((u.0 - SHARE) / (1.0 - SHARE)).clamp(0.0, 1.0 - f64::EPSILON / 2.0),
            );
        }
        let v = u.0 / SHARE * self.n as f64;
        let k = (v as usize).min(self.n - 1);
        let w = (v - k as f64).clamp(0.0, 1.0);
        let c = &self.cones[k];
        // cos θ uniform in [cos θ_max, 1].
        let omc = w * c.one_minus_cos;
        let cos_t = 1.0 - omc;
        let sin_t = (omc * (2.0 - omc)).max(0.0).sqrt();
        let (cos_phi, sin_phi) = crate::sampler::cos_sin_turn(u.1);
        let (t, b) = crate::light::frame(c.axis);
        Pick::Cone(
            k,
            t * (sin_t * cos_phi) + b * (sin_t * sin_phi) + c.axis * cos_t,
        )
    }

    /// The mixture's density of direction `dir` (unit), given the cosine lobe's
    /// `cos_pdf` for it; `own` is the cone it was drawn from, if any (inside it whatever
    /// the rounding of the test says).
    pub fn pdf(&self, cos_pdf: f64, dir: DVec3, own: Option<usize>) -> f64 {
        let mut cones = 0.0;
        for (k, c) in self.cones[..self.n].iter().enumerate() {
            if own == Some(k) || dir.dot(c.axis) >= 1.0 - c.one_minus_cos {
                cones += c.pdf;
            }
        }
        (1.0 - SHARE) * cos_pdf + SHARE / self.n as f64 * cones
    }
}

/// The spheres around the top-level specular objects, and whether every specular surface
/// of the scene lies in one and reflects about its geometric normal, as light paths need
/// (light_paths.rs): not when a specular object is unbounded (a mirror plane), when a
/// definition placed by `type = "instance"` may hold one, nor when a specular triangle or
/// mesh may have interpolated normals (a light path would need the shading normal's
/// correction at it).
pub(super) fn specular_balls(scene: &Scene) -> (Vec<Ball>, bool) {
    let mut balls = Vec::new();
    let mut complete = true;
    for inst in scene.root.in_scene_order() {
        if matches!(inst.shape, Shape::Group(_)) {
            complete = false;
        }
        let m = scene.material(inst.material);
        if !matches!(
            m.model,
            MaterialModel::Conductor | MaterialModel::Dielectric
        ) {
            continue;
        }
        if matches!(inst.shape, Shape::Mesh(_) | Shape::Triangle(_)) {
            complete = false;
        }
        let ball = crate::light::sphere_ball(inst)
            .map(|(centre, radius)| Ball { centre, radius })
            .or_else(|| {
                let b = inst.bounds();
                let (lo, hi) = (dvec3(b.min), dvec3(b.max));
                (lo.is_finite() && hi.is_finite()).then(|| Ball {
                    centre: (lo + hi) * 0.5,
                    radius: (hi - lo).length() * 0.5,
                })
            });
        match ball {
            Some(b) if b.radius > 0.0 && b.radius.is_finite() => balls.push(b),
            // An unbounded specular object (a mirror plane): no cone to aim at.
            _ => complete = false,
        }
    }
    (balls, complete)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex() -> AtVertex {
        let balls = [
            Ball {
                centre: DVec3::new(0.0, 2.0, 0.0),
                radius: 0.5,
            },
            Ball {
                centre: DVec3::new(3.0, 1.0, 0.0),
                radius: 1.0,
            },
            // Below the horizon: not a guide here.
            Ball {
                centre: DVec3::new(0.0, -3.0, 0.0),
                radius: 1.0,
            },
            // Around the vertex: not a guide here.
            Ball {
                centre: DVec3::new(0.2, 0.0, 0.0),
                radius: 1.0,
            },
        ];
        AtVertex::new(&balls, DVec3::ZERO, DVec3::Y)
    }

    #[test]
    fn cones_face_the_surface_from_outside() {
        let v = vertex();
        assert_eq!(v.n, 2);
        assert!(!AtVertex::new(&[], DVec3::ZERO, DVec3::Y).active());
    }

    /// The mixture's density integrates to one over the sphere, and a histogram of
    /// picked directions follows it (cone directions by their own density, cosine ones
    /// by cos θ/π).
    #[test]
    fn the_density_is_the_mixture_that_is_sampled() {
        let v = vertex();
        let n = 200_000u64;
        // Monte Carlo integral of pdf over the sphere (uniform directions).
        let mut integral = 0.0;
        for i in 0..n {
            let u1 = crate::sampler::uniform(1, i, 0);
            let u2 = crate::sampler::uniform(1, i, 1);
            let z = 1.0 - 2.0 * u1;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (c, s) = crate::sampler::cos_sin_turn(u2);
            let d = DVec3::new(r * c, z, r * s);
            let cos_pdf = d.y.max(0.0) / PI;
            integral += v.pdf(cos_pdf, d, None) * 4.0 * PI;
        }
        let integral = integral / n as f64;
        assert!((integral - 1.0).abs() < 0.01, "∫ p = {integral}");
        // P(a picked direction lies in cone 0) against ∫ p over cone 0.
        let mut hits = 0u64;
        for i in 0..n {
            let u = (
                crate::sampler::uniform(2, i, 0),
                crate::sampler::uniform(2, i, 1),
            );
            let d = match v.pick(u) {
                Pick::Cone(_, d) => d,
                Pick::Cosine(w) => {
                    let r = w.sqrt();
                    let (c, s) = crate::sampler::cos_sin_turn(u.1);
                    DVec3::new(r * c, (1.0 - w).sqrt(), r * s)
                }
            };
            if d.dot(v.cones[0].axis) >= 1.0 - v.cones[0].one_minus_cos {
                hits += 1;
            }
        }
        let frac = hits as f64 / n as f64;
        // ∫_cone0 p(ω) dω by uniform sampling inside cone 0.
        let c0 = v.cones[0];
        let mut inside = 0.0;
        for i in 0..n {
            let w = crate::sampler::uniform(3, i, 0) * c0.one_minus_cos;
            let cos_t = 1.0 - w;
            let sin_t = (w * (2.0 - w)).sqrt();
            let (c, s) = crate::sampler::cos_sin_turn(crate::sampler::uniform(3, i, 1));
            let (t, b) = crate::light::frame(c0.axis);
            let d = t * (sin_t * c) + b * (sin_t * s) + c0.axis * cos_t;
            inside += v.pdf(d.y.max(0.0) / PI, d, None) / c0.pdf;
        }
        let want = inside / n as f64;
        assert!(
            (frac - want).abs() < 0.005,
            "picked {frac}, density says {want}"
        );
    }
}
