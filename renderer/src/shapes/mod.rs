//! Canonical primitives in normalized object space. Shapes never see a transform: an
//! [`Instance`](crate::aggregate::Instance) maps the ray in and the hit out.
//!
//! | shape | object space |
//! |---|---|
//! | sphere | unit sphere at the origin |
//! | plane | y = 0, outward normal +y |
//! | box | the cube [−1, 1]³ |
//! | cylinder | radius 1 about the y axis, y ∈ [−1, 1], open or capped |
//! | cone | apex (0, 1, 0), base radius 1 at y = −1, optional base cap |
//! | disk | radius 1 in y = 0, normal +y |
//! | rectangle | [−1, 1] × [−1, 1] in x and z, y = 0, normal +y |
//! | triangle | three vertices; normal (p1 − p0) × (p2 − p0) |
//! | mesh | triangles from Wavefront OBJ, per-mesh BVH, watertight test |
//!
//! Every hit returns t, the outward geometric normal (not normalized; the normal of the
//! face the ray hit, even from inside), a shading normal and uv.

mod cone;
mod cube;
mod cylinder;
mod flat;
pub mod mesh;
mod sphere;
pub mod triangle;

use crate::aabb::Aabb;
use crate::aggregate::{Aggregate, Hit};
use crate::ray::Ray;
use crate::real::{Real, Vec2, Vec3};
use std::sync::Arc;

pub use mesh::Mesh;
pub use triangle::Triangle;

/// A primitive or a shared sub-scene, in its own object space.
#[derive(Clone, Debug)]
pub enum Shape {
    /// Unit sphere.
    Sphere,
    /// The plane y = 0.
    Plane,
    /// The cube [−1, 1]³.
    Cube,
    /// Cylinder of radius 1, y ∈ [−1, 1].
    Cylinder {
        /// Whether the end disks are part of the surface.
        capped: bool,
    },
    /// Cone with apex (0, 1, 0) and base radius 1 at y = −1.
    Cone {
        /// Whether the base disk is part of the surface.
        capped: bool,
    },
    /// Unit disk in y = 0.
    Disk,
    /// [−1, 1]² in y = 0.
    Rectangle,
    /// A single triangle.
    Triangle(Box<Triangle>),
    /// A triangle mesh, shared by every instance that uses it.
    Mesh(Arc<Mesh>),
    /// A named definition (a sub-scene with its own BVH), shared by every instance.
    Group(Arc<Aggregate>),
}

/// A hit in a shape's object space, with the point's error bound and one normal.
#[inline]
pub(crate) fn local_hit(t: Real, p: Vec3, err: Vec3, n: Vec3, uv: Vec2) -> Hit {
    Hit::new(t, p, err, n, n, uv)
}

impl Shape {
    /// Bounds in object space (infinite for the plane).
    pub fn bounds(&self) -> Aabb {
        let unit = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        match self {
            Shape::Sphere | Shape::Cube | Shape::Cylinder { .. } | Shape::Cone { .. } => unit,
            Shape::Plane => Aabb {
                min: Vec3::splat(Real::NEG_INFINITY),
                max: Vec3::splat(Real::INFINITY),
            },
            Shape::Disk | Shape::Rectangle => Aabb {
                min: Vec3::new(-1.0, 0.0, -1.0),
                max: Vec3::new(1.0, 0.0, 1.0),
            },
            Shape::Triangle(t) => t.bounds(),
            Shape::Mesh(m) => m.bounds(),
            Shape::Group(g) => g.bounds(),
        }
    }

    /// The closest hit with `t_min < t < t_max`, in object space.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        match self {
            Shape::Sphere => sphere::intersect(ray, t_min, t_max),
            Shape::Plane => flat::plane(ray, t_min, t_max),
            Shape::Cube => cube::intersect(ray, t_min, t_max),
            Shape::Cylinder { capped } => cylinder::intersect(ray, *capped, t_min, t_max),
            Shape::Cone { capped } => cone::intersect(ray, *capped, t_min, t_max),
            Shape::Disk => flat::disk(ray, t_min, t_max),
            Shape::Rectangle => flat::rectangle(ray, t_min, t_max),
            Shape::Triangle(t) => t.intersect(ray, t_min, t_max),
            Shape::Mesh(m) => m.intersect(ray, t_min, t_max),
            Shape::Group(g) => g.intersect(ray, t_min, t_max),
        }
    }

    /// Whether anything is hit with `t_min < t < t_max` (shadow rays).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        match self {
            Shape::Mesh(m) => m.occluded(ray, t_min, t_max),
            Shape::Group(g) => g.occluded(ray, t_min, t_max),
            _ => self.intersect(ray, t_min, t_max).is_some(),
        }
    }

    /// Whether the shape is a closed convex solid (a spawned ray leaving it outward can
    /// never hit it again).
    pub fn is_convex_solid(&self) -> bool {
        matches!(
            self,
            Shape::Sphere
                | Shape::Cube
                | Shape::Cylinder { capped: true }
                | Shape::Cone { capped: true }
        )
    }
}

/// Roots of `a·t² + 2·b·t + c = 0`, given `disc = b² − a·c ≥ 0` and `a > 0`, in
/// ascending order, computed without cancellation (Haines et al., Ray Tracing Gems ch. 7).
#[inline]
pub(crate) fn stable_roots(a: Real, b: Real, c: Real, disc: Real) -> (Real, Real) {
    let s = disc.sqrt();
    let q = -(b + s.copysign(b));
    if q == 0.0 {
        // b = 0 and disc = 0: a double root at 0 (c = 0).
        return (0.0, 0.0);
    }
    let (r0, r1) = (q / a, c / q);
    if r0 <= r1 {
        (r0, r1)
    } else {
        (r1, r0)
    }
}

/// Angle about the y axis as a fraction of a turn, in [0, 1): `atan2(z, x) / 2π`.
#[inline]
pub(crate) fn azimuth(x: Real, z: Real) -> Real {
    let a = z.atan2(x) * (0.5 / (std::f64::consts::PI as Real));
    if a < 0.0 {
        a + 1.0
    } else {
        a
    }
}
