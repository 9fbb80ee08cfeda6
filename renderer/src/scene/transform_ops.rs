//! The transform operations of the file (translate, rotate, scale, shear, matrix) as
//! affine maps in f64.

use super::format::dv;
use super::format::{ScaleArg, TransformOp};
use crate::transform::Affine64;
use glam::{DMat3, DVec3};

/// The affine map of one transform operation.
pub fn op_affine(op: &TransformOp) -> Result<Affine64, String> {
    Ok(match op {
        TransformOp::Translate(v) => Affine64::translate(dv(*v)),
        TransformOp::Rotate { axis, degrees } => {
            let a = dv(*axis);
            if !(a.length() > 0.0 && a.is_finite()) {
                return Err("the rotation axis is a zero-length or non-finite vector".into());
            }
            if !degrees.is_finite() {
                return Err("the rotation angle is not finite".into());
            }
            Affine64::linear(DMat3::from_axis_angle(a.normalize(), degrees.to_radians()))
        }
        TransformOp::Scale(ScaleArg::Uniform(s)) => {
            Affine64::linear(DMat3::from_diagonal(DVec3::splat(*s)))
        }
        TransformOp::Scale(ScaleArg::PerAxis(s)) => Affine64::linear(DMat3::from_diagonal(dv(*s))),
        TransformOp::Shear(s) => Affine64::linear(DMat3::from_cols(
            DVec3::new(1.0, s.yx, s.zx),
            DVec3::new(s.xy, 1.0, s.zy),
            DVec3::new(s.xz, s.yz, 1.0),
        )),
        TransformOp::Matrix(rows) => Affine64 {
            m: DMat3::from_cols(dv(rows[0]), dv(rows[1]), dv(rows[2])),
            d: dv(rows[3]),
        },
    })
}
