//! The precision switch. The renderer computes in `Real`, which is `f32` by default and
//! `f64` with the `f64` cargo feature. Scene files are always parsed in `f64` and converted
//! once, when the scene is built.

#[cfg(not(feature = "f64"))]
mod imp {
    /// The floating-point type of every geometric computation.
    pub type Real = f32;
    /// A 3-vector of `Real`.
    pub type Vec3 = glam::Vec3;
    /// A 3×3 matrix of `Real` (glam, column-major, column-vector convention).
    pub type Mat3 = glam::Mat3;
    /// A 2-vector of `Real`.
    pub type Vec2 = glam::Vec2;
    /// A 4-vector of `Real` (SIMD lanes: the four children of a BVH node).
    pub type Vec4 = glam::Vec4;
    /// [`Vec3`] in a 16-byte SIMD register (glam's `Vec3A`): the same arithmetic on each
    /// component, done for all three at once. For maps computed once and stored back as
    /// [`Vec3`].
    pub type Vec3A = glam::Vec3A;
    /// [`Mat3`] with [`Vec3A`] columns.
    pub type Mat3A = glam::Mat3A;
    /// Name of the precision, for reports.
    pub const PRECISION: &str = "f32";

    /// 2^e for `e` clamped to the normal range, built from its bits (no `powi` call).
    #[inline]
    pub fn pow2(e: i32) -> Real {
        f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
    }
}

#[cfg(feature = "f64")]
mod imp {
    /// The floating-point type of every geometric computation.
    pub type Real = f64;
    /// A 3-vector of `Real`.
    pub type Vec3 = glam::DVec3;
    /// A 3×3 matrix of `Real` (glam, column-major, column-vector convention).
    pub type Mat3 = glam::DMat3;
    /// A 2-vector of `Real`.
    pub type Vec2 = glam::DVec2;
    /// A 4-vector of `Real` (SIMD lanes: the four children of a BVH node).
    pub type Vec4 = glam::DVec4;
    /// [`Vec3`] itself: glam has no SIMD 3-vector of `f64`.
    pub type Vec3A = glam::DVec3;
    /// [`Mat3`] itself.
    pub type Mat3A = glam::DMat3;
    /// Name of the precision, for reports.
    pub const PRECISION: &str = "f64";

    /// 2^e for `e` clamped to the normal range, built from its bits (no `powi` call).
    #[inline]
    pub fn pow2(e: i32) -> Real {
        f64::from_bits(((e.clamp(-1022, 1023) + 1023) as u64) << 52)
    }
}

pub use imp::*;

/// Converts an `f64` vector from the scene file into the renderer's precision.
#[inline]
pub fn vec3(v: glam::DVec3) -> Vec3 {
    Vec3::new(v.x as Real, v.y as Real, v.z as Real)
}

/// Converts a renderer vector to `f64` (for reports and AOVs).
#[inline]
pub fn dvec3(v: Vec3) -> glam::DVec3 {
    glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// Machine epsilon of `Real` halved (the unit roundoff), as in pbrt's `gamma(n)`.
pub const UNIT_ROUNDOFF: Real = Real::EPSILON * 0.5;

/// pbrt's γ(n) = nε/(1 − nε): a bound on the relative error of n chained roundings.
#[inline]
pub const fn gamma(n: i32) -> Real {
    let ne = n as Real * UNIT_ROUNDOFF;
    ne / (1.0 - ne)
}
