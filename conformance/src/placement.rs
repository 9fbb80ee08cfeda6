//! A scene's instances flattened to leaf shapes placed in world space, for the exporters
//! that write every shape with its own matrix (Mitsuba's XML, Cycles' JSON): definitions
//! and groups are walked through, their maps composed, and a material inherited from the
//! enclosing instance resolved.

use glam::DMat3;
use renderer::aggregate::{Aggregate, Instance, Shape, INHERIT};
use renderer::real::dvec3;
use renderer::transform::Affine64;

/// Calls `leaf(instance, world_from_object, material)` for every shape under `agg` that
/// is not a group, in scene order; `outer` places `agg`, `inherited` is the material of
/// the enclosing instance (`None` at the top: material 0). A shape in mixed precision is
/// given as the scene placed it ([`Instance::unanchored`]). Each instance's map is
/// rounded to f32 first, so that the f32 and f64 builds compose the same numbers in the
/// same f64 arithmetic and export the same text (and the references stay shared).
pub fn each_leaf<E>(
    agg: &Aggregate,
    outer: &Affine64,
    inherited: Option<u32>,
    leaf: &mut impl FnMut(&Instance, &Affine64, u32) -> Result<(), E>,
) -> Result<(), E> {
    for inst in agg.in_scene_order() {
        let inst = &*inst.unanchored();
        let local = match &inst.xf {
            Some(x) => Affine64 {
                m: DMat3::from_cols_array(&x.matrix().to_cols_array().map(|v| v as f32 as f64)),
                d: dvec3(x.translation()).as_vec3().as_dvec3(),
            },
            None => Affine64::IDENTITY,
        };
        let world = outer.compose(&local);
        let material = if inst.material == INHERIT {
            inherited.unwrap_or(0)
        } else {
            inst.material
        };
        match &inst.shape {
            Shape::Group(g) => each_leaf(g, &world, Some(material), leaf)?,
            _ => leaf(inst, &world, material)?,
        }
    }
    Ok(())
}
