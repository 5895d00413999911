//! Dense output, events, long-time energy behaviour, stiffness, failures and bad input.

use std::f64::consts::PI;
use std::ops::ControlFlow;

use crate::common::*;
use num::{
    integrate, integrate_to, Config, Direction, Event, Method, ObservationKind, OdeSystem, Output, RhsError,
    SolveError, Solver, StopReason,
};

fn tight() -> Config {
    Config { rtol: 1e-12, atol: 1e-12, ..Config::default() }
}

/// Dense output of every method against `x = sin t` on evenly spaced samples.
#[test]
fn dense_output_accuracy() {
    for (method, config, bound) in [
        (Method::Dopri5, Config { rtol: 1e-9, atol: 1e-9, ..Config::default() }, 1e-7),
        (Method::Dop853, tight(), 1e-10),
        (Method::Radau5, Config { rtol: 1e-9, atol: 1e-9, ..Config::default() }, 1e-6),
        (Method::Verlet, Config { dt: Some(1e-3), ..Config::default() }, 1e-6),
        // Cubic Hermite: error about h^4/384 for sin.
        (Method::KahanLi8, Config { dt: Some(0.05), ..Config::default() }, 5e-8),
        (Method::Gauss6, Config { dt: Some(0.05), ..Config::default() }, 1e-7),
    ] {
        let mut solver = method.build_separable(Oscillator, 0.0, &[0.0, 1.0], &config).unwrap();
        let mut worst = 0.0_f64;
        let mut count = 0;
        integrate(&mut solver, 10.0, Output::Samples(1001), &mut [], |o| {
            assert_eq!(o.kind, ObservationKind::Sample);
            worst = worst.max((o.y[0] - o.t.sin()).abs()).max((o.y[1] - o.t.cos()).abs());
            count += 1;
            ControlFlow::Continue(())
        })
        .unwrap();
        eprintln!("{method}: dense output error {worst:.2e}");
        assert_eq!(count, 1001);
        assert!(worst < bound, "{method}: dense output error {worst:e}");
    }
}

