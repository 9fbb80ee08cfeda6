//! Mitsuba 3: the XML exporter, reference generation (geometry and `moment` radiance), the
//! statistical and geometric comparison with its harness and outcome, and [`Mitsuba`], the
//! whole as a [`crate::reference::Reference`].

pub mod compare;
pub mod harness;
pub mod outcome;
pub mod reference;
pub mod refgen;
pub mod xml;

pub use reference::Mitsuba;
pub use xml::export;
