//! Affine transforms, named destination-from-source (`world_from_object`).
//!
//! DEVELOPERS.md writes points as row vectors, `p' = p M + d`. glam uses column vectors, so
//! the stored `m` is the transpose of that `M`: `p' = m·p + d`. Both keep their inverse,
//! computed once in `f64` when the scene is built. Points, vectors and normals map through
//! separate methods:
//! - points: `m·p + d`;
//! - vectors (ray directions): `m·v`, never renormalized, so that ray parameters agree
//!   across spaces;
//! - normals: `m⁻ᵀ·n` (the spec's `n M⁻ᵀ`), read straight from the stored inverse.

use crate::aabb::Aabb;
use crate::ray::Ray;
use crate::real::{Mat3, Mat3A, Real, Vec3, Vec3A};
use glam::{DMat3, DVec3};

/// Largest accepted condition number (Frobenius norms of `m` and `m⁻¹`). Past this the
/// matrix is singular for practical purposes even in `f64`.
pub const MAX_CONDITION: f64 = 1e14;

/// Why a matrix cannot be an instance transform.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TransformError {
    /// An entry is NaN or infinite.
    #[error("the transform has a non-finite entry")]
    NonFinite,
    /// The transform's numbers are too large: its determinant, or an entry once converted to
    /// the render precision, overflows.
    #[error("the transform overflows: {0}")]
    Overflow(String),
    /// The determinant is zero or the matrix is too ill-conditioned to invert.
    #[error("the transform is singular (determinant {det:e}{})", if cond.is_finite() { format!(", condition number {cond:e}") } else { String::new() })]
    Singular {
        /// The determinant.
        det: f64,
        /// Frobenius condition number.
        cond: f64,
    },
}

/// An affine map in `f64`, used while building scenes: `p' = m·p + d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine64 {
    /// Linear part (column-vector convention).
    pub m: DMat3,
    /// Translation.
    pub d: DVec3,
}

impl Default for Affine64 {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Affine64 {
    /// The identity.
    pub const IDENTITY: Affine64 = Affine64 {
        m: DMat3::IDENTITY,
        d: DVec3::ZERO,
    };

    /// A translation by `d`.
    pub fn translate(d: DVec3) -> Self {
        Affine64 {
            m: DMat3::IDENTITY,
            d,
        }
    }

    /// A linear map.
    pub fn linear(m: DMat3) -> Self {
        Affine64 { m, d: DVec3::ZERO }
    }

    /// `self ∘ inner`: apply `inner` first, then `self`.
    pub fn compose(&self, inner: &Affine64) -> Affine64 {
        Affine64 {
            m: self.m * inner.m,
            d: self.m * inner.d + self.d,
        }
    }

    /// Maps a point.
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.m * p + self.d
    }

    /// Whether this is exactly the identity.
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// Checks that the map is finite and invertible and returns the inverse.
    pub fn inverse(&self) -> Result<Affine64, TransformError> {
        if !self.m.is_finite() || !self.d.is_finite() {
            return Err(TransformError::NonFinite);
        }
        let det = self.m.determinant();
        if det.is_infinite() {
            return Err(TransformError::Overflow(
                "its scale is too large (the determinant exceeds the largest f64); \
scale the scene down"
                    .into(),
            ));
        }
        let inv = match inverse_gepp(&self.m) {
            Some(inv) if det != 0.0 => inv,
            _ => DMat3::from_cols_array(&[f64::NAN; 9]),
        };
        let frob =
            |a: &DMat3| -> f64 { a.to_cols_array().iter().map(|x| x * x).sum::<f64>().sqrt() };
        let cond = frob(&self.m) * frob(&inv);
        if det == 0.0 || !inv.is_finite() || !cond.is_finite() || cond > MAX_CONDITION {
            return Err(TransformError::Singular { det, cond });
        }
        Ok(Affine64 {
            m: inv,
            d: -(inv * self.d),
        })
    }
}

/// The inverse of `m` by Gaussian elimination with partial pivoting, or `None` when a pivot
/// is zero. Its error is about ε·κ(m). glam's `inverse` (adjugate over determinant) is not
/// used: when two singular values are small (a needle, or scales 10⁴, 10⁻⁴, 10⁻⁴ under a
/// rotation) its cross products cancel and its error grows like ε·κ², e.g. 8 % for
/// κ = 10⁸, well inside the accepted range.
fn inverse_gepp(m: &DMat3) -> Option<DMat3> {
    // a[i][j] is row i, column j; x starts as the identity and ends as the inverse.
    let mut a = [[0.0f64; 3]; 3];
    let mut x = [[0.0f64; 3]; 3];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = m.col(j)[i];
        }
        x[i][i] = 1.0;
    }
    for c in 0..3 {
        let p = (c..3).fold(c, |p, r| if a[r][c].abs() > a[p][c].abs() { r } else { p });
        if a[p][c] == 0.0 || !a[p][c].is_finite() {
            return None;
        }
        a.swap(c, p);
        x.swap(c, p);
        for r in c + 1..3 {
            let f = a[r][c] / a[c][c];
            for k in c..3 {
                a[r][k] -= f * a[c][k];
            }
            for k in 0..3 {
                x[r][k] -= f * x[c][k];
            }
        }
    }
    for c in (0..3).rev() {
        for k in 0..3 {
            let mut s = x[c][k];
            for j in c + 1..3 {
                s -= a[c][j] * x[j][k];
            }
            x[c][k] = s / a[c][c];
        }
    }
    Some(DMat3::from_cols(
        DVec3::new(x[0][0], x[1][0], x[2][0]),
        DVec3::new(x[0][1], x[1][1], x[2][1]),
        DVec3::new(x[0][2], x[1][2], x[2][2]),
    ))
}

