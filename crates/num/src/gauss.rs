//! Gauss–Legendre collocation with 1, 2 or 3 stages (orders 2, 4, 6): implicit,
//! symmetric and symplectic for any Hamiltonian system written as an [`OdeSystem`],
//! with a fixed step. Enter with [`Gauss::new`].
//!
//! The stage equations `Z_i = h Σ_j a_ij F(t + c_j h, y + Z_j)` are solved by
//! simplified Newton iteration with the matrix `I − h A ⊗ J` (`J` the Jacobian at the
//! start of a step, kept while convergence stays fast), factored as one dense
//! `sn × sn` LU: `O((sn)³)` per factorization, which is fine for the few dozen
//! coordinates of a mechanics model. If Newton fails, fixed-point iteration from the
//! same start is tried. Iteration runs to round-off (the correction falls to a few
//! ulps of the state, or stops shrinking), so the quadratic invariants are kept
//! exactly and energy shows no drift. Starting values extrapolate the previous
//! step's collocation polynomial; the state is updated with compensated summation.
//! Dense output is the polynomial through `y_n`, the stage values and `y_{n+1}`
//! (of order s); where that is not accurate enough (the state at an event),
//! [`Solver::restep`] solves the step from its start to the time asked for.

use crate::error::SolveError;
use crate::linalg::DenseLu;
use crate::method::Method;
use crate::solver::{
    check_initial, check_interpolation, check_len, compensated_add, Config, FixedClock, Solver, SolverState,
    Statistics, StepOutcome,
};
use crate::system::{first_non_finite, OdeSystem};

/// Most iterations per attempt; simplified Newton typically needs 5–12 to round-off.
const MAX_ITER: usize = 60;

/// Butcher tableau of an `s`-stage Gauss method (padded to 3).
#[derive(Clone, Copy, Debug)]
struct Tableau {
    s: usize,
    a: [[f64; 3]; 3],
    b: [f64; 3],
    c: [f64; 3],
}

