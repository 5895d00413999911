//! The stepping interface every integrator implements ([`Solver`], shaped like
//! diffsol's `OdeSolverMethod`), the [`SolverState`] every integrator holds and the
//! trait's accessors read (like diffsol's `OdeSolverState`), its [`Config`],
//! [`Statistics`] and the small helpers the integrators share (validation, error
//! norms, Hermite dense output, the fixed-step clock).

use crate::error::SolveError;
use crate::method::Method;
use crate::system::first_non_finite;

/// What a successful [`Solver::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepOutcome {
    /// An internal step was accepted; [`Solver::t`] advanced.
    Stepped,
    /// The accepted step landed exactly on the stop time set with
    /// [`Solver::set_stop_time`] (which is then cleared).
    ReachedStop,
}

/// Work counters of a solver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Statistics {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error test or Newton failure).
    pub rejected: usize,
    /// Calls of the right-hand side made by the solver (for separable systems: calls
    /// of `force`; the cheap `velocity` calls are not counted). Calls made inside a
    /// default finite-difference [`crate::OdeSystem::jacobian`] are not counted.
    pub rhs_evaluations: usize,
    /// Calls of [`crate::OdeSystem::jacobian`].
    pub jacobian_evaluations: usize,
    /// LU factorizations.
    pub lu_decompositions: usize,
    /// Newton (or fixed-point) iterations of implicit methods.
    pub newton_iterations: usize,
    /// Evaluations of the right-hand side by the Taylor method's look-ahead
    /// ([`Config::look_ahead`]), not counted in `rhs_evaluations` (which counts
    /// its expansions).
    pub look_ahead_evaluations: usize,
}

/// The PI or standard step-size controller of the adaptive explicit methods.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Controller {
    /// Proportional–integral control (Gustafsson; Hairer's `beta = 0.04` for DOPRI5,
    /// `beta = 0` for DOP853, where it reduces to standard control). Smoother step
    /// sequences with the same error.
    #[default]
    Pi,
    /// Standard (integral-only) control: `h_new = h · safety · err^(-1/(p+1))`.
    Standard,
}

/// Options of every solver. Fields a method does not use are ignored
/// (`dt` by adaptive methods, `rtol`/`atol` by fixed-step methods given a `dt`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Relative tolerance (dimensionless). Default `1e-6`: about six correct digits
    /// per step, the usual default of ODE suites.
    pub rtol: f64,
    /// Absolute tolerance, in the units of the state. Default `1e-9`: for states of
    /// order one it rarely binds, yet protects components passing through zero.
    pub atol: f64,
    /// Maximal number of accepted steps. Default `10_000_000`: large enough for long
    /// symplectic runs, small enough to stop a stalled adaptive run.
    pub max_steps: usize,
    /// First step of adaptive methods; `None` estimates it (Hairer's `hinit`).
    pub h_init: Option<f64>,
    /// Largest step of adaptive methods; `None` means unbounded.
    pub h_max: Option<f64>,
    /// Step of fixed-step methods; `None` picks one from `rtol`/`atol` with
    /// [`crate::select_step`].
    pub dt: Option<f64>,
    /// Step-size controller of the explicit adaptive methods.
    pub controller: Controller,
    /// The Taylor method's look-ahead: a step longer than this is checked at
    /// points this far apart against the equations themselves (see
    /// [`crate::Taylor`]); `None` trusts the series' own step.
    pub look_ahead: Option<f64>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            rtol: 1e-6,
            atol: 1e-9,
            max_steps: 10_000_000,
            h_init: None,
            h_max: None,
            dt: None,
            controller: Controller::Pi,
            look_ahead: None,
        }
    }
}

impl Config {
    /// Checks every field: tolerances finite and positive (`rtol` at least `1e-15`
    /// would be asking for less than round-off, so it is raised by the methods, not
    /// rejected), steps finite and positive, `max_steps` positive.
    pub fn validate(&self) -> Result<(), SolveError> {
        let positive = |name: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(SolveError::InvalidConfig { name, value, reason: "must be finite and positive" })
            }
        };
        positive("rtol", self.rtol)?;
        if !(self.atol.is_finite() && self.atol >= 0.0) {
            return Err(SolveError::InvalidConfig {
                name: "atol",
                value: self.atol,
                reason: "must be finite and non-negative",
            });
        }
        if let Some(h) = self.h_init {
            positive("h_init", h)?;
        }
        if let Some(h) = self.h_max {
            positive("h_max", h)?;
        }
        if let Some(h) = self.dt {
            positive("dt", h)?;
        }
        if self.max_steps == 0 {
            return Err(SolveError::InvalidConfig { name: "max_steps", value: 0.0, reason: "must be positive" });
        }
        Ok(())
    }
}

