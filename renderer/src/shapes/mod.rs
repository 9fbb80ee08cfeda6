//! Canonical primitives in normalized object space, one file per family. Shapes never see
//! a transform: an [`Instance`](crate::aggregate::Instance) maps the ray in and the hit
//! out. They depend only on the hit record; the [`Shape`](crate::aggregate::Shape) enum
//! that dispatches to them (and that can hold a whole sub-scene) lives with the aggregate.
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

pub mod anchored;
pub(crate) mod cone;
pub(crate) mod cube;
pub(crate) mod cylinder;
pub(crate) mod flat;
pub mod mesh;
pub(crate) mod sphere;
pub mod triangle;

use crate::hit::Hit;
use crate::real::{Real, Vec2, Vec3};

pub use mesh::Mesh;
pub use triangle::Triangle;

/// A hit in a shape's object space, with the point's error bound and one normal.
#[inline]
pub(crate) fn local_hit(t: Real, p: Vec3, err: Vec3, n: Vec3, uv: Vec2) -> Hit {
    Hit::new(t, p, err, n, n, uv)
}

/// Roots of `a·t² + 2·b·t + c = 0`, given `disc = b² − a·c ≥ 0` and `a > 0`, in
/// ascending order, computed without cancellation (Haines et al., Ray Tracing Gems ch. 7).
/// Written with selects, not branches, so that the lanes (aggregate/lanes.rs), which call
/// it lane by lane, stay vector code (a lane with `disc < 0` gets NaNs its caller masks).
#[inline(always)]
pub(crate) fn stable_roots(a: Real, b: Real, c: Real, disc: Real) -> (Real, Real) {
    let s = disc.sqrt();
    let q = -(b + s.copysign(b));
    let (r0, r1) = (q / a, c / q);
    let (t0, t1) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
    if q == 0.0 {
        // b = 0 and disc = 0: a double root at 0 (c = 0).
        (0.0, 0.0)
    } else {
        (t0, t1)
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
