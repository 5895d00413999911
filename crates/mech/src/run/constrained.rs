//! Constrained dynamics, numerically: `M q'' = f + Aᵀλ` with the constraints
//! differentiated to acceleration level (index reduction), solved for q'' and λ
//! together at every evaluation,
//!
//! ```text
//! [ M  −Aᵀ ] [ q'' ]   [ f ]
//! [ A   0  ] [ λ   ] = [ c ],   c = −(Σ_j ∂g/∂q_j q_j' + ∂g/∂t),  g = A q' + a_t,
//! ```
//!
//! and kept on the constraint manifold by projection after every step: positions
//! by Gauss–Newton on the holonomic `f(q, t) = 0` (minimum-norm corrections
//! `Δq = −Aᵀ(AAᵀ)⁻¹f`, iterated to round-off), then velocities onto
//! `A q' + a_t = 0` (one exact linear projection). Without it the residual of an
//! index-reduced system drifts (linearly in t for the velocities, quadratically
//! for the positions); with it the residual stays at round-off over any run. An
//! integrable velocity constraint whose integral F is known is held at position
//! level too, at F = F(q(0), 0), so it keeps its holonomic meaning over long runs.
//!
//! M and f come from the kernel of [`Dynamics`]; A, c, a_t and f(q, t) are this
//! module's kernels. Entry point: [`Constrained::start`] (called by [`crate::simulate`] for models with
//! `[[constraints]]`). Initial values must satisfy the constraints: a residual
//! beyond round-off (`INITIAL_TOLERANCE`) is bad input (exit 2) naming the
//! constraint and by how much; within it the state is projected silently.

use crate::derive::constraint::generic_rank;
use crate::derive::Derivation;
use crate::error::ModelError;
use crate::model::ConstraintKind;
use crate::run::dynamics::{Dynamics, Form, Kernel};
use crate::run::{
    Audit, ConstraintAudit, ProjectionMap, RowBuffer, RunConfig, RunError, RunFailure, RunWarning, Start, Stepping,
    TimeScale, VelocityMap,
};
use num::{LinearSolver, Method, OdeSystem, RhsError, SolveError};
use sym::{ExprId, Tape};

/// The largest initial residual (relative to the size of the constraint's
/// terms) that is taken for round-off and projected away; beyond it the
/// initial values are rejected (the start's own check,
/// [`crate::Derivation::check_constraints_at`], uses the same).
pub use crate::derive::constraint::INITIAL_TOLERANCE;

/// The CSV columns a constrained run adds, in the order of [`Row::constraints`](crate::Row::constraints):
/// per constraint `lambda_NAME`, `force_NAME` (|Aᵀλ|), `residual_NAME` (f for a
/// holonomic constraint, A q' + a_t for a velocity one) and, for a holonomic
/// constraint, `residual_NAME'` (its time derivative A q' + a_t); then, when the
/// constraints do work on a system whose H would be conserved,
/// `W_constraints` = ∫ Aᵀλ·q' dt (so that H − W is conserved).
pub fn constraint_columns(d: &Derivation) -> Vec<String> {
    let mut cols = Vec::new();
    for c in &d.constraints.list {
        cols.extend(crate::model::columns::constraint_columns(&c.name, c.kind));
    }
    if d.constraints.work_balances_h {
        cols.push("W_constraints".into());
    }
    cols
}

/// The compiled constrained system in the Lagrange form `[q, q']`.
#[derive(Debug, Clone)]
pub struct ConstrainedSystem {
    dynamics: Dynamics,
    n: usize,
    m: usize,
    /// Indices of the holonomic constraints.
    holonomic: Vec<usize>,
    /// Whether the state carries W = ∫ Aᵀλ·q' dt as a last component.
    work: bool,
    /// Indices of the constraints kept at position level by the projection: the
    /// holonomic ones, then the integrable velocity constraints with a known
    /// integral F (whose gradient is their row of A), kept at F = F(t = 0).
    positional: Vec<usize>,
    /// What each positional constraint's expression must equal (0, or F(t = 0)).
    levels: Vec<f64>,
    /// `[A (m×n), c (m)]` from `[q, q', t, params]`.
    accel: Kernel,
    /// `[A (m×n), a_t (m), f_h (holonomic count)]` from `[q, q', t, params]`.
    geometry: Kernel,
    inputs: Vec<f64>,
    mf: Vec<f64>,
    ac: Vec<f64>,
    geo: Vec<f64>,
    kkt: Vec<f64>,
    sol: Vec<f64>,
    lu: LinearSolver,
    projection: Projection,
}

