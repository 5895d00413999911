//! How a front end spells what a user can ask for. A few sentences of the
//! text outputs point the reader at a setting ("the step was given (--dt)",
//! "see --format json"); the CLI names its flags there, the Python package
//! its arguments. [`Terms`] carries those words, so that view names neither.

/// The words a front end uses for the settings the text outputs mention.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    /// The fixed step of a run (the CLI's `--dt`).
    pub step: &'static str,
    /// The start of the search for an equilibrium, instead of the model's
    /// `[initial]` (the CLI's `--at`).
    pub start_at: &'static str,
    /// The output that lists every number of an analysis (the CLI's
    /// `--format json`).
    pub full_output: &'static str,
    /// The animation of the normal modes (the CLI's `--animate`).
    pub animation: &'static str,
    /// The end time of a run (the CLI's `--until`).
    pub until: &'static str,
    /// The choice of integration method (the CLI's `--method`).
    pub method: &'static str,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::Terms;

    /// Words no flag of the CLI uses, so that a test sees where they land.
    pub(crate) const OTHER: Terms = Terms {
        step: "dt=",
        start_at: "at=",
        full_output: "the report",
        animation: "animate()",
        until: "until=",
        method: "method=",
    };
}
