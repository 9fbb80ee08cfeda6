//! The conformance harness: the scene catalog, exporters to POV-Ray SDL and Mitsuba XML,
//! image metrics and the report.

pub mod catalog;
pub mod compare;
pub mod harness;
pub mod manifest;
pub mod mitsuba;
pub mod mitsuba_harness;
pub mod povray;
pub mod refgen;
pub mod report;
pub mod stats;