/// Scratch space of the projection, allocated once.
#[derive(Debug, Clone)]
struct Projection {
    all_rows: Vec<usize>,
    residual: Vec<f64>,
    gram: Vec<f64>,
    mu: Vec<f64>,
    dq: Vec<f64>,
    lu_positions: LinearSolver,
    lu_velocities: LinearSolver,
}

/// Which rows of A a correction uses (the solvers are sized for each).
#[derive(Clone, Copy)]
enum RowsOf {
    Positions,
    All,
}

/// The minimum-norm correction `Bᵀ(BBᵀ)⁻¹r` for the rows B of A (row-major in
/// `geo`, n columns) that `which` names, and the residual `p.residual[..rows]`,
/// into `p.dq`.
fn min_norm_correction(
    geo: &[f64],
    n: usize,
    positional: &[usize],
    p: &mut Projection,
    which: RowsOf,
) -> Result<(), RhsError> {
    let (rows, lu) = match which {
        RowsOf::Positions => (positional, &mut p.lu_positions),
        RowsOf::All => (&p.all_rows[..], &mut p.lu_velocities),
    };
    let k = rows.len();
    let gram = &mut p.gram[..k * k];
    for (i, &ri) in rows.iter().enumerate() {
        for (j, &rj) in rows.iter().enumerate() {
            gram[i * k + j] = (0..n).map(|c| geo[ri * n + c] * geo[rj * n + c]).sum();
        }
    }
    lu.factor(gram).map_err(RhsError::from)?;
    let mu = &mut p.mu[..k];
    mu.copy_from_slice(&p.residual[..k]);
    lu.solve_in_place(mu).map_err(RhsError::from)?;
    for (j, d) in p.dq.iter_mut().enumerate() {
        *d = rows.iter().enumerate().map(|(i, &ri)| geo[ri * n + j] * mu[i]).sum();
    }
    Ok(())
}

impl ConstrainedSystem {
    /// Compiles the constraint kernels of a derivation next to its dynamics.
    pub fn new(d: &Derivation, dynamics: Dynamics) -> ConstrainedSystem {
        let n = d.q.len();
        let list = d.constraints.list.clone();
        let m = list.len();
        let input_syms = d.layout.symbols();
        let pool = d.pool();
        let a: Vec<ExprId> = list.iter().flat_map(|c| c.jacobian.iter().copied()).collect();
        let mut accel_out = a.clone();
        accel_out.extend(list.iter().map(|c| c.acceleration_rhs));
        accel_out.extend(list.iter().map(|c| c.time_term));
        let mut geo_out = a;
        geo_out.extend(list.iter().map(|c| c.time_term));
        let holonomic: Vec<usize> = (0..m).filter(|&k| list[k].kind == ConstraintKind::Holonomic).collect();
        let integrals: Vec<usize> =
            (0..m).filter(|&k| list[k].kind == ConstraintKind::Velocity && list[k].integral.is_some()).collect();
        let positional: Vec<usize> = holonomic.iter().chain(&integrals).copied().collect();
        geo_out.extend(positional.iter().map(|&k| list[k].integral.unwrap_or(list[k].expr)));
        let compile =
            |outs: &[ExprId]| Kernel::new(Tape::compile(pool, outs, input_syms).expect("model symbols are inputs"));
        let accel = compile(&accel_out);
        let geometry = compile(&geo_out);
        let inputs = dynamics.input_template().to_vec();
        let mh = positional.len();
        ConstrainedSystem {
            dynamics,
            n,
            m,
            holonomic,
            work: d.constraints.work_balances_h,
            levels: vec![0.0; positional.len()],
            positional,
            accel,
            geometry,
            inputs,
            mf: vec![0.0; n * n + n],
            ac: vec![0.0; m * n + 2 * m],
            geo: vec![0.0; m * n + m + mh],
            kkt: vec![0.0; (n + m) * (n + m)],
            sol: vec![0.0; n + m],
            lu: LinearSolver::new(n + m).with_pivot_threshold(0.0),
            projection: Projection {
                all_rows: (0..m).collect(),
                residual: vec![0.0; m],
                gram: vec![0.0; m * m],
                mu: vec![0.0; m],
                dq: vec![0.0; n],
                lu_positions: LinearSolver::new(mh).with_pivot_threshold(0.0),
                lu_velocities: LinearSolver::new(m).with_pivot_threshold(0.0),
            },
        }
    }

