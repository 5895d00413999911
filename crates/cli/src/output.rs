//! What the analyses' outputs share: the `--format` of `modes`, `orbit`, `top`,
//! `inertia` and `extremal`. Their text (and numbers for people) is `view`'s.
//! Each command's `--format` help names its own JSON schema; the values' help
//! here is shared, so it names none.

/// Output formats of the analyses.
#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
pub enum ReportFormat {
    /// Text that reads like the lecture notes.
    Text,
    /// JSON, in the command's own schema (`lagrange.<command>/1`, named above).
    Json,
}
