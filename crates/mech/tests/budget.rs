//! A run's step budget and its events, through the library's API: a fixed step
//! beyond the budget refused before the run, an adaptive run that spends its
//! budget or is foreseen far beyond it diagnosed as such (not as a blow-up), with
//! the last state reached as its final state, and stop events located to the
//! accuracy of the steps and audited like every row.

use crate::common::{derive, PENDULUM};
use mech::{BudgetAdvice, BudgetStage, Method, RunConfig, RunError, RunFailure, StepBudget, StopCondition, TimeScale};
use std::ops::ControlFlow;

/// A stiff oscillator: k = 10^12 (ω = 10^6, period 2π·10^-6).
const STIFF: &str = r#"
coordinates = ["x"]
kinetic = "m*x'^2/2"
potential = "k*x^2/2"
[parameters]
m = 1.0
k = 1e12
[initial]
x = 1.0
"x'" = 0.0
"#;

/// Runs and expects a failure midway, returning its budget diagnosis, the
/// report and the last row written.
#[track_caller]
fn ran_out(d: &mech::Derivation, config: &RunConfig) -> (StepBudget, mech::RunReport, String, f64) {
    let mut last_row = f64::NAN;
    let result = mech::simulate(d, config, |row| {
        last_row = row.t;
        ControlFlow::Continue(())
    });
    let Err(RunError::Failed { message, report }) = result else { panic!("the run must fail midway: {result:?}") };
    let Some(RunFailure::StepBudget(budget)) = report.failure_reason.clone() else {
        panic!("{:?}: {message}", report.failure_reason)
    };
    (budget, *report, message, last_row)
}

#[test]
fn a_fixed_step_beyond_the_budget_is_refused_before_the_run() {
    let d = derive(STIFF);
    let mut rows = 0;
    let config = RunConfig { until: 10.0, method: Some(Method::KahanLi8), ..RunConfig::default() };
    let e = mech::simulate(&d, &config, |_| {
        rows += 1;
        ControlFlow::Continue(())
    })
    .unwrap_err();
    let RunError::StepBudget(b) = e else { panic!("{e}") };
    assert_eq!(rows, 0);
    assert_eq!((b.stage, b.method, b.steps, b.max_steps), (BudgetStage::Refused, Method::KahanLi8, 0, 10_000_000));
    assert!((b.steps_needed - 10.0 / b.step).abs() < 1e-6 * b.steps_needed, "{b:?}");
    assert!(b.steps_needed > 1e7 && b.step < 2.0 * std::f64::consts::PI * 1e-6, "{b:?}");
    // 15 force evaluations per step of the 15-stage composition.
    assert!((b.rhs_evaluations_needed / b.steps_needed - 15.0).abs() < 0.5, "{b:?}");
    let Some(TimeScale::Oscillation { period }) = b.time_scale else { panic!("{b:?}") };
    assert!((period / (2.0 * std::f64::consts::PI * 1e-6) - 1.0).abs() < 1e-6, "{period}");
    assert_eq!(b.advice(), BudgetAdvice::ShorterRun);
    assert!((b.reach - b.step * 1e7).abs() < 1e-9 * b.reach);
    // A shorter run is run.
    let short = RunConfig { until: 1e-3 * b.reach, ..config };
    let report = mech::simulate(&d, &short, |_| ControlFlow::Continue(())).unwrap();
    assert_eq!(report.method, Method::KahanLi8);
}