    /// Solves the saddle-point system at (q, q', t): q'' in `sol[..n]`, λ in `sol[n..]`.
    fn solve(&mut self, t: f64, y: &[f64]) -> Result<(), RhsError> {
        let (n, m) = (self.n, self.m);
        self.inputs[..2 * n].copy_from_slice(&y[..2 * n]);
        self.inputs[2 * n] = t;
        self.dynamics.eval_mass_forcing(&self.inputs, &mut self.mf);
        self.accel.eval(&self.inputs, &mut self.ac);
        let w = n + m;
        self.kkt.fill(0.0);
        for i in 0..n {
            self.kkt[i * w..i * w + n].copy_from_slice(&self.mf[i * n..(i + 1) * n]);
        }
        for k in 0..m {
            for j in 0..n {
                let a = self.ac[k * n + j];
                self.kkt[(n + k) * w + j] = a;
                self.kkt[j * w + n + k] = -a;
            }
        }
        self.sol[..n].copy_from_slice(&self.mf[n * n..]);
        self.sol[n..].copy_from_slice(&self.ac[m * n..m * n + m]);
        self.lu.factor(&self.kkt).map_err(RhsError::from)?;
        self.lu.solve_in_place(&mut self.sol).map_err(RhsError::from)?;
        Ok(())
    }

    /// Evaluates A, a_t and the holonomic f at (q, t) into `geo`.
    fn geometry_at(&mut self, t: f64, q: &[f64]) {
        let n = self.n;
        self.inputs[..n].copy_from_slice(q);
        self.inputs[n..2 * n].fill(0.0);
        self.inputs[2 * n] = t;
        self.geometry.eval(&self.inputs, &mut self.geo);
    }

    /// Keeps the integrals of integrable velocity constraints at their values at (t, y).
    pub fn fix_integral_levels(&mut self, t: f64, y: &[f64]) {
        let (n, m) = (self.n, self.m);
        self.geometry_at(t, &y[..n]);
        let n_holonomic = self.holonomic.len();
        for h in n_holonomic..self.positional.len() {
            self.levels[h] = self.geo[m * n + m + h];
        }
    }

    /// Projects `y = [q, q']` onto the constraint manifold at time t. Allocates
    /// nothing: it runs after every step.
    pub fn project(&mut self, t: f64, y: &mut [f64]) -> Result<(), RhsError> {
        let (n, m) = (self.n, self.m);
        let mh = self.positional.len();
        if mh > 0 {
            for _ in 0..8 {
                self.geometry_at(t, &y[..n]);
                let p = &mut self.projection;
                for (h, r) in p.residual[..mh].iter_mut().enumerate() {
                    *r = self.geo[m * n + m + h] - self.levels[h];
                }
                if p.residual[..mh].iter().all(|&v| v == 0.0) {
                    break;
                }
                min_norm_correction(&self.geo, n, &self.positional, p, RowsOf::Positions)?;
                let size = y[..n].iter().fold(1.0f64, |a, v| a.max(v.abs()));
                for i in 0..n {
                    y[i] -= p.dq[i];
                }
                if p.dq.iter().all(|v| v.abs() <= 2.0 * f64::EPSILON * size) {
                    break;
                }
            }
        }
        self.geometry_at(t, &y[..n]);
        let p = &mut self.projection;
        for k in 0..m {
            p.residual[k] = (0..n).map(|j| self.geo[k * n + j] * y[n + j]).sum::<f64>() + self.geo[m * n + k];
        }
        min_norm_correction(&self.geo, n, &self.positional, p, RowsOf::All)?;
        for i in 0..n {
            y[n + i] -= p.dq[i];
        }
        if let Some(index) = y.iter().position(|v| !v.is_finite()) {
            return Err(RhsError::NonFinite { index });
        }
        Ok(())
    }

