//! The audit of a run's invariants, row by row, and the warnings for those the
//! derivation calls conserved that drifted more than the tolerance explains.

use super::{Audit, RunWarning};
use crate::derive::Derivation;
use crate::run::dynamics::Dynamics;

/// The audit of the invariants, row by row: the first row is the reference,
/// the drift is the largest departure from it, the final value the last row's.
/// Plain and constrained runs share it.
pub(crate) struct InvariantAudit {
    names: Vec<String>,
    conserved: Vec<bool>,
    initial: Option<Vec<f64>>,
    /// The sum of the jumps at impacts, per invariant.
    jumps: Vec<f64>,
    last: Vec<f64>,
    max_abs: Vec<f64>,
    max_rel: Vec<f64>,
}

impl InvariantAudit {
    /// The audit of the invariants `dynamics` evaluates; H is conserved as the
    /// derivation says, E never on its own, the conserved momenta always.
    pub(crate) fn new(d: &Derivation, dynamics: &Dynamics) -> InvariantAudit {
        let invariants = dynamics.invariants();
        let n = invariants.len();
        InvariantAudit {
            names: invariants.iter().map(|i| i.name.clone()).collect(),
            conserved: invariants
                .iter()
                .map(|inv| if inv.name == "H" { d.hamiltonian_conserved } else { inv.name != "E" })
                .collect(),
            initial: None,
            jumps: vec![0.0; n],
            last: vec![0.0; n],
            max_abs: vec![0.0; n],
            max_rel: vec![0.0; n],
        }
    }

    /// How many invariants there are.
    pub(crate) fn len(&self) -> usize {
        self.names.len()
    }

    /// Records one row's values, every row alike: the states at events are
    /// the method's own or from dense output as accurate as its steps
    /// (`num::Solver::restep`), so their drift is the integrator's.
    pub(crate) fn observe(&mut self, inv: &[f64]) {
        let init = self.initial.get_or_insert_with(|| inv.to_vec());
        for k in 0..inv.len() {
            let a = (inv[k] - init[k] - self.jumps[k]).abs();
            if a.is_finite() {
                self.max_abs[k] = self.max_abs[k].max(a);
                let scale = init[k].abs();
                self.max_rel[k] = self.max_rel[k].max(if scale > 0.0 { a / scale } else { a });
            }
        }
        self.last.copy_from_slice(inv);
    }

    /// Records the jump of the invariants at an impact, from `before` to
    /// `after`: the drift measured after it leaves the jump out.
    pub(crate) fn jump(&mut self, before: &[f64], after: &[f64]) {
        for ((j, b), a) in self.jumps.iter_mut().zip(before).zip(after) {
            *j += a - b;
        }
    }

    /// The sum of each invariant's jumps at impacts so far.
    pub(crate) fn jumps(&self) -> &[f64] {
        &self.jumps
    }

    /// One audit per invariant.
    pub(crate) fn audits(&self) -> Vec<Audit> {
        let initial = self.initial.as_ref().unwrap_or(&self.last);
        (0..self.len())
            .map(|k| Audit {
                name: self.names[k].clone(),
                conserved: self.conserved[k],
                initial: initial[k],
                final_value: self.last[k],
                max_abs_drift: self.max_abs[k],
                max_rel_drift: self.max_rel[k],
                impact_change: self.jumps[k],
            })
            .collect()
    }
}

/// A warning for each conserved invariant that drifted by more than
/// `explained` (relative), the drift the method's tolerance accounts for.
pub(crate) fn drift_warnings(audits: &[Audit], explained: f64) -> Vec<RunWarning> {
    audits
        .iter()
        .filter(|a| a.conserved && a.max_rel_drift > explained)
        .map(|a| RunWarning::Drift { invariant: a.name.clone(), drift: a.max_rel_drift, explained })
        .collect()
}
