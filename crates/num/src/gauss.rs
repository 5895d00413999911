//! Gauss–Legendre collocation with 1, 2 or 3 stages (orders 2, 4, 6): implicit,
//! symmetric and symplectic for any Hamiltonian system written as an [`OdeSystem`],
//! with a fixed step. Enter with [`Gauss::new`].
//!
//! The stage equations `Z_i = h Σ_j a_ij F(t + c_j h, y + Z_j)` are solved by
//! simplified Newton iteration with the matrix `I − h A ⊗ J` (`J` the Jacobian at the
//! start of a step, kept across steps while convergence stays fast), factored as one
//! dense `sn × sn` LU: `O((sn)³)` per factorization, which is fine for the few dozen
//! coordinates of a mechanics model. If Newton fails, fixed-point iteration from the
//! same start is tried. (Fixed-point iteration first, where it contracts by 20 per
//! sweep, took 17.6 evaluations a step on the double pendulum against Newton's 12.9:
//! to reach round-off without a bias it needs twice the sweeps.) Starting values
//! extrapolate the previous step's collocation polynomial. Iteration runs until the
//! correction is at round-off (or stops shrinking), and the update is `Σ d_i Z_i`
//! (`dᵀ = bᵀA⁻¹`) from the corrected stages, which needs no further evaluation of
//! `F` and keeps no bias of the iterates: quadratic invariants are kept exactly and
//! energy shows no drift. The state is updated with compensated summation.
//!
//! A step whose stages do not converge (a motion faster than the step was chosen
//! for) is taken as 2, 4, … sub-steps, each a Gauss step and so a symplectic map;
//! the next step of the grid tries one halving fewer. (Subdividing also the steps
//! whose stages converge far from their prediction, by a bound tied to `rtol`,
//! followed the runaway of `tests` more closely, but cut steps of the chaotic double
//! pendulum and of a user's long `dt` too, and a step that depends on the state is
//! no longer symplectic: H then drifts.) [`Solver::subdivisions`] tells how many steps were
//! subdivided; a step that fails as `2^16` sub-steps fails the run.
//! Dense output is the polynomial through `y_n`, the stage values and `y_{n+1}`
//! (of order s); where that is not accurate enough (the state at an event),
//! [`Solver::restep`] solves the step from its start to the time asked for.

use crate::error::SolveError;
use crate::linalg::DenseLu;
use crate::method::Method;
use crate::solver::{
    check_initial, check_interpolation, check_len, compensated_add, Config, FixedClock, Solver, SolverState,
    Statistics, StepOutcome, Subdivisions,
};
use crate::system::{first_non_finite, OdeSystem};

/// Most iterations per attempt; simplified Newton typically needs 5–12 to round-off.
const MAX_ITER: usize = 60;

/// Butcher tableau of an `s`-stage Gauss method (padded to 3).
#[derive(Clone, Copy, Debug)]
struct Tableau {
    s: usize,
    a: [[f64; 3]; 3],
    /// The weights; the update uses `d` instead (the tests check `dᵀA = bᵀ`).
    #[cfg_attr(not(test), allow(dead_code))]
    b: [f64; 3],
    c: [f64; 3],
    /// `d = bᵀA⁻¹`: the update `h Σ b_i F(Y_i)` equals `Σ d_i Z_i` at the solution.
    d: [f64; 3],
}

