//! Numerics of `lagrange` that know nothing of symbols: ODE integrators over plain
//! `f64` slices, event location, root finding, Newton's method, quadrature and small
//! dense linear algebra.
//!
//! ```
//! use num::{integrate, Config, Method, OdeSystem, Output, RhsError};
//!
//! struct Oscillator; // x'' = -x as y = [x, v]
//! impl OdeSystem for Oscillator {
//!     fn dim(&self) -> usize { 2 }
//!     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
//!         dy[0] = y[1];
//!         dy[1] = -y[0];
//!         Ok(())
//!     }
//! }
//!
//! let config = Config { rtol: 1e-10, atol: 1e-12, ..Config::default() };
//! let mut solver = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
//! integrate(&mut solver, std::f64::consts::PI, Output::EveryStep, &mut [], |_| {
//!     std::ops::ControlFlow::Continue(())
//! })
//! .unwrap();
//! assert!((solver.state()[0] + 1.0).abs() < 1e-8);
//! ```
//!
//! # Map
//!
//! - Problems: [`OdeSystem`] (`y' = F(t, y)`), [`SeparableSystem`]
//!   (`H = T(p) + V(q, t)`, state `[q, p]`).
//! - Stepping: the [`Solver`] trait (`step`, `t`, `state`, `interpolate`,
//!   `statistics`), implemented by [`Dopri5`], [`Dop853`] (adaptive explicit),
//!   [`Composition`] (Verlet and its symplectic compositions), [`Gauss`]
//!   (Gauss–Legendre, implicit symplectic), [`Radau5`] (stiff) and [`Taylor`]
//!   (Taylor series, for systems that give their coefficients).
//! - [`Method`] names them for the command line and builds any of them;
//!   [`select_step`] picks a fixed step from a tolerance.
//! - [`integrate`] drives a solver with output sampling and [`Event`]s.
//! - [`eigenvalues`] of a general matrix, [`symmetric_definite`] of K v = μ M v.
//! - [`LinearSolver`] solves `M x = f` (dense or banded LU); [`brent`] finds roots
//!   of a function of one variable, [`newton`] and [`newton_fd`] of small systems,
//!   [`gauss_newton`] of overdetermined ones with the caller's acceptance test.
//! - Quadrature: the [`midpoint`] rule (Gauss–Chebyshev after `x = cos φ`),
//!   Gauss–Legendre rules ([`gauss_legendre_rule`], [`gauss_legendre`],
//!   [`gauss_legendre_doubling`]), [`tanh_sinh`] for endpoint singularities, and
//!   7/15-point Gauss–Kronrod ([`gauss_kronrod_15`], [`adaptive_gauss_kronrod`],
//!   [`gauss_kronrod`]) as the 1-D building block of nested cubature.

// Numerical kernels index several arrays with one loop variable; iterator zips over
// four slices read worse than the formulas they implement.
#![allow(clippy::needless_range_loop)]

mod adaptive;
mod build;
mod composition;
mod dop853;
mod dopri5;
mod eigen;
mod error;
mod gauss;
mod gauss_newton;
mod integrate;
pub mod lanes;
mod linalg;
mod method;
mod newton;
mod quadrature;
mod radau5;
mod root;
mod shortest;
mod solver;
mod stepsize;
mod system;
mod taylor;
#[cfg(test)]
mod test_models;

// `num::` names this crate inside it as well, so that `test_models.rs` reads the same
// compiled as a unit-test module and included by the integration tests.
#[cfg(test)]
extern crate self as num;

pub use composition::{Composition, Scheme};
pub use dop853::Dop853;
pub use dopri5::Dopri5;
pub use eigen::{balanced, eigenvalue_rounding, eigenvalues, symmetric_definite, symmetric_rounding, EigenError};
pub use error::{LinalgError, NewtonError, QuadratureError, RhsError, SolveError};
pub use gauss::Gauss;
pub use gauss_newton::{
    gauss_newton, gauss_newton_step, GaussNewtonConfig, GaussNewtonError, GaussNewtonSolution, LeastSquares,
};
pub use integrate::{
    integrate, integrate_projected, integrate_resumed, integrate_to, probe_spacing, Direction, Event, Observation,
    ObservationKind, Output, Projection, Resume, StopReason, Summary, FORESIGHT_MARGIN,
};
pub use linalg::{LinearSolver, DEFAULT_PIVOT_RATIO};
pub use method::Method;
pub use newton::{newton, newton_fd, NewtonConfig, NewtonSolution, FD_RELATIVE_STEP};
pub use quadrature::{
    adaptive_gauss_kronrod, gauss_kronrod, gauss_kronrod_15, gauss_legendre, gauss_legendre_centered,
    gauss_legendre_doubling, gauss_legendre_rule, midpoint, tanh_sinh, Adaptive, AdaptiveConfig, Doubling,
    DoublingConfig, Estimate, Integral, Integrand, GAUSS_7_WEIGHTS, KRONROD_15_NODES, KRONROD_15_WEIGHTS,
    KRONROD_MAX_INTERVALS, KRONROD_ROUND_OFF, MAX_GAUSS_LEGENDRE_ORDER,
};
pub use radau5::Radau5;
pub use root::brent;
pub use shortest::Shortest;
pub use solver::{Config, Controller, Solver, SolverState, Statistics, StepOutcome, Subdivisions};
pub use stepsize::{run_fixed, select_step};
pub use system::{finite_difference_jacobian, OdeSystem, Separable, SeparableSystem};
pub use taylor::{taylor_advance, taylor_order, taylor_ratio, taylor_step, Taylor};