    /// The residuals at (q, q', t): per constraint, f (holonomic) or A q' + a_t
    /// (velocity, the rule of [`crate::Constraint::residual`]) into `position`, and A q' + a_t into `velocity`; `scale` gets the
    /// size of each constraint's terms at position and at velocity level (at least
    /// 1), for relative tests.
    fn residuals(&mut self, t: f64, y: &[f64], position: &mut [f64], velocity: &mut [f64], scale: &mut [(f64, f64)]) {
        let (n, m) = (self.n, self.m);
        self.geometry_at(t, &y[..n]);
        let qsize = y[..n].iter().fold(1.0f64, |a, v| a.max(v.abs()));
        for k in 0..m {
            let row = &self.geo[k * n..(k + 1) * n];
            let at = self.geo[m * n + k];
            velocity[k] = row.iter().zip(&y[n..2 * n]).map(|(a, v)| a * v).sum::<f64>() + at;
            let vel_scale =
                1.0f64.max(row.iter().zip(&y[n..2 * n]).map(|(a, v)| (a * v).abs()).sum::<f64>() + at.abs());
            match self.holonomic.iter().position(|&h| h == k) {
                Some(h) => {
                    position[k] = self.geo[m * n + m + h];
                    let pos_scale = 1.0f64.max(row.iter().fold(0.0f64, |a, v| a.max(v.abs())) * qsize);
                    scale[k] = (pos_scale, vel_scale);
                }
                None => {
                    position[k] = velocity[k];
                    scale[k] = (vel_scale, vel_scale);
                }
            }
        }
    }

    /// The constraint columns of a row (see [`constraint_columns`]) at (q, q', t).
    fn columns(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), RhsError> {
        let (n, m) = (self.n, self.m);
        self.solve(t, y)?;
        let lambda: Vec<f64> = self.sol[n..].to_vec();
        let mut pos = vec![0.0; m];
        let mut vel = vec![0.0; m];
        let mut scale = vec![(0.0, 0.0); m];
        self.residuals(t, y, &mut pos, &mut vel, &mut scale);
        let mut c = 0;
        for k in 0..m {
            let norm = (0..n).map(|j| self.geo[k * n + j].powi(2)).sum::<f64>().sqrt();
            out[c] = lambda[k];
            out[c + 1] = (lambda[k] * norm).abs();
            out[c + 2] = pos[k];
            c += 3;
            if self.holonomic.contains(&k) {
                out[c] = vel[k];
                c += 1;
            }
        }
        if self.work {
            out[c] = y[2 * n];
        }
        Ok(())
    }
}

impl OdeSystem for ConstrainedSystem {
    fn dim(&self) -> usize {
        2 * self.n + usize::from(self.work)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        let n = self.n;
        self.solve(t, y)?;
        dy[..n].copy_from_slice(&y[n..2 * n]);
        dy[n..2 * n].copy_from_slice(&self.sol[..n]);
        if self.work {
            // dW/dt = Aᵀλ·q' = −Σ λ_k a_t,k on the constraints.
            let m = self.m;
            dy[2 * n] = -(0..m).map(|k| self.sol[n + k] * self.ac[m * n + m + k]).sum::<f64>();
        }
        if let Some(index) = dy.iter().position(|v| !v.is_finite()) {
            return Err(RhsError::NonFinite { index });
        }
        Ok(())
    }
}

