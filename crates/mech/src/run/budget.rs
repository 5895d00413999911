//! A run's step budget (`RunConfig::max_steps`): the estimate that refuses a
//! fixed step which cannot reach the end time before the run starts, the
//! diagnosis of an adaptive run that spent its budget or was foreseen to
//! exceed it ([`StepBudget`]), the motion's fastest time scale that explains
//! why ([`TimeScale`]), and what to do about it ([`BudgetAdvice`]).
//!
//! Entry points: [`StepBudget::refused`] (from `plain.rs`, after the step of a
//! fixed-step method is chosen) and [`StepBudget::ran_out`] (from the driver,
//! when the solver stops on its budget).

use num::{Method, OdeSystem, SolveError, Solver};
use std::fmt;

/// The fastest time scale of the motion at a state, from the eigenvalue of
/// largest modulus of the Jacobian of the equations of motion there.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TimeScale {
    /// An oscillation (a complex pair ±iω dominates): its period 2π/ω.
    Oscillation {
        /// The period.
        period: f64,
    },
    /// A decay (a negative real part dominates): its time constant 1/|Re λ|.
    /// Much shorter than the run, it is stiff: an implicit method steps over it.
    Decay {
        /// The time constant.
        time_constant: f64,
    },
    /// Neighbouring motions separating (a positive real part dominates): the
    /// time 1/Re λ in which they separate by a factor e.
    Divergence {
        /// The e-folding time.
        time_constant: f64,
    },
}

impl TimeScale {
    /// The period or time constant.
    pub fn seconds(&self) -> f64 {
        match *self {
            TimeScale::Oscillation { period } => period,
            TimeScale::Decay { time_constant } | TimeScale::Divergence { time_constant } => time_constant,
        }
    }

    /// What the time is, in words: "the period of an oscillation".
    pub fn meaning(&self) -> &'static str {
        match self {
            TimeScale::Oscillation { .. } => "the period of an oscillation",
            TimeScale::Decay { .. } => "the time constant of a decay",
            TimeScale::Divergence { .. } => "the time in which neighbouring motions separate by a factor e",
        }
    }

    /// The time scale of `system` at (t, y); None when the Jacobian is not
    /// finite or vanishes (no motion to speak of).
    pub(crate) fn of(system: &mut impl OdeSystem, t: f64, y: &[f64]) -> Option<TimeScale> {
        let n = y.len();
        let mut jac = vec![0.0; n * n];
        system.jacobian(t, y, &mut jac).ok()?;
        if jac.iter().any(|v| !v.is_finite()) {
            return None;
        }
        // Our QR iteration (bounded, an error rather than a panic on a
        // nilpotent Jacobian, where nalgebra's Schur indexes out of bounds);
        // if it does not converge the time scale is left untold.
        let eigenvalues: Vec<nalgebra::Complex<f64>> =
            num::eigenvalues(n, &jac).ok()?.into_iter().map(|(re, im)| nalgebra::Complex::new(re, im)).collect();
        let fastest = eigenvalues.iter().copied().max_by(|a, b| a.norm().total_cmp(&b.norm()))?;
        if !(fastest.norm() > 0.0 && fastest.norm().is_finite()) {
            return None;
        }
        if fastest.im.abs() >= fastest.re.abs() {
            return Some(TimeScale::Oscillation { period: std::f64::consts::TAU / fastest.im.abs() });
        }
        // Real parts dominate. A Hamiltonian system's come in pairs ±λ: the
        // separating one is the one that tells.
        let re_max = eigenvalues.iter().map(|e| e.re).fold(f64::NEG_INFINITY, f64::max);
        let re_min = eigenvalues.iter().map(|e| e.re).fold(f64::INFINITY, f64::min);
        Some(if re_max >= -re_min * (1.0 - 1e-6) {
            TimeScale::Divergence { time_constant: 1.0 / re_max }
        } else {
            TimeScale::Decay { time_constant: 1.0 / -re_min }
        })
    }
}

/// Where a run met its step budget.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BudgetStage {
    /// Before it started: a fixed step that cannot reach the end time.
    Refused,
    /// Midway, before spending it: its pace foreseen far beyond it.
    Foreseen,
    /// Midway, having spent it.
    Spent,
}