impl Tableau {
    fn of(stages: usize) -> Tableau {
        match stages {
            1 => Tableau {
                s: 1,
                a: [[0.5, 0.0, 0.0], [0.0; 3], [0.0; 3]],
                b: [1.0, 0.0, 0.0],
                c: [0.5, 0.0, 0.0],
                d: [2.0, 0.0, 0.0],
            },
            2 => {
                let r = 3f64.sqrt() / 6.0;
                Tableau {
                    s: 2,
                    a: [[0.25, 0.25 - r, 0.0], [0.25 + r, 0.25, 0.0], [0.0; 3]],
                    b: [0.5, 0.5, 0.0],
                    c: [0.5 - r, 0.5 + r, 0.0],
                    d: [-3f64.sqrt(), 3f64.sqrt(), 0.0],
                }
            }
            _ => {
                let r = 15f64.sqrt();
                Tableau {
                    s: 3,
                    a: [
                        [5.0 / 36.0, 2.0 / 9.0 - r / 15.0, 5.0 / 36.0 - r / 30.0],
                        [5.0 / 36.0 + r / 24.0, 2.0 / 9.0, 5.0 / 36.0 - r / 24.0],
                        [5.0 / 36.0 + r / 30.0, 2.0 / 9.0 + r / 15.0, 5.0 / 36.0],
                    ],
                    b: [5.0 / 18.0, 4.0 / 9.0, 5.0 / 18.0],
                    c: [0.5 - r / 10.0, 0.5, 0.5 + r / 10.0],
                    d: [5.0 / 3.0, -4.0 / 3.0, 5.0 / 3.0],
                }
            }
        }
    }
}

/// How the stage equations are iterated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Iteration {
    Newton,
    FixedPoint,
}

/// Most halvings of a step: a step of the fixed grid is taken as at most
/// `2^MAX_LEVEL` (65,536) sub-steps before the run fails.
const MAX_LEVEL: u32 = 16;

/// A step of the fixed grid being taken as sub-steps: `[start, end]` cut into
/// `2^level` sub-steps, `done` of them taken.
#[derive(Clone, Copy, Debug)]
struct Pending {
    start: f64,
    end: f64,
    /// Whether `end` is the stop time.
    reached: bool,
    done: u64,
    /// Whether any sub-step of it was shorter than the whole, and whether it was
    /// counted in [`Subdivisions::steps`].
    subdivided: bool,
    counted: bool,
}

/// A Gauss–Legendre collocation solver; see the module documentation.
#[derive(Clone, Debug)]
pub struct Gauss<S> {
    system: S,
    method: Method,
    tab: Tableau,
    /// Time, state, step, stop time and counters (what the accessors read).
    state: SolverState,
    clock: FixedClock,
    n: usize,
    comp: Vec<f64>,
    /// The last step's start and its compensation.
    comp_old: Vec<f64>,
    y_old: Vec<f64>,
    /// Stage increments `Z` (`s·n`) of the last step, the working ones, their
    /// starting values and the stage derivatives `F(Y_i)`.
    z_old: Vec<f64>,
    z: Vec<f64>,
    z_pred: Vec<f64>,
    f: Vec<f64>,
    delta: Vec<f64>,
    y_stage: Vec<f64>,
    incr: Vec<f64>,
    y_new: Vec<f64>,
    comp_new: Vec<f64>,
    jac: Vec<f64>,
    lu: DenseLu,
    /// Step size the LU was factored for (NaN: none), and whether `J` is from this state.
    lu_h: f64,
    jac_fresh: bool,
    jac_valid: bool,
    have_previous: bool,
    /// Whether the working stages started from the previous step's polynomial.
    predicted: bool,
    /// The contraction of the last converged iteration.
    rate: f64,
    /// The step of the fixed grid in progress, when it is taken as sub-steps.
    pending: Option<Pending>,
    /// Sub-steps are `2^-level` of the fixed step, `level ≤ max_level`.
    level: u32,
    max_level: u32,
    subdivisions: Option<Subdivisions>,
}

