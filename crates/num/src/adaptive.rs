//! What the adaptive explicit Runge–Kutta methods ([`crate::Dopri5`],
//! [`crate::Dop853`]) share: Hairer's initial step guess (`hinit`), the scaled
//! error norm, the standard/PI controller of `DOPRI5`/`DOP853`, and the step
//! loop itself ([`step`]), which a method drives through [`EmbeddedPair`].

use crate::error::SolveError;
use crate::solver::{Config, Controller, SolverState, Statistics, StepOutcome};
use crate::system::{first_non_finite, OdeSystem};

/// Controller state and constants (Hairer, Nørsett, Wanner, *Solving ODEs I*, §II.4).
#[derive(Clone, Debug)]
pub(crate) struct StepControl {
    pub(crate) rtol: f64,
    pub(crate) atol: f64,
    pub(crate) h_max: f64,
    /// Safety factor: aim a little below the tolerance so the next step is accepted.
    safety: f64,
    /// Largest allowed step decrease `h_new >= fac_min · h`.
    fac_min: f64,
    /// Largest allowed step increase `h_new <= fac_max · h`.
    fac_max: f64,
    /// PI weight of the previous error.
    beta: f64,
    /// Exponent of the current error.
    expo: f64,
    fac_old: f64,
    pub(crate) last_rejected: bool,
}

impl StepControl {
    /// `order` is the order used for the step-size exponent (5 for DOPRI5, 8 for
    /// DOP853), `fac_min`/`fac_max` Hairer's defaults for the method.
    pub(crate) fn new(config: &Config, order: u32, fac_min: f64, fac_max: f64) -> Self {
        let beta = match config.controller {
            Controller::Pi => 0.04,
            Controller::Standard => 0.0,
        };
        // Hairer's exponents: `expo1 = 0.2 - 0.75·beta` in DOPRI5, `1/8 - 0.2·beta` in DOP853.
        let expo = if order >= 8 { 0.125 - 0.2 * beta } else { 1.0 / f64::from(order) - 0.75 * beta };
        StepControl {
            // Asking for less than ~100 ulps per step is asking for round-off.
            rtol: config.rtol.max(100.0 * f64::EPSILON),
            atol: config.atol,
            h_max: config.h_max.unwrap_or(f64::INFINITY),
            safety: 0.9,
            fac_min,
            fac_max,
            beta,
            expo,
            fac_old: 1e-4,
            last_rejected: false,
        }
    }

    /// Decides on a step with scaled error `err`; returns whether it is accepted and
    /// the next step size.
    pub(crate) fn decide(&mut self, h: f64, err: f64) -> (bool, f64) {
        if !err.is_finite() {
            self.last_rejected = true;
            return (false, h * self.fac_min);
        }
        let fac11 = err.powf(self.expo);
        if err <= 1.0 {
            let fac = fac11 / self.fac_old.powf(self.beta);
            let fac = (fac / self.safety).clamp(1.0 / self.fac_max, 1.0 / self.fac_min);
            let mut h_new = (h / fac).min(self.h_max);
            if self.last_rejected {
                h_new = h_new.min(h);
            }
            self.fac_old = err.max(1e-4);
            self.last_rejected = false;
            (true, h_new)
        } else {
            self.last_rejected = true;
            (false, h / (fac11 / self.safety).min(1.0 / self.fac_min))
        }
    }

    /// Error weight of component `i`.
    #[inline]
    pub(crate) fn scale(&self, y0: f64, y1: f64) -> f64 {
        self.atol + self.rtol * y0.abs().max(y1.abs())
    }

    /// Smallest step that still changes `t`.
    pub(crate) fn h_min(t: f64) -> f64 {
        16.0 * f64::EPSILON * t.abs().max(f64::MIN_POSITIVE.sqrt())
    }
}

/// The start of an explicit method: `f0 = F(t0, y0)` (checked finite) and the
/// first step, `h_init` (capped by `h_max`) or Hairer's estimate. `y1`, `f1` are
/// scratch. Shared by the adaptive methods and the fixed-step guess.
#[allow(clippy::too_many_arguments)]
pub(crate) fn first_step<S: OdeSystem + ?Sized>(
    system: &mut S,
    control: &StepControl,
    order: u32,
    h_init: Option<f64>,
    t0: f64,
    y0: &[f64],
    f0: &mut [f64],
    y1: &mut [f64],
    f1: &mut [f64],
    stats: &mut Statistics,
) -> Result<f64, SolveError> {
    system.rhs(t0, y0, f0).map_err(|source| SolveError::Rhs { t: t0, source })?;
    stats.rhs_evaluations += 1;
    if let Some(index) = first_non_finite(f0) {
        return Err(SolveError::NonFiniteState { t: t0, index });
    }
    match h_init {
        Some(h) => Ok(h.min(control.h_max)),
        None => initial_step(system, control, order, t0, y0, f0, y1, f1, stats),
    }
}

