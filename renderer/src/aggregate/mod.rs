//! Instances and aggregates: the two-level (or deeper) acceleration structure.
//!
//! [`Shape`] is what an instance places: a canonical primitive (`crate::shapes`), a mesh,
//! or a whole named definition (an aggregate of its own). It lives here, with the
//! aggregate, because a definition is both: so the shapes depend only on the hit record,
//! and this module on the shapes, one way.
//!
//! An [`Instance`] is a shape with an optional affine transform. It maps the ray into object
//! space by the inverse, without renormalizing the direction (so `t` is the same in both
//! spaces), and maps the hit's normals back by `M⁻ᵀ`. An [`Aggregate`] holds instances under
//! a BVH; unbounded instances (planes) sit beside it and are tested for every ray. The scene
//! root is an aggregate; so is every named definition, shared through `Arc` by the
//! instances that use it.

use crate::aabb::Aabb;
use crate::bvh::{mask_ray_by_ray, Bvh, Visit, BATCH, INTERLEAVE_ABOVE};
pub use crate::hit::{Hit, RayHit, INHERIT};
use crate::ray::Ray;
use crate::real::{Mat3, Real, Vec3};
use crate::shapes::anchored::{self, Anchored};
use crate::shapes::{self, Mesh, Triangle};
use crate::transform::{map_normal, map_point_with_error, Transform};
use std::sync::Arc;