impl<S: OdeSystem> Gauss<S> {
    /// A solver from `(t0, y0)` with step `config.dt` (required). `method` is one of
    /// [`Method::Gauss2`], [`Method::Gauss4`], [`Method::Gauss6`]; other methods give
    /// [`SolveError::InvalidConfig`].
    pub fn new(system: S, method: Method, t0: f64, y0: &[f64], config: &Config) -> Result<Self, SolveError> {
        config.validate()?;
        let stages = match method {
            Method::Gauss2 => 1,
            Method::Gauss4 => 2,
            Method::Gauss6 => 3,
            _ => {
                return Err(SolveError::InvalidConfig {
                    name: "method",
                    value: f64::NAN,
                    reason: "Gauss::new takes gauss2, gauss4 or gauss6",
                })
            }
        };
        let n = system.dim();
        check_initial(n, t0, y0)?;
        let dt = config.dt.ok_or(SolveError::InvalidConfig {
            name: "dt",
            value: f64::NAN,
            reason: "a fixed-step method needs a step (or use Method::build)",
        })?;
        let sn = stages * n;
        Ok(Gauss {
            system,
            method,
            tab: Tableau::of(stages),
            clock: FixedClock::new(t0),
            state: SolverState::new(t0, y0, dt, Statistics::default(), config),
            n,
            comp: vec![0.0; n],
            comp_old: vec![0.0; n],
            y_old: y0.to_vec(),
            z_old: vec![0.0; sn],
            z: vec![0.0; sn],
            z_pred: vec![0.0; sn],
            f: vec![0.0; sn],
            delta: vec![0.0; sn],
            y_stage: vec![0.0; n],
            incr: vec![0.0; n],
            y_new: vec![0.0; n],
            comp_new: vec![0.0; n],
            jac: vec![0.0; n * n],
            lu: DenseLu::new(sn),
            lu_h: f64::NAN,
            jac_fresh: false,
            jac_valid: false,
            have_previous: false,
            predicted: false,
            rate: 1.0,
            pending: None,
            level: 0,
            max_level: MAX_LEVEL,
            subdivisions: None,
        })
    }

    /// The solver without sub-steps: a step whose stages do not converge fails the
    /// run at once, and every step is of the fixed size. For measuring what the
    /// fixed step does, as the step selection's trial steps do.
    pub fn without_sub_steps(mut self) -> Self {
        self.max_level = 0;
        self
    }

    /// The system, e.g. to read parameters or counters it keeps.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// Evaluates the collocation polynomial of the last step at `theta` (in units of
    /// the last step, from its start), minus `offset`, into `out`.
    fn polynomial(&self, theta: f64, out: &mut [f64]) {
        // Nodes 0, c_1..c_s, 1 with values 0, Z_1..Z_s, y - y_old (relative to y_old).
        let s = self.tab.s;
        let mut nodes = [0.0; 5];
        nodes[1..=s].copy_from_slice(&self.tab.c[..s]);
        nodes[s + 1] = 1.0;
        let m = s + 2;
        let mut weights = [0.0; 5];
        for (k, w) in weights.iter_mut().enumerate().take(m) {
            let mut l = 1.0;
            for j in 0..m {
                if j != k {
                    l *= (theta - nodes[j]) / (nodes[k] - nodes[j]);
                }
            }
            *w = l;
        }
        let n = self.n;
        for a in 0..n {
            let mut v = self.y_old[a];
            for i in 0..s {
                v += weights[i + 1] * self.z_old[i * n + a];
            }
            v += weights[s + 1] * (self.state.y[a] - self.y_old[a]);
            out[a] = v;
        }
    }

    /// Starting values for the stages of the step `[t, t + h]`: the previous step's
    /// collocation polynomial extrapolated (kept in `z_pred`), or at the first step
    /// Euler's `c_i h F(t, y)`.
    fn start_values(&mut self, t: f64, h: f64) -> Result<(), SolveError> {
        let n = self.n;
        let s = self.tab.s;
        self.predicted = self.have_previous;
        if self.have_previous {
            let h_old = t - self.state.t_old;
            let mut stage = std::mem::take(&mut self.y_stage);
            for i in 0..s {
                let theta = 1.0 + self.tab.c[i] * h / h_old;
                self.polynomial(theta, &mut stage);
                for a in 0..n {
                    self.z[i * n + a] = stage[a] - self.state.y[a];
                }
            }
            self.y_stage = stage;
            self.z_pred.copy_from_slice(&self.z);
        } else {
            self.system.rhs(t, &self.state.y, &mut self.incr).map_err(|source| SolveError::Rhs { t, source })?;
            self.state.stats.rhs_evaluations += 1;
            for i in 0..s {
                for a in 0..n {
                    self.z[i * n + a] = self.tab.c[i] * h * self.incr[a];
                }
            }
        }
        Ok(())
    }