/// What every solver keeps of its run: the time, the state, the last step, the
/// step to try next, a pending stop time and the work counters. Each integrator
/// holds one, and [`Solver`]'s accessors read it through
/// [`Solver::solver_state`], so they are written once here.
#[derive(Clone, Debug)]
pub struct SolverState {
    /// Current time.
    pub(crate) t: f64,
    /// Start of the last accepted step.
    pub(crate) t_old: f64,
    /// The step the next attempt tries (fixed-step methods: their step).
    pub(crate) h: f64,
    /// The stop time set by [`Solver::set_stop_time`], until a step lands on it.
    pub(crate) stop: Option<f64>,
    /// Current state.
    pub(crate) y: Vec<f64>,
    /// Work counters.
    pub(crate) stats: Statistics,
    /// Most accepted steps ([`Config::max_steps`]).
    pub(crate) max_steps: usize,
}

impl SolverState {
    /// The state at `(t0, y0)` before the first step, which will try `h`.
    pub fn new(t0: f64, y0: &[f64], h: f64, stats: Statistics, config: &Config) -> Self {
        SolverState { t: t0, t_old: t0, h, stop: None, y: y0.to_vec(), stats, max_steps: config.max_steps }
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn y(&self) -> &[f64] {
        &self.y
    }

    /// Start of the last accepted step.
    pub fn step_start(&self) -> f64 {
        self.t_old
    }

    /// The step the next attempt tries.
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Work counters so far.
    pub fn statistics(&self) -> Statistics {
        self.stats
    }

    /// The most accepted steps a run may take ([`Config::max_steps`]).
    pub fn max_steps(&self) -> usize {
        self.max_steps
    }

    /// The stop time, if one is pending.
    pub fn stop_time(&self) -> Option<f64> {
        self.stop
    }

    /// Sets the stop time, which must not lie before the current time.
    pub(crate) fn set_stop(&mut self, t_stop: f64) -> Result<(), SolveError> {
        check_stop(self.t, t_stop)?;
        self.stop = Some(t_stop);
        Ok(())
    }

    /// Fails when the run has taken its [`Config::max_steps`] steps.
    pub(crate) fn check_max_steps(&self) -> Result<(), SolveError> {
        if self.stats.steps >= self.max_steps {
            return Err(SolveError::MaxStepsExceeded { t: self.t, max_steps: self.max_steps });
        }
        Ok(())
    }
}

/// A time-stepping integrator: advance with [`step`](Solver::step), read
/// [`t`](Solver::t) and [`state`](Solver::state), and interpolate within the last step.
///
/// Integration runs forward in time. The trait is object safe, so
/// [`Method::build`] can hand out `Box<dyn Solver>`.
pub trait Solver {
    /// The method this solver implements.
    fn method(&self) -> Method;
    /// The time, state, step and counters the solver keeps.
    fn solver_state(&self) -> &SolverState;
    /// The same, to change (for the trait's own [`set_stop_time`](Solver::set_stop_time)).
    fn solver_state_mut(&mut self) -> &mut SolverState;
    /// Current time.
    fn t(&self) -> f64 {
        self.solver_state().t
    }
    /// Current state.
    fn state(&self) -> &[f64] {
        &self.solver_state().y
    }
    /// Start of the last accepted step (equal to [`t`](Solver::t) before the first step).
    fn step_start(&self) -> f64 {
        self.solver_state().t_old
    }
    /// The step the next [`step`](Solver::step) will try.
    fn step_size(&self) -> f64 {
        self.solver_state().h
    }
    /// Takes one accepted step (adaptive methods retry rejected attempts internally).
    fn step(&mut self) -> Result<StepOutcome, SolveError>;
    /// Writes the dense-output state at `t` into `out`; `t` must lie within the last
    /// step, `[step_start(), t()]`.
    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError>;
    /// Work counters so far.
    fn statistics(&self) -> Statistics {
        self.solver_state().stats
    }
    /// Makes the solver land exactly on `t_stop` (the step that would pass it is
    /// shortened). `t_stop` must not lie before [`t`](Solver::t).
    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolveError> {
        self.solver_state_mut().set_stop(t_stop)
    }
    /// Replaces the state at the current time, e.g. by its projection onto a
    /// constraint manifold after a step, and continues from it as from an initial
    /// value (one evaluation of the right-hand side for the first-same-as-last
    /// methods). The dense output of the last step is left as it was. Methods whose
    /// steps carry more than the state return [`SolveError::RestartUnsupported`].
    fn set_state(&mut self, y: &[f64]) -> Result<(), SolveError> {
        let _ = y;
        Err(SolveError::RestartUnsupported { method: self.method().name() })
    }
    /// Asks the solver to compute the dense output of a step only when
    /// [`prepare_dense`](Solver::prepare_dense) is called for it, instead of after
    /// every step. For DOP853 this saves the three extra evaluations of its
    /// interpolant on the steps nobody interpolates in (most of them, when a run
    /// samples 1001 rows over thousands of steps or only needs its end state).
    /// With it on, [`interpolate`](Solver::interpolate) fails with
    /// [`SolveError::DenseOutputNotPrepared`] until `prepare_dense` ran for the
    /// last step. Methods whose dense output is free ignore it.
    fn set_lazy_dense(&mut self, lazy: bool) {
        let _ = lazy;
    }
    /// Computes the dense output of the last step if it is pending (see
    /// [`set_lazy_dense`](Solver::set_lazy_dense)); otherwise does nothing.
    fn prepare_dense(&mut self) -> Result<(), SolveError> {
        Ok(())
    }
    /// Writes the state at `t`, within the last step (`[step_start(), t()]`), as
    /// the method itself computes it: by one step of its own from the last step's
    /// start to `t`, not by [`interpolate`](Solver::interpolate). For the methods
    /// whose dense output is of lower order than their steps (the compositions'
    /// cubic Hermite, the Gauss collocation polynomial), so that a state at an
    /// event inside a step is as accurate as the states at the step ends. The
    /// solver stays where it was (its counters include the work). `None` for the
    /// methods whose dense output is as accurate as their steps (the default).
    fn restep(&mut self, t: f64, out: &mut [f64]) -> Option<Result<(), SolveError>> {
        let _ = (t, out);
        None
    }
    /// The steps of a fixed-step method taken as shorter sub-steps so far (see
    /// [`crate::Gauss`]), if any; `None` for the other methods.
    fn subdivisions(&self) -> Option<Subdivisions> {
        None
    }
}

impl<S: Solver + ?Sized> Solver for Box<S> {
    fn method(&self) -> Method {
        (**self).method()
    }
    fn solver_state(&self) -> &SolverState {
        (**self).solver_state()
    }
    fn solver_state_mut(&mut self) -> &mut SolverState {
        (**self).solver_state_mut()
    }
    fn t(&self) -> f64 {
        (**self).t()
    }
    fn state(&self) -> &[f64] {
        (**self).state()
    }
    fn step_start(&self) -> f64 {
        (**self).step_start()
    }
    fn step_size(&self) -> f64 {
        (**self).step_size()
    }
    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        (**self).step()
    }
    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError> {
        (**self).interpolate(t, out)
    }
    fn statistics(&self) -> Statistics {
        (**self).statistics()
    }
    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SolveError> {
        (**self).set_stop_time(t_stop)
    }
    fn set_state(&mut self, y: &[f64]) -> Result<(), SolveError> {
        (**self).set_state(y)
    }
    fn set_lazy_dense(&mut self, lazy: bool) {
        (**self).set_lazy_dense(lazy)
    }
    fn prepare_dense(&mut self) -> Result<(), SolveError> {
        (**self).prepare_dense()
    }
    fn restep(&mut self, t: f64, out: &mut [f64]) -> Option<Result<(), SolveError>> {
        (**self).restep(t, out)
    }
    fn subdivisions(&self) -> Option<Subdivisions> {
        (**self).subdivisions()
    }
}

