//! Mitsuba 3: the XML exporter, reference generation (geometry and `moment` radiance), the
//! statistical and geometric tests, and their harness.

pub mod harness;
pub mod refgen;
pub mod stats;
pub mod xml;

pub use xml::export;
