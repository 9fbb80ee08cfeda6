//! The hit record (pbrt's surface interaction): what a shape reports about where a ray met
//! it. Shapes produce it, instances and aggregates map it to their space, and the
//! integrators read it. It depends on nothing but the precision types.

use crate::real::{Real, Vec2, Vec3};

/// Marks a hit whose material or object id comes from the enclosing instance.
pub const INHERIT: u32 = u32::MAX;

/// A hit record in the space of whoever returned it. (The default, all zeros, is only a
/// place for a search to write its record into.)
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    /// Which surface of the scene was hit: every leaf shape under every instance path
    /// has its own number (a definition instanced twice gives each copy its own). Shapes
    /// report 0; each aggregate adds the offset of the instance the hit came through.
    /// Shading keys its interior list by it (an instance is only a placement, so the
    /// shapes inside one stay distinct objects).
    pub surface: u64,
    /// Which primitive of its shape was hit: a mesh's triangle, numbered in the order the
    /// mesh was given (its file's); 0 for the single primitives. Embree's `primID`: the
    /// peers benchmark compares it ray by ray (renderer/docs/performance.md).
    pub prim: u32,
}

/// What a search for the closest hit reports when its caller needs no shading record
/// ([`Aggregate::nearest`](crate::aggregate::Aggregate::nearest)): the fields of Embree's
/// `RTCHit` (distance, geometric normal, barycentric coordinates, which surface and
/// which primitive), without the point and its error bound, the shading normal, the uv
/// or the material, which a mesh's record builds from the winning triangle. Each field has
/// the bits of the same field of the full record ([`Hit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Ray parameter.
    pub t: Real,
    /// Outward geometric normal (not normalized), in the space of whoever returned it.
    pub n_geo: Vec3,
    /// A mesh triangle's barycentric coordinates at the hit, `(b₁, b₂)` (Embree's `u`,
    /// `v`; the full record's `uv` when the mesh has no uvs of its own); `(0, 0)` for
    /// every other shape.
    pub b: Vec2,
    /// Which surface of the scene was hit ([`Hit::surface`]).
    pub surface: u64,
    /// Which primitive of its shape was hit ([`Hit::prim`]).
    pub prim: u32,
}

impl RayHit {
    /// The fields of a full record, for a shape whose search builds one anyway.
    #[inline]
    pub fn of(h: &Hit) -> RayHit {
        RayHit {
            t: h.t,
            n_geo: h.n_geo,
            b: Vec2::ZERO,
            surface: h.surface,
            prim: h.prim,
        }
    }
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
            surface: 0,
            prim: 0,
        }
    }

    /// Whether the shading normal is the geometric one, bit for bit (a flat-shaded
    /// surface: every shape but smooth triangles). Then whatever maps or normalizes one
    /// gives the other's result too, and is done once.
    #[inline]
    pub(crate) fn flat_shaded(&self) -> bool {
        self.n_shade.to_array().map(Real::to_bits) == self.n_geo.to_array().map(Real::to_bits)
    }

    /// Maps both normals by `map`, the shading normal only when it differs from the
    /// geometric one (the same bits as mapping each).
    #[inline]
    pub(crate) fn map_normals(&mut self, map: impl Fn(Vec3) -> Vec3) {
        let flat = self.flat_shaded();
        self.n_geo = map(self.n_geo);
        self.n_shade = if flat { self.n_geo } else { map(self.n_shade) };
    }

    /// The material this record has once it inherits `material` from an enclosing
    /// instance: its own, unless it has none yet ([`INHERIT`]).
    #[inline]
    pub(crate) fn material_or(&self, material: u32) -> u32 {
        if self.material == INHERIT {
            material
        } else {
            self.material
        }
    }

    /// Fills in the material and object id still unassigned, from an enclosing instance.
    #[inline]
    pub(crate) fn inherit(&mut self, material: u32, object_id: u32) {
        self.material = self.material_or(material);
        if self.object_id == 0 {
            self.object_id = object_id;
        }
    }
}
