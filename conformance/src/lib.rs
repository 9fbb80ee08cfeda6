//! The conformance harness. What every reference shares sits at the top (the scene catalog,
//! the manifest of references, the verdict, the report); each reference renderer has its
//! own folder with its exporter, reference generation and comparison (`povray/`,
//! `mitsuba/`), so a third reference is one more folder.

pub mod catalog;
pub mod cycles;
pub mod gate;
pub mod images;
pub mod manifest;
pub mod mitsuba;
pub mod povray;
pub mod report;
pub mod verdict;
pub mod waivers;
