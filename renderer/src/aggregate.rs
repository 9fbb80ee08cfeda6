//! Instances and aggregates: the two-level (or deeper) acceleration structure.
//!
//! An [`Instance`] is a shape with an optional affine transform. It maps the ray into object
//! space by the inverse, without renormalizing the direction (so `t` is the same in both
//! spaces), and maps the hit's normals back by `M⁻ᵀ`. An [`Aggregate`] holds instances under
//! a BVH; unbounded instances (planes) sit beside it and are tested for every ray. The scene
//! root is an aggregate; so is every named definition, shared through `Arc` by the
//! instances that use it.

use crate::aabb::Aabb;
use crate::bvh::{Bvh, Visit};
use crate::ray::Ray;
use crate::real::{Real, Vec2, Vec3};
use crate::shapes::Shape;
use crate::transform::Transform;

/// Marks a hit whose material or object id comes from the enclosing instance.
pub const INHERIT: u32 = u32::MAX;

/// A hit record in the space of whoever returned it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: Real,
    /// Hit point (re-projected onto the surface where the shape can).
    pub p: Vec3,
    /// Per-component bound on the rounding error of `p`.
    pub err: Vec3,
    /// Outward geometric normal (not normalized).
    pub n_geo: Vec3,
    /// Shading normal (not normalized).
    pub n_shade: Vec3,
    /// Surface parameterisation.
    pub uv: Vec2,
    /// Material index, or [`INHERIT`].
    pub material: u32,
    /// 1-based object id, or 0 while unassigned.
    pub object_id: u32,
}

impl Hit {
    /// A bare hit: material and object id unassigned.
    #[inline]
    pub fn new(t: Real, p: Vec3, err: Vec3, n_geo: Vec3, n_shade: Vec3, uv: Vec2) -> Self {
        Hit {
            t,
            p,
            err,
            n_geo,
            n_shade,
            uv,
            material: INHERIT,
            object_id: 0,
        }
    }
}

/// A shape placed by a transform.
#[derive(Clone, Debug)]
pub struct Instance {
    /// What is placed.
    pub shape: Shape,
    /// `outer_from_object`; `None` is the identity (no ray transform at all).
    pub xf: Option<Transform>,
    /// Material index, or [`INHERIT`].
    pub material: u32,
    /// Object id, or 0 to inherit.
    pub object_id: u32,
}

impl Instance {
    /// Bounds in the outer space.
    pub fn bounds(&self) -> Aabb {
        let b = self.shape.bounds();
        match &self.xf {
            Some(x) => x.bounds(&b),
            None => b,
        }
    }

    /// Closest hit in the outer space.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut h = match &self.xf {
            Some(x) => {
                let mut h = self.shape.intersect(&x.inv_ray(ray), t_min, t_max)?;
                (h.p, h.err) = x.point_with_error(h.p, h.err);
                h.n_geo = x.normal(h.n_geo);
                h.n_shade = x.normal(h.n_shade);
                h
            }
            None => self.shape.intersect(ray, t_min, t_max)?,
        };
        if h.material == INHERIT {
            h.material = self.material;
        }
        if h.object_id == 0 {
            h.object_id = self.object_id;
        }
        Some(h)
    }

    /// Whether anything is hit.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        match &self.xf {
            Some(x) => self.shape.occluded(&x.inv_ray(ray), t_min, t_max),
            None => self.shape.occluded(ray, t_min, t_max),
        }
    }
}

/// Instances under a BVH, plus the unbounded ones.
#[derive(Clone, Debug, Default)]
pub struct Aggregate {
    /// Every instance: first the bounded ones in BVH leaf order, then the unbounded ones.
    pub instances: Vec<Instance>,
    /// Number of bounded instances (the BVH's primitives are `instances[..bounded]`).
    bounded: usize,
    bvh: Bvh,
    /// For each instance in the order given to [`Aggregate::new`], its index in `instances`.
    scene_order: Vec<u32>,
}

impl Aggregate {
    /// Builds the BVH over the bounded instances and stores them in leaf order.
    pub fn new(instances: Vec<Instance>) -> Self {
        let (bounded, unbounded): (Vec<(usize, Instance)>, Vec<(usize, Instance)>) = instances
            .into_iter()
            .enumerate()
            .partition(|(_, inst)| inst.bounds().is_finite());
        let boxes: Vec<Aabb> = bounded.iter().map(|(_, i)| i.bounds()).collect();
        let mut bvh = Bvh::build(&boxes);
        let mut tagged = bvh.reorder(bounded);
        let bounded = tagged.len();
        tagged.extend(unbounded);
        let mut scene_order = vec![0u32; tagged.len()];
        for (k, (original, _)) in tagged.iter().enumerate() {
            scene_order[*original] = k as u32;
        }
        Aggregate {
            instances: tagged.into_iter().map(|(_, i)| i).collect(),
            bounded,
            bvh,
            scene_order,
        }
    }

    /// The instances in the order they were given (scene order), independent of how the
    /// BVH was built: exporters use it, so that the f32 and f64 builds write the same text.
    pub fn in_scene_order(&self) -> impl Iterator<Item = &Instance> {
        self.scene_order
            .iter()
            .map(|&k| &self.instances[k as usize])
    }

    fn unbounded(&self) -> &[Instance] {
        &self.instances[self.bounded..]
    }

    /// Bounds (infinite when an unbounded instance is present).
    pub fn bounds(&self) -> Aabb {
        if !self.unbounded().is_empty() {
            return Aabb {
                min: Vec3::splat(Real::NEG_INFINITY),
                max: Vec3::splat(Real::INFINITY),
            };
        }
        self.bvh.bounds()
    }

    /// Closest hit with `t_min < t < t_max`.
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        for inst in self.unbounded() {
            if let Some(h) = inst.intersect(ray, t_min, t_max) {
                t_max = h.t;
                best = Some(h);
            }
        }
        if self.bounded > 0 {
            self.bvh.traverse(ray, t_min, t_max, false, |k, tmax| {
                let inst = &self.instances[k as usize];
                match inst.intersect(ray, t_min, tmax) {
                    Some(h) => {
                        best = Some(h);
                        Visit::Hit(h.t)
                    }
                    None => Visit::Miss,
                }
            });
        }
        best
    }

    /// Whether anything is hit with `t_min < t < t_max`.
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        if self
            .unbounded()
            .iter()
            .any(|inst| inst.occluded(ray, t_min, t_max))
        {
            return true;
        }
        self.bounded > 0
            && self.bvh.traverse(ray, t_min, t_max, true, |k, tmax| {
                if self.instances[k as usize].occluded(ray, t_min, tmax) {
                    Visit::Hit(tmax)
                } else {
                    Visit::Miss
                }
            })
    }

    /// Brute force closest hit over every instance (the reference for BVH tests).
    pub fn intersect_brute_force(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        for inst in &self.instances {
            if let Some(h) = inst.intersect(ray, t_min, t_max) {
                t_max = h.t;
                best = Some(h);
            }
        }
        best
    }
}
