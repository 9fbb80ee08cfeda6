//! Where secondary rays start: the self-intersection strategies.
//!
//! - [`Spawn::Robust`] (default) moves the origin off the surface along the geometric
//!   normal, to the side the new ray leaves from, by the hit point's rounding-error bound,
//!   which every shape computes and every instance transform propagates (pbrt-v3 §3.9).
//!   The offset therefore scales with the coordinates, not with a fixed world unit.
//! - [`Spawn::Fixed`] starts the ray exactly at the hit point and ignores hits closer than
//!   a fixed distance, as POV-Ray does (1e-3 for shadow rays; trace.cpp SHADOW_TOLERANCE).
//! - [`Spawn::None`] starts exactly at the hit point with no tolerance: broken on purpose,
//!   so tests can show that the offset matters.

use crate::ray::Ray;
use crate::real::{Real, Vec3};

/// A self-intersection strategy.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Spawn {
    /// Offset along the normal by the rounding-error bound of the hit point.
    Robust,
    /// No offset; ignore hits closer than this distance along the unit direction.
    Fixed(f64),
    /// No offset and no tolerance.
    None,
}

impl Default for Spawn {
    fn default() -> Self {
        Spawn::Robust
    }
}

/// Offsets `p` (with per-component error bound `err`) along the unit normal `n`, to the
/// side `dir` leaves from, by `dot(|n|, err)` and then one more float outward per
/// component (pbrt's OffsetRayOrigin): the new origin lies strictly outside the error box.
#[inline(always)]
pub fn offset_origin(p: Vec3, err: Vec3, n: Vec3, dir: Vec3) -> Vec3 {
    let dist = n.abs().dot(err);
    let mut off = n * dist;
    if dir.dot(n) < 0.0 {
        off = -off;
    }
    let mut po = p + off;
    for k in 0..3 {
        if off[k] > 0.0 {
            po[k] = po[k].next_up();
        } else if off[k] < 0.0 {
            po[k] = po[k].next_down();
        }
    }
    po
}

impl Spawn {
    /// A ray leaving hit point `p` (error bound `err`, unit outward geometric normal `n`)
    /// along `dir`. Returns the ray and the `t_min` to search from.
    ///
    /// Always inlined, with [`offset_origin`]: as a call (LLVM declined the plain hint),
    /// the vectors went through memory, written as single floats and read back as pairs,
    /// which the processor cannot forward from its store buffer; that stall alone was 9 %
    /// of a reflective Whitted frame's time (renderer/docs/performance.md).
    #[inline(always)]
    pub fn ray(&self, p: Vec3, err: Vec3, n: Vec3, dir: Vec3) -> (Ray, Real) {
        match *self {
            Spawn::Robust => (Ray::new(offset_origin(p, err, n, dir), dir), 0.0),
            Spawn::Fixed(eps) => (Ray::new(p, dir), eps as Real / dir.length()),
            Spawn::None => (Ray::new(p, dir), 0.0),
        }
    }
}