/// A run of a model with constraints: DOP853 (default) or DOPRI5, which restart
/// cheaply from a projected state, with the constraint columns and audits.
pub(crate) struct Constrained {
    /// The system rows are projected and evaluated with.
    system: ConstrainedSystem,
    /// The invariants are those of the unconstrained dynamics, at the projected state.
    dynamics: Dynamics,
    list: Vec<crate::derive::Constraint>,
    n: usize,
    /// The projected row state `[q, q', W]`.
    y: Vec<f64>,
    audits: Vec<ConstraintAudit>,
    /// H − W, audited when the constraints' work is all that changes H. Its
    /// relative drift is measured against the largest |H| of the run: H and W
    /// grow together, and their difference cannot be better than H's own digits.
    work: bool,
    hw_initial: Option<f64>,
    hw_last: f64,
    hw_abs: f64,
    h_size: f64,
}

impl Constrained {
    /// Checks the method and the constraints, projects the initial values onto
    /// the constraints (rejecting more than round-off), and builds the solver.
    pub(crate) fn start(
        d: &Derivation,
        dynamics: &Dynamics,
        config: &RunConfig,
        q0: &[f64],
        qd0: &[f64],
    ) -> Result<(Constrained, Start), RunError> {
        let method = match config.method {
            None => Method::Dop853,
            Some(m @ (Method::Dop853 | Method::Dopri5)) => m,
            Some(m) => {
                return Err(RunError::Input(
                    ModelError::whole(format!(
                        "method '{}' cannot run a model with constraints: the state is projected onto the constraints after every step, and only the explicit Runge–Kutta methods restart from a projected state",
                        m.name()
                    ))
                    .with_help("use dop853 (the default) or dopri5"),
                ));
            }
        };
        if config.dt.is_some() {
            return Err(RunError::StepNotApplicable { method });
        }
        let set = &d.constraints;
        let (m, n) = (set.list.len(), d.q.len());
        let mut system = ConstrainedSystem::new(d, dynamics.clone());
        if set.independent < m {
            return Err(RunError::Input(dependent_constraints(d, &mut system, q0, qd0)));
        }
        let list = d.constraints.list.clone();

        // Initial values: round-off is projected away, anything more is an error.
        let mut y0: Vec<f64> = q0.iter().chain(qd0).copied().collect();
        let work = d.constraints.work_balances_h;
        if work {
            y0.push(0.0);
        }
        let (mut pos, mut vel, mut scale) = (vec![0.0; m], vec![0.0; m], vec![(0.0, 0.0); m]);
        system.residuals(0.0, &y0, &mut pos, &mut vel, &mut scale);
        for k in 0..m {
            // A residual that is not a number (NaN) does not hold either.
            let (what, r) = if pos[k].is_nan() || pos[k].abs() > INITIAL_TOLERANCE * scale[k].0 {
                ("", pos[k])
            } else if vel[k].is_nan() || vel[k].abs() > INITIAL_TOLERANCE * scale[k].1 {
                (" at velocity level (A q' + a_t)", vel[k])
            } else {
                continue;
            };
            let c = &list[k];
            return Err(RunError::Input(
                ModelError::at(
                    c.span.clone(),
                    format!(
                        "the initial values violate the constraint '{}'{what}: its residual at t = 0 is {r:.3e}, not 0",
                        c.name
                    ),
                )
                .with_help(format!(
                    "give [initial] values that satisfy the constraint (velocities too: A q' + a_t = 0); residuals up to {INITIAL_TOLERANCE:.0e} of the terms' size are taken for round-off and projected away"
                )),
            ));
        }
        system.fix_integral_levels(0.0, &y0);
        system.project(0.0, &mut y0).map_err(|e| RunError::Input(ModelError::whole(format!("at t = 0: {e}"))))?;

        let solver_config = config.solver_config();
        let solver = method
            .build(system.clone(), 0.0, &y0, &solver_config)
            .map_err(|e| RunError::Input(ModelError::whole(e.to_string())))?;
        let audits = list
            .iter()
            .map(|c| ConstraintAudit {
                name: c.name.clone(),
                kind: c.kind,
                max_abs_residual: 0.0,
                max_abs_velocity_residual: 0.0,
                final_lambda: 0.0,
                max_force: 0.0,
            })
            .collect();
        let constrained = Constrained {
            system,
            dynamics: dynamics.clone(),
            list,
            n,
            y: vec![0.0; y0.len()],
            audits,
            work,
            hw_initial: None,
            hw_last: 0.0,
            hw_abs: 0.0,
            h_size: 0.0,
        };
        let initial = (y0[..n].to_vec(), y0[n..2 * n].to_vec());
        let start = Start {
            solver,
            y0,
            initial,
            method,
            form: Form::Lagrange,
            dt: None,
            pilot_rhs_evaluations: 0,
            restart: None,
        };
        Ok((constrained, start))
    }
}