/// A validated affine transform in renderer precision with its cached inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    m: Mat3,
    d: Vec3,
    inv: Mat3,
    inv_d: Vec3,
}

fn to_real(m: &DMat3) -> Mat3 {
    Mat3::from_cols_array(&m.to_cols_array().map(|x| x as Real))
}

impl Transform {
    /// Validates `a` (finite, invertible in `f64` and in `Real`) and caches its inverse.
    pub fn new(a: &Affine64) -> Result<Self, TransformError> {
        let inv = a.inverse()?;
        let t = Transform {
            m: to_real(&a.m),
            d: crate::real::vec3(a.d),
            inv: to_real(&inv.m),
            inv_d: crate::real::vec3(inv.d),
        };
        if !(t.m.is_finite() && t.d.is_finite()) || !t.m.determinant().is_finite() {
            return Err(TransformError::Overflow(format!(
                "its {} is too large for the renderer's precision ({}); scale the scene down, \
or use the f64 build",
                if t.d.is_finite() {
                    "scale"
                } else {
                    "translation"
                },
                crate::real::PRECISION
            )));
        }
        let finite = t.m.is_finite() && t.d.is_finite() && t.inv.is_finite() && t.inv_d.is_finite();
        let real_det = t.m.determinant();
        if !finite || real_det == 0.0 || !real_det.is_finite() {
            return Err(TransformError::Singular {
                det: real_det as f64,
                cond: f64::INFINITY,
            });
        }
        Ok(t)
    }

    /// The same map with its object space moved so that its origin is the object point
    /// `a`: `m·p + (d + m·a)`, the translation computed in f64 (for anchored shapes).
    pub fn shifted(&self, a: glam::DVec3) -> Transform {
        let m64 = glam::DMat3::from_cols(
            crate::real::dvec3(self.m.x_axis),
            crate::real::dvec3(self.m.y_axis),
            crate::real::dvec3(self.m.z_axis),
        );
        let inv64 = glam::DMat3::from_cols(
            crate::real::dvec3(self.inv.x_axis),
            crate::real::dvec3(self.inv.y_axis),
            crate::real::dvec3(self.inv.z_axis),
        );
        let d = crate::real::dvec3(self.d) + m64 * a;
        Transform {
            m: self.m,
            d: crate::real::vec3(d),
            inv: self.inv,
            inv_d: crate::real::vec3(-(inv64 * d)),
        }
    }

    /// Linear part, `world_from_object` (column-vector convention).
    pub fn matrix(&self) -> Mat3 {
        self.m
    }

    /// Translation part.
    pub fn translation(&self) -> Vec3 {
        self.d
    }

    /// Linear part of the inverse.
    pub fn inverse_matrix(&self) -> Mat3 {
        self.inv
    }

    /// Maps a point to the outer space: `m·p + d`.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        mul(&self.m, p) + self.d
    }

    /// Maps a point and its error bound to the outer space (see [`map_point_with_error`]).
    #[inline]
    pub fn point_with_error(&self, p: Vec3, err: Vec3) -> (Vec3, Vec3) {
        map_point_with_error(&self.m, self.d, p, err)
    }

    /// Maps a vector to the outer space: `m·v`.
    #[inline]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        mul(&self.m, v)
    }

    /// Maps a normal to the outer space: `m⁻ᵀ·n` (not renormalized).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        map_normal(&self.inv, n)
    }

    /// Maps a point to the inner space: `m⁻¹·(p − d)`.
    #[inline]
    pub fn inv_point(&self, p: Vec3) -> Vec3 {
        mul(&self.inv, p - self.d)
    }

    /// Maps a vector to the inner space: `m⁻¹·v`.
    #[inline]
    pub fn inv_vector(&self, v: Vec3) -> Vec3 {
        mul(&self.inv, v)
    }

    /// Maps a ray to the inner space. The direction is not renormalized.
    #[inline]
    pub fn inv_ray(&self, r: &Ray) -> Ray {
        Ray::new(self.inv_point(r.o), self.inv_vector(r.d))
    }

    /// Bounds of the image of a box (the box of its eight mapped corners).
    pub fn bounds(&self, b: &Aabb) -> Aabb {
        if !b.is_finite() {
            return Aabb {
                min: Vec3::splat(Real::NEG_INFINITY),
                max: Vec3::splat(Real::INFINITY),
            };
        }
        let mut out = Aabb::EMPTY;
        for c in b.corners() {
            out.grow(self.point(c));
        }
        out
    }
}