    /// Evaluates `F` at all stages.
    fn eval_stages(&mut self, t: f64, h: f64) -> Result<(), SolveError> {
        let n = self.n;
        for i in 0..self.tab.s {
            for a in 0..n {
                self.y_stage[a] = self.state.y[a] + self.z[i * n + a];
            }
            let ti = t + self.tab.c[i] * h;
            self.system
                .rhs(ti, &self.y_stage, &mut self.f[i * n..(i + 1) * n])
                .map_err(|source| SolveError::Rhs { t: ti, source })?;
            self.state.stats.rhs_evaluations += 1;
            // A rate that is not finite ends the run there (the Newton solve would
            // spread it over every component, and no iteration recovers from it).
            if let Some(index) = first_non_finite(&self.f[i * n..(i + 1) * n]) {
                return Err(SolveError::NonFiniteState { t: ti, index });
            }
        }
        Ok(())
    }

    /// Refreshes `J` at `(t, y)` and factors `I − h A ⊗ J`.
    fn refresh_matrix(&mut self, t: f64, h: f64, new_jacobian: bool) -> Result<(), SolveError> {
        let n = self.n;
        let s = self.tab.s;
        if new_jacobian || !self.jac_valid {
            self.system.jacobian(t, &self.state.y, &mut self.jac).map_err(|source| SolveError::Rhs { t, source })?;
            self.state.stats.jacobian_evaluations += 1;
            self.jac_fresh = true;
            self.jac_valid = true;
        }
        let sn = s * n;
        let m = self.lu.matrix_mut();
        for i in 0..s {
            for j in 0..s {
                let haij = h * self.tab.a[i][j];
                for a in 0..n {
                    let row = (i * n + a) * sn + j * n;
                    for b in 0..n {
                        m[row + b] = -haij * self.jac[a * n + b];
                    }
                    if i == j {
                        m[row + a] += 1.0;
                    }
                }
            }
        }
        self.state.stats.lu_decompositions += 1;
        self.lu.factor().map_err(|source| SolveError::Linalg { t, source })?;
        self.lu_h = h;
        Ok(())
    }

    /// Iterates the stage equations from the current `z` until `F` (in `f`) is
    /// evaluated at stages whose remaining error is at round-off; returns whether
    /// that happened.
    ///
    /// The step's update `h Σ b_i F(Y_i)` is then taken from that `f`, without
    /// evaluating `F` once more at the corrected stages: its error is about `h‖J‖`
    /// times the distance of the stages to the solution, which the contraction
    /// (`rate`) bounds by `rate/(1 − rate)` times the last correction.
    fn iterate(&mut self, t: f64, h: f64, mode: Iteration) -> Result<bool, SolveError> {
        let n = self.n;
        let s = self.tab.s;
        let scale = self.state.y.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        let mut prev = f64::INFINITY;
        let mut rate = 1.0;
        for k in 1..=MAX_ITER {
            self.state.stats.newton_iterations += 1;
            self.eval_stages(t, h)?;
            // Residual r = h A F − Z (the fixed-point correction).
            for i in 0..s {
                for a in 0..n {
                    let mut acc = 0.0;
                    for j in 0..s {
                        acc += self.tab.a[i][j] * self.f[j * n + a];
                    }
                    self.delta[i * n + a] = h * acc - self.z[i * n + a];
                }
            }
            if mode == Iteration::Newton {
                self.lu.solve_in_place(&mut self.delta);
            }
            let size = self.delta.iter().fold(0.0_f64, |m, v| m.max(v.abs())) / scale;
            if !size.is_finite() {
                return Ok(false);
            }
            if k > 1 {
                rate = size / prev;
            }
            // Stalled at round-off: the correction is noise, and `f` belongs to `z`.
            if size >= prev && prev <= 1e-12 {
                return Ok(true);
            }
            for (z, d) in self.z.iter_mut().zip(&self.delta) {
                *z += d;
            }
            // Converged: the correction is at round-off, and the corrected stages
            // are off by `rate` times less. Fixed-point iteration contracts slowly,
            // and an error of a fraction of an ulp of one sign step after step (the
            // predictions err alike) would show as a drift of H: it runs on until
            // the correction vanishes or stalls.
            if size == 0.0 || (mode == Iteration::Newton && size <= f64::EPSILON) {
                self.rate = rate;
                return Ok(true);
            }
            if k > 2 && (rate > 0.9 || size > prev) {
                return Ok(false);
            }
            prev = size;
        }
        Ok(false)
    }

