//! What `mech`'s integration tests share: the test models of
//! `src/test_models.rs` (the unit tests use the same file) and a run that keeps
//! every row.

#![allow(dead_code)] // each test binary uses some of the helpers

/// The test models, compiled here as part of the test (the library's copy is
/// `cfg(test)`, where `mech` names the crate itself).
#[path = "../../src/test_models.rs"]
mod models;
pub use models::*;

use std::ops::ControlFlow;

/// Every row of a run: (t, q, q', constraint columns).
pub type Rows = Vec<(f64, Vec<f64>, Vec<f64>, Vec<f64>)>;

/// Simulates a derivation and keeps every row.
#[track_caller]
pub fn run(d: &mech::Derivation, config: &mech::RunConfig) -> (mech::RunReport, Rows) {
    let mut rows = Vec::new();
    let report = mech::simulate(d, config, |row| {
        rows.push((row.t, row.q.to_vec(), row.qd.to_vec(), row.constraints.to_vec()));
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("the run failed: {e}"));
    (report, rows)
}