/// Maps a point and its error bound by `m·p + d` (pbrt's rule): the new bound is
/// `γ(3)·(|m|·|p| + |d|) + (1 + γ(3))·|m|·err`. A free function so that a caller holding
/// the matrix in another form (the aggregate's compact spheres) computes the same bits.
#[inline]
pub(crate) fn map_point_with_error(m: &Mat3, d: Vec3, p: Vec3, err: Vec3) -> (Vec3, Vec3) {
    let m = Mat3A::from(*m);
    let (d, p, err) = (Vec3A::from(d), Vec3A::from(p), Vec3A::from(err));
    let am = Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
    let g = crate::real::gamma(3);
    let e = (am * p.abs() + d.abs()) * g + am * err * (1.0 + g);
    (Vec3::from(m * p + d), Vec3::from(e))
}

/// Maps a normal by `m⁻ᵀ`, given `inv = m⁻¹` (not renormalized).
#[inline]
pub(crate) fn map_normal(inv: &Mat3, n: Vec3) -> Vec3 {
    mul(&inv.transpose(), n)
}

/// `m·v`, with glam's operations in glam's order (`Mat3`'s product: the columns times
/// v's components, summed left to right), so the same bits, but in the `f32` build on all
/// three components at once in a SIMD register ([`Mat3A`]): a record mapped out of an
/// instance took 35 % fewer instructions than by `Mat3`'s product, which works component
/// by component (the time about the same: renderer/docs/performance.md).
#[inline(always)]
pub(crate) fn mul(m: &Mat3, v: Vec3) -> Vec3 {
    Vec3::from(Mat3A::from(*m) * Vec3A::from(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A counter through the sampler's `mix64` (as the lanes' tests draw).
    struct Gen(u64);

    impl Gen {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            crate::sampler::mix64(self.0)
        }

        /// Mostly ordinary numbers of mixed sizes; one in four an awkward one (a signed
        /// zero, a subnormal, the largest finite, an infinity, a NaN).
        fn value(&mut self) -> Real {
            let awkward = [
                0.0,
                -0.0,
                Real::MIN_POSITIVE / 4.0,
                -Real::MAX,
                Real::INFINITY,
                Real::NEG_INFINITY,
                Real::NAN,
                1.0,
            ];
            let h = self.next();
            if h % 4 == 0 {
                return awkward[(h >> 8) as usize % awkward.len()];
            }
            let unit = (h >> 11) as f64 / (1u64 << 53) as f64;
            let exp = ((h >> 2) % 40) as i32 - 20;
            ((unit * 2.0 - 1.0) * 2f64.powi(exp)) as Real
        }

        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.value(), self.value(), self.value())
        }

        fn mat(&mut self) -> Mat3 {
            Mat3::from_cols(self.vec(), self.vec(), self.vec())
        }
    }

    /// The bits of each component, every NaN as one: which of two NaN operands an
    /// operation passes on depends on the operands' order, which the compiler may swap
    /// (Rust promises no NaN's bits), so no two builds of one expression need agree there.
    fn bits(v: Vec3) -> [u64; 3] {
        v.to_array().map(|x| {
            if x.is_nan() {
                u64::MAX
            } else {
                x.to_bits() as u64
            }
        })
    }

    /// `mul` and `map_point_with_error` compute with [`Mat3A`] what glam's [`Mat3`]
    /// computes, with the same bits (signed zeros included; a NaN is a NaN): the
    /// instances' maps (and the lanes, which repeat them in glam's order) rest on it.
    #[test]
    fn products_in_registers_are_glams_bit_for_bit() {
        let mut g = Gen(0x9e37_79b9_7f4a_7c15);
        for case in 0..50_000 {
            let (m, d, p, err) = (g.mat(), g.vec(), g.vec(), g.vec());
            assert_eq!(
                bits(mul(&m, p)),
                bits(m * p),
                "case {case}: mul({m:?}, {p:?})"
            );
            let am = Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
            let gm = crate::real::gamma(3);
            let want_e = (am * p.abs() + d.abs()) * gm + am * err * (1.0 + gm);
            let (q, e) = map_point_with_error(&m, d, p, err);
            assert_eq!(
                (bits(q), bits(e)),
                (bits(m * p + d), bits(want_e)),
                "case {case}: map_point_with_error({m:?}, {d:?}, {p:?}, {err:?})"
            );
            assert_eq!(
                bits(map_normal(&m, p)),
                bits(m.transpose() * p),
                "case {case}"
            );
        }
    }
}