impl Stepping for Constrained {
    fn velocity_map(&self) -> VelocityMap {
        let n = self.n;
        Box::new(move |_t, y, qd| {
            qd.copy_from_slice(&y[n..2 * n]);
            Ok(())
        })
    }

    fn projection(&self) -> Option<ProjectionMap> {
        let mut projector = self.system.clone();
        Some(Box::new(move |t, y| projector.project(t, y)))
    }

    fn row(&mut self, t: f64, y: &[f64], row: &mut RowBuffer) -> Result<(), RhsError> {
        // Samples come from the step's dense output: project them too.
        let n = self.n;
        self.y.copy_from_slice(y);
        self.system.project(t, &mut self.y)?;
        self.system.columns(t, &self.y, &mut row.constraints)?;
        row.q.copy_from_slice(&self.y[..n]);
        row.qd.copy_from_slice(&self.y[n..2 * n]);
        self.dynamics.eval_invariants(t, &row.q, &row.qd, &mut row.invariants);
        let cols = &row.constraints;
        let mut c = 0;
        for (k, audit) in self.audits.iter_mut().enumerate() {
            audit.final_lambda = cols[c];
            audit.max_force = audit.max_force.max(cols[c + 1]);
            audit.max_abs_residual = audit.max_abs_residual.max(cols[c + 2].abs());
            c += 3;
            if self.list[k].kind == ConstraintKind::Holonomic {
                audit.max_abs_velocity_residual = audit.max_abs_velocity_residual.max(cols[c].abs());
                c += 1;
            } else {
                audit.max_abs_velocity_residual = audit.max_abs_residual;
            }
        }
        if self.work {
            let hw = row.invariants[0] - self.y[2 * n];
            let h0 = *self.hw_initial.get_or_insert(hw);
            self.hw_abs = self.hw_abs.max((hw - h0).abs());
            self.h_size = self.h_size.max(row.invariants[0].abs());
            self.hw_last = hw;
        }
        Ok(())
    }

    fn audits(&mut self, invariants: &mut Vec<Audit>, constraints: &mut Vec<ConstraintAudit>) {
        if let Some(h0) = self.hw_initial {
            invariants.push(Audit {
                name: "H-W".into(),
                conserved: true,
                initial: h0,
                final_value: self.hw_last,
                max_abs_drift: self.hw_abs,
                max_rel_drift: if self.h_size > 0.0 { self.hw_abs / self.h_size } else { self.hw_abs },
                impact_change: 0.0,
            });
        }
        constraints.clone_from(&self.audits);
    }

    fn warnings(&self, warnings: &mut Vec<RunWarning>) {
        for a in &self.audits {
            if a.max_abs_residual > 1e-9 || a.max_abs_velocity_residual > 1e-9 {
                warnings.push(RunWarning::ConstraintViolated {
                    constraint: a.name.clone(),
                    residual: a.max_abs_residual.max(a.max_abs_velocity_residual),
                });
            }
        }
    }

    fn describe(&mut self, e: &SolveError, _y0: &[f64], (t_last, _): (f64, Vec<f64>)) -> (RunFailure, String) {
        match e {
            SolveError::Rhs { t, source: RhsError::Singular { detail } } => (RunFailure::Singular { t: *t }, format!(
                "the constrained equations became singular at t = {t} ({detail}): the constraints are no longer independent there",
                t = num::Shortest(*t)
            )),
            other => (RunFailure::Step { t: t_last }, other.to_string()),
        }
    }

