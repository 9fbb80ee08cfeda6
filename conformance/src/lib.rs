//! The conformance harness. What every reference shares sits at the top (the scene catalog,
//! the manifest of references, the verdict, the [`reference::Reference`] interface and the
//! [`registry`] of references, the gate, the waivers, the report); each reference renderer
//! has its own folder with its exporter, reference generation, comparison and its
//! `Reference` (`povray/`, `mitsuba/`). A further reference is one more folder and one
//! line in `registry.rs` (conformance/docs/references.md).

pub mod catalog;
pub mod checked;
pub mod cycles;
pub mod gate;
pub mod images;
pub mod manifest;
pub mod mitsuba;
pub mod oracle;
pub mod placement;
pub mod povray;
pub mod reference;
pub mod registry;
pub mod report;
pub mod verdict;
pub mod waivers;
