//! Explicit symplectic integrators for separable Hamiltonians `H = T(p) + V(q, t)`:
//! Störmer–Verlet and symmetric compositions of it (Hairer, Lubich, Wanner,
//! *Geometric Numerical Integration*, §II.4 and §V.3). Enter with [`Composition::new`]
//! and a [`Scheme`].
//!
//! One Verlet substep of length `τ` is kick–drift–kick:
//! `p += τ/2·F(t, q)`, `q += τ·v(p)`, `t += τ`, `p += τ/2·F(t, q)`. A composition
//! applies substeps `γ_1 h, …, γ_s h`; the force at the end of one substep is the force
//! at the start of the next, so a step costs `s` force evaluations. Time-dependent
//! potentials are handled by drifting `t` with `q` (extended phase space), which keeps
//! the order. State updates use compensated summation, so round-off does not
//! accumulate over millions of steps. Dense output is the cubic Hermite interpolant
//! through the states and derivatives at both ends of the step; where that is not
//! accurate enough (the state at an event), [`Solver::restep`] takes the step from
//! its start to the time asked for.
#![allow(clippy::excessive_precision)] // Coefficients are quoted as published.

use crate::error::SolveError;
use crate::method::Method;
use crate::solver::{
    check_initial, check_interpolation, check_len, compensated_add, hermite, Config, FixedClock, Solver, SolverState,
    Statistics, StepOutcome,
};
use crate::system::{first_non_finite, SeparableSystem};

/// A composition scheme: the substep fractions `γ_i` (summing to one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Störmer–Verlet, order 2, one force evaluation per step.
    Verlet,
    /// Yoshida's (1990) triple jump, order 4, 3 substeps:
    /// `γ_1 = γ_3 = 1/(2 − 2^(1/3))`, `γ_2 = 1 − 2γ_1`.
    Yoshida4,
    /// Kahan & Li (1997) `s9odr6a`, order 6, 9 substeps; smaller error constants than
    /// Yoshida's 7-substep solution A for the same order.
    KahanLi6,
    /// Kahan & Li (1997) `s15odr8`, order 8, 15 substeps.
    KahanLi8,
}

const YOSHIDA4: [f64; 3] =
    [1.3512071919596576340476878089715, -1.7024143839193152680953756179429, 1.3512071919596576340476878089715];
const KAHANLI6_HALF: [f64; 5] = [
    0.39216144400731413927925056,
    0.33259913678935943859974864,
    -0.70624617255763935980996482,
    0.08221359629355080023149045,
    0.79854399093482996339895035,
];
const KAHANLI8_HALF: [f64; 8] = [
    0.74167036435061295344822780,
    -0.40910082580003159399730010,
    0.19075471029623837995387626,
    -0.57386247111608226665638773,
    0.29906418130365592384446354,
    0.33462491824529818378495798,
    0.31529309239676659663205666,
    -0.79688793935291635401978884,
];

/// The full symmetric sequence from its first half and middle element.
const fn mirror<const H: usize, const S: usize>(half: [f64; H]) -> [f64; S] {
    let mut out = [0.0; S];
    let mut i = 0;
    while i < H {
        out[i] = half[i];
        out[S - 1 - i] = half[i];
        i += 1;
    }
    out
}

const KAHANLI6: [f64; 9] = mirror::<5, 9>(KAHANLI6_HALF);
const KAHANLI8: [f64; 15] = mirror::<8, 15>(KAHANLI8_HALF);

impl Scheme {
    /// The scheme implementing `method`, if it is a composition.
    pub fn of(method: Method) -> Option<Scheme> {
        match method {
            Method::Verlet => Some(Scheme::Verlet),
            Method::Yoshida4 => Some(Scheme::Yoshida4),
            Method::KahanLi6 => Some(Scheme::KahanLi6),
            Method::KahanLi8 => Some(Scheme::KahanLi8),
            _ => None,
        }
    }

