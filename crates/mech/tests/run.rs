//! Runs through the library's API on the shared test models of `common`: the
//! one driver for plain and constrained models, stop conditions, and its
//! typed errors.

use crate::common::{derive, run, BLOW_UP, CONSTRAINED_PENDULUM, PENDULUM};
use mech::RunFailure;
use mech::{RunConfig, RunError, StopCondition};
use std::f64::consts::PI;

/// A small swing's period, 2π√(l/g), for the pendulum of `common`.
fn period() -> f64 {
    2.0 * PI * (1.5f64 / 9.81).sqrt()
}

#[test]
fn a_small_swing_returns_after_one_period() {
    let d = derive(PENDULUM);
    let (report, rows) = run(&d, &RunConfig { until: period(), ..RunConfig::default() });
    let (t, q, _, _) = rows.last().unwrap();
    assert_eq!(*t, period());
    // The amplitude's correction to the period is (1 + θ₀²/16): 6e-6 here.
    assert!((q[0] - 0.01).abs() < 1e-7, "{}", q[0]);
    assert_eq!(report.stopped_by, None);
    assert!(report.invariants.iter().filter(|a| a.conserved).all(|a| a.max_rel_drift < 1e-8));
}

#[test]
fn initial_values_given_with_the_run_replace_the_models() {
    let d = derive(PENDULUM);
    let initial = vec![("th".to_string(), 0.02), ("th'".to_string(), -0.5)];
    let (_, rows) = run(&d, &RunConfig { until: 0.1, initial, ..RunConfig::default() });
    let (t, q, qd, _) = &rows[0];
    assert_eq!((*t, q[0], qd[0]), (0.0, 0.02, -0.5));
    let unknown = vec![("x'".to_string(), 1.0)];
    let e = mech::simulate(&d, &RunConfig { initial: unknown, ..RunConfig::default() }, |_| {
        std::ops::ControlFlow::Continue(())
    })
    .unwrap_err();
    let RunError::Input(e) = e else { panic!("{e}") };
    assert_eq!(e.setting, Some(mech::Setting::Start { name: "x'".into() }));
    assert!(e.message.contains("'x' is not a coordinate"), "{}", e.message);
}

#[test]
fn a_stop_condition_ends_the_run_where_it_crosses() {
    let d = derive(PENDULUM);
    let stop = StopCondition::parse(&d, "th < 0", "the stop condition").unwrap();
    let config = RunConfig { until: 10.0, stop_when: vec![stop], ..RunConfig::default() };
    let (report, rows) = run(&d, &config);
    assert_eq!(report.stopped_by.as_deref(), Some("th < 0"));
    // A quarter period, up to the amplitude's correction.
    let t = rows.last().unwrap().0;
    assert!((t / (period() / 4.0) - 1.0).abs() < 1e-4, "{t}");
}

#[test]
fn a_stop_condition_with_an_unknown_name_points_at_it() {
    let d = derive(PENDULUM);
    let e = StopCondition::parse(&d, "th < qq", "the stop condition").unwrap_err();
    assert_eq!(e.span, Some(5..7), "{}", e.message);
}

#[test]
fn the_same_driver_runs_a_constrained_model_and_reports_the_rod_tension() {
    let d = derive(CONSTRAINED_PENDULUM);
    let (report, rows) = run(&d, &RunConfig { until: 1.0, ..RunConfig::default() });
    assert_eq!(mech::constraint_columns(&d), ["lambda_rod", "force_rod", "residual_rod", "residual_rod'"]);
    // At the bottom with speed v: T = m g + m v²/l.
    let (_, _, _, cols) = &rows[0];
    let tension = 2.0 * 9.81 + 2.0 * 1.0 / 1.5;
    assert!((cols[1] - tension).abs() < 1e-9 * tension, "{}", cols[1]);
    let rod = &report.constraints[0];
    assert!(rod.max_abs_residual < 1e-10 && rod.max_abs_velocity_residual < 1e-10, "{rod:?}");
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
}