impl Tableau {
    fn of(stages: usize) -> Tableau {
        match stages {
            1 => Tableau { s: 1, a: [[0.5, 0.0, 0.0], [0.0; 3], [0.0; 3]], b: [1.0, 0.0, 0.0], c: [0.5, 0.0, 0.0] },
            2 => {
                let r = 3f64.sqrt() / 6.0;
                Tableau {
                    s: 2,
                    a: [[0.25, 0.25 - r, 0.0], [0.25 + r, 0.25, 0.0], [0.0; 3]],
                    b: [0.5, 0.5, 0.0],
                    c: [0.5 - r, 0.5 + r, 0.0],
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
    /// Stage increments `Z` (`s·n`) of the last step, the working ones and the stage
    /// derivatives `F(Y_i)`.
    z_old: Vec<f64>,
    z: Vec<f64>,
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
        })
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

    /// Starting values for the stages of the step `[t, t + h]`.
    fn start_values(&mut self, t: f64, h: f64) -> Result<(), SolveError> {
        let n = self.n;
        let s = self.tab.s;
        if self.have_previous {
            let h_old = t - self.state.t_old;
            for i in 0..s {
                let theta = 1.0 + self.tab.c[i] * h / h_old;
                // Borrow dance: evaluate into y_stage, then store.
                let mut tmp = std::mem::take(&mut self.y_stage);
                self.polynomial(theta, &mut tmp);
                for a in 0..n {
                    self.z[i * n + a] = tmp[a] - self.state.y[a];
                }
                self.y_stage = tmp;
            }
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

    /// Iterates the stage equations from the current `z`; returns whether it converged
    /// and the number of iterations.
    fn iterate(&mut self, t: f64, h: f64, mode: Iteration) -> Result<(bool, usize), SolveError> {
        let n = self.n;
        let s = self.tab.s;
        let scale = self.state.y.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        let mut prev = f64::INFINITY;
        let mut prev_rate = 1.0;
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
                return Ok((false, k));
            }
            for (z, d) in self.z.iter_mut().zip(&self.delta) {
                *z += d;
            }
            // Converged: the correction is at round-off, or stopped shrinking there.
            if size <= 2.0 * f64::EPSILON || (size >= prev && prev <= 1e-12) || size == 0.0 {
                // Final derivatives at the converged stages (used for the update).
                self.eval_stages(t, h)?;
                return Ok((true, k));
            }
            let rate = size / prev;
            if k > 2 && (rate > 1.0 || (rate * prev_rate).sqrt() > 0.9) {
                return Ok((false, k));
            }
            prev_rate = rate;
            prev = size;
        }
        Ok((false, MAX_ITER))
    }

    /// `y_new += h Σ b_i F(Y_i)` with compensation in `comp_new`, from the solved stages.
    fn add_increment(&mut self, h: f64) {
        let n = self.n;
        for a in 0..n {
            let mut acc = 0.0;
            for i in 0..self.tab.s {
                acc += self.tab.b[i] * self.f[i * n + a];
            }
            self.incr[a] = h * acc;
        }
        compensated_add(&mut self.y_new, &mut self.comp_new, &self.incr);
    }

    /// Solves the stage equations of `[t, t + h]` into `z` and `f`.
    fn solve_stages(&mut self, t: f64, h: f64) -> Result<(), SolveError> {
        // 1. Newton with the current matrix (refactored if h changed).
        if self.lu_h != h || !self.jac_valid {
            self.refresh_matrix(t, h, false)?;
        }
        self.start_values(t, h)?;
        let (ok, iters) = self.iterate(t, h, Iteration::Newton)?;
        if ok {
            // Slow convergence: take a new Jacobian at the next step.
            if iters > 10 {
                self.jac_valid = false;
            }
            self.jac_fresh = false;
            return Ok(());
        }
        self.state.stats.rejected += 1;
        // 2. Newton with a fresh Jacobian.
        if !self.jac_fresh {
            self.refresh_matrix(t, h, true)?;
            self.start_values(t, h)?;
            let (ok, _) = self.iterate(t, h, Iteration::Newton)?;
            self.jac_fresh = false;
            if ok {
                return Ok(());
            }
            self.state.stats.rejected += 1;
        }
        // 3. Fixed-point iteration.
        self.start_values(t, h)?;
        let (ok, _) = self.iterate(t, h, Iteration::FixedPoint)?;
        if ok {
            return Ok(());
        }
        Err(SolveError::NoConvergence { t, h })
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

    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        let t = self.state.t;
        self.state.check_max_steps()?;
        let (t_next, reached) = self.clock.next(self.state.h, self.state.stop);
        let h = t_next - t;
        self.solve_stages(t, h)?;
        self.y_new.copy_from_slice(&self.state.y);
        self.comp_new.copy_from_slice(&self.comp);
        self.add_increment(h);
        if let Some(index) = first_non_finite(&self.y_new) {
            return Err(SolveError::NonFiniteState { t: t_next, index });
        }
        std::mem::swap(&mut self.y_old, &mut self.state.y);
        std::mem::swap(&mut self.state.y, &mut self.y_new);
        std::mem::swap(&mut self.comp_old, &mut self.comp);
        std::mem::swap(&mut self.comp, &mut self.comp_new);
        std::mem::swap(&mut self.z_old, &mut self.z);
        self.have_previous = true;
        self.state.t_old = t;
        self.state.t = self.clock.advance(self.state.h, reached, &mut self.state.stop);
        self.state.stats.steps += 1;
        Ok(if reached { StepOutcome::ReachedStop } else { StepOutcome::Stepped })
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
            let solved = self.solve_stages(t0, h);
            self.have_previous = had_previous;
            if solved.is_ok() {
                self.y_new.copy_from_slice(&self.state.y);
                self.comp_new.copy_from_slice(&self.comp_old);
                self.add_increment(h);
                out.copy_from_slice(&self.y_new);
            }
            std::mem::swap(&mut self.state.y, &mut self.y_old);
            solved
        })())
    }
}