    fn time_scale(&mut self, t: f64, y: &[f64]) -> Option<TimeScale> {
        TimeScale::of(&mut self.system, t, y)
    }
}

/// The error for constraints whose Jacobian A has lower rank than their
/// number: it names the constraints that take part in a dependency (those
/// whose row can be dropped without lowering the rank) and, when some of them
/// hold at the start and others do not, says they may contradict each other
/// (x = 0 and x = 1 have the same gradient but no common solution) rather than
/// that one follows from the others.
fn dependent_constraints(d: &Derivation, system: &mut ConstrainedSystem, q0: &[f64], qd0: &[f64]) -> ModelError {
    let list = &d.constraints.list;
    let rows: Vec<Vec<ExprId>> = list.iter().map(|c| c.jacobian.clone()).collect();
    let rank = d.constraints.independent;
    let involved: Vec<usize> = (0..list.len())
        .filter(|&k| {
            let others: Vec<Vec<ExprId>> =
                rows.iter().enumerate().filter(|&(j, _)| j != k).map(|(_, r)| r.clone()).collect();
            generic_rank(d.pool(), &others) == rank
        })
        .collect();
    let names = |ks: &[usize]| ks.iter().map(|&k| format!("'{}'", list[k].name)).collect::<Vec<_>>().join(", ");
    let m = list.len();
    let mut y0: Vec<f64> = q0.iter().chain(qd0).copied().collect();
    if d.constraints.work_balances_h {
        y0.push(0.0);
    }
    let (mut pos, mut vel, mut scale) = (vec![0.0; m], vec![0.0; m], vec![(0.0, 0.0); m]);
    system.residuals(0.0, &y0, &mut pos, &mut vel, &mut scale);
    let violated: Vec<usize> =
        involved.iter().copied().filter(|&k| pos[k].abs() > INITIAL_TOLERANCE * scale[k].0).collect();
    let held: Vec<usize> = involved.iter().copied().filter(|k| !violated.contains(k)).collect();
    let head = format!(
        "the constraints {} are not independent (their Jacobian A has rank {rank}, not {m}), so their multipliers are not determined",
        names(&involved)
    );
    if !violated.is_empty() && !held.is_empty() {
        let residuals: Vec<String> = violated.iter().map(|&k| format!("'{}' = {:.3e}", list[k].name, pos[k])).collect();
        ModelError::whole(format!(
            "{head}; at the start {} hold{} but {} do{} not ({}): they may contradict each other",
            names(&held),
            if held.len() == 1 { "s" } else { "" },
            names(&violated),
            if violated.len() == 1 { "es" } else { "" },
            residuals.join(", ")
        ))
        .with_help("constraints with the same gradient but different values (x = 0 and x = 1) have no common solution; correct or remove the one you did not mean")
    } else {
        ModelError::whole(head).with_help(format!(
            "keep only independent constraints: drop one of {}, which follows from the others",
            names(&involved)
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_saddle_point_solve_gives_the_tension() {
        let d = crate::test_models::derive(crate::test_models::CONSTRAINED_PENDULUM);
        let dynamics = Dynamics::new(&d);
        let mut sys = ConstrainedSystem::new(&d, dynamics);
        let (m, l, g) = (2.0, 1.5, 9.81);
        let th: f64 = 0.4;
        let om = 1.3;
        let y = [l * th.sin(), -l * th.cos(), l * th.cos() * om, l * th.sin() * om];
        let mut out = [0.0; 4];
        sys.columns(0.0, &y, &mut out).unwrap();
        let tension = m * g * th.cos() + m * l * om * om;
        assert!((out[1] - tension).abs() < 1e-12 * tension, "{out:?} vs {tension}");
        assert!(out[2].abs() < 1e-15 && out[3].abs() < 1e-15);
        // A perturbed state is projected back onto the circle and its tangent.
        let mut z = [y[0] * 1.01, y[1], y[2] + 0.1, y[3]];
        sys.project(0.0, &mut z).unwrap();
        assert!((z[0].hypot(z[1]) - l).abs() < 1e-15);
        assert!((z[0] * z[2] + z[1] * z[3]).abs() < 1e-14);
    }
}