/// A run that its step budget cannot carry to its end time, as data.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StepBudget {
    /// Where the run met its budget.
    pub stage: BudgetStage,
    /// The method.
    #[serde(serialize_with = "method_name")]
    pub method: Method,
    /// The fixed step, or the adaptive method's last step.
    pub step: f64,
    /// The time reached (0 for a refused run).
    pub t: f64,
    /// The steps taken (0 for a refused run).
    pub steps: usize,
    /// The steps the whole run would take, estimated from its step or pace.
    pub steps_needed: f64,
    /// The right-hand-side evaluations the whole run would take, estimated
    /// from the evaluations per step.
    pub rhs_evaluations_needed: f64,
    /// The most steps a run takes.
    pub max_steps: usize,
    /// The end time.
    pub until: f64,
    /// The time the budget reaches at this step or pace.
    pub reach: f64,
    /// The motion's fastest time scale where the budget was met (None when it
    /// cannot be told).
    pub time_scale: Option<TimeScale>,
}

fn method_name<S: serde::Serializer>(method: &Method, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(method.name())
}

/// A method following a motion takes at least about this many steps per period
/// or time constant (an explicit 8th-order method at rtol 1e-9 takes 15 to 25
/// per period of an oscillation); a run holding more time scales than the
/// budget covers at this rate is too long for the motion, whatever the
/// tolerance or method.
pub const STEPS_PER_TIME_SCALE: f64 = 10.0;

/// What would let the run fit its budget, most helpful first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BudgetAdvice {
    /// The motion is fast for the run (an oscillation, or a divergence): any
    /// method follows it step by step, so the run must be shorter.
    ShorterRun,
    /// A fast decay (stiffness): an implicit method (radau5) steps over it.
    ImplicitMethod,
    /// The step is set by the tolerance on a method of low order: one of
    /// higher order (or a looser tolerance) takes far fewer steps.
    HigherOrder,
    /// The method is of high order already: a looser tolerance or a shorter run.
    LooserTolerance,
}

impl StepBudget {
    /// A fixed step `step` of `method` that cannot reach `until` within
    /// `max_steps`, with the evaluations per step and the time scale at the start;
    /// None when it can.
    pub(crate) fn refused(
        method: Method,
        step: f64,
        until: f64,
        max_steps: usize,
        rhs_per_step: f64,
        time_scale: impl FnOnce() -> Option<TimeScale>,
    ) -> Option<StepBudget> {
        let steps_needed = until / step;
        (steps_needed > max_steps as f64).then(|| StepBudget {
            stage: BudgetStage::Refused,
            method,
            step,
            t: 0.0,
            steps: 0,
            steps_needed,
            rhs_evaluations_needed: steps_needed * rhs_per_step,
            max_steps,
            until,
            reach: step * max_steps as f64,
            time_scale: time_scale(),
        })
    }

    /// The budget a solver stopped on (`MaxStepsExceeded`, `MaxStepsForeseen`),
    /// or None for any other error.
    pub(crate) fn ran_out(
        e: &SolveError,
        solver: &dyn Solver,
        until: f64,
        time_scale: impl FnOnce() -> Option<TimeScale>,
    ) -> Option<StepBudget> {
        let stats = solver.statistics();
        let (stage, t, steps, max_steps) = match *e {
            SolveError::MaxStepsExceeded { t, max_steps } => (BudgetStage::Spent, t, stats.steps, max_steps),
            SolveError::MaxStepsForeseen { t, steps, max_steps, .. } => (BudgetStage::Foreseen, t, steps, max_steps),
            _ => return None,
        };
        // The pace over the whole run so far; the foresight's estimate, from
        // its recent steps, where it stopped the run.
        let pace = steps as f64 / t;
        let steps_needed = match *e {
            SolveError::MaxStepsForeseen { projected, .. } => projected,
            _ => pace * until,
        };
        Some(StepBudget {
            stage,
            method: solver.method(),
            step: solver.step_size(),
            t,
            steps,
            steps_needed,
            rhs_evaluations_needed: steps_needed * stats.rhs_evaluations as f64 / steps.max(1) as f64,
            max_steps,
            until,
            reach: if stage == BudgetStage::Spent { t } else { max_steps as f64 / pace },
            time_scale: time_scale(),
        })
    }

