//! What the analyses' outputs share: the `--format` of `modes`, `orbit`, `top`,
//! `inertia` and `extremal`. Their text (and numbers for people) is `view`'s.

/// Output formats of the analyses.
#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
pub enum ReportFormat {
    /// Text that reads like the lecture notes.
    Text,
    /// JSON (`lagrange.modes/1`, `lagrange.orbit/1`, ...).
    Json,
}