mod lanes;

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
    /// A sphere, cube or cylinder seen from an anchor on its surface, in mixed precision:
    /// for an instance whose scale is huge next to the distances the camera sees
    /// (`shapes::anchored`; the scene builder decides, renderer/docs/precision.md).
    Anchored(Box<Anchored>),
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
            Shape::Anchored(a) => {
                let (min, max) = a.bounds();
                Aabb { min, max }
            }
        }
    }

    /// The closest hit with `t_min < t < t_max`, in object space.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        match self {
            Shape::Sphere => shapes::sphere::intersect(ray, t_min, t_max),
            Shape::Plane => shapes::flat::plane(ray, t_min, t_max),
            Shape::Cube => shapes::cube::intersect(ray, t_min, t_max),
            Shape::Cylinder { capped } => shapes::cylinder::intersect(ray, *capped, t_min, t_max),
            Shape::Cone { capped } => shapes::cone::intersect(ray, *capped, t_min, t_max),
            Shape::Disk => shapes::flat::disk(ray, t_min, t_max),
            Shape::Rectangle => shapes::flat::rectangle(ray, t_min, t_max),
            Shape::Triangle(t) => t.intersect(ray, t_min, t_max),
            Shape::Mesh(m) => m.intersect(ray, t_min, t_max),
            Shape::Group(g) => g.intersect(ray, t_min, t_max),
            Shape::Anchored(a) => a.intersect(ray, t_min, t_max),
        }
    }

    /// [`Shape::intersect`] as the search for a closest hit needs it: a record that
    /// [`Shape::complete`] finishes once the search has a winner (a sphere leaves out its
    /// uv, which costs an `acos` and an `atan2`, for every candidate that loses).
    /// [`Shape::candidate_into`] says which test each shape's candidate comes from.
    #[inline(always)]
    fn candidate(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut h = Hit::default();
        self.candidate_into(ray, t_min, t_max, &mut h).then_some(h)
    }

    /// [`Shape::candidate`] written into `out` (left alone when there is no hit): the
    /// search's own record ([`Best`]), so that the winner of a mesh or a definition, found
    /// out of line, is not copied into it again. The one place that says which test a
    /// shape's candidate is: [`Shape::intersect`]'s, but for the spheres' bare tests.
    /// (Each shape's test is written into `out` in its own arm: a record chosen by the
    /// match and then written was built in memory first and copied, 6 % more
    /// instructions on a Whitted frame.)
    #[inline(always)]
    fn candidate_into(&self, ray: &Ray, t_min: Real, t_max: Real, out: &mut Hit) -> bool {
        match self {
            Shape::Sphere => put(shapes::sphere::intersect_bare(ray, t_min, t_max), out),
            Shape::Plane => put(shapes::flat::plane(ray, t_min, t_max), out),
            Shape::Cube => put(shapes::cube::intersect(ray, t_min, t_max), out),
            Shape::Cylinder { capped } => {
                put(shapes::cylinder::intersect(ray, *capped, t_min, t_max), out)
            }
            Shape::Cone { capped } => put(shapes::cone::intersect(ray, *capped, t_min, t_max), out),
            Shape::Disk => put(shapes::flat::disk(ray, t_min, t_max), out),
            Shape::Rectangle => put(shapes::flat::rectangle(ray, t_min, t_max), out),
            Shape::Triangle(t) => put(t.intersect(ray, t_min, t_max), out),
            Shape::Mesh(m) => m.intersect_into(ray, t_min, t_max, out),
            Shape::Group(g) => g.intersect_into::<true>(ray, t_min, t_max, out),
            Shape::Anchored(a) => put(a.intersect_bare(ray, t_min, t_max), out),
        }
    }

    /// [`Shape::candidate`] for [`Aggregate::nearest`]: meshes and definitions search
    /// without building a record; every other shape's candidate is its record already.
    #[inline(always)]
    fn nearest(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<RayHit> {
        match self {
            Shape::Mesh(m) => m.nearest(ray, t_min, t_max),
            Shape::Group(g) => g.nearest(ray, t_min, t_max),
            _ => self.candidate(ray, t_min, t_max).map(|h| RayHit::of(&h)),
        }
    }

    /// [`Shape::candidate`] for up to [`BATCH`] rays, each with its own `t_max`: meshes
    /// and definitions walk their trees with the rays together (their candidates are
    /// whole records); other shapes take the rays one by one. Each result is exactly
    /// `candidate`'s.
    fn candidate_batch(&self, rays: &[Ray], t_min: Real, t_max: &[Real], out: &mut [Option<Hit>]) {
        match self {
            Shape::Mesh(m) => m.intersect_batch(rays, t_min, t_max, out),
            Shape::Group(g) => g.intersect_batch::<true>(rays, t_min, t_max, out),
            _ => {
                for ((r, &tm), o) in rays.iter().zip(t_max).zip(out.iter_mut()) {
                    *o = self.candidate(r, t_min, tm);
                }
            }
        }
    }

    /// Completes a [`Shape::candidate`] record in object space: then it has the bits
    /// [`Shape::intersect`] gives.
    /// Without `UV` the uv stays as the candidate left it (for the renderer's own
    /// integrators, which never read it; see [`Aggregate::intersect_for_shading`]).
    #[inline]
    fn complete<const UV: bool>(&self, h: &mut Hit) {
        match (UV, self) {
            (true, Shape::Sphere) => h.uv = shapes::sphere::uv(h.p),
            (true, Shape::Anchored(a)) => h.uv = a.uv(h),
            _ => {}
        }
    }

    /// Whether anything is hit with `t_min < t < t_max` (shadow rays).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        match self {
            Shape::Sphere => shapes::sphere::hits(ray, t_min, t_max),
            Shape::Plane => shapes::flat::plane_hits(ray, t_min, t_max),
            Shape::Rectangle => shapes::flat::rectangle_hits(ray, t_min, t_max),
            Shape::Disk => shapes::flat::disk_hits(ray, t_min, t_max),
            Shape::Cube => shapes::cube::hits(ray, t_min, t_max),
            Shape::Cylinder { capped } => shapes::cylinder::hits(ray, *capped, t_min, t_max),
            Shape::Mesh(m) => m.occluded(ray, t_min, t_max),
            Shape::Group(g) => g.occluded(ray, t_min, t_max),
            Shape::Anchored(a) => a.intersect_bare(ray, t_min, t_max).is_some(),
            _ => self.intersect(ray, t_min, t_max).is_some(),
        }
    }

    /// [`Shape::occluded`] for up to [`BATCH`] rays, each with its own `t_max`: bit `r` of
    /// the result for `rays[r]`. Meshes and definitions walk their trees with the rays
    /// together where they interleave; other shapes take the rays one by one.
    fn occluded_batch(&self, rays: &[Ray], t_min: Real, t_max: &[Real]) -> u64 {
        match self {
            Shape::Mesh(m) => m.occluded_batch(rays, t_min, t_max),
            Shape::Group(g) => g.occluded_batch(rays, t_min, t_max),
            _ => mask_ray_by_ray(rays, t_max, |ray, t| self.occluded(ray, t_min, t)),
        }
    }

    /// How many surfaces the shape counts as for [`Hit::surface`]: 1 for a primitive or a
    /// mesh (one object, as in POV-Ray), and every surface below for a definition.
    pub fn surfaces(&self) -> u64 {
        match self {
            Shape::Group(g) => g.surfaces,
            _ => 1,
        }
    }

    /// Whether the shape is a closed convex solid (a spawned ray leaving it outward can
    /// never hit it again).
    pub fn is_convex_solid(&self) -> bool {
        match self {
            Shape::Anchored(a) => matches!(
                a.kind,
                anchored::Kind::Sphere
                    | anchored::Kind::Cube
                    | anchored::Kind::Cylinder { capped: true }
            ),
            _ => matches!(
                self,
                Shape::Sphere
                    | Shape::Cube
                    | Shape::Cylinder { capped: true }
                    | Shape::Cone { capped: true }
            ),
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
    /// The instance as the scene placed it: an anchored shape (mixed precision) as its
    /// canonical shape, its transform composed with the anchor's shift back. For the
    /// exporters, which write the scene's own shapes; every other instance as it is.
    pub fn unanchored(&self) -> std::borrow::Cow<'_, Instance> {
        let Shape::Anchored(a) = &self.shape else {
            return std::borrow::Cow::Borrowed(self);
        };
        let shape = match a.kind {
            anchored::Kind::Sphere => Shape::Sphere,
            anchored::Kind::Cube => Shape::Cube,
            anchored::Kind::Cylinder { capped } => Shape::Cylinder { capped },
        };
        let xf = self.xf.map(|x| x.shifted(-a.a));
        std::borrow::Cow::Owned(Instance {
            shape,
            xf,
            material: self.material,
            object_id: self.object_id,
        })
    }

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
        let mut h = Hit::default();
        if !self.local_hit_into(ray, t_min, t_max, &mut h) {
            return None;
        }
        self.finish::<true>(&mut h);
        Some(h)
    }

    /// Closest hit in object space (`t` is the same in both spaces), as a candidate that
    /// [`Instance::finish`] completes ([`Shape::candidate_into`]), written into `out` (left
    /// alone when there is none).
    #[inline]
    fn local_hit_into(&self, ray: &Ray, t_min: Real, t_max: Real, out: &mut Hit) -> bool {
        match &self.xf {
            Some(x) => self
                .shape
                .candidate_into(&x.inv_ray(ray), t_min, t_max, out),
            None => self.shape.candidate_into(ray, t_min, t_max, out),
        }
    }

    /// [`Instance::local_hit_into`] for [`Aggregate::nearest`].
    #[inline]
    fn nearest_local(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<RayHit> {
        match &self.xf {
            Some(x) => self.shape.nearest(&x.inv_ray(ray), t_min, t_max),
            None => self.shape.nearest(ray, t_min, t_max),
        }
    }

    /// [`Instance::local_hit_into`] for up to [`BATCH`] rays, each with its own `t_max`: the
    /// shape walks them together where it has a tree of its own.
    fn local_hit_batch(&self, rays: &[Ray], t_min: Real, t_max: &[Real], out: &mut [Option<Hit>]) {
        match &self.xf {
            Some(x) => {
                self.shape
                    .candidate_batch(&object_rays(x, rays)[..rays.len()], t_min, t_max, out)
            }
            None => self.shape.candidate_batch(rays, t_min, t_max, out),
        }
    }

    /// Maps an object-space hit of [`Instance::local_hit_into`] to the outer space and fills in
    /// the material and object id it inherits.
    #[inline]
    fn finish<const UV: bool>(&self, h: &mut Hit) {
        self.shape.complete::<UV>(h);
        if let Some(x) = &self.xf {
            (h.p, h.err) = x.point_with_error(h.p, h.err);
            h.map_normals(|n| x.normal(n));
        }
        h.inherit(self.material, self.object_id);
    }

    /// [`Instance::finish`] for a [`RayHit`]: its normal mapped as the record's.
    #[inline]
    fn finish_nearest(&self, h: &mut RayHit) {
        if let Some(x) = &self.xf {
            h.n_geo = x.normal(h.n_geo);
        }
    }

    /// Whether anything is hit.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        match &self.xf {
            Some(x) => self.shape.occluded(&x.inv_ray(ray), t_min, t_max),
            None => self.shape.occluded(ray, t_min, t_max),
        }
    }

    /// [`Instance::occluded`] for up to [`BATCH`] rays ([`Shape::occluded_batch`]).
    fn occluded_batch(&self, rays: &[Ray], t_min: Real, t_max: &[Real]) -> u64 {
        match &self.xf {
            Some(x) => self
                .shape
                .occluded_batch(&object_rays(x, rays)[..rays.len()], t_min, t_max),
            None => self.shape.occluded_batch(rays, t_min, t_max),
        }
    }
}