    /// The method this scheme implements.
    pub fn method(self) -> Method {
        match self {
            Scheme::Verlet => Method::Verlet,
            Scheme::Yoshida4 => Method::Yoshida4,
            Scheme::KahanLi6 => Method::KahanLi6,
            Scheme::KahanLi8 => Method::KahanLi8,
        }
    }

    /// The substep fractions `γ_1..γ_s`.
    pub fn coefficients(self) -> &'static [f64] {
        match self {
            Scheme::Verlet => &[1.0],
            Scheme::Yoshida4 => &YOSHIDA4,
            Scheme::KahanLi6 => &KAHANLI6,
            Scheme::KahanLi8 => &KAHANLI8,
        }
    }
}

/// A fixed-step composition of Störmer–Verlet; see the module documentation.
#[derive(Clone, Debug)]
pub struct Composition<S> {
    system: S,
    scheme: Scheme,
    /// Time, state, step, stop time and counters (what the accessors read).
    state: SolverState,
    clock: FixedClock,
    n: usize,
    /// Accepted state `[q, p]`, its derivative `[v(p), F(t, q)]` and compensation.
    dy: Vec<f64>,
    comp: Vec<f64>,
    /// Previous accepted state, derivative and compensation (dense output, restep).
    y_old: Vec<f64>,
    dy_old: Vec<f64>,
    comp_old: Vec<f64>,
    /// Working copies for the step in progress.
    y_new: Vec<f64>,
    dy_new: Vec<f64>,
    comp_new: Vec<f64>,
    incr: Vec<f64>,
}

impl<S: SeparableSystem> Composition<S> {
    /// A solver from `(t0, y0)`, `y0 = [q0, p0]`, with step `config.dt` (required).
    pub fn new(mut system: S, scheme: Scheme, t0: f64, y0: &[f64], config: &Config) -> Result<Self, SolveError> {
        config.validate()?;
        let n = system.n();
        check_initial(2 * n, t0, y0)?;
        let dt = config.dt.ok_or(SolveError::InvalidConfig {
            name: "dt",
            value: f64::NAN,
            reason: "a fixed-step method needs a step (or use Method::build_separable)",
        })?;
        let mut dy = vec![0.0; 2 * n];
        let mut stats = Statistics::default();
        {
            let (q, p) = y0.split_at(n);
            let (dq, dp) = dy.split_at_mut(n);
            system.velocity(p, dq).map_err(|source| SolveError::Rhs { t: t0, source })?;
            system.force(t0, q, dp).map_err(|source| SolveError::Rhs { t: t0, source })?;
            stats.rhs_evaluations += 1;
        }
        if let Some(index) = first_non_finite(&dy) {
            return Err(SolveError::NonFiniteState { t: t0, index });
        }
        Ok(Composition {
            system,
            scheme,
            clock: FixedClock::new(t0),
            state: SolverState::new(t0, y0, dt, stats, config),
            n,
            dy: dy.clone(),
            comp: vec![0.0; 2 * n],
            y_old: y0.to_vec(),
            dy_old: dy.clone(),
            comp_old: vec![0.0; 2 * n],
            y_new: vec![0.0; 2 * n],
            dy_new: dy,
            comp_new: vec![0.0; 2 * n],
            incr: vec![0.0; n],
        })
    }

