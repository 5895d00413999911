//! Measured orders of convergence of every method on problems with known solutions.

use crate::common::*;
use num::{integrate_to, Config, Method, Solver};

/// Error after one Kepler period (eccentricity `e`) with `steps` equal steps.
fn kepler_error(method: Method, e: f64, steps: usize) -> f64 {
    let y0 = kepler_start(e);
    let t_end = 2.0 * std::f64::consts::PI;
    let h = t_end / steps as f64;
    // Adaptive methods run at a fixed step: a tolerance nothing violates, h_init = h_max = h.
    let config = Config { dt: Some(h), h_init: Some(h), h_max: Some(h), rtol: 1e6, atol: 1e6, ..Config::default() };
    let mut solver = method.build_separable(Kepler, 0.0, &y0, &config).unwrap();
    let mut y = [0.0; 4];
    integrate_to(&mut solver, t_end, &mut y).unwrap();
    let s = solver.statistics();
    assert!(s.steps.abs_diff(steps) <= 1, "{method}: {} steps, wanted {steps}", s.steps);
    dist(&y, &y0)
}

/// Checks the order on Kepler's problem with e = 0.5 from `steps` to `2·steps`.
#[track_caller]
fn check_order(method: Method, steps: usize, expected: f64) {
    check_order_e(method, 0.5, steps, expected);
}

#[track_caller]
fn check_order_e(method: Method, e: f64, steps: usize, expected: f64) {
    let e1 = kepler_error(method, e, steps);
    let e2 = kepler_error(method, e, 2 * steps);
    let p = order(e1, e2);
    eprintln!("{method}: N = {steps}: {e1:.3e}, 2N: {e2:.3e}, order {p:.2}");
    assert!(
        (p - expected).abs() < 0.35,
        "{method}: measured order {p:.2}, expected {expected} (errors {e1:e}, {e2:e})"
    );
}

#[test]
fn explicit_runge_kutta_orders() {
    check_order(Method::Dopri5, 200, 5.0);
    // Order 8 reaches round-off (1e-13) fast; a mildly eccentric orbit keeps the
    // measurement in the asymptotic range (e = 0.5 needs N > 100 and then hits round-off).
    check_order_e(Method::Dop853, 0.1, 25, 8.0);
}

#[test]
fn composition_orders() {
    check_order(Method::Verlet, 400, 2.0);
    check_order(Method::Yoshida4, 400, 4.0);
    check_order(Method::KahanLi6, 200, 6.0);
    check_order(Method::KahanLi8, 100, 8.0);
}

#[test]
fn gauss_orders() {
    check_order(Method::Gauss2, 400, 2.0);
    check_order(Method::Gauss4, 200, 4.0);
    check_order(Method::Gauss6, 100, 6.0);
}

/// Exponential decay `y' = -y` with Radau5 at decreasing tolerances: the error must
/// follow the tolerance, and the work grow like `tol^(-1/5)`-ish.
#[test]
fn radau5_tracks_tolerance() {
    struct Decay;
    impl num::OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), num::RhsError> {
            dy[0] = -y[0];
            Ok(())
        }
    }
    let mut last = (f64::INFINITY, 0);
    for k in [4, 6, 8, 10] {
        let tol = 10f64.powi(-k);
        let config = Config { rtol: tol, atol: tol, ..Config::default() };
        let mut s = Method::Radau5.build(Decay, 0.0, &[1.0], &config).unwrap();
        let mut y = [0.0];
        integrate_to(&mut s, 5.0, &mut y).unwrap();
        let err = (y[0] - (-5f64).exp()).abs();
        let steps = s.statistics().steps;
        eprintln!("radau5 tol {tol:e}: error {err:.3e}, {steps} steps");
        assert!(err < 20.0 * tol, "error {err} for tol {tol}");
        assert!(err < last.0 && steps > last.1);
        last = (err, steps);
    }
}

/// DOP853 against the analytic solution at a tight tolerance, and its work against a
/// reference run of DOPRI5 at the same tolerance (DOP853 must win there).
#[test]
fn dop853_reference_run() {
    let y0 = kepler_start(0.9);
    let t_end = 2.0 * std::f64::consts::PI;
    let config = Config { rtol: 1e-12, atol: 1e-12, ..Config::default() };
    let mut y = [0.0; 4];
    let mut a = Method::Dop853.build_separable(Kepler, 0.0, &y0, &config).unwrap();
    integrate_to(&mut a, t_end, &mut y).unwrap();
    let err853 = dist(&y, &y0);
    let mut b = Method::Dopri5.build_separable(Kepler, 0.0, &y0, &config).unwrap();
    integrate_to(&mut b, t_end, &mut y).unwrap();
    let err5 = dist(&y, &y0);
    let (sa, sb) = (a.statistics(), b.statistics());
    eprintln!("e = 0.9, rtol 1e-12: dop853 {err853:.2e} in {sa:?}; dopri5 {err5:.2e} in {sb:?}");
    assert!(err853 < 1e-8, "dop853 error {err853}");
    assert!(err5 < 1e-8, "dopri5 error {err5}");
    assert!(sa.rhs_evaluations * 2 < sb.rhs_evaluations);
}