#[test]
fn a_run_that_blows_up_fails_with_its_reason_as_data() {
    let d = derive(BLOW_UP);
    let config = RunConfig { until: 5.0, method: Some(mech::Method::Dop853), ..RunConfig::default() };
    let Err(RunError::Failed { message, report }) =
        mech::simulate(&d, &config, |_| std::ops::ControlFlow::Continue(()))
    else {
        panic!("the run must fail")
    };
    let reason = report.failure_reason.clone().expect("a failed run says why as data");
    assert_eq!(report.failure.as_deref(), Some(message.as_str()));
    let t = match &reason {
        RunFailure::BlowUp { t, component } | RunFailure::NonFiniteRate { t, component } => {
            assert_eq!(component, "x'", "{message}");
            *t
        }
        other => panic!("{other:?}: {message}"),
    };
    // At the analytic blow-up, t = 1.3110287771, to the step size.
    assert!((t - 1.3110287771).abs() < 0.02, "{t}");
    assert!(matches!(reason.code(), "blow_up" | "non_finite_rate"));
}

#[test]
fn settings_that_cannot_be_run_are_refused_before_the_run() {
    let d = derive(PENDULUM);
    let refuse = |config: RunConfig| mech::simulate(&d, &config, |_| std::ops::ControlFlow::Continue(())).unwrap_err();
    let base = RunConfig { until: 10.0, ..RunConfig::default() };
    assert!(matches!(refuse(RunConfig { dt: Some(1e-300), ..base.clone() }), RunError::TooManySteps { .. }));
    assert!(matches!(refuse(RunConfig { dt: Some(1.0), ..base.clone() }), RunError::StepOverSamples { .. }));
    let adaptive = RunConfig { dt: Some(1e-3), method: Some(mech::Method::Dop853), ..base.clone() };
    assert!(matches!(refuse(adaptive), RunError::StepNotApplicable { method: mech::Method::Dop853 }));
    let many = RunConfig { output: mech::Output::Samples(mech::MAX_SAMPLES + 1), ..base.clone() };
    assert!(matches!(refuse(many), RunError::TooManySamples { .. }));
    // A fixed step that fits is taken as given.
    let (report, _) = run(&d, &RunConfig { dt: Some(1e-3), method: Some(mech::Method::Verlet), ..base });
    assert_eq!(report.dt, Some(1e-3));
}

#[test]
fn an_end_time_that_is_not_positive_is_a_typed_error() {
    let d = derive(PENDULUM);
    for until in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e =
            mech::simulate(&d, &RunConfig { until, ..RunConfig::default() }, |_| std::ops::ControlFlow::Continue(()));
        assert!(matches!(e, Err(RunError::Until { .. })), "{until}");
    }
}

/// The example program of `examples/pendulum.rs`, run on the pendulum of `common`.
#[allow(dead_code)] // its `main` is the example's, not the test's
#[path = "../examples/pendulum.rs"]
mod example;

#[test]
fn the_example_program_derives_runs_and_audits() {
    let text = example::report(PENDULUM, period()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "th:  l^2*m*th'' + g*l*m*sin(th) = 0");
    assert_eq!(lines[2], "t  th");
    assert_eq!(lines[3], "0.00  0.010000");
    // Half a period later the pendulum is at the other end, one period later back.
    assert_eq!(lines[8], format!("{:.2}  -0.010000", period() / 2.0));
    assert_eq!(lines[13], format!("{:.2}  0.010000", period()));
    assert!(lines.iter().any(|l| l.starts_with("H (conserved): drifted by")), "{text}");
}

#[test]
fn a_row_the_caller_declines_ends_the_run_at_the_row_before() {
    // As Ctrl-C does: the sink stops at the 6th row without keeping it, and the
    // summary's final state is the 5th, the last one kept.
    for model in [PENDULUM, CONSTRAINED_PENDULUM] {
        let d = derive(model);
        let mut kept: Vec<(f64, Vec<f64>, Vec<f64>)> = Vec::new();
        let config = RunConfig { until: 10.0, ..RunConfig::default() };
        let report = mech::simulate(&d, &config, |row| {
            if kept.len() == 5 {
                return std::ops::ControlFlow::Break(());
            }
            kept.push((row.t, row.q.to_vec(), row.qd.to_vec()));
            std::ops::ControlFlow::Continue(())
        })
        .unwrap();
        let (t, q, qd) = kept.last().unwrap();
        assert_eq!(report.t_final, *t);
        assert_eq!((&report.final_q, &report.final_qd), (q, qd));
        assert!(report.t_final < 10.0);
    }
}