    /// The system, e.g. to read parameters or counters it keeps.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// The composition scheme.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// Advances the working copies from `t` to `t_next`, starting from the
    /// current state, or from the last step's start when `from_step_start`.
    fn advance(&mut self, t: f64, t_next: f64, from_step_start: bool) -> Result<(), SolveError> {
        let n = self.n;
        let h = t_next - t;
        if from_step_start {
            self.y_new.copy_from_slice(&self.y_old);
            self.comp_new.copy_from_slice(&self.comp_old);
            self.dy_new.copy_from_slice(&self.dy_old);
        } else {
            self.y_new.copy_from_slice(&self.state.y);
            self.comp_new.copy_from_slice(&self.comp);
            self.dy_new.copy_from_slice(&self.dy);
        }
        let coefficients = self.scheme.coefficients();
        let mut t_sub = t;
        for (i, &gamma) in coefficients.iter().enumerate() {
            let tau = gamma * h;
            let (q, p) = self.y_new.split_at_mut(n);
            let (cq, cp) = self.comp_new.split_at_mut(n);
            let (dq, dp) = self.dy_new.split_at_mut(n);
            // Kick.
            for j in 0..n {
                self.incr[j] = 0.5 * tau * dp[j];
            }
            compensated_add(p, cp, &self.incr);
            // Drift.
            self.system.velocity(p, dq).map_err(|source| SolveError::Rhs { t: t_sub, source })?;
            for j in 0..n {
                self.incr[j] = tau * dq[j];
            }
            compensated_add(q, cq, &self.incr);
            t_sub = if i + 1 == coefficients.len() { t_next } else { t_sub + tau };
            // Kick.
            self.system.force(t_sub, q, dp).map_err(|source| SolveError::Rhs { t: t_sub, source })?;
            self.state.stats.rhs_evaluations += 1;
            for j in 0..n {
                self.incr[j] = 0.5 * tau * dp[j];
            }
            compensated_add(p, cp, &self.incr);
        }
        // Velocity at the end, for dense output.
        let (_, p) = self.y_new.split_at(n);
        let (dq, _) = self.dy_new.split_at_mut(n);
        self.system.velocity(p, dq).map_err(|source| SolveError::Rhs { t: t_next, source })?;
        Ok(())
    }
}

impl<S: SeparableSystem> Solver for Composition<S> {
    fn method(&self) -> Method {
        self.scheme.method()
    }
    fn solver_state(&self) -> &SolverState {
        &self.state
    }
    fn solver_state_mut(&mut self) -> &mut SolverState {
        &mut self.state
    }

    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        let t = self.state.t;
        self.state.check_max_steps()?;
        let (t_next, reached) = self.clock.next(self.state.h, self.state.stop);
        self.advance(t, t_next, false)?;
        if let Some(index) = first_non_finite(&self.y_new).or_else(|| first_non_finite(&self.dy_new)) {
            return Err(SolveError::NonFiniteState { t: t_next, index });
        }
        std::mem::swap(&mut self.y_old, &mut self.state.y);
        std::mem::swap(&mut self.dy_old, &mut self.dy);
        std::mem::swap(&mut self.comp_old, &mut self.comp);
        std::mem::swap(&mut self.state.y, &mut self.y_new);
        std::mem::swap(&mut self.dy, &mut self.dy_new);
        std::mem::swap(&mut self.comp, &mut self.comp_new);
        self.state.t_old = t;
        self.state.t = self.clock.advance(self.state.h, reached, &mut self.state.stop);
        self.state.stats.steps += 1;
        Ok(if reached { StepOutcome::ReachedStop } else { StepOutcome::Stepped })
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError> {
        check_len(self.state.y.len(), out.len())?;
        let t1 = self.state.t;
        check_interpolation(t, self.state.t_old, t1)?;
        let h = t1 - self.state.t_old;
        if h == 0.0 {
            out.copy_from_slice(&self.state.y);
            return Ok(());
        }
        let theta = (t - self.state.t_old) / h;
        hermite(theta, h, &self.y_old, &self.dy_old, &self.state.y, &self.dy, out);
        Ok(())
    }

    /// The composition from the last step's start to `t`: its error is a
    /// step's (order 8 for Kahan–Li 8), where the Hermite interpolant's is of
    /// order 4.
    fn restep(&mut self, t: f64, out: &mut [f64]) -> Option<Result<(), SolveError>> {
        Some((|| {
            check_len(self.state.y.len(), out.len())?;
            let (t0, t1) = (self.state.t_old, self.state.t);
            check_interpolation(t, t0, t1)?;
            if t >= t1 {
                out.copy_from_slice(&self.state.y);
            } else if t <= t0 {
                out.copy_from_slice(&self.y_old);
            } else {
                self.advance(t0, t, true)?;
                out.copy_from_slice(&self.y_new);
            }
            Ok(())
        })())
    }
}