#[test]
fn an_adaptive_run_that_spends_its_budget_says_so_and_ends_where_it_stood() {
    let d = derive(STIFF);
    // DOP853 follows the oscillation at about 2.5·10^6 steps per unit time:
    // 0.012 needs about 30 000 steps, twice the budget (short of the
    // foresight's margin, so the budget is spent). The run holds 1900 periods,
    // more than the budget follows at 10 steps each: it is too long for the motion.
    let config = RunConfig { until: 0.012, method: Some(Method::Dop853), max_steps: 15_000, ..RunConfig::default() };
    let (b, report, message, last_row) = ran_out(&d, &config);
    assert_eq!((b.stage, b.steps, report.steps), (BudgetStage::Spent, 15_000, 15_000), "{message}");
    assert!(b.steps_needed > 15_000.0 && b.steps_needed < 60_000.0, "{b:?}");
    assert_eq!(b.advice(), BudgetAdvice::ShorterRun);
    assert!(!message.contains("blew up"), "{message}");
    // The summary's time and final state are where the solver stood, past the
    // last sample; the message says the same time.
    assert_eq!(report.t_final, b.t);
    assert!(b.t > last_row && b.t < config.until, "{} after the row at {last_row}", b.t);
    assert!(message.contains(&format!("reached t = {} of 0.012", b.t)), "{message}");
    let (x, v) = (report.final_q[0], report.final_qd[0]);
    let h = v * v / 2.0 + 1e12 * x * x / 2.0;
    let audit = &report.invariants[0];
    assert_eq!(audit.name, "H");
    assert!((audit.final_value - h).abs() < 1e-12 * h, "{} vs {h}", audit.final_value);
    assert!(audit.max_abs_drift >= (audit.final_value - audit.initial).abs());
}

#[test]
fn an_adaptive_run_foreseen_far_beyond_its_budget_stops_early() {
    let d = derive(PENDULUM);
    let config = RunConfig { until: 1e12, method: Some(Method::Dop853), ..RunConfig::default() };
    let (b, report, message, _) = ran_out(&d, &config);
    assert_eq!(b.stage, BudgetStage::Foreseen, "{message}");
    // At its first checkpoint, a 128th of the budget.
    assert_eq!(report.steps, 10_000_000 / 128);
    assert!(b.steps_needed > 1e12, "{b:?}");
    assert_eq!(report.t_final, b.t);
    assert!(matches!(b.time_scale, Some(TimeScale::Oscillation { .. })), "{b:?}");
    assert!(message.contains("stopped early"), "{message}");
}

#[test]
fn a_stop_event_is_as_accurate_as_the_steps_and_audited_like_every_row() {
    // A swing of one radian: at the bottom, th'² = 2 g/l (1 − cos 1) by energy.
    let d = derive(&PENDULUM.replace("th = 0.01", "th = 1.0"));
    let stop = StopCondition::parse(&d, "th < 0", "the stop condition").unwrap();
    let run = |method: Option<Method>, rtol: f64| {
        let config = RunConfig { until: 10.0, method, rtol, stop_when: vec![stop.clone()], ..RunConfig::default() };
        mech::simulate(&d, &config, |_| ControlFlow::Continue(())).unwrap()
    };
    let reference = run(Some(Method::Dop853), 1e-13);
    // The default (Taylor) and a fixed-step composition, whose event falls between steps.
    for (method, expected) in [(None, Method::Taylor), (Some(Method::KahanLi8), Method::KahanLi8)] {
        let report = run(method, 1e-9);
        assert_eq!(report.method, expected);
        assert_eq!(report.stopped_by.as_deref(), Some("th < 0"));
        let speed = -(2.0 * 9.81 / 1.5 * (1.0 - 1f64.cos())).sqrt();
        assert!(report.final_q[0].abs() < 1e-12, "{}", report.final_q[0]);
        assert!((report.final_qd[0] / speed - 1.0).abs() < 1e-9, "{} vs {speed}", report.final_qd[0]);
        let h = &report.invariants[0];
        assert!((h.final_value - h.initial).abs() < 1e-9 * h.initial.abs(), "{h:?}");
        assert!(h.max_abs_drift >= (h.final_value - h.initial).abs(), "{h:?}");
        // The time agrees with a run at a far tighter tolerance.
        assert!((report.t_final - reference.t_final).abs() < 1e-9, "{} vs {}", report.t_final, reference.t_final);
    }
}
