//! The conformance harness: the scene catalog, exporters to POV-Ray SDL and Mitsuba XML,
//! image metrics and the report.

pub mod povray;