    /// `y_new += Σ d_i Z_i` with compensation in `comp_new`, from the solved stages:
    /// `h Σ b_i F(Y_i)` at the solution, and free of the bias `F` at the last iterate
    /// would have (it lags the corrected stages by one correction, which the
    /// predictions make of one sign from step to step).
    fn add_increment(&mut self) {
        let n = self.n;
        for a in 0..n {
            let mut acc = 0.0;
            for i in 0..self.tab.s {
                acc += self.tab.d[i] * self.z[i * n + a];
            }
            self.incr[a] = acc;
        }
        compensated_add(&mut self.y_new, &mut self.comp_new, &self.incr);
    }

    /// Solves the stage equations of `[t, t + h]` into `z` and `f`; false when no
    /// iteration converged.
    fn solve_stages(&mut self, t: f64, h: f64) -> Result<bool, SolveError> {
        self.start_values(t, h)?;
        // 1. Simplified Newton with the kept matrix (refactored if h changed).
        // (The fixed clock's steps differ in their last bits: that is the same step;
        // lu_h is NaN before the first factorization.)
        let same_step = (self.lu_h - h).abs() <= 1e-6 * h;
        if !same_step || !self.jac_valid {
            self.refresh_matrix(t, h, false)?;
        }
        if self.iterate(t, h, Iteration::Newton)? {
            // Slow convergence: take a new Jacobian at the next step.
            if self.rate > 0.1 {
                self.jac_valid = false;
            }
            self.jac_fresh = false;
            return Ok(true);
        }
        // 2. Newton with a fresh Jacobian.
        if !self.jac_fresh {
            self.restart_values(h);
            self.refresh_matrix(t, h, true)?;
            let converged = self.iterate(t, h, Iteration::Newton)?;
            self.jac_fresh = false;
            if converged {
                return Ok(true);
            }
        }
        // 3. Fixed-point iteration.
        self.restart_values(h);
        self.iterate(t, h, Iteration::FixedPoint)
    }

    /// The starting values again, after an iteration that diverged from them.
    fn restart_values(&mut self, h: f64) {
        if self.predicted {
            self.z.copy_from_slice(&self.z_pred);
        } else {
            // Euler's start; `incr` still holds F(t, y).
            let n = self.n;
            for i in 0..self.tab.s {
                for a in 0..n {
                    self.z[i * n + a] = self.tab.c[i] * h * self.incr[a];
                }
            }
        }
    }

    /// One attempt at the step `[t, t + h]` from the current state, into `y_new`:
    /// false when its stages do not converge.
    fn attempt(&mut self, t: f64, h: f64) -> Result<bool, SolveError> {
        if !self.solve_stages(t, h)? {
            return Ok(false);
        }
        self.y_new.copy_from_slice(&self.state.y);
        self.comp_new.copy_from_slice(&self.comp);
        self.add_increment();
        Ok(true)
    }
}

impl<S: OdeSystem> Solver for Gauss<S> {
    fn method(&self) -> Method {
        self.method
    }
    fn solver_state(&self) -> &SolverState {
        &self.state
    }
    fn solver_state_mut(&mut self) -> &mut SolverState {
        &mut self.state
    }