/// Hairer's `hinit`: an initial step for a method of order `order` from the size of
/// `f0 = F(t, y)` and a finite-difference estimate of the second derivative. Uses one
/// right-hand-side evaluation; `y1`, `f1` are scratch.
#[allow(clippy::too_many_arguments)]
pub(crate) fn initial_step<S: OdeSystem + ?Sized>(
    system: &mut S,
    control: &StepControl,
    order: u32,
    t: f64,
    y: &[f64],
    f0: &[f64],
    y1: &mut [f64],
    f1: &mut [f64],
    stats: &mut Statistics,
) -> Result<f64, SolveError> {
    let n = y.len();
    let mut dnf = 0.0;
    let mut dny = 0.0;
    for i in 0..n {
        let sk = control.atol + control.rtol * y[i].abs();
        dnf += (f0[i] / sk).powi(2);
        dny += (y[i] / sk).powi(2);
    }
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { (dny / dnf).sqrt() * 0.01 };
    h = h.min(control.h_max);
    for i in 0..n {
        y1[i] = y[i] + h * f0[i];
    }
    system.rhs(t + h, y1, f1).map_err(|source| SolveError::Rhs { t: t + h, source })?;
    stats.rhs_evaluations += 1;
    let mut der2 = 0.0;
    for i in 0..n {
        let sk = control.atol + control.rtol * y[i].abs();
        der2 += ((f1[i] - f0[i]) / sk).powi(2);
    }
    let der2 = der2.sqrt() / h;
    let der12 = der2.abs().max(dnf.sqrt());
    let h1 = if !der12.is_finite() || der12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        (0.01 / der12).powf(1.0 / f64::from(order))
    };
    let h = (100.0 * h).min(h1).min(control.h_max);
    let h = h.max(StepControl::h_min(t));
    Ok(h)
}

/// The error of a failed adaptive step loop: non-finite values if the last attempt had
/// them, otherwise a too small step.
pub(crate) fn step_failure(t: f64, h: f64, y_trial: &[f64], f_trial: &[f64]) -> SolveError {
    if let Some(index) = first_non_finite(y_trial).or_else(|| first_non_finite(f_trial)) {
        SolveError::NonFiniteState { t: t + h, index }
    } else {
        SolveError::StepSizeTooSmall { t, h }
    }
}

/// An embedded explicit Runge–Kutta pair as [`step`] drives it: the methods
/// differ in their stages and their dense output only.
pub(crate) trait EmbeddedPair {
    fn state(&mut self) -> &mut SolverState;
    fn control(&mut self) -> &mut StepControl;
    /// Tries a step of `h` from the current state: the trial's scaled error.
    fn attempt(&mut self, h: f64) -> Result<f64, SolveError>;
    /// Why a step of `h` cannot be taken ([`step_failure`] of the last trial).
    fn failure(&self, h: f64) -> SolveError;
    /// Keeps the trial of an accepted step of `h`: its dense output, the trial
    /// state as the current one, and its last stage as the next step's first.
    fn accept(&mut self, h: f64) -> Result<(), SolveError>;
}

/// One accepted step of an embedded pair: trials shortened by the controller
/// until one is accepted, the last one cut to land on the stop time.
pub(crate) fn step<P: EmbeddedPair>(pair: &mut P) -> Result<StepOutcome, SolveError> {
    pair.state().check_max_steps()?;
    loop {
        let state = pair.state();
        let mut h = state.h;
        let mut reaches_stop = false;
        if let Some(stop) = state.stop {
            if state.t + h * (1.0 + 1e-10) >= stop {
                h = stop - state.t;
                reaches_stop = true;
            }
        }
        if !reaches_stop && h < StepControl::h_min(state.t) {
            return Err(pair.failure(h));
        }
        if reaches_stop && h == 0.0 {
            state.stop = None;
            return Ok(StepOutcome::ReachedStop);
        }
        let err = pair.attempt(h)?;
        let (accepted, h_new) = pair.control().decide(h, err);
        if !accepted {
            let state = pair.state();
            state.stats.rejected += 1;
            state.h = h_new;
            if h_new < StepControl::h_min(state.t) {
                return Err(pair.failure(h));
            }
            continue;
        }
        pair.accept(h)?;
        let state = pair.state();
        state.t_old = state.t;
        state.t = if reaches_stop { state.stop.take().unwrap_or(state.t + h) } else { state.t + h };
        state.stats.steps += 1;
        // A step shortened to hit the stop time says little about the next one.
        state.h = if reaches_stop { h_new.max(state.h) } else { h_new };
        return Ok(if reaches_stop { StepOutcome::ReachedStop } else { StepOutcome::Stepped });
    }
}