/// Zero crossings of `x = sin t` at multiples of π, with direction filter and a
/// terminal event.
#[test]
fn events_at_multiples_of_pi() {
    for (method, config, tol) in [
        (Method::Dop853, tight(), 1e-11),
        (Method::Dopri5, Config { rtol: 1e-10, atol: 1e-10, ..Config::default() }, 1e-8),
        (Method::Yoshida4, Config { dt: Some(0.01), ..Config::default() }, 1e-7),
        (Method::Gauss4, Config { dt: Some(0.01), ..Config::default() }, 1e-7),
    ] {
        let mut solver = method.build_separable(Oscillator, 0.0, &[0.0, 1.0], &config).unwrap();
        let mut times = Vec::new();
        let mut events = [Event::new(|_, y| y[0]), Event::new(|_, y| y[0]).with_direction(Direction::Falling)];
        let summary = integrate(&mut solver, 10.0, Output::EveryStep, &mut events, |o| {
            if let ObservationKind::Event { index } = o.kind {
                times.push((index, o.t));
                assert!(o.y[0].abs() < 10.0 * tol);
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(summary.stop, StopReason::Finished);
        assert_eq!(summary.t, 10.0);
        let both: Vec<f64> = times.iter().filter(|e| e.0 == 0).map(|e| e.1).collect();
        let falling: Vec<f64> = times.iter().filter(|e| e.0 == 1).map(|e| e.1).collect();
        assert_eq!(both.len(), 3, "{method}: {times:?}");
        assert_eq!(falling.len(), 2, "{method}: {times:?}");
        for (k, t) in both.iter().enumerate() {
            assert!((t - (k + 1) as f64 * PI).abs() < tol, "{method}: crossing at {t}");
        }
        for (k, t) in falling.iter().enumerate() {
            assert!((t - (2 * k + 1) as f64 * PI).abs() < tol, "{method}: falling at {t}");
        }
        // Time order of observations is kept.
        assert!(times.windows(2).all(|w| w[0].1 <= w[1].1));
    }
    // Terminal: stop at the first rising crossing, 2π.
    let mut solver = Method::Dop853.build_separable(Oscillator, 0.0, &[0.0, 1.0], &tight()).unwrap();
    let mut events = [Event::new(|_, y| y[0]).with_direction(Direction::Rising).with_terminal(true)];
    let mut last_t = 0.0;
    let summary = integrate(&mut solver, 100.0, Output::Samples(101), &mut events, |o| {
        last_t = o.t;
        ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!(summary.stop, StopReason::Event { index: 0 });
    assert!((summary.t - 2.0 * PI).abs() < 1e-11);
    assert_eq!(last_t, summary.t);
}

/// Max energy error over the first and the last tenth of `steps` steps.
fn energy_drift(method: Method, dt: f64, steps: usize) -> (f64, f64) {
    let y0 = [2.0, 0.0]; // a large swing (amplitude 2 rad)
    let e0 = pendulum_energy(&y0);
    let config = Config { dt: Some(dt), ..Config::default() };
    let mut solver = method.build_separable(Pendulum, 0.0, &y0, &config).unwrap();
    let (mut first, mut last) = (0.0_f64, 0.0_f64);
    for k in 0..steps {
        solver.step().unwrap();
        let err = (pendulum_energy(solver.state()) - e0).abs();
        if k < steps / 10 {
            first = first.max(err);
        } else if k >= steps - steps / 10 {
            last = last.max(err);
        }
    }
    assert_eq!(solver.statistics().steps, steps);
    (first, last)
}

#[test]
fn symplectic_energy_has_no_drift() {
    for (method, dt, steps) in [
        (Method::Verlet, 0.05, 1_000_000),
        (Method::Yoshida4, 0.1, 1_000_000),
        (Method::KahanLi8, 0.2, 200_000),
        (Method::Gauss4, 0.1, 200_000),
    ] {
        let (first, last) = energy_drift(method, dt, steps);
        eprintln!("{method}: max energy error first tenth {first:.3e}, last tenth {last:.3e}");
        assert!(first > 0.0 && first < 1e-2);
        // Bounded: the last tenth looks like the first (no secular growth).
        assert!(last < 1.5 * first + 1e-13, "{method}: {first:e} -> {last:e}");
    }
}

/// Gauss iterates to round-off: energy of the pendulum is kept to ~1e-14 (its error
/// is only the method's bounded oscillation, tiny for gauss6).
#[test]
fn gauss6_energy_to_round_off() {
    let (first, last) = energy_drift(Method::Gauss6, 0.05, 100_000);
    eprintln!("gauss6: {first:.3e} {last:.3e}");
    assert!(first < 1e-11 && last < 1e-11, "{first:e} {last:e}");
}

#[test]
fn radau5_van_der_pol_stiff() {
    let config = Config { rtol: 1e-6, atol: 1e-6, ..Config::default() };
    let mut solver = Method::Radau5.build(VanDerPol(1000.0), 0.0, &[2.0, 0.0], &config).unwrap();
    let mut y = [0.0; 2];
    integrate_to(&mut solver, 3000.0, &mut y).unwrap();
    let s = solver.statistics();
    eprintln!("radau5 Van der Pol mu = 1000 to t = 3000: {s:?}, y = {y:?}");
    assert!(s.steps < 2000, "{s:?}");
    // The relaxation oscillation keeps |x| <= ~2.
    assert!(y[0].abs() < 2.1);
}

#[test]
fn radau5_robertson() {
    let config = Config { rtol: 1e-6, atol: 1e-10, ..Config::default() };
    let mut solver = Method::Radau5.build(Robertson, 0.0, &[1.0, 0.0, 0.0], &config).unwrap();
    let mut y = [0.0; 3];
    integrate_to(&mut solver, 1e5, &mut y).unwrap();
    let s = solver.statistics();
    eprintln!("radau5 Robertson to 1e5: {s:?}, y = {y:?}");
    assert!(s.steps < 500, "{s:?}");
    // Against a tight reference run.
    let tight = Config { rtol: 1e-11, atol: 1e-14, ..Config::default() };
    let mut reference = Method::Radau5.build(Robertson, 0.0, &[1.0, 0.0, 0.0], &tight).unwrap();
    let mut y_ref = [0.0; 3];
    integrate_to(&mut reference, 1e5, &mut y_ref).unwrap();
    eprintln!("reference {y_ref:?} in {:?}", reference.statistics());
    assert!((y[0] - y_ref[0]).abs() < 1e-5 * y_ref[0].abs() * 10.0, "{y:?} vs {y_ref:?}");
    assert!((y[1] - y_ref[1]).abs() < 1e-4 * y_ref[1].abs(), "{y:?} vs {y_ref:?}");
    // Mass is conserved (the system is linear in its sum).
    assert!((y[0] + y[1] + y[2] - 1.0).abs() < 1e-9);
    // An explicit method needs orders of magnitude more work on the same interval.
    let mut explicit = Method::Dopri5.build(Robertson, 0.0, &[1.0, 0.0, 0.0], &config).unwrap();
    integrate_to(&mut explicit, 10.0, &mut y).unwrap();
    assert!(explicit.statistics().steps > s.steps);
}

/// `y1' = sqrt(1 − t)` is NaN past t = 1: every method reports time and index.
struct Sqrt;
impl OdeSystem for Sqrt {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, _y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        dy[0] = 1.0;
        dy[1] = (1.0 - t).sqrt();
        Ok(())
    }
}

#[test]
fn non_finite_state_reports_time_and_index() {
    for method in [Method::Dopri5, Method::Dop853, Method::Radau5, Method::Gauss4] {
        let config = Config { dt: Some(0.1), ..Config::default() };
        let mut solver = method.build(Sqrt, 0.0, &[0.0, 0.0], &config).unwrap();
        let mut y = [0.0; 2];
        match integrate_to(&mut solver, 2.0, &mut y) {
            Err(SolveError::NonFiniteState { t, index }) => {
                eprintln!("{method}: non-finite at t = {t}, index {index}");
                assert_eq!(index, 1, "{method}");
                assert!(t > 1.0 && t < 1.2, "{method}: t = {t}");
                // The solver keeps the last finite state.
                assert!(solver.state().iter().all(|v| v.is_finite()));
                assert!(solver.t() <= 1.0 + 1e-9);
            }
            other => panic!("{method}: expected NonFiniteState, got {other:?}"),
        }
    }
    // A separable system blowing up in the force.
    struct Blow;
    impl num::SeparableSystem for Blow {
        fn n(&self) -> usize {
            2
        }
        fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
            dq.copy_from_slice(p);
            Ok(())
        }
        fn force(&mut self, t: f64, _q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
            dp[0] = 0.0;
            dp[1] = (0.5 - t).ln();
            Ok(())
        }
    }
    let config = Config { dt: Some(0.1), ..Config::default() };
    let mut solver = Method::Verlet.build_separable(Blow, 0.0, &[0.0; 4], &config).unwrap();
    let err = integrate_to(&mut solver, 1.0, &mut [0.0; 4]).unwrap_err();
    assert!(matches!(err, SolveError::NonFiniteState { t, index: 3 } if (t - 0.5).abs() < 1e-9), "{err:?}");
}

#[test]
fn rhs_errors_carry_time() {
    struct Fails;
    impl OdeSystem for Fails {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, t: f64, _y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            if t > 0.5 {
                return Err(RhsError::Singular { detail: "mass matrix".into() });
            }
            dy[0] = 1.0;
            Ok(())
        }
    }
    let mut s = Method::Dopri5.build(Fails, 0.0, &[0.0], &Config::default()).unwrap();
    let err = integrate_to(&mut s, 1.0, &mut [0.0]).unwrap_err();
    assert!(matches!(err, SolveError::Rhs { t, source: RhsError::Singular { .. } } if t > 0.5), "{err:?}");
}

#[test]
fn bad_input_is_an_error() {
    let nan = Config { rtol: f64::NAN, ..Config::default() };
    for method in Method::ALL {
        let err = method.build_separable(Oscillator, 0.0, &[1.0, 0.0], &nan).unwrap_err();
        assert!(matches!(err, SolveError::InvalidConfig { name: "rtol", .. }), "{method}: {err:?}");
        let err = method.build_separable(Oscillator, 0.0, &[1.0], &Config::default()).unwrap_err();
        assert!(matches!(err, SolveError::DimensionMismatch { expected: 2, found: 1 }), "{err:?}");
        let err = method.build_separable(Oscillator, 0.0, &[f64::NAN, 0.0], &Config::default()).unwrap_err();
        assert!(matches!(err, SolveError::NonFiniteInitial { index: 0 }), "{err:?}");
        let bad_dt = Config { dt: Some(-1.0), ..Config::default() };
        assert!(method.build_separable(Oscillator, 0.0, &[1.0, 0.0], &bad_dt).is_err());
    }
    struct Empty;
    impl OdeSystem for Empty {
        fn dim(&self) -> usize {
            0
        }
        fn rhs(&mut self, _: f64, _: &[f64], _: &mut [f64]) -> Result<(), RhsError> {
            Ok(())
        }
    }
    for method in [Method::Dopri5, Method::Dop853, Method::Radau5, Method::Gauss4] {
        let err = method.build(Empty, 0.0, &[], &Config::default()).unwrap_err();
        assert_eq!(err, SolveError::EmptySystem);
    }
    let err = Method::Verlet.build(Oscillator, 0.0, &[1.0, 0.0], &Config::default()).unwrap_err();
    assert!(matches!(err, SolveError::RequiresSeparable { method: "verlet" }));
    // End before start, NaN end, too few samples, interpolation outside the step.
    let mut s = Method::Dopri5.build(Oscillator, 1.0, &[1.0, 0.0], &Config::default()).unwrap();
    let noop = |_: &num::Observation<'_>| ControlFlow::Continue(());
    assert!(matches!(integrate(&mut s, 0.0, Output::EveryStep, &mut [], noop), Err(SolveError::EndBeforeStart { .. })));
    assert!(integrate(&mut s, f64::NAN, Output::EveryStep, &mut [], noop).is_err());
    assert!(integrate(&mut s, 2.0, Output::Samples(1), &mut [], noop).is_err());
    s.step().unwrap();
    let mut out = [0.0; 2];
    assert!(matches!(s.interpolate(s.t() + 1.0, &mut out), Err(SolveError::InterpolationOutOfRange { .. })));
    assert!(matches!(s.interpolate(s.t(), &mut [0.0; 3]), Err(SolveError::DimensionMismatch { .. })));
    // NaN from an event function.
    let mut s = Method::Dopri5.build(Oscillator, 0.0, &[1.0, 0.0], &Config::default()).unwrap();
    let mut ev = [Event::new(|t, _| if t > 0.5 { f64::NAN } else { 1.0 })];
    assert!(matches!(
        integrate(&mut s, 1.0, Output::EveryStep, &mut ev, noop),
        Err(SolveError::EventNonFinite { event: 0, .. })
    ));
    // t_end == t0 gives just the initial point.
    let mut s = Method::Dopri5.build(Oscillator, 0.0, &[1.0, 0.0], &Config::default()).unwrap();
    let mut n = 0;
    let sum = integrate(&mut s, 0.0, Output::Samples(3), &mut [], |_| {
        n += 1;
        ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!((n, sum.stop), (3, StopReason::Finished));
}

/// A run that cannot reach its end time within its step budget: a fixed step
/// fails before its first step, an adaptive run foreseen far beyond its budget at
/// its first checkpoint, and one that needs a little more than its budget when the
/// budget is spent.
#[test]
fn step_budget_by_foresight() {
    let few = Config { max_steps: 3, dt: Some(0.1), ..Config::default() };
    let mut s = Method::Verlet.build_separable(Oscillator, 0.0, &[1.0, 0.0], &few).unwrap();
    let e = integrate_to(&mut s, 1.0, &mut [0.0; 2]).unwrap_err();
    let SolveError::MaxStepsForeseen { t, steps, projected, max_steps: 3, .. } = e else { panic!("{e:?}") };
    assert_eq!((t, steps, s.statistics().steps), (0.0, 0, 0));
    assert!((projected - 10.0).abs() < 1e-9, "{projected}");

    let budget = 12_800;
    let config = Config { max_steps: budget, rtol: 1e-9, atol: 1e-12, ..Config::default() };
    let mut s = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
    let e = integrate_to(&mut s, 1e9, &mut [0.0; 2]).unwrap_err();
    let SolveError::MaxStepsForeseen { steps, projected, .. } = e else { panic!("{e:?}") };
    assert_eq!(steps, budget / 128);
    assert!(projected > 1e8, "{projected}");

    // The pace of this run: steps per unit time.
    let mut s = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
    integrate_to(&mut s, 100.0, &mut [0.0; 2]).unwrap();
    let pace = s.statistics().steps as f64 / 100.0;
    let mut s = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
    let e = integrate_to(&mut s, 2.0 * budget as f64 / pace, &mut [0.0; 2]).unwrap_err();
    assert!(matches!(e, SolveError::MaxStepsExceeded { max_steps, .. } if max_steps == budget), "{e:?}");
    assert_eq!(s.statistics().steps, budget);
}

/// A run with a terminal event is not stopped by foresight: its pace to the end
/// time says nothing when the event ends it long before (a shot that stops where
/// it reaches its target).
#[test]
fn a_terminal_event_is_reached_however_far_the_end_time() {
    let config = Config { max_steps: 12_800, rtol: 1e-9, atol: 1e-12, ..Config::default() };
    let mut s = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
    let target = 50.0;
    let mut events = [Event::new(move |t, _: &[f64]| t - target).with_terminal(true)];
    let sum = integrate(&mut s, 1e9, Output::EveryStep, &mut events, |_| ControlFlow::Continue(())).unwrap();
    assert_eq!(sum.stop, StopReason::Event { index: 0 });
    assert!((sum.t - target).abs() < 1e-9, "{}", sum.t);
}

/// An event inside a step of a method whose dense output is of lower order than
/// its steps is located on the method's own states: its time and state are as
/// accurate as the step ends, where the interpolant is off by far more.
#[test]
fn events_inside_a_step_have_the_accuracy_of_the_steps() {
    for method in [Method::KahanLi8, Method::KahanLi6, Method::Gauss4, Method::Gauss6] {
        let config = Config { dt: Some(0.1), ..Config::default() };
        let mut solver = method.build_separable(Oscillator, 0.0, &[0.0, 1.0], &config).unwrap();
        // x = sin t: x' falls through 0 at π/2, where x = 1.
        let mut events = [Event::new(|_, y| y[1]).with_direction(Direction::Falling).with_terminal(true)];
        let mut at = (0.0, vec![]);
        integrate(&mut solver, 10.0, Output::EveryStep, &mut events, |o| {
            at = (o.t, o.y.to_vec());
            ControlFlow::Continue(())
        })
        .unwrap();
        let (t, y) = at;
        let mut interpolated = [0.0; 2];
        solver.interpolate(t, &mut interpolated).unwrap();
        // The steps' own error at the step end, for scale.
        let (t_b, y_b) = (solver.t(), solver.state());
        let step_error = (y_b[0] - t_b.sin()).abs().max((y_b[1] - t_b.cos()).abs());
        let event_error = (t - PI / 2.0).abs().max((y[0] - 1.0).abs()).max(y[1].abs());
        let interpolant_error = (interpolated[0] - 1.0).abs().max(interpolated[1].abs());
        eprintln!("{method}: event {event_error:.1e}, step end {step_error:.1e}, interpolant {interpolant_error:.1e}");
        assert!(event_error <= 2.0 * step_error.max(1e-15), "{method}: {event_error:e} vs {step_error:e}");
        assert!(interpolant_error > 10.0 * event_error, "{method}: {interpolant_error:e} vs {event_error:e}");
    }
}

/// A restep to a time inside the first step is the step of that length from the
/// start: bit for bit for a composition, to round-off for Gauss.
#[test]
fn restep_is_a_step_from_the_start() {
    for (method, tol) in [(Method::KahanLi8, 0.0), (Method::Gauss6, 4.0 * f64::EPSILON)] {
        let mut solver = method
            .build_separable(Oscillator, 0.0, &[0.3, 1.0], &Config { dt: Some(0.2), ..Config::default() })
            .unwrap();
        solver.step().unwrap();
        let mut restepped = [0.0; 2];
        solver.restep(0.07, &mut restepped).unwrap().unwrap();
        let mut fresh = method
            .build_separable(Oscillator, 0.0, &[0.3, 1.0], &Config { dt: Some(0.07), ..Config::default() })
            .unwrap();
        fresh.step().unwrap();
        assert!(dist(&restepped, fresh.state()) <= tol, "{method}: {restepped:?} vs {:?}", fresh.state());
        // The solver stays at the end of its step.
        assert_eq!(solver.t(), 0.2);
        solver.restep(0.2, &mut restepped).unwrap().unwrap();
        assert_eq!(restepped, solver.state());
    }
    let mut dop = Method::Dop853.build(Oscillator, 0.0, &[0.3, 1.0], &Config::default()).unwrap();
    dop.step().unwrap();
    assert!(dop.restep(dop.t() / 2.0, &mut [0.0; 2]).is_none());
}

/// Fixed-step methods given only a tolerance pick a step that meets it.
#[test]
fn fixed_step_from_tolerance() {
    for method in [Method::Verlet, Method::Yoshida4, Method::KahanLi6, Method::Gauss4] {
        let mut errs = Vec::new();
        for rtol in [1e-5, 1e-8] {
            let config = Config { rtol, atol: rtol, h_max: Some(2.0 * PI), ..Config::default() };
            let y0 = kepler_start(0.0);
            let mut s = method.build_separable(Kepler, 0.0, &y0, &config).unwrap();
            let dt = s.step_size();
            let mut y = [0.0; 4];
            integrate_to(&mut s, 2.0 * PI, &mut y).unwrap();
            let err = dist(&y, &y0);
            eprintln!("{method}: rtol {rtol:e} -> dt {dt:.3e}, error after one orbit {err:.2e}");
            errs.push((dt, err));
            // Local error per step <= ~rtol, so the global error stays below
            // (number of steps)·rtol, up to a modest factor.
            let steps = s.statistics().steps as f64;
            assert!(err < 10.0 * steps * rtol, "{method}: error {err} at rtol {rtol}, {steps} steps");
        }
        assert!(errs[1].0 < errs[0].0 && errs[1].1 < errs[0].1);
    }
}

/// Stop times are hit exactly and stepping may continue afterwards.
#[test]
fn stop_time_is_exact() {
    // The Taylor method needs a system with Taylor coefficients, which this
    // separable oscillator does not give; `taylor.rs` tests its stop times.
    for method in Method::ALL.into_iter().filter(|&m| m != Method::Taylor) {
        let config = Config { dt: Some(0.3), ..Config::default() };
        let mut s = method.build_separable(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
        let mut y = [0.0; 2];
        integrate_to(&mut s, 1.0, &mut y).unwrap();
        assert_eq!(s.t(), 1.0, "{method}");
        integrate_to(&mut s, 2.5, &mut y).unwrap();
        assert_eq!(s.t(), 2.5, "{method}");
        assert!((y[0] - 2.5f64.cos()).abs() < 0.05, "{method}: {y:?}");
    }
}

/// Free fall `x'' = -1`, `y = [x, v]`: its Taylor series ends at order 2, so
/// the Taylor method's step spans the whole run.
struct FreeFall;

impl OdeSystem for FreeFall {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        dy[0] = y[1];
        dy[1] = -1.0;
        Ok(())
    }
    fn taylor_series(&mut self, _t: f64, y: &[f64], order: usize, s: &mut [f64]) -> Option<Result<(), RhsError>> {
        s.fill(0.0);
        s[..2].copy_from_slice(y);
        if order >= 1 {
            s[2] = y[1];
            s[3] = -1.0;
        }
        if order >= 2 {
            s[4] = -0.5;
        }
        Some(Ok(()))
    }
}

/// A ball thrown up passes a height twice within one Taylor step: both
/// crossings are found, in order, at their exact times 1 ∓ 1/√2.
#[test]
fn two_crossings_in_one_long_step_are_both_found() {
    let config = Config { rtol: 1e-10, atol: 1e-10, ..Config::default() };
    let mut s = Method::Taylor.build(FreeFall, 0.0, &[0.0, 1.0], &config).unwrap();
    let mut events = [Event::new(|_, y: &[f64]| y[0] - 0.25)];
    let mut crossings = Vec::new();
    let sum = integrate(&mut s, 4.0, Output::Samples(5), &mut events, |o| {
        if let ObservationKind::Event { .. } = o.kind {
            crossings.push(o.t);
        }
        ControlFlow::Continue(())
    })
    .unwrap();
    assert!(s.statistics().steps <= 2, "the run is one long step: {:?}", s.statistics());
    assert_eq!(sum.events, 2, "{crossings:?}");
    let r = 0.5f64.sqrt();
    assert!((crossings[0] - (1.0 - r)).abs() < 1e-12 && (crossings[1] - (1.0 + r)).abs() < 1e-12, "{crossings:?}");
}
