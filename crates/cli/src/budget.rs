//! The step budget's diagnoses in the command line's terms: what happened (the
//! library's [`mech::StepBudget::what_happened`]) and what to do about it,
//! naming the flags (`--until`, `--rtol`, `--method`).

use crate::diagnostics::Failure;
use mech::{BudgetAdvice, StepBudget};
use num::Method;

/// A run refused before it started (exit 2): the estimate, and what to do.
pub fn refused(b: &StepBudget) -> Failure {
    Failure::Input { file: "command line".into(), message: b.what_happened(), located: None, help: Some(advice(b)) }
}

/// The message of a run that stopped on its budget midway (exit 1).
pub fn ran_out(b: &StepBudget) -> String {
    format!("{}; {}", b.what_happened(), advice(b))
}

/// What would let the run fit, with the flags that do it.
fn advice(b: &StepBudget) -> String {
    let reach = mech::approx(b.reach);
    match b.advice() {
        BudgetAdvice::ShorterRun => {
            format!("any method follows such motion step by step: give a shorter --until (at most about {reach})")
        }
        BudgetAdvice::ImplicitMethod => format!(
            "a decay that much faster than the run is stiff: --method radau5 (implicit) steps over it; or give a shorter --until (at most about {reach})"
        ),
        BudgetAdvice::HigherOrder => {
            let higher = match b.method {
                Method::Verlet | Method::Yoshida4 | Method::KahanLi6 => "kahanli8",
                Method::Gauss2 | Method::Gauss4 => "gauss6",
                _ => "dop853 or taylor",
            };
            format!(
                "the step is set by the tolerance on a method of order {}: one of higher order (--method {higher}) takes far fewer steps; or give a looser --rtol, or a shorter --until (at most about {reach})",
                b.method.order()
            )
        }
        BudgetAdvice::LooserTolerance => format!(
            "give a looser --rtol (fewer steps for the same motion), or a shorter --until (at most about {reach})"
        ),
    }
}