    /// What would let the run fit, most helpful first.
    pub fn advice(&self) -> BudgetAdvice {
        let fast =
            self.time_scale.is_some_and(|ts| self.until / ts.seconds() * STEPS_PER_TIME_SCALE > self.max_steps as f64);
        match self.time_scale {
            Some(TimeScale::Decay { .. }) if fast && self.method != Method::Radau5 => BudgetAdvice::ImplicitMethod,
            _ if fast => BudgetAdvice::ShorterRun,
            _ if self.method.order() < 8 && self.method != Method::Taylor => BudgetAdvice::HigherOrder,
            _ => BudgetAdvice::LooserTolerance,
        }
    }

    /// What happened, without the advice: the facts of a diagnosis.
    pub fn what_happened(&self) -> String {
        let method = self.method.name();
        let (needed, reach) = (approx(self.steps_needed), approx(self.reach));
        let mut s = match self.stage {
            BudgetStage::Refused => format!(
                "{method} would take {needed} steps of {} (about {} evaluations of the equations of motion) to reach t = {}, more than the {} steps a run may take, which reach t ≈ {reach}",
                approx(self.step),
                approx(self.rhs_evaluations_needed),
                num::Shortest(self.until),
                self.max_steps
            ),
            BudgetStage::Foreseen => format!(
                "{method} stopped early, at t = {} after {} steps: at its pace (steps of about {}) reaching t = {} would take about {needed} steps, more than {} times the {} steps a run may take, which reach t ≈ {reach}",
                num::Shortest(self.t),
                self.steps,
                approx(self.step),
                num::Shortest(self.until),
                num::FORESIGHT_MARGIN,
                self.max_steps
            ),
            BudgetStage::Spent => format!(
                "{method} took the {} steps a run may take and reached t = {} of {} (its last step {}); at that pace the run needs about {needed} steps",
                self.max_steps,
                num::Shortest(self.t),
                num::Shortest(self.until),
                approx(self.step)
            ),
        };
        if let Some(ts) = self.time_scale {
            s.push_str(&format!(
                ". The motion's fastest time scale {} is {} ({}), {} times shorter than the run",
                if self.stage == BudgetStage::Refused { "at the start" } else { "there" },
                approx(ts.seconds()),
                ts.meaning(),
                approx(self.until / ts.seconds())
            ));
        }
        s
    }
}

impl fmt::Display for StepBudget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let advice = match self.advice() {
            BudgetAdvice::ShorterRun => "any method follows such motion step by step: a shorter run fits".to_string(),
            BudgetAdvice::ImplicitMethod => {
                "a decay that much faster than the run is stiff: an implicit method (radau5) steps over it".to_string()
            }
            BudgetAdvice::HigherOrder => format!(
                "the step is set by the tolerance on a method of order {}: a method of higher order or a looser tolerance takes far fewer steps",
                self.method.order()
            ),
            BudgetAdvice::LooserTolerance => "a looser tolerance takes fewer steps, or a shorter run fits".to_string(),
        };
        write!(f, "{}; {advice}", self.what_happened())
    }
}

