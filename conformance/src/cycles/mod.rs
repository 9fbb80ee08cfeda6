//! Blender Cycles (through `bpy`, Blender as a Python module): the JSON exporter, reference
//! generation (a geometry render and K radiance seeds), the reference files, the harness
//! and outcome (Mitsuba's statistical and geometric tests), and [`Cycles`], the whole as a
//! [`crate::reference::Reference`].

pub mod export;
pub mod harness;
pub mod outcome;
pub mod reference;
pub mod refgen;
pub mod refs;

pub use export::export;
pub use reference::Cycles;
