//! POV-Ray 3.7: the SDL exporter, reference generation, and the deterministic pixel-centre
//! comparison with its harness.

pub mod compare;
pub mod harness;
pub mod refgen;
pub mod sdl;

pub use sdl::export;