/// A number to three significant digits, as the diagnoses print estimates:
/// positional from 10⁻³ to below 10⁶ (`2.86`, `143000`), scientific beyond
/// (`3.50e7`).
pub fn approx(v: f64) -> String {
    let scientific = format!("{v:.2e}");
    let rounded: f64 = scientific.parse().unwrap_or(v);
    if !(1e-3..1e6).contains(&rounded.abs()) {
        return scientific;
    }
    let decimals = (2 - rounded.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{rounded:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num::RhsError;

    /// x'' = −k x − c x' as y = [x, x'].
    struct Oscillator {
        k: f64,
        c: f64,
    }

    impl OdeSystem for Oscillator {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = y[1];
            dy[1] = -self.k * y[0] - self.c * y[1];
            Ok(())
        }
    }

    #[track_caller]
    fn check(k: f64, c: f64, expect: Option<TimeScale>) {
        let found = TimeScale::of(&mut Oscillator { k, c }, 0.0, &[1.0, 0.0]);
        match (found, expect) {
            (Some(found), Some(expect)) => {
                let rel = (found.seconds() - expect.seconds()).abs() / expect.seconds();
                let same_kind = std::mem::discriminant(&found) == std::mem::discriminant(&expect);
                assert!(same_kind && rel < 1e-6, "{found:?}, expected {expect:?}");
            }
            _ => assert_eq!(found, expect),
        }
    }

    #[test]
    fn time_scales_of_oscillators() {
        use std::f64::consts::TAU;
        check(1e12, 0.0, Some(TimeScale::Oscillation { period: TAU / 1e6 }));
        check(4.0, 0.1, Some(TimeScale::Oscillation { period: TAU / (4.0 - 0.0025f64).sqrt() }));
        // Overdamped: the roots −c/2 ± sqrt(c²/4 − k); the fast one ≈ −c.
        let fast = -(1e4 / 2.0) - (1e8 / 4.0 - 1.0f64).sqrt();
        check(1.0, 1e4, Some(TimeScale::Decay { time_constant: -1.0 / fast }));
        // Upside down (x'' = x): neighbours separate like e^t.
        check(-1.0, 0.0, Some(TimeScale::Divergence { time_constant: 1.0 }));
        // A free particle: nothing to tell.
        check(0.0, 0.0, None);
    }

    /// y' = J y for a fixed J, with its exact Jacobian.
    struct Linear(Vec<f64>);

    impl OdeSystem for Linear {
        fn dim(&self) -> usize {
            (self.0.len() as f64).sqrt() as usize
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            let n = y.len();
            for i in 0..n {
                dy[i] = (0..n).map(|j| self.0[i * n + j] * y[j]).sum();
            }
            Ok(())
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
            jac.copy_from_slice(&self.0);
            Ok(())
        }
    }

    #[test]
    fn nilpotent_jacobians_tell_no_fast_time_scale() {
        // A 4×4 Jordan block (a chain x' = v, v' = a, a' = j, j' = 0) and a
        // shifted-cycle nilpotent 3×3, inputs nalgebra's Schur could not
        // take: every eigenvalue is 0, so no time scale, or a very long one.
        let mut jordan = vec![0.0; 16];
        for i in 0..3 {
            jordan[i * 4 + i + 1] = 1.0;
        }
        let cycle = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        for j in [jordan, cycle] {
            let n = (j.len() as f64).sqrt() as usize;
            let found = TimeScale::of(&mut Linear(j), 0.0, &vec![1.0; n]);
            assert!(found.is_none_or(|f| f.seconds() > 1e2), "{found:?}");
        }
    }

    #[test]
    fn advice_follows_the_time_scale_and_the_order() {
        let budget = |method, time_scale| StepBudget {
            stage: BudgetStage::Spent,
            method,
            step: 1e-7,
            t: 1.0,
            steps: 10_000_000,
            steps_needed: 1e8,
            rhs_evaluations_needed: 1e9,
            max_steps: 10_000_000,
            until: 10.0,
            reach: 1.0,
            time_scale,
        };
        let fast = |kind: fn(f64) -> TimeScale| Some(kind(1e-6));
        let oscillation = |period| TimeScale::Oscillation { period };
        let decay = |time_constant| TimeScale::Decay { time_constant };
        assert_eq!(budget(Method::Dop853, fast(oscillation)).advice(), BudgetAdvice::ShorterRun);
        assert_eq!(budget(Method::Dop853, fast(decay)).advice(), BudgetAdvice::ImplicitMethod);
        assert_eq!(budget(Method::Radau5, fast(decay)).advice(), BudgetAdvice::ShorterRun);
        assert_eq!(budget(Method::Gauss2, Some(oscillation(2.0))).advice(), BudgetAdvice::HigherOrder);
        assert_eq!(budget(Method::KahanLi8, Some(oscillation(2.0))).advice(), BudgetAdvice::LooserTolerance);
        assert_eq!(budget(Method::Gauss6, None).advice(), BudgetAdvice::HigherOrder);
        let told = budget(Method::Dop853, fast(oscillation)).to_string();
        assert!(told.contains("dop853 took the 10000000 steps a run may take and reached t = 1 of 10"), "{told}");
        assert!(told.contains("the period of an oscillation"), "{told}");
    }

    #[test]
    fn estimates_read_to_three_digits() {
        assert_eq!(approx(2.8564083521380215), "2.86");
        assert_eq!(approx(142_857.14), "143000");
        assert_eq!(approx(0.0031241), "0.00312");
        assert_eq!(approx(1.4285714e11), "1.43e11");
        assert_eq!(approx(2.5e-5), "2.50e-5");
        assert_eq!(approx(40.0), "40");
    }
}
