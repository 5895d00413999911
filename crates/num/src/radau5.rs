//! Radau IIA with 3 stages (order 5), adaptive, for stiff problems: Hairer's `RADAU5`
//! approach (Hairer & Wanner, *Solving ODEs II*, §IV.8). Enter with [`Radau5::new`].
//!
//! - Stage equations by simplified Newton with `I − h A ⊗ J`, factored as one real
//!   `3n × 3n` LU. RADAU5 instead diagonalizes `A` and factors one real and one complex
//!   `n × n` matrix (about `5n³/3` flops against `9n³` here); for the small systems of
//!   mechanics models the simpler form costs little and is easier to trust.
//! - Newton convergence monitored by the contraction rate `θ`, with Hairer's stopping
//!   test `θ/(1−θ)·‖ΔZ‖ ≤ κ·tol` and his early step reduction when convergence is too slow.
//! - Error estimate `(I − hγ₀J)⁻¹[hγ₀ f(y₀) + e₁Z₁ + e₂Z₂ + e₃Z₃]`, refined by one more
//!   solve after a rejection (the stiff-safe variant), and the predictive (Gustafsson)
//!   step-size controller.
//! - Jacobian kept while Newton converges fast (`θ ≤ 0.001`), LU kept while the step
//!   changes by less than 20 %.
//! - Dense output: the collocation polynomial through `y₀` and the three stage values.
//!
//! Tolerances are transformed as in RADAU5 (`rtol' = 0.1·rtol^(2/3)`), so the
//! user's `rtol` is comparable with the explicit methods'.

use crate::adaptive::StepControl;
use crate::error::SolveError;
use crate::linalg::DenseLu;
use crate::method::Method;
use crate::solver::{
    check_initial, check_interpolation, check_len, Config, Solver, SolverState, Statistics, StepOutcome,
};
use crate::system::{first_non_finite, OdeSystem};

/// Most Newton iterations per attempt (RADAU5's `NIT`).
const NIT: usize = 7;
/// Safety factor of the step-size choice.
const SAFE: f64 = 0.9;
/// Keep the Jacobian when the Newton contraction rate is below this (RADAU5's `THET`).
const THET: f64 = 0.001;
/// Step ratio window in which the LU is kept.
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
/// `h_old/h_new` bounds: the step grows at most 8× and shrinks at most 5× per step.
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;

/// The Radau IIA (order 5) solver; see the module documentation.
#[derive(Clone, Debug)]
pub struct Radau5<S> {
    system: S,
    rtol: f64,
    atol: f64,
    h_max: f64,
    /// Time, state, step, stop time and counters (what the accessors read).
    state: SolverState,
    fnewt: f64,
    a: [[f64; 3]; 3],
    c: [f64; 3],
    e: [f64; 3],
    u1: f64,
    n: usize,
    h_old: f64,
    y_old: Vec<f64>,
    f0: Vec<f64>,
    scal: Vec<f64>,
    z: Vec<f64>,
    z_old: Vec<f64>,
    f: Vec<f64>,
    delta: Vec<f64>,
    y_stage: Vec<f64>,
    cont: Vec<f64>,
    err_vec: Vec<f64>,
    jac: Vec<f64>,
    lu: DenseLu,
    lu_err: DenseLu,
    faccon: f64,
    theta: f64,
    first: bool,
    have_previous: bool,
    last_rejected: bool,
    /// Gustafsson controller memory.
    h_acc: f64,
    err_acc: f64,
}

