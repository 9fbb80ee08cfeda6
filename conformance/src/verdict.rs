//! The verdict of one scene against one reference, shared by every reference.

/// The outcome of one scene against one reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Within tolerance and silhouette budget.
    Pass,
    /// Outside tolerance or over budget.
    Fail,
    /// The reference was made from a different scene: never a pass.
    Stale,
    /// No reference.
    Missing,
    /// Fails only in checks that `conformance/waivers.toml` waives: a deliberate
    /// divergence, never a pass.
    Waived,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "FAIL",
            Verdict::Stale => "STALE",
            Verdict::Missing => "MISSING",
            Verdict::Waived => "WAIVED",
        })
    }
}