/// The closest hit a search has found so far: the instance it came through (bounded, or
/// unbounded after the bounded ones; [`Best::NONE`] while there is none) and its record,
/// in that instance's object space. The instances' tests write the record in place
/// ([`Aggregate::local_hit_into`]): a record they returned was copied into the search's
/// with wide loads of fields just written one by one, which the processor cannot forward
/// from its store buffer (a stall). The batch search keeps one a ray; the one-ray search
/// ([`Aggregate::intersect_into`]) keeps the index alone, its record being the caller's.
#[derive(Clone, Copy)]
struct Best {
    k: usize,
    h: Hit,
}

impl Best {
    /// No hit yet.
    const NONE: usize = usize::MAX;

    #[inline(always)]
    fn none() -> Self {
        Best {
            k: Best::NONE,
            h: Hit::default(),
        }
    }
}

/// Writes `h` into `out` when there is one.
#[inline(always)]
fn put(h: Option<Hit>, out: &mut Hit) -> bool {
    match h {
        Some(h) => {
            *out = h;
            true
        }
        None => false,
    }
}

/// Up to [`BATCH`] rays taken into an instance's object space (the first `rays.len()`
/// of the result).
#[inline(always)]
fn object_rays(x: &Transform, rays: &[Ray]) -> [Ray; BATCH] {
    let mut local = [Ray::new(Vec3::ZERO, Vec3::ONE); BATCH];
    for (l, r) in local.iter_mut().zip(rays) {
        *l = x.inv_ray(r);
    }
    local
}

/// What traversal reads for one bounded instance. Scenes of many spheres place the unit
/// sphere by a uniform scale and a translation; for those the lead holds everything the
/// search and the final hit need (the translation `c`, the scale `r` and its inverse
/// `s`, the material and the object id) in 32 bytes, so neither reads the instance (128
/// bytes, most of it the transform and its cached inverse, at a scattered address: at a
/// million spheres that one read cost as much as the whole traversal). `s == 0` marks
/// every other instance. The lead's maps use the same operations as [`Transform`]'s on
/// the same values, so both paths give the same bits.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug)]
struct Lead {
    c: Vec3,
    s: Real,
    r: Real,
    material: u32,
    object_id: u32,
}

/// Whether `m` has exactly the bits of `x·I`.
fn is_scaled_identity(m: &Mat3, x: Real) -> bool {
    let d = Mat3::from_diagonal(Vec3::splat(x)).to_cols_array();
    m.to_cols_array()
        .iter()
        .zip(d)
        .all(|(a, b)| a.to_bits() == b.to_bits())
}

impl Lead {
    const GENERAL: Lead = Lead {
        c: Vec3::ZERO,
        s: 0.0,
        r: 0.0,
        material: 0,
        object_id: 0,
    };