    /// One step of the fixed grid, or one sub-step of it: a step whose stages do not
    /// converge, or that is too long for the motion, is taken as 2, 4, … sub-steps
    /// (each a Gauss step, a symplectic map), and the next grid step tries one
    /// halving fewer.
    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        self.state.check_max_steps()?;
        let mut p = match self.pending {
            Some(p) => p,
            None => {
                let (end, reached) = self.clock.next(self.state.h, self.state.stop);
                self.level = self.level.saturating_sub(1);
                Pending { start: self.state.t, end, reached, done: 0, subdivided: self.level > 0, counted: false }
            }
        };
        let (t, t_next) = loop {
            let count = 1u64 << self.level;
            let at = |j: u64| if j == count { p.end } else { p.start + (p.end - p.start) * (j as f64 / count as f64) };
            let (t, t_next) = (at(p.done), at(p.done + 1));
            if self.attempt(t, t_next - t)? {
                break (t, t_next);
            }
            self.state.stats.rejected += 1;
            if self.level == self.max_level {
                self.pending = None;
                return Err(if count == 1 {
                    SolveError::NoConvergence { t, h: p.end - p.start }
                } else {
                    SolveError::SubStepsFailed { t, h: p.end - p.start, sub_steps: count as usize }
                });
            }
            self.level += 1;
            p.done *= 2;
            p.subdivided = true;
        };
        if let Some(index) = first_non_finite(&self.y_new) {
            self.pending = None;
            return Err(SolveError::NonFiniteState { t: t_next, index });
        }
        std::mem::swap(&mut self.y_old, &mut self.state.y);
        std::mem::swap(&mut self.state.y, &mut self.y_new);
        std::mem::swap(&mut self.comp_old, &mut self.comp);
        std::mem::swap(&mut self.comp, &mut self.comp_new);
        std::mem::swap(&mut self.z_old, &mut self.z);
        self.have_previous = true;
        self.state.t_old = t;
        self.state.stats.steps += 1;
        p.done += 1;
        if p.subdivided {
            let sub = t_next - t;
            let d = self.subdivisions.get_or_insert(Subdivisions { steps: 0, first_t: p.start, shortest: sub });
            d.shortest = d.shortest.min(sub);
            // Counted at its first sub-step, so that a run failing inside it counts it.
            if !p.counted {
                d.steps += 1;
                p.counted = true;
            }
        }
        if p.done < 1u64 << self.level {
            self.pending = Some(p);
            self.state.t = t_next;
            return Ok(StepOutcome::Stepped);
        }
        self.pending = None;
        if p.reached {
            // The stop time this grid step was cut to, even if it was moved since.
            self.state.stop = Some(p.end);
        }
        self.state.t = self.clock.advance(self.state.h, p.reached, &mut self.state.stop);
        Ok(if p.reached { StepOutcome::ReachedStop } else { StepOutcome::Stepped })
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError> {
        check_len(self.n, out.len())?;
        let t1 = self.state.t;
        check_interpolation(t, self.state.t_old, t1)?;
        let h = t1 - self.state.t_old;
        if h == 0.0 {
            out.copy_from_slice(&self.state.y);
            return Ok(());
        }
        self.polynomial((t - self.state.t_old) / h, out);
        Ok(())
    }

    /// The collocation step from the last step's start to `t` (order 2s), where
    /// the collocation polynomial is of order s.
    fn subdivisions(&self) -> Option<Subdivisions> {
        self.subdivisions
    }