/// Checks an initial value problem: non-empty, matching lengths, finite values.
pub(crate) fn check_initial(dim: usize, t0: f64, y0: &[f64]) -> Result<(), SolveError> {
    if dim == 0 {
        return Err(SolveError::EmptySystem);
    }
    if y0.len() != dim {
        return Err(SolveError::DimensionMismatch { expected: dim, found: y0.len() });
    }
    if !t0.is_finite() {
        return Err(SolveError::NonFiniteInitial { index: usize::MAX });
    }
    if let Some(index) = first_non_finite(y0) {
        return Err(SolveError::NonFiniteInitial { index });
    }
    Ok(())
}

/// Checks a stop time against the current time.
pub(crate) fn check_stop(t: f64, t_stop: f64) -> Result<(), SolveError> {
    if t_stop.is_nan() || t_stop < t {
        return Err(SolveError::EndBeforeStart { t, t_end: t_stop });
    }
    Ok(())
}

/// Checks that `t` lies in `[start, end]` up to round-off.
pub(crate) fn check_interpolation(t: f64, start: f64, end: f64) -> Result<(), SolveError> {
    let slack = 1e-12 * (end - start).abs().max(f64::MIN_POSITIVE) + 4.0 * f64::EPSILON * end.abs();
    if !(t >= start - slack && t <= end + slack) {
        return Err(SolveError::InterpolationOutOfRange { t, start, end });
    }
    Ok(())
}