    fn of(inst: &Instance) -> Lead {
        let Some(x) = &inst.xf else {
            return Lead::GENERAL;
        };
        let (r, s) = (x.matrix().x_axis.x, x.inverse_matrix().x_axis.x);
        if matches!(inst.shape, Shape::Sphere)
            && s != 0.0
            && is_scaled_identity(&x.matrix(), r)
            && is_scaled_identity(&x.inverse_matrix(), s)
        {
            Lead {
                c: x.translation(),
                s,
                r,
                material: inst.material,
                object_id: inst.object_id,
            }
        } else {
            Lead::GENERAL
        }
    }

    /// The ray in the sphere's object space: `s·I·(o − c)` and `s·I·d`.
    #[inline]
    fn object_ray(&self, ray: &Ray) -> Ray {
        let m = Mat3::from_diagonal(Vec3::splat(self.s));
        // (Glam's `Mat3` product, not `transform::mul`: for this diagonal, component by
        // component is the cheaper, 4 % fewer instructions for a million spheres' rays.)
        Ray::new(m * (ray.o - self.c), m * ray.d)
    }

    /// [`Instance::finish`] for the instance this lead stands for.
    #[inline]
    fn finish<const UV: bool>(&self, h: &mut Hit) {
        Shape::Sphere.complete::<UV>(h);
        let m = Mat3::from_diagonal(Vec3::splat(self.r));
        let inv = Mat3::from_diagonal(Vec3::splat(self.s));
        (h.p, h.err) = map_point_with_error(&m, self.c, h.p, h.err);
        h.map_normals(|n| map_normal(&inv, n));
        h.inherit(self.material, self.object_id);
    }

    /// [`Lead::finish`] for a [`RayHit`]: its normal mapped as the record's.
    #[inline]
    fn finish_nearest(&self, h: &mut RayHit) {
        h.n_geo = map_normal(&Mat3::from_diagonal(Vec3::splat(self.s)), h.n_geo);
    }
}

/// Cost of one instance-level node visit in units of one primitive test, for the SAH.
const TRAVERSAL_COST: Real = 1.0;

/// Instances under a BVH, plus the unbounded ones.
#[derive(Clone, Debug, Default)]
pub struct Aggregate {
    /// Every instance: first the bounded ones in BVH leaf order, then the unbounded ones.
    pub instances: Vec<Instance>,
    /// One lead per bounded instance, in the same order.
    leads: Vec<Lead>,
    bvh: Bvh<8>,
    /// For each instance in the order given to [`Aggregate::new`], its index in `instances`.
    scene_order: Vec<u32>,
    /// [`Hit::surface`] offset of each instance (the surfaces of the instances before it),
    /// or empty when every instance is one surface and the offset is its index.
    surface_base: Vec<u64>,
    /// Surfaces below this aggregate ([`Shape::surfaces`] summed), or `u64::MAX` when
    /// that overflows (the scene builder refuses such a scene).
    surfaces: u64,
    /// The instances as the closest-hit search of many rays tests them in lanes, when
    /// there are few and every one is a shape lanes can test (lanes.rs).
    lanes: Option<Vec<lanes::Item>>,
}

impl Aggregate {
    /// Builds the BVH over the bounded instances and stores them in leaf order.
    pub fn new(instances: Vec<Instance>) -> Self {
        let (bounded, unbounded): (Vec<(usize, Instance)>, Vec<(usize, Instance)>) = instances
            .into_iter()
            .enumerate()
            .partition(|(_, inst)| inst.bounds().is_finite());
        let boxes: Vec<Aabb> = bounded.iter().map(|(_, i)| i.bounds()).collect();
        let (bvh, mut tagged) = Bvh::<8>::build_spread(bounded, &boxes, TRAVERSAL_COST);
        let mut leads = crate::pages::huge_with_capacity(tagged.len());
        leads.extend(tagged.iter().map(|(_, i)| Lead::of(i)));
        tagged.extend(unbounded);
        let mut scene_order = vec![0u32; tagged.len()];
        for (k, (original, _)) in tagged.iter().enumerate() {
            scene_order[*original] = k as u32;
        }
        let instances: Vec<Instance> = tagged.into_iter().map(|(_, i)| i).collect();
        let (surface_base, surfaces) = surface_offsets(&instances);
        let mut agg = Aggregate {
            instances,
            leads,
            bvh,
            scene_order,
            surface_base,
            surfaces,
            lanes: None,
        };
        agg.lanes = agg.lane_items();
        agg
    }

    /// The instances as the lanes test them (lanes.rs), when there are at most
    /// [`lanes::MAX_INSTANCES`] and each is a sphere, cube, cylinder, rectangle, disk or
    /// plane: its shape, the map of its lead (a sphere's uniform scale and inverse about
    /// its centre) or of its transform, and what its hits carry.
    fn lane_items(&self) -> Option<Vec<lanes::Item>> {
        if self.instances.is_empty() || self.instances.len() > lanes::MAX_INSTANCES {
            return None;
        }
        let kinds = self.instances.iter().map(|inst| match inst.shape {
            Shape::Sphere => Some(lanes::Kind::Sphere),
            Shape::Cube => Some(lanes::Kind::Cube),
            Shape::Cylinder { capped } => Some(lanes::Kind::Cylinder { capped }),
            Shape::Rectangle => Some(lanes::Kind::Rectangle),
            Shape::Disk => Some(lanes::Kind::Disk),
            Shape::Plane => Some(lanes::Kind::Plane),
            _ => None,
        });
        kinds
            .zip(&self.instances)
            .enumerate()
            .map(|(k, (kind, inst))| {
                let xf = match self.leads.get(k) {
                    Some(l) if l.s != 0.0 => Some((
                        Mat3::from_diagonal(Vec3::splat(l.s)),
                        Mat3::from_diagonal(Vec3::splat(l.r)),
                        l.c,
                    )),
                    _ => inst
                        .xf
                        .map(|x| (x.inverse_matrix(), x.matrix(), x.translation())),
                };
                Some(lanes::Item::new(
                    kind?,
                    xf,
                    &inst.bounds(),
                    inst.material,
                    inst.object_id,
                    self.surface_offset(k),
                ))
            })
            .collect()
    }