    fn restep(&mut self, t: f64, out: &mut [f64]) -> Option<Result<(), SolveError>> {
        Some((|| {
            check_len(self.n, out.len())?;
            let (t0, t1) = (self.state.t_old, self.state.t);
            check_interpolation(t, t0, t1)?;
            if t >= t1 {
                out.copy_from_slice(&self.state.y);
                return Ok(());
            }
            if t <= t0 {
                out.copy_from_slice(&self.y_old);
                return Ok(());
            }
            // The stages are solved about `state.y`: put the step's start there,
            // with starting values from the right-hand side (the extrapolation of
            // the previous step assumes the solver at its end), and swap back.
            let h = t - t0;
            std::mem::swap(&mut self.state.y, &mut self.y_old);
            let had_previous = std::mem::replace(&mut self.have_previous, false);
            let rate = self.rate;
            let solved = self.solve_stages(t0, h);
            (self.have_previous, self.rate) = (had_previous, rate);
            if let Ok(true) = solved {
                self.y_new.copy_from_slice(&self.state.y);
                self.comp_new.copy_from_slice(&self.comp_old);
                self.add_increment();
                out.copy_from_slice(&self.y_new);
            }
            std::mem::swap(&mut self.state.y, &mut self.y_old);
            match solved? {
                true => Ok(()),
                false => Err(SolveError::NoConvergence { t: t0, h }),
            }
        })())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::Separable;
    use crate::test_models::Pendulum;
    use crate::RhsError;

    #[test]
    fn the_update_weights_are_b_times_a_inverse() {
        for s in 1..=3 {
            let tab = Tableau::of(s);
            for j in 0..s {
                let da: f64 = (0..s).map(|i| tab.d[i] * tab.a[i][j]).sum();
                assert!((da - tab.b[j]).abs() < 1e-15, "s = {s}, column {j}: {da} vs {}", tab.b[j]);
            }
        }
    }

    /// Newton iterations per step of gauss6 on a pendulum swinging to 2 rad.
    fn iterations_per_step(extrapolate: bool) -> f64 {
        let config = Config { dt: Some(0.05), ..Config::default() };
        let mut solver = Gauss::new(Separable(Pendulum), Method::Gauss6, 0.0, &[2.0, 0.0], &config).unwrap();
        for _ in 0..1000 {
            if !extrapolate {
                solver.have_previous = false;
            }
            solver.step().unwrap();
        }
        let stats = solver.statistics();
        stats.newton_iterations as f64 / stats.steps as f64
    }

    #[test]
    fn starting_values_from_the_last_step_save_iterations() {
        let (extrapolated, euler) = (iterations_per_step(true), iterations_per_step(false));
        assert!(extrapolated <= 4.0 && extrapolated < 0.9 * euler, "{extrapolated} vs {euler} iterations per step");
    }

    /// `y' = y²` from `y(0) = 1`: `y = 1/(1 − t)` blows up at t = 1.
    struct Blowup;
    impl OdeSystem for Blowup {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = y[0] * y[0];
            Ok(())
        }
    }

    #[test]
    fn steps_that_do_not_converge_are_taken_as_sub_steps() {
        let config = Config { dt: Some(0.1), ..Config::default() };
        let end = 0.99;
        // The step from 0.9 reaches past the blow-up: its stages have no solution.
        let mut fixed = Gauss::new(Blowup, Method::Gauss6, 0.0, &[1.0], &config).unwrap().without_sub_steps();
        fixed.set_stop_time(end).unwrap();
        let e = loop {
            match fixed.step() {
                Ok(StepOutcome::ReachedStop) => panic!("reached {end} without sub-steps"),
                Ok(StepOutcome::Stepped) => {}
                Err(e) => break e,
            }
        };
        assert!(matches!(e, SolveError::NoConvergence { .. }), "{e}");
        // With sub-steps it reaches the end, close to the solution.
        let mut solver = Gauss::new(Blowup, Method::Gauss6, 0.0, &[1.0], &config).unwrap();
        solver.set_stop_time(end).unwrap();
        while solver.step().unwrap() != StepOutcome::ReachedStop {}
        assert_eq!(solver.t(), end);
        let exact = 1.0 / (1.0 - end);
        assert!((solver.state()[0] - exact).abs() < 1e-2 * exact, "{} vs {exact}", solver.state()[0]);
        let sub = solver.subdivisions().expect("sub-steps were taken");
        assert!(sub.first_t >= 0.8 && sub.first_t < end && sub.shortest < 0.05, "{sub:?}");
        assert!(sub.steps >= 1, "{sub:?}");
        // A step that fails even as 2^16 sub-steps fails the run, naming its time.
        let mut solver = Gauss::new(Blowup, Method::Gauss6, 0.0, &[1.0], &config).unwrap();
        solver.set_stop_time(1.5).unwrap();
        let e = loop {
            match solver.step() {
                Ok(StepOutcome::ReachedStop) => panic!("stepped past the blow-up"),
                Ok(StepOutcome::Stepped) => {}
                Err(e) => break e,
            }
        };
        match e {
            SolveError::SubStepsFailed { t, sub_steps, .. } => {
                assert!(t > 0.99 && t <= 1.0, "{e}");
                assert_eq!(sub_steps, 1 << MAX_LEVEL);
            }
            // Or a stage past the singularity where y overflows.
            SolveError::NonFiniteState { t, .. } => assert!(t > 0.99 && t <= 1.0 + 1e-9, "{e}"),
            other => panic!("{other}"),
        }
    }
}