/// Checks the length of an output slice.
pub(crate) fn check_len(expected: usize, found: usize) -> Result<(), SolveError> {
    if expected != found {
        return Err(SolveError::DimensionMismatch { expected, found });
    }
    Ok(())
}

/// Cubic Hermite interpolation on a step of length `h` at `theta = (t - t0)/h`, from
/// the values and derivatives at both ends.
pub(crate) fn hermite(theta: f64, h: f64, y0: &[f64], f0: &[f64], y1: &[f64], f1: &[f64], out: &mut [f64]) {
    let t2 = theta * theta;
    let t3 = t2 * theta;
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + theta;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    for i in 0..out.len() {
        out[i] = h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i];
    }
}

/// A fixed-step time grid `t = base + k·h`, computed by multiplication so that a
/// million steps do not accumulate round-off in `t`, and landing exactly on a stop
/// time. The step and the stop time are the [`SolverState`]'s.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FixedClock {
    base: f64,
    k: u64,
}

/// A fixed step that would end within this fraction of `h` before the stop time is
/// stretched onto it, to avoid a sliver step of round-off size.
const SLIVER: f64 = 1e-6;

impl FixedClock {
    pub(crate) fn new(t0: f64) -> Self {
        FixedClock { base: t0, k: 0 }
    }
    /// The end of the next step of size `h` and whether it is the stop time.
    pub(crate) fn next(&self, h: f64, stop: Option<f64>) -> (f64, bool) {
        let t_next = self.base + (self.k + 1) as f64 * h;
        match stop {
            Some(stop) if t_next >= stop - SLIVER * h => (stop, true),
            _ => (t_next, false),
        }
    }
    /// Moves to the end of the step [`next`](Self::next) gave (clearing the stop
    /// time when it was reached) and returns the new time.
    pub(crate) fn advance(&mut self, h: f64, reached_stop: bool, stop: &mut Option<f64>) -> f64 {
        if reached_stop {
            self.base = stop.take().unwrap_or(self.base);
            self.k = 0;
        } else {
            self.k += 1;
        }
        self.base + self.k as f64 * h
    }
}

/// Sum `y += incr` with Kahan compensation held in `comp`: long fixed-step runs then
/// do not accumulate round-off in the state (which would show as energy drift).
pub(crate) fn compensated_add(y: &mut [f64], comp: &mut [f64], incr: &[f64]) {
    for i in 0..y.len() {
        let dy = incr[i] + comp[i];
        let new = y[i] + dy;
        comp[i] = dy - (new - y[i]);
        y[i] = new;
    }
}

impl std::fmt::Debug for dyn Solver + '_ {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Solver")
            .field("method", &self.method())
            .field("t", &self.t())
            .field("step_size", &self.step_size())
            .field("statistics", &self.statistics())
            .finish_non_exhaustive()
    }
}

/// The steps of a run that were taken as shorter sub-steps, for its warnings
/// (worded by the front end, which knows how a user picks another method).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Subdivisions {
    /// Steps of the fixed grid taken as sub-steps.
    pub steps: usize,
    /// The start of the first of them.
    pub first_t: f64,
    /// The shortest sub-step taken.
    pub shortest: f64,
}