impl<S: OdeSystem> Radau5<S> {
    /// A solver for `y' = F(t, y)` from `(t0, y0)`. Uses `rtol`, `atol`, `h_init`,
    /// `h_max` and `max_steps` of `config`; without `h_init` the first step is `1e-6`
    /// (RADAU5's default; the controller grows it by up to 8× per step).
    pub fn new(mut system: S, t0: f64, y0: &[f64], config: &Config) -> Result<Self, SolveError> {
        config.validate()?;
        let n = system.dim();
        check_initial(n, t0, y0)?;
        let s6 = 6f64.sqrt();
        let a = [
            [(88.0 - 7.0 * s6) / 360.0, (296.0 - 169.0 * s6) / 1800.0, (-2.0 + 3.0 * s6) / 225.0],
            [(296.0 + 169.0 * s6) / 1800.0, (88.0 + 7.0 * s6) / 360.0, (-2.0 - 3.0 * s6) / 225.0],
            [(16.0 - s6) / 36.0, (16.0 + s6) / 36.0, 1.0 / 9.0],
        ];
        let c = [(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0];
        // Real eigenvalue of A⁻¹ and the error-estimate weights (RADAU5's DD1..DD3).
        let u1 = 30.0 / (6.0 + 81f64.cbrt() - 9f64.cbrt());
        let e = [-(13.0 + 7.0 * s6) / 3.0, (-13.0 + 7.0 * s6) / 3.0, -1.0 / 3.0];
        // Tolerance transformation of RADAU5.
        let rtol_user = config.rtol.max(100.0 * f64::EPSILON);
        let quot = config.atol / rtol_user;
        let rtol = 0.1 * rtol_user.powf(2.0 / 3.0);
        let atol = rtol * quot;
        let fnewt = (10.0 * f64::EPSILON / rtol).max(0.03_f64.min(rtol.sqrt()));
        let mut f0 = vec![0.0; n];
        system.rhs(t0, y0, &mut f0).map_err(|source| SolveError::Rhs { t: t0, source })?;
        if let Some(index) = first_non_finite(&f0) {
            return Err(SolveError::NonFiniteState { t: t0, index });
        }
        let h_max = config.h_max.unwrap_or(f64::INFINITY);
        let h = config.h_init.unwrap_or(1e-6).min(h_max);
        Ok(Radau5 {
            system,
            rtol,
            atol,
            h_max,
            fnewt,
            a,
            c,
            e,
            u1,
            n,
            state: SolverState::new(t0, y0, h, Statistics { rhs_evaluations: 1, ..Statistics::default() }, config),
            h_old: h,
            y_old: y0.to_vec(),
            f0,
            scal: vec![0.0; n],
            z: vec![0.0; 3 * n],
            z_old: vec![0.0; 3 * n],
            f: vec![0.0; 3 * n],
            delta: vec![0.0; 3 * n],
            y_stage: vec![0.0; n],
            cont: vec![0.0; n],
            err_vec: vec![0.0; n],
            jac: vec![0.0; n * n],
            lu: DenseLu::new(3 * n),
            lu_err: DenseLu::new(n),
            faccon: 1.0,
            theta: 1.0,
            first: true,
            have_previous: false,
            last_rejected: false,
            h_acc: h,
            err_acc: 1e-2,
        })
    }

    /// The system, e.g. to read parameters or counters it keeps.
    pub fn system(&self) -> &S {
        &self.system
    }

    fn new_jacobian(&mut self) -> Result<(), SolveError> {
        self.system
            .jacobian(self.state.t, &self.state.y, &mut self.jac)
            .map_err(|source| SolveError::Rhs { t: self.state.t, source })?;
        self.state.stats.jacobian_evaluations += 1;
        Ok(())
    }

    /// Factors `I − h A ⊗ J` and `(u1/h) I − J`.
    fn factor(&mut self, h: f64) -> Result<(), SolveError> {
        let n = self.n;
        let sn = 3 * n;
        let m = self.lu.matrix_mut();
        for i in 0..3 {
            for j in 0..3 {
                let haij = h * self.a[i][j];
                for r in 0..n {
                    let row = (i * n + r) * sn + j * n;
                    for col in 0..n {
                        m[row + col] = -haij * self.jac[r * n + col];
                    }
                    if i == j {
                        m[row + r] += 1.0;
                    }
                }
            }
        }
        let fac = self.u1 / h;
        let me = self.lu_err.matrix_mut();
        for r in 0..n {
            for col in 0..n {
                me[r * n + col] = -self.jac[r * n + col];
            }
            me[r * n + r] += fac;
        }
        self.state.stats.lu_decompositions += 2;
        let t = self.state.t;
        self.lu.factor().map_err(|source| SolveError::Linalg { t, source })?;
        self.lu_err.factor().map_err(|source| SolveError::Linalg { t, source })?;
        Ok(())
    }

    /// Collocation polynomial of the last step at `theta`, into `out`.
    fn polynomial(&self, theta: f64, out: &mut [f64]) {
        let nodes = [0.0, self.c[0], self.c[1], 1.0];
        let mut w = [0.0; 4];
        for (k, wk) in w.iter_mut().enumerate() {
            let mut l = 1.0;
            for (j, &nj) in nodes.iter().enumerate() {
                if j != k {
                    l *= (theta - nj) / (nodes[k] - nj);
                }
            }
            *wk = l;
        }
        let n = self.n;
        for r in 0..n {
            out[r] = self.y_old[r] + w[1] * self.z_old[r] + w[2] * self.z_old[n + r] + w[3] * self.z_old[2 * n + r];
        }
    }

    fn start_values(&mut self, h: f64) {
        let n = self.n;
        if !self.have_previous {
            self.z.fill(0.0);
            return;
        }
        let mut tmp = std::mem::take(&mut self.y_stage);
        for i in 0..3 {
            let theta = 1.0 + self.c[i] * h / self.h_old;
            self.polynomial(theta, &mut tmp);
            for r in 0..n {
                self.z[i * n + r] = tmp[r] - self.state.y[r];
            }
        }
        self.y_stage = tmp;
    }

    fn eval_stages(&mut self, h: f64) -> Result<(), SolveError> {
        let n = self.n;
        for i in 0..3 {
            for r in 0..n {
                self.y_stage[r] = self.state.y[r] + self.z[i * n + r];
            }
            let ti = self.state.t + self.c[i] * h;
            self.system
                .rhs(ti, &self.y_stage, &mut self.f[i * n..(i + 1) * n])
                .map_err(|source| SolveError::Rhs { t: ti, source })?;
            self.state.stats.rhs_evaluations += 1;
        }
        Ok(())
    }

    fn norm(&self, v: &[f64]) -> f64 {
        let n = self.n;
        let mut sum = 0.0;
        for (k, x) in v.iter().enumerate() {
            sum += (x / self.scal[k % n]).powi(2);
        }
        (sum / v.len() as f64).sqrt()
    }

    /// Newton iteration; `Ok(Some(newt))` when converged, `Ok(None)` when it must be
    /// retried with step `self.state.h` (already reduced).
    fn newton(&mut self, h: f64) -> Result<Option<usize>, SolveError> {
        let n = self.n;
        self.faccon = self.faccon.max(f64::EPSILON).powf(0.8);
        self.theta = self.theta.abs();
        let mut dynold = 0.0_f64;
        let mut thqold = 0.0_f64;
        let mut newt = 0;
        loop {
            if newt >= NIT {
                return Ok(None);
            }
            self.eval_stages(h)?;
            self.state.stats.newton_iterations += 1;
            for i in 0..3 {
                for r in 0..n {
                    let mut acc = 0.0;
                    for j in 0..3 {
                        acc += self.a[i][j] * self.f[j * n + r];
                    }
                    self.delta[i * n + r] = h * acc - self.z[i * n + r];
                }
            }
            self.lu.solve_in_place(&mut self.delta);
            let dyno = self.norm(&self.delta);
            if !dyno.is_finite() {
                return Ok(None);
            }
            if newt >= 1 {
                let thq = dyno / dynold;
                self.theta = if newt == 1 { thq } else { (thq * thqold).sqrt() };
                thqold = thq;
                if self.theta < 0.99 {
                    self.faccon = self.theta / (1.0 - self.theta);
                    let dyth = self.faccon * dyno * self.theta.powi((NIT - 1 - newt) as i32) / self.fnewt;
                    if dyth >= 1.0 {
                        // Convergence too slow for the iterations left: reduce h early.
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let hhfac = 0.8 * qnewt.powf(-1.0 / (4.0 + (NIT - 1 - newt) as f64));
                        self.state.h = h * hhfac;
                        return Ok(None);
                    }
                } else {
                    return Ok(None);
                }
            }
            dynold = dyno.max(f64::EPSILON);
            for (z, d) in self.z.iter_mut().zip(&self.delta) {
                *z += d;
            }
            newt += 1;
            if self.faccon * dyno <= self.fnewt {
                return Ok(Some(newt));
            }
        }
    }

    /// RADAU5's error estimate for the converged stages of step `h`.
    fn error_estimate(&mut self, h: f64) -> Result<f64, SolveError> {
        let n = self.n;
        for r in 0..n {
            let f2 = (self.e[0] * self.z[r] + self.e[1] * self.z[n + r] + self.e[2] * self.z[2 * n + r]) / h;
            self.err_vec[r] = f2;
            self.cont[r] = f2 + self.f0[r];
        }
        self.lu_err.solve_in_place(&mut self.cont);
        let mut err = self.norm(&self.cont).max(1e-10);
        if err >= 1.0 && (self.first || self.last_rejected) {
            for r in 0..n {
                self.y_stage[r] = self.state.y[r] + self.cont[r];
            }
            self.system
                .rhs(self.state.t, &self.y_stage, &mut self.delta[..n])
                .map_err(|source| SolveError::Rhs { t: self.state.t, source })?;
            self.state.stats.rhs_evaluations += 1;
            for r in 0..n {
                self.cont[r] = self.delta[r] + self.err_vec[r];
            }
            self.lu_err.solve_in_place(&mut self.cont);
            err = self.norm(&self.cont).max(1e-10);
        }
        Ok(if err.is_finite() { err } else { f64::INFINITY })
    }

    fn failure(&self, h: f64) -> SolveError {
        let n = self.n;
        if let Some(index) = first_non_finite(&self.z).or_else(|| first_non_finite(&self.f)) {
            SolveError::NonFiniteState { t: self.state.t + h, index: index % n }
        } else {
            SolveError::StepSizeTooSmall { t: self.state.t, h }
        }
    }
}

impl<S: OdeSystem> Solver for Radau5<S> {
    fn method(&self) -> Method {
        Method::Radau5
    }
    fn solver_state(&self) -> &SolverState {
        &self.state
    }
    fn solver_state_mut(&mut self) -> &mut SolverState {
        &mut self.state
    }

    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        self.state.check_max_steps()?;
        let n = self.n;
        for r in 0..n {
            self.scal[r] = self.atol + self.rtol * self.state.y[r].abs();
        }
        // Jacobian at the step start, unless the last step said it could be kept.
        let mut jac_current = false;
        if self.first || self.theta > THET || self.state.stats.jacobian_evaluations == 0 {
            self.new_jacobian()?;
            jac_current = true;
        }
        let mut factored_h = f64::NAN;
        loop {
            let mut h = self.state.h.min(self.h_max);
            let mut reaches_stop = false;
            if let Some(stop) = self.state.stop {
                if self.state.t + 1.0001 * h >= stop {
                    h = stop - self.state.t;
                    reaches_stop = true;
                }
            }
            if reaches_stop && h == 0.0 {
                self.state.stop = None;
                return Ok(StepOutcome::ReachedStop);
            }
            if !reaches_stop && h < StepControl::h_min(self.state.t) {
                return Err(self.failure(h));
            }
            if factored_h != h {
                self.factor(h)?;
                factored_h = h;
            }
            self.start_values(h);
            let converged = self.newton(h)?;
            let Some(newt) = converged else {
                // Newton failed: smaller step (if not already reduced), fresh Jacobian.
                self.state.stats.rejected += 1;
                if self.state.h >= h {
                    self.state.h = 0.5 * h;
                }
                self.last_rejected = true;
                if self.state.h < StepControl::h_min(self.state.t) {
                    return Err(self.failure(h));
                }
                if !jac_current {
                    self.new_jacobian()?;
                    jac_current = true;
                }
                continue;
            };
            let err = self.error_estimate(h)?;
            let fac = SAFE.min(SAFE * (1.0 + 2.0 * NIT as f64) / (newt as f64 + 2.0 * NIT as f64));
            let mut quot = (err.powf(0.25) / fac).clamp(FACR, FACL);
            if err < 1.0 {
                // Accepted.
                if !self.first {
                    let facgus = (self.h_acc / h) * (err * err / self.err_acc).powf(0.25) / SAFE;
                    quot = quot.max(facgus.clamp(FACR, FACL));
                }
                self.h_acc = h;
                self.err_acc = err.max(1e-2);
                let mut h_new = (h / quot).min(self.h_max);
                if self.last_rejected {
                    h_new = h_new.min(h);
                }
                // Commit.
                std::mem::swap(&mut self.y_old, &mut self.state.y);
                for r in 0..n {
                    self.state.y[r] = self.y_old[r] + self.z[2 * n + r];
                }
                if let Some(index) = first_non_finite(&self.state.y) {
                    std::mem::swap(&mut self.y_old, &mut self.state.y);
                    return Err(SolveError::NonFiniteState { t: self.state.t + h, index });
                }
                std::mem::swap(&mut self.z_old, &mut self.z);
                self.state.t_old = self.state.t;
                self.state.t =
                    if reaches_stop { self.state.stop.take().unwrap_or(self.state.t + h) } else { self.state.t + h };
                self.h_old = h;
                self.have_previous = true;
                self.first = false;
                self.last_rejected = false;
                self.state.stats.steps += 1;
                let t = self.state.t;
                self.system.rhs(t, &self.state.y, &mut self.f0).map_err(|source| SolveError::Rhs { t, source })?;
                self.state.stats.rhs_evaluations += 1;
                // Keep h (and the LU) if the change would be small and Newton was fast.
                let qt = h_new / h;
                self.state.h = if self.theta <= THET && (QUOT1..=QUOT2).contains(&qt) { h } else { h_new };
                if reaches_stop {
                    self.state.h = self.state.h.max(h_new);
                }
                return Ok(if reaches_stop { StepOutcome::ReachedStop } else { StepOutcome::Stepped });
            }
            // Rejected.
            self.state.stats.rejected += 1;
            self.last_rejected = true;
            self.state.h = if self.first { 0.1 * h } else { h / quot };
            if self.state.h < StepControl::h_min(self.state.t) {
                return Err(self.failure(h));
            }
            if !jac_current {
                self.new_jacobian()?;
                jac_current = true;
            }
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError> {
        check_len(self.n, out.len())?;
        check_interpolation(t, self.state.t_old, self.state.t)?;
        let h = self.state.t - self.state.t_old;
        if h == 0.0 {
            out.copy_from_slice(&self.state.y);
            return Ok(());
        }
        self.polynomial((t - self.state.t_old) / h, out);
        Ok(())
    }
}
