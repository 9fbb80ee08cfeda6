//! Lights: point, directional and environment lights, and area lights (emissive spheres and
//! rectangles). Scene data, read by both integrators; area lights also know how to sample
//! themselves.

use crate::aggregate::Instance;
use crate::aggregate::Shape;
use crate::material::Color;
use crate::real::{Real, Vec3};
use crate::transform::Transform;
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
}

impl AreaLight {
    /// The area light of an emissive instance (a sphere or a rectangle).
    pub fn new(inst: &Instance, radiance: Color) -> Self {
        let det = inst.xf.map_or(1.0, |x| x.matrix().determinant().abs());
        AreaLight {
            shape: inst.shape.clone(),
            xf: inst.xf,
            radiance,
            det,
        }
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
        let (p, n) = match self.shape {
            Shape::Sphere => {
                let z = 1.0 - 2.0 * u.0;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * PI * u.1;
                let v = Vec3::new((r * phi.cos()) as Real, z as Real, (r * phi.sin()) as Real);
                (v, v)
            }
            _ => (
                Vec3::new((2.0 * u.0 - 1.0) as Real, 0.0, (2.0 * u.1 - 1.0) as Real),
                Vec3::Y,
            ),
        };
        match &self.xf {
            Some(x) => (x.point(p), x.normal(n)),
            None => (p, n),
        }
    }
}
