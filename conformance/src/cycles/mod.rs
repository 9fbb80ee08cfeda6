//! Blender Cycles (through `bpy`, Blender as a Python module): the JSON exporter, reference
//! generation (a geometry render and K radiance seeds), the reference files, and the
//! harness, which applies Mitsuba's statistical and geometric tests.

pub mod export;
pub mod harness;
pub mod refgen;
pub mod refs;

pub use export::export;