    /// Surfaces below this aggregate, or `None` when there are more than `u64::MAX - 1`.
    pub fn surface_count(&self) -> Option<u64> {
        (self.surfaces != u64::MAX).then_some(self.surfaces)
    }

    /// The [`Hit::surface`] offset of instance `k`.
    #[inline]
    fn surface_offset(&self, k: usize) -> u64 {
        match self.surface_base.get(k) {
            Some(&b) => b,
            None => k as u64,
        }
    }

    /// The instances in the order they were given (scene order), independent of how the
    /// BVH was built: exporters use it, so that the f32 and f64 builds write the same text.
    pub fn in_scene_order(&self) -> impl Iterator<Item = &Instance> {
        self.scene_order
            .iter()
            .map(|&k| &self.instances[k as usize])
    }

    fn bounded(&self) -> usize {
        self.leads.len()
    }

    fn unbounded(&self) -> &[Instance] {
        &self.instances[self.bounded()..]
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

    /// The instances with infinite bounds (planes), which sit beside the BVH.
    pub fn unbounded_instances(&self) -> &[Instance] {
        self.unbounded()
    }

    /// Bounds of the bounded instances alone (the BVH's), or `None` when there are none.
    pub fn bounded_bounds(&self) -> Option<Aabb> {
        (self.bounded() > 0).then(|| self.bvh.bounds())
    }

    /// Closest hit of bounded instance `k`, in its object space, written into `out` (left
    /// alone when there is none).
    #[inline]
    fn local_hit_into(&self, k: usize, ray: &Ray, t_min: Real, t_max: Real, out: &mut Hit) -> bool {
        let lead = &self.leads[k];
        if lead.s != 0.0 {
            put(
                shapes::sphere::intersect_bare(&lead.object_ray(ray), t_min, t_max),
                out,
            )
        } else {
            self.instances[k].local_hit_into(ray, t_min, t_max, out)
        }
    }

    /// Closest hit with `t_min < t < t_max`. The search keeps the winner in its object
    /// space and maps only the final hit to this space.
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        self.intersect_with::<true>(ray, t_min, t_max)
    }

    /// [`Aggregate::intersect`] for the renderer's integrators, which read no uv: the
    /// record is the same but for `uv`, which is left unset (0) where computing it costs
    /// (a sphere's takes an `acos` and an `atan2`).
    pub fn intersect_for_shading(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        self.intersect_with::<false>(ray, t_min, t_max)
    }

    /// [`Aggregate::intersect_for_shading`] written into `out` (left alone when there is no
    /// hit): the caller's record, which the instances' tests then write in place
    /// ([`Best`]). (A record returned was copied out with wide loads of fields just
    /// written one by one: a store-forwarding stall in the path loop's every search.)
    pub fn intersect_for_shading_into(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        out: &mut Hit,
    ) -> bool {
        self.intersect_into::<false>(ray, t_min, t_max, out)
    }

    #[inline]
    fn intersect_with<const UV: bool>(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut h = Hit::default();
        self.intersect_into::<UV>(ray, t_min, t_max, &mut h)
            .then_some(h)
    }

    /// The search of [`Aggregate::intersect_with`], written into `h` (left alone when
    /// there is no hit).
    #[inline(always)]
    fn intersect_into<const UV: bool>(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        h: &mut Hit,
    ) -> bool {
        let best = self.search_into(ray, t_min, t_max, h);
        if best == Best::NONE {
            return false;
        }
        self.finish::<UV>(best, h);
        true
    }

    /// The search of [`Aggregate::intersect_into`]: the winner's instance
    /// ([`Best::NONE`] when nothing is hit) and its record, unfinished (in its instance's
    /// object space), in `h`.
    #[inline(always)]
    fn search_into(&self, ray: &Ray, t_min: Real, t_max: Real, h: &mut Hit) -> usize {
        let mut best = Best::NONE;
        let t_max = self.nearest_unbounded(ray, t_min, t_max, &mut best, h);
        self.bvh.traverse(ray, t_min, t_max, false, |k, tmax| {
            self.visit(k, ray, t_min, tmax, &mut best, h)
        });
        best
    }

    /// [`Aggregate::intersect_for_shading_into`] for a ray whose hit matters only when its
    /// material is `wanted` (a path's last vertex, which adds nothing but emission): the
    /// same search, and the record finished only for such a hit. `None` when nothing is
    /// hit; `Some(true)` with the full record in `out`; `Some(false)` when the hit's
    /// material is not wanted (then `out` holds an unfinished record, not to be read).
    pub fn intersect_for_shading_if(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        out: &mut Hit,
        wanted: impl Fn(u32) -> bool,
    ) -> Option<bool> {
        let best = self.search_into(ray, t_min, t_max, out);
        if best == Best::NONE {
            return None;
        }
        if !wanted(self.material_of(best, out)) {
            return Some(false);
        }
        self.finish::<false>(best, out);
        Some(true)
    }

