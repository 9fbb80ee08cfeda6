//! POV-Ray 3.7: the SDL exporter, reference generation, the deterministic pixel-centre
//! comparison with its harness and outcome, and [`PovRay`], the whole as a
//! [`crate::reference::Reference`].

pub mod compare;
pub mod harness;
pub mod outcome;
pub mod reference;
pub mod refgen;
pub mod sdl;

pub use reference::PovRay;
pub use sdl::export;
