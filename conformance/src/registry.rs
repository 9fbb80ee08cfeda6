//! The references the gate checks against, in one list: the gate, the report, the
//! waivers, the command line and the gate's tests iterate over a [`Registry`] and name no
//! reference themselves. Adding a reference is its folder (`conformance/src/<name>/`, a
//! type implementing [`Reference`]) and one line in [`COMMITTED`]
//! (conformance/docs/references.md).

use crate::catalog::{choose, scenes, Entry, Source};
use crate::reference::Reference;
use anyhow::{Context, Result};

/// The references of this repository, one line each, in the order the report and the
/// gate list them.
pub static COMMITTED: [&dyn Reference; 4] = [
    &crate::povray::PovRay,
    &crate::mitsuba::Mitsuba,
    &crate::oracle::ClosedForm,
    &crate::cycles::Cycles,
];

/// A set of references with distinct names.
#[derive(Clone, Debug)]
pub struct Registry {
    references: Vec<&'static dyn Reference>,
}

impl Registry {
    /// The committed references ([`COMMITTED`]).
    pub fn committed() -> Registry {
        Registry::new(COMMITTED.to_vec()).expect("the committed references have distinct names")
    }

    /// A registry of `references`, in this order; two of the same name are an error.
    pub fn new(references: Vec<&'static dyn Reference>) -> Result<Registry> {
        for (k, r) in references.iter().enumerate() {
            anyhow::ensure!(
                !references[..k].iter().any(|q| q.name() == r.name()),
                "two references are named `{}`",
                r.name()
            );
            anyhow::ensure!(
                !r.name().is_empty()
                    && r.name()
                        .chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'),
                "a reference's name `{}` must be lower-case letters, digits and underscores \
(it names a folder, tests and manifest keys)",
                r.name()
            );
        }
        Ok(Registry { references })
    }

    /// This registry and `reference` after it.
    pub fn with(&self, reference: &'static dyn Reference) -> Result<Registry> {
        let mut v = self.references.clone();
        v.push(reference);
        Registry::new(v)
    }

    /// The references, in order.
    pub fn iter(&self) -> impl Iterator<Item = &'static dyn Reference> + '_ {
        self.references.iter().copied()
    }

    /// Their names, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.iter().map(|r| r.name()).collect()
    }

    /// The reference named `name`, or an error that lists the names.
    pub fn get(&self, name: &str) -> Result<&'static dyn Reference> {
        self.iter().find(|r| r.name() == name).with_context(|| {
            format!(
                "unknown reference `{name}` (one of: {})",
                self.names().join(", ")
            )
        })
    }

    /// Where the reference named `name` comes in the order (past the end when unknown).
    pub fn position(&self, name: &str) -> usize {
        self.iter()
            .position(|r| r.name() == name)
            .unwrap_or(self.references.len())
    }

    /// The catalogs the references check, in order of first use.
    pub fn catalogs(&self) -> Vec<&'static str> {
        let mut v: Vec<&'static str> = Vec::new();
        for r in self.iter() {
            if !v.contains(&r.catalog()) {
                v.push(r.catalog());
            }
        }
        v
    }

    /// The references that check scenes of `catalog`, in order.
    pub fn of_catalog(&self, catalog: &str) -> Vec<&'static dyn Reference> {
        self.iter().filter(|r| r.catalog() == catalog).collect()
    }

    /// The scenes `reference` checks: those of its catalog that it covers, by name.
    pub fn scenes(&self, reference: &dyn Reference) -> Result<Vec<Entry>> {
        let all = scenes(reference.catalog(), "")
            .with_context(|| format!("reading conformance/scenes/{}/", reference.catalog()))?;
        let mut v = Vec::new();
        for e in all {
            let covered = reference.covers(&e).with_context(|| {
                format!("{}: does {} cover it", e.path.display(), reference.name())
            })?;
            if covered {
                v.push(e);
            }
        }
        Ok(v)
    }

    /// The (reference, scene) pairs a command line's FILTER selects, in reference then
    /// name order; `NAME::SCENE` looks at the reference NAME's scenes only
    /// ([`crate::catalog::choose`]).
    pub fn select(&self, filter: &str) -> Result<Vec<(&'static dyn Reference, Entry)>> {
        let sources: Vec<Source<'_, &'static dyn Reference>> = self
            .iter()
            .map(|r| Source {
                key: r,
                name: r.name(),
                folder: r.catalog(),
                list: Box::new(move || self.scenes(r)),
            })
            .collect();
        choose(&sources, filter)
    }

    /// The scenes of `reference` a FILTER selects (a `NAME::` prefix must be its name).
    pub fn select_for(&self, reference: &dyn Reference, filter: &str) -> Result<Vec<Entry>> {
        let source = Source {
            key: (),
            name: reference.name(),
            folder: reference.catalog(),
            list: Box::new(|| self.scenes(reference)),
        };
        Ok(choose(&[source], filter)?
            .into_iter()
            .map(|(_, e)| e)
            .collect())
    }
}