    /// The closest hit among the unbounded instances, its index into `best` and its record
    /// into `h` (both left alone when there is none), and the end of the interval it
    /// leaves for the BVH. (It writes the
    /// caller's record rather than returning one: a returned record was copied with wide
    /// loads of fields just written one by one, which stalls store forwarding.)
    /// (Inlined down to the test for none, the common case: as a call it cost a scene
    /// without planes 24 instructions a ray.)
    #[inline(always)]
    fn nearest_unbounded(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        best: &mut usize,
        h: &mut Hit,
    ) -> Real {
        if self.bounded() == self.instances.len() {
            return t_max;
        }
        self.nearest_of_unbounded(ray, t_min, t_max, best, h)
    }

    /// [`Aggregate::nearest_unbounded`] when there are some.
    #[inline]
    fn nearest_of_unbounded(
        &self,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        best: &mut usize,
        h: &mut Hit,
    ) -> Real {
        let mut t_max = t_max;
        for (k, inst) in self.unbounded().iter().enumerate() {
            if inst.local_hit_into(ray, t_min, t_max, h) {
                t_max = h.t;
                *best = self.bounded() + k;
            }
        }
        t_max
    }

    /// Tests bounded instance `k` for [`Bvh::traverse`]: a hit (closer than the walk's
    /// `t_max`, so than any before it) becomes the best, its index in `best` and its
    /// record written into `h`.
    #[inline(always)]
    fn visit(
        &self,
        k: u32,
        ray: &Ray,
        t_min: Real,
        t_max: Real,
        best: &mut usize,
        h: &mut Hit,
    ) -> Visit {
        if self.local_hit_into(k as usize, ray, t_min, t_max, h) {
            *best = k as usize;
            Visit::Hit(h.t)
        } else {
            Visit::Miss
        }
    }

    /// [`Aggregate::intersect`] for many rays: `out[r]` gets exactly what
    /// `intersect(&rays[r], t_min, t_max)` returns. When the BVH and its records are
    /// larger than [`INTERLEAVE_ABOVE`], rays are walked [`BATCH`] at a time through
    /// [`Bvh::traverse_batch`], so that one ray's cache misses overlap the others' work;
    /// a smaller tree stays in cache and is cheaper one ray at a time. Only this tree's
    /// walk is interleaved: the BVHs of meshes and nested groups below it are walked one
    /// ray at a time. Both models' camera rays and the AOVs go through here.
    pub fn intersect_many(&self, rays: &[Ray], t_min: Real, t_max: Real, out: &mut [Option<Hit>]) {
        self.intersect_many_with::<true>(rays, t_min, t_max, out)
    }

    /// [`Aggregate::intersect_many`] without uv, as [`Aggregate::intersect_for_shading`].
    pub fn intersect_many_for_shading(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: Real,
        out: &mut [Option<Hit>],
    ) {
        self.intersect_many_with::<false>(rays, t_min, t_max, out)
    }

