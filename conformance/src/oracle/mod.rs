//! An independent closed-form oracle for the classic (POV-Ray-checked) catalog scenes:
//! our own `f64` re-derivation of POV-Ray 3.7's Whitted model, separate from the renderer's
//! code, so that when our renderer and POV-Ray disagree a third opinion settles it
//! (conformance/docs/oracle.md).
//!
//! - `world.rs`: the scene flattened to primitives with `f64` maps, or why it is declined;
//! - `camera.rs`: rays from the viewing model;
//! - `shapes.rs`: closed-form intersections;
//! - `intersect.rs`: the closest hit, instances mapped by M⁻¹ and normals by M⁻ᵀ;
//! - `shade.rs`: POV-Ray's illumination terms and recursion;
//! - `vote.rs`: the three-way comparison with POV-Ray and our renderer;
//! - `render.rs`: the oracle for one scene, its image and its re-traced samples;
//! - `harness.rs`, `outcome.rs`, `reference.rs`: the oracle as a registered reference.

pub mod camera;
pub mod harness;
pub mod intersect;
pub mod outcome;
pub mod reference;
pub mod render;
pub mod shade;
pub mod shapes;
pub mod vote;
pub mod world;

pub use reference::ClosedForm;
pub use render::Oracle;
