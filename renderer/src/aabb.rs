//! Axis-aligned bounding boxes and the robust slab test (Ize, JCGT 2013).

use crate::real::{gamma, Real, Vec3};

/// An axis-aligned box. The empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box, the identity of `union`.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(Real::INFINITY),
        max: Vec3::splat(Real::NEG_INFINITY),
    };

    /// The box spanning two points.
    #[inline]
    pub fn from_points(a: Vec3, b: Vec3) -> Self {
        Aabb {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// Smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Grows the box to hold `p`.
    #[inline]
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Centre of the box.
    #[inline]
    pub fn centroid(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Whether the box is empty.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Whether every coordinate is finite (an unbounded primitive has an infinite box).
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Surface area; 0 for an empty box.
    #[inline]
    pub fn area(&self) -> Real {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.max - self.min;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// Slab test. Returns the entry distance when the ray overlaps the box within
    /// `[t_min, t_max]`. `inv_d` is `1/d` per component (infinite for a zero component).
    /// The far distance is inflated by `1 + 2γ(3)` so rounding never loses a hit on a face.
    #[inline]
    pub fn hit(&self, o: Vec3, inv_d: Vec3, t_min: Real, t_max: Real) -> Option<Real> {
        let t0 = (self.min - o) * inv_d;
        let t1 = (self.max - o) * inv_d;
        // 0·inf = NaN when the origin lies on a slab plane and the direction is parallel to
        // it: the ray is then inside the closed slab, which must not constrain it. glam's
        // min/max (`if a < b { a } else { b }`) do not ignore NaN, and even f32::min would
        // turn (NaN, +inf) into +inf, so the NaN slabs are replaced explicitly.
        let nan = t0.is_nan_mask() | t1.is_nan_mask();
        let tn = Vec3::select(nan, Vec3::NEG_INFINITY, t0.min(t1));
        let tf = Vec3::select(nan, Vec3::INFINITY, t0.max(t1));
        let near = tn.x.max(tn.y).max(tn.z).max(t_min);
        let far = tf.x.min(tf.y).min(tf.z).min(t_max) * (1.0 + 2.0 * gamma(3));
        if near <= far {
            Some(near)
        } else {
            None
        }
    }
}