    #[inline]
    fn intersect_many_with<const UV: bool>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: Real,
        out: &mut [Option<Hit>],
    ) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            self.intersect_batch::<UV>(rays, t_min, &[t_max; BATCH][..rays.len()], out);
        }
    }

    /// [`Aggregate::intersect_many`] for up to [`BATCH`] rays, each with its own `t_max`.
    fn intersect_batch<const UV: bool>(
        &self,
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        out: &mut [Option<Hit>],
    ) {
        if let Some(items) = &self.lanes {
            // In lanes (lanes.rs); a ray whose closest distance two instances share takes
            // the scalar search, which keeps the first in the tree's order.
            let ties = lanes::intersect::<UV>(items, rays, t_min, t_max, out);
            for r in (0..rays.len()).filter(|r| ties >> r & 1 == 1) {
                out[r] = self.intersect_with::<UV>(&rays[r], t_min, t_max[r]);
            }
            return;
        }
        if self.bounded() == 1 && self.leads[0].s == 0.0 {
            // One bounded instance (a mesh, a definition): its own tree is the one to
            // walk rays together through, which the instance's batch does. (The single
            // leaf's box test is skipped, as `Bvh::traverse` does.) The unbounded
            // instances go first and bound each ray's search, as in `intersect`.
            if self.unbounded().is_empty() {
                self.instances[0].local_hit_batch(rays, t_min, t_max, out);
                for o in out.iter_mut() {
                    if let Some(h) = o {
                        self.finish::<UV>(0, h);
                    }
                }
                return;
            }
            let mut bound = [0.0; BATCH];
            let mut unbounded = [Best::none(); BATCH];
            for (r, ray) in rays.iter().enumerate() {
                let u = &mut unbounded[r];
                bound[r] = self.nearest_unbounded(ray, t_min, t_max[r], &mut u.k, &mut u.h);
            }
            self.instances[0].local_hit_batch(rays, t_min, &bound[..rays.len()], out);
            for (o, mut u) in out.iter_mut().zip(unbounded) {
                match o.as_mut() {
                    Some(h) => self.finish::<UV>(0, h),
                    None if u.k != Best::NONE => {
                        self.finish::<UV>(u.k, &mut u.h);
                        *o = Some(u.h);
                    }
                    None => {}
                }
            }
            return;
        }
        let mut best = [Best::none(); BATCH];
        let mut bound = [0.0; BATCH];
        for (r, ray) in rays.iter().enumerate() {
            let b = &mut best[r];
            bound[r] = self.nearest_unbounded(ray, t_min, t_max[r], &mut b.k, &mut b.h);
        }
        let bound = &bound[..rays.len()];
        if self.interleaves() {
            self.bvh.traverse_batch(
                rays,
                t_min,
                bound,
                |r, k, tmax| {
                    let b = &mut best[r];
                    self.visit(k, &rays[r], t_min, tmax, &mut b.k, &mut b.h)
                },
                |first| self.leads.as_ptr().wrapping_add(first as usize).cast(),
            );
        } else {
            for (r, ray) in rays.iter().enumerate() {
                self.bvh.traverse(ray, t_min, bound[r], false, |k, tmax| {
                    let b = &mut best[r];
                    self.visit(k, ray, t_min, tmax, &mut b.k, &mut b.h)
                });
            }
        }
        for (o, mut b) in out.iter_mut().zip(best) {
            *o = (b.k != Best::NONE).then(|| {
                self.finish::<UV>(b.k, &mut b.h);
                b.h
            });
        }
    }

    /// Whether [`Aggregate::intersect_many`] tests this aggregate's instances in lanes
    /// (lanes.rs): a few canonical spheres, cubes, cylinders, rectangles, disks and planes.
    pub fn searches_in_lanes(&self) -> bool {
        self.lanes.is_some()
    }

    /// Whether [`Aggregate::intersect_many`] interleaves rays: whether the BVH nodes and
    /// leads take more than [`INTERLEAVE_ABOVE`] bytes.
    pub fn interleaves(&self) -> bool {
        self.bvh.node_bytes() + std::mem::size_of_val(self.leads.as_slice()) > INTERLEAVE_ABOVE
    }

    /// The material [`Aggregate::finish`] gives the record `h` of instance `k`: its own,
    /// or the instance's (its lead's) when it inherits (`Hit::material_or`).
    #[inline(always)]
    fn material_of(&self, k: usize, h: &Hit) -> u32 {
        h.material_or(match self.leads.get(k) {
            Some(lead) if lead.s != 0.0 => lead.material,
            _ => self.instances[k].material,
        })
    }

    /// Maps the winner of a search, bounded instance or not, to this space, and numbers
    /// its surface. (In place, as the instance's and the shape's steps are: a record
    /// passed by value was copied in and out at each, 75 instructions a ray here on the
    /// peers bench's coherent rays, 41 now. Always inlined: as a call, its one-by-one
    /// writes of the record's fields were read back by the caller's wide copy of the
    /// record, a store-forwarding stall; inlined, path-traced scenes took 1.5–2 % less
    /// time.)
    #[inline(always)]
    fn finish<const UV: bool>(&self, k: usize, h: &mut Hit) {
        match self.leads.get(k) {
            Some(lead) if lead.s != 0.0 => lead.finish::<UV>(h),
            _ => self.instances[k].finish::<UV>(h),
        }
        h.surface = h.surface.wrapping_add(self.surface_offset(k));
    }

    /// The closest hit with `t_min < t < t_max` as Embree's `rtcIntersect1` reports one
    /// ([`RayHit`]: distance, geometric normal, barycentrics, surface and primitive), for a
    /// caller that needs no shading record: the search of [`Aggregate::intersect`], whose
    /// meshes build no record for their winner, and each field the bits of the same field
    /// of `intersect`'s record (tests/bvh.rs checks it). What the peers benchmark times
    /// against Embree (renderer/docs/performance.md).
    pub fn nearest(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<RayHit> {
        // A scene of one instance (one mesh, say) is asked directly, outside the frame of
        // the instance tree's walk (its stacks and saved registers), which stays out of
        // line: on the peers bench's one-mesh scene this took 69 instructions off a
        // coherent ray's 1,403 (Callgrind), and one thread traced 1.014-1.031x as fast
        // (four alternating pairs; bounce rays 0.99-1.02x).
        if let [inst] = self.instances.as_slice() {
            if self.bounded() == 1 && self.leads[0].s == 0.0 {
                let mut h = inst.nearest_local(ray, t_min, t_max)?;
                inst.finish_nearest(&mut h);
                h.surface = h.surface.wrapping_add(self.surface_offset(0));
                return Some(h);
            }
        }
        self.nearest_in_tree(ray, t_min, t_max)
    }

    /// [`Aggregate::nearest`] over the instance tree and the unbounded instances.
    #[inline(never)]
    fn nearest_in_tree(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<RayHit> {
        let mut best: Option<(usize, RayHit)> = None;
        let mut t_max = t_max;
        for (k, inst) in self.unbounded().iter().enumerate() {
            if let Some(h) = inst.nearest_local(ray, t_min, t_max) {
                t_max = h.t;
                best = Some((self.bounded() + k, h));
            }
        }
        let local = |k: usize, t_max: Real| {
            let lead = &self.leads[k];
            if lead.s != 0.0 {
                shapes::sphere::intersect_bare(&lead.object_ray(ray), t_min, t_max)
                    .map(|h| RayHit::of(&h))
            } else {
                self.instances[k].nearest_local(ray, t_min, t_max)
            }
        };
        if self.bounded() == 1 {
            // One bounded instance beside planes, or a lone uniformly scaled sphere (a
            // lone instance of any other kind took the shortcut in `nearest`): asked
            // directly, without the tree's walk, as `occluded` does.
            if let Some(h) = local(0, t_max) {
                best = Some((0, h));
            }
        } else {
            self.bvh.traverse(ray, t_min, t_max, false, |k, tmax| {
                match local(k as usize, tmax) {
                    Some(h) => {
                        best = Some((k as usize, h));
                        Visit::Hit(h.t)
                    }
                    None => Visit::Miss,
                }
            });
        }
        let (k, mut h) = best?;
        match self.leads.get(k) {
            Some(lead) if lead.s != 0.0 => lead.finish_nearest(&mut h),
            _ => self.instances[k].finish_nearest(&mut h),
        }
        h.surface = h.surface.wrapping_add(self.surface_offset(k));
        Some(h)
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
        self.occluded_bounded(ray, t_min, t_max)
    }

    /// [`Aggregate::occluded`] among the bounded instances.
    #[inline]
    fn occluded_bounded(&self, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        // A tree of one instance (a scene of one mesh, say): asked directly, without the
        // tree's walk (whose box test `Bvh::traverse` skips for a lone primitive anyway;
        // on the peers bench's one-mesh scene the walk cost another 52 instructions a ray
        // for any hit). The same shortcut in the search for the closest hit cost the
        // frames of many instances, which never take it, 0.3 to 0.8 % instructions (the
        // compiler laid `intersect_with` out otherwise) for 1.7 % on a one-mesh scene;
        // there `Bvh::traverse`'s shortcut does most of it.
        if self.bounded() == 1 {
            return self.occludes(0, ray, t_min, t_max);
        }
        self.bounded() > 0
            && self.bvh.traverse(ray, t_min, t_max, true, |k, tmax| {
                if self.occludes(k as usize, ray, t_min, tmax) {
                    Visit::Hit(tmax)
                } else {
                    Visit::Miss
                }
            })
    }

    /// [`Aggregate::occluded`] for many rays: `out[r]` gets exactly what
    /// `occluded(&rays[r], t_min, t_max)` returns. Rays go [`BATCH`] at a time: the
    /// unbounded instances one ray at a time, then the tree's walk with the rays together
    /// when the tree and its leads are larger than [`INTERLEAVE_ABOVE`] (a scene of one
    /// mesh: the mesh's own walk, when its tree is), so that one ray's cache misses
    /// overlap the others' work; each ray takes exactly the steps it takes alone. For a
    /// renderer's shadow rays, or any caller with many rays to test at once.
    pub fn occluded_many(&self, rays: &[Ray], t_min: Real, t_max: Real, out: &mut [bool]) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            let hits = self.occluded_batch(rays, t_min, &[t_max; BATCH][..rays.len()]);
            for (r, o) in out.iter_mut().enumerate() {
                *o = (hits >> r) & 1 == 1;
            }
        }
    }

    /// [`Aggregate::occluded_many`] for up to [`BATCH`] rays, each with its own `t_max`:
    /// bit `r` of the result for `rays[r]`.
    fn occluded_batch(&self, rays: &[Ray], t_min: Real, t_max: &[Real]) -> u64 {
        let mut hits = 0u64;
        for (r, (ray, &t)) in rays.iter().zip(t_max).enumerate() {
            if self
                .unbounded()
                .iter()
                .any(|inst| inst.occluded(ray, t_min, t))
            {
                hits |= 1 << r;
            }
        }
        // The rays an unbounded instance occludes are walked too (their answer is
        // already known): the walk takes them all or none.
        hits | match self.bounded() {
            0 => 0,
            // As `occluded`: a tree of one instance is asked directly.
            1 if self.leads[0].s == 0.0 => self.instances[0].occluded_batch(rays, t_min, t_max),
            _ if self.interleaves() => self.bvh.traverse_batch_leaves::<true, _, _>(
                rays,
                t_min,
                t_max,
                |r, first, count, tmax| {
                    let ray = &rays[r];
                    match (first..first + count as u32)
                        .any(|k| self.occludes(k as usize, ray, t_min, tmax))
                    {
                        true => Visit::Hit(tmax),
                        false => Visit::Miss,
                    }
                },
                |first| self.leads.as_ptr().wrapping_add(first as usize).cast(),
            ),
            _ => mask_ray_by_ray(rays, t_max, |ray, t| self.occluded_bounded(ray, t_min, t)),
        }
    }

    /// Whether bounded instance `k` is hit with `t_min < t < t_max`.
    #[inline(always)]
    fn occludes(&self, k: usize, ray: &Ray, t_min: Real, t_max: Real) -> bool {
        let lead = &self.leads[k];
        if lead.s != 0.0 {
            shapes::sphere::hits(&lead.object_ray(ray), t_min, t_max)
        } else {
            self.instances[k].occluded(ray, t_min, t_max)
        }
    }

    /// Brute force closest hit over every instance (the reference for BVH tests).
    pub fn intersect_brute_force(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        for (k, inst) in self.instances.iter().enumerate() {
            if let Some(mut h) = inst.intersect(ray, t_min, t_max) {
                t_max = h.t;
                h.surface = h.surface.wrapping_add(self.surface_offset(k));
                best = Some(h);
            }
        }
        best
    }
}

/// The [`Hit::surface`] offsets of `instances` (in stored order) and their total, with the
/// offsets left out (empty) when every instance is one surface, so that the offset is the
/// index and costs no memory read. The total saturates at `u64::MAX`.
fn surface_offsets(instances: &[Instance]) -> (Vec<u64>, u64) {
    if instances.iter().all(|i| i.shape.surfaces() == 1) {
        return (Vec::new(), instances.len() as u64);
    }
    let mut base = Vec::with_capacity(instances.len());
    let mut total = 0u64;
    for i in instances {
        base.push(total);
        total = total.saturating_add(i.shape.surfaces());
    }
    (base, total)
}
