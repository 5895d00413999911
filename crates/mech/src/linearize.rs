//! Linearization of the equations of motion about an equilibrium or a steady
//! motion: the state-space matrix A of x' = A x for the small deviation x of the
//! coordinates and speeds, in the minimal coordinates and speeds when the model
//! has constraints, its eigenvalues and the verdict on stability.
//!
//! Entry point: [`linearize`]. The operating point is found from a start
//! (`[initial]`, overridden by `at`) by [`crate::equilibria::search`]: at an
//! equilibrium every speed is zero and nothing accelerates; in a steady motion
//! the cyclic coordinates move at constant rates (`[initial]`, overridden by
//! `rates`) and the others stand still. With constraints the equations are
//! `M q'' = f + Bᵀλ`, `B q'' = c` (B the constraint Jacobian, c the
//! acceleration terms, [`crate::Constraints`]); a dependent speed (one the
//! velocity constraints fix, as the rolling disc's x' and y') may accelerate.
//!
//! The derivatives are symbolic: ∂f/∂q, ∂f/∂q', ∂M/∂q, ∂B/∂q, ∂c/∂q, ∂c/∂q'
//! are differentiated from the derivation and compiled; at the point, with
//! q''₀ and λ₀, differentiating `M q'' − Bᵀλ = f`, `B q'' = c` gives
//! `K (δq'', δλ) = (F_q δq + f_q' δq', C_q δq + c_q' δq')` with
//! `K = [[M, −Bᵀ], [B, 0]]`, `F_q = f_q − (∂M/∂q) q''₀ + (∂Bᵀ/∂q) λ₀` and
//! `C_q = c_q − (∂B/∂q) q''₀` (without constraints this is `M⁻¹ f_x`, q''₀
//! being zero). Then the constraints are eliminated as SymPy's `Linearizer`
//! does: dependent coordinates (pivots of the holonomic Jacobian) follow from
//! `Φ_q δq = 0`, dependent speeds (pivots of B) from `B δq' + ∂(Bq')/∂q δq = 0`,
//! and A acts on (independent coordinates, independent speeds).
//!
//! Idle coordinates (a row of M proven zero: no inertia) are left out, at their
//! start value. With `[inputs]`, u is held at u₀ (the inputs' values at t = 0)
//! and B = ∂x'/∂u follows from `K [∂q''/∂u; ∂λ/∂u] = [∂f/∂u; 0]`, reduced to the
//! same state as A.

mod compiled;
mod report;
mod spectrum;

pub use report::{Eigenvalue, LinearizeReport};

use crate::derive::Derivation;
use crate::equilibria::{self, Assessment, Equilibrium, Landscape, Solved, Stability};
use crate::error::ModelError;
use crate::probe::{self, Decision};
use compiled::{kkt, pivots, Compiled, Numbers};
use nalgebra::{DMatrix, DVector};
use num::{GaussNewtonConfig, GaussNewtonError, LeastSquares};
use serde::Serialize;
use sym::Pool;

/// The search for the operating point: `num`'s Gauss–Newton with its default
/// tolerances, asking [`Problem::accept`] once a step is below [`ACCEPT`].
const SEARCH: GaussNewtonConfig = GaussNewtonConfig { accept: ACCEPT, ..GaussNewtonConfig::DEFAULT };
/// A point is an operating point when Newton's step from it is below this,
/// relative to (1 + |x|), and what of the residual (accelerations and
/// holonomic constraints) that step cannot remove is below this fraction of
/// the size of the terms it is a sum of (Σ|terms| of f, c and the constraints,
/// through |K⁻¹|): eight digits either way. A lone force of 1e-13 is not
/// cancelled by anything and is not zero; a residual that a step of 1e-20
/// removes is.
const ACCEPT: f64 = 1e-8;

/// What to linearize about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum About {
    /// Rest: every q' = 0 and q'' = 0.
    #[default]
    Equilibrium,
    /// The cyclic coordinates at constant rates, the others at rest.
    Steady,
}

/// Options of [`linearize`].
#[derive(Debug, Clone, Default)]
pub struct LinearizeConfig {
    /// Equilibrium or steady motion.
    pub about: About,
    /// Starting values for some coordinates; the others start at `[initial]`.
    pub at: Vec<(String, f64)>,
    /// Rates of cyclic coordinates (steady motion); the others come from `[initial]`.
    pub rates: Vec<(String, f64)>,
    /// Keep Newton's landing point from the start even when it is unstable.
    pub keep_unstable: bool,
}

/// Why there is no linearization to report.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LinearizeError {
    /// The model is wrong at a place, or a place keeps the analysis out.
    #[error("{0}")]
    Model(ModelError),
    /// A rate given for a coordinate is not usable.
    #[error("{message}")]
    Rate {
        /// The coordinate named.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// The equations depend on the time, or cannot be evaluated.
    #[error("{reason}")]
    NotAutonomous {
        /// Why.
        reason: String,
    },
    /// No operating point was found.
    #[error("no {what} near {start}: {why}")]
    NoPoint {
        /// "equilibrium" or "steady motion".
        what: &'static str,
        /// The start, as `q=v` pairs.
        start: String,
        /// What went wrong.
        why: String,
    },
    /// A or its eigenvalues cannot be computed at the point.
    #[error("no linearization at {at}: {why}")]
    Spectrum {
        /// The point, as `q=v` pairs.
        at: String,
        /// Why.
        why: String,
    },
    /// The equations cannot be solved for q'' and λ at the point.
    #[error("the equations cannot be solved for q'' at {at}: M (with the constraints) is singular there")]
    Singular {
        /// The point, as `q=v` pairs.
        at: String,
    },
}

impl LinearizeError {
    /// A hint on how to fix it.
    pub fn help(&self) -> Option<String> {
        match self {
            LinearizeError::Model(e) => e.help.clone(),
            LinearizeError::Rate { .. } => Some("in a steady motion only cyclic coordinates move (∂L/∂q = 0)".into()),
            LinearizeError::NotAutonomous { .. } => {
                Some("linearization about a fixed point needs equations free of the time t".into())
            }
            LinearizeError::NoPoint { .. } => {
                Some("start elsewhere (give the coordinates other starting values) or change the rates".into())
            }
            LinearizeError::Spectrum { .. } => None,
            LinearizeError::Singular { .. } => {
                Some("the coordinates are singular there (like Euler angles at β = 0); choose others".into())
            }
        }
    }
}

impl From<ModelError> for LinearizeError {
    fn from(e: ModelError) -> Self {
        LinearizeError::Model(e)
    }
}

/// The linearized motion about one point.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// Equilibrium or steady motion.
    pub about: About,
    /// The model's coordinates.
    pub coordinates: Vec<String>,
    /// q at the operating point (every coordinate).
    pub q: Vec<f64>,
    /// q' there.
    pub qd: Vec<f64>,
    /// q'' there (zero but for dependent speeds).
    pub qdd: Vec<f64>,
    /// The multipliers λ₀ there, by constraint name.
    pub multipliers: Vec<(String, f64)>,
    /// Coordinates without inertia, left out.
    pub idle: Vec<String>,
    /// Cyclic coordinates moving at constant rates (steady motion), with the rates.
    pub moving: Vec<(String, f64)>,
    /// Coordinates the holonomic constraints fix, eliminated.
    pub dependent_coordinates: Vec<String>,
    /// Speeds the constraints fix, eliminated.
    pub dependent_speeds: Vec<String>,
    /// The state: the independent coordinates, then the independent speeds (`q'`).
    pub state: Vec<String>,
    /// A, row-major: x' = A x.
    pub a: Vec<Vec<f64>>,
    /// The inputs u (`[inputs]`), held at u₀, their values at t = 0.
    pub inputs: Vec<String>,
    /// B of x' = A x + B u, one column per input (None without inputs).
    pub b: Option<Vec<Vec<f64>>>,
    /// The eigenvalues (Re, Im) of A, by decay rate (−Re) ascending, then |Im| descending (+ before −).
    pub eigenvalues: Vec<(f64, f64)>,
    /// The verdict.
    pub stability: Stability,
    /// The coordinates the search solved for (all of them at an equilibrium).
    pub unknowns: Vec<String>,
    /// The start of the search, in `unknowns`.
    pub start: Vec<f64>,
    /// The operating points met near the start, in `unknowns`.
    pub equilibria: Vec<Equilibrium>,
    /// Which of them is analysed.
    pub chosen: usize,
    /// Which of them Newton's method reached from the start.
    pub landing: Option<usize>,
    /// Remarks for the reader.
    pub notes: Vec<String>,
}

/// Everything fixed while the search runs: which coordinates move, the speeds.
struct Setup {
    /// Active indices (into the model's coordinates) the search solves for.
    unknown: Vec<usize>,
    /// Full q with the fixed coordinates at their start values.
    base_q: Vec<f64>,
    /// Per active coordinate: the given speed (rates of moving coordinates, else 0).
    speeds: Vec<f64>,
    /// Dependent speeds (positions in the active list), m of them.
    dependent: Vec<usize>,
    /// Speeds given by the user (positions in the active list): not made dependent if avoidable.
    avoid: Vec<usize>,
}

/// The linearization at one point, in active positions.
struct AtPoint {
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    a: DMatrix<f64>,
    /// B of the reduced state (zero columns without inputs).
    b: DMatrix<f64>,
    eigenvalues: Vec<(f64, f64)>,
    stability: Stability,
    /// M and F_q (∂f/∂q with the constraints' terms) at the point.
    mm: DMatrix<f64>,
    fq: DMatrix<f64>,
    /// Whether K v = ω² M v gives the spectrum (no constraints, no velocity terms).
    symmetric: bool,
    independent_q: Vec<usize>,
    independent_v: Vec<usize>,
    dependent_q: Vec<usize>,
    dependent_v: Vec<usize>,
}

struct Problem<'a> {
    c: Compiled,
    setup: Setup,
    names: &'a [String],
}

impl Problem<'_> {
    /// Full q and q' for the unknowns x: dependent speeds from the constraints.
    fn state(&mut self, x: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let mut q = self.setup.base_q.clone();
        for (k, &i) in self.setup.unknown.iter().enumerate() {
            q[self.c.act[i]] = x[k];
        }
        let mut qd = vec![0.0; self.c.big_n];
        for (k, &i) in self.c.act.iter().enumerate() {
            qd[i] = self.setup.speeds[k];
        }
        if self.c.m > 0 {
            let nb = self.c.eval(&q, &qd);
            let dep = &self.setup.dependent;
            let n = self.c.act.len();
            let ind: Vec<usize> = (0..n).filter(|j| !dep.contains(j)).collect();
            let bd = nb.b.select_columns(dep.iter());
            let bi = nb.b.select_columns(ind.iter());
            let vi = DVector::from_iterator(ind.len(), ind.iter().map(|&j| self.setup.speeds[j]));
            let vd = bd.lu().solve(&(-(bi * vi)))?;
            for (k, &j) in dep.iter().enumerate() {
                qd[self.c.act[j]] = vd[k];
            }
        }
        Some((q, qd))
    }

    /// q'' and λ at a state.
    fn accelerations(&mut self, q: &[f64], qd: &[f64]) -> Option<(Numbers, DVector<f64>, DVector<f64>)> {
        let nb = self.c.eval(q, qd);
        let n = nb.m.nrows();
        let k = kkt(&nb);
        let mut rhs = DVector::zeros(n + self.c.m);
        rhs.rows_mut(0, n).copy_from(&nb.f);
        rhs.rows_mut(n, self.c.m).copy_from(&nb.c);
        let z = k.lu().solve(&rhs)?;
        if !z.iter().all(|v| v.is_finite()) {
            return None;
        }
        let a = z.rows(0, n).into_owned();
        let lam = z.rows(n, self.c.m).into_owned();
        Some((nb, a, lam))
    }

    /// The residual: holonomic constraints, the accelerations that must vanish.
    fn residual(&mut self, x: &[f64]) -> Option<DVector<f64>> {
        let (q, qd) = self.state(x)?;
        let (nb, a, _) = self.accelerations(&q, &qd)?;
        let n = a.len();
        let dep = &self.setup.dependent;
        let rows: Vec<f64> = nb
            .phi
            .iter()
            .copied()
            .chain((0..n).filter(|j| !dep.contains(j) || self.setup.unknown.contains(j)).map(|j| a[j]))
            .collect();
        rows.iter().all(|v| v.is_finite()).then(|| DVector::from_vec(rows))
    }

    /// The size of the terms each residual row is a sum of: Σ|terms| of the
    /// holonomic constraints, and of f and c carried through |K⁻¹| for the
    /// accelerations.
    fn residual_scale(&mut self, x: &[f64]) -> Option<DVector<f64>> {
        let (q, qd) = self.state(x)?;
        let (nb, qdd, lam) = self.accelerations(&q, &qd)?;
        let n = nb.m.nrows();
        let kinv = kkt(&nb).try_inverse()?;
        // The terms of M q'' − Bᵀλ = f and B q'' = c: the constraint forces
        // balance f, so their size is part of the scale.
        let mut terms = DVector::zeros(n + self.c.m);
        let f_side = &nb.f_terms + nb.b.abs().transpose() * lam.abs() + nb.m.abs() * qdd.abs();
        let c_side = &nb.c_terms + nb.b.abs() * qdd.abs();
        terms.rows_mut(0, n).copy_from(&f_side);
        terms.rows_mut(n, self.c.m).copy_from(&c_side);
        // Rounding in the solve spreads across rows (a normal acceleration
        // on a constraint is the difference of f and Bᵀλ, both large): every
        // acceleration's scale is at least the largest of these.
        let mut acc = kinv.abs() * terms;
        let floor = acc.amax();
        acc.iter_mut().for_each(|v| *v = v.max(floor));
        let dep = &self.setup.dependent;
        let rows: Vec<f64> = nb
            .phi_terms
            .iter()
            .copied()
            .chain((0..n).filter(|j| !dep.contains(j) || self.setup.unknown.contains(j)).map(|j| acc[j]))
            .collect();
        rows.iter().all(|v| v.is_finite()).then(|| DVector::from_vec(rows))
    }

    /// Whether x (residual r, Jacobian, step) is an operating point: the step
    /// is below [`ACCEPT`] of (1 + |x|), and the residual the step leaves is
    /// below [`ACCEPT`] of the size of its terms. The error says why not.
    fn accept(&mut self, x: &[f64], r: &DVector<f64>, jac: &DMatrix<f64>, step: &DVector<f64>) -> Result<(), String> {
        let scale = self.residual_scale(x).ok_or_else(|| "the equations cannot be evaluated there".to_string())?;
        let left = r + jac * step;
        let size = |v: f64| 1.0 + v.abs();
        let small_step = step.iter().zip(x).all(|(s, v)| s.abs() <= ACCEPT * size(*v));
        let small_left = left.iter().zip(scale.iter()).all(|(l, t)| l.abs() <= ACCEPT * t);
        if small_step && small_left {
            return Ok(());
        }
        let k = (0..r.len())
            .max_by(|&a, &b| {
                (left[a].abs() / scale[a].max(f64::MIN_POSITIVE))
                    .total_cmp(&(left[b].abs() / scale[b].max(f64::MIN_POSITIVE)))
            })
            .unwrap_or(0);
        let at = self.point_text(x);
        if !small_left {
            Err(format!(
                "the forces do not balance at {at}: a residual acceleration of {} remains that no nearby point removes, against terms of size {}",
                equilibria::short(left[k].abs()),
                equilibria::short(scale[k])
            ))
        } else {
            Err(format!(
                "the forces do not vanish near {at}: Newton's method still moves by {} there",
                equilibria::short(step.amax())
            ))
        }
    }

    fn point_text(&self, x: &[f64]) -> String {
        let at: Vec<String> = self
            .setup
            .unknown
            .iter()
            .zip(x)
            .map(|(&i, v)| format!("{}={}", self.names[self.c.act[i]], equilibria::short(*v)))
            .collect();
        format!("({})", at.join(", "))
    }

    /// The search for the operating point from x0 ([`num::gauss_newton`],
    /// ended by [`Problem::accept`]), its failures in the analysis' words.
    fn gauss_newton(&mut self, x0: &[f64]) -> Result<Solved, String> {
        match num::gauss_newton(self, x0, &SEARCH) {
            Ok(s) => Ok(Solved { x: s.x, iterations: s.iterations, residual: s.residual }),
            Err(e) => Err(self.search_failure(e)),
        }
    }

    /// A failure of the search, said for the point where it happened.
    fn search_failure(&self, e: GaussNewtonError) -> String {
        match e {
            GaussNewtonError::StartNotEvaluable => "the equations cannot be evaluated at the start".into(),
            GaussNewtonError::NotEvaluable => "the equations cannot be evaluated".into(),
            GaussNewtonError::Solve(why) => format!("the Jacobian cannot be solved: {why}"),
            GaussNewtonError::Underflow { x } => format!(
                "the forces only underflow to zero at {}, far from where Newton's method started",
                self.point_text(&x)
            ),
            GaussNewtonError::Stalls { x } => format!("Newton's method stalls at {}", self.point_text(&x)),
            GaussNewtonError::RunsAway { x } => format!("Newton's method runs away at {}", self.point_text(&x)),
            GaussNewtonError::Refused(why) => why,
        }
    }

    /// How well the point x is known, per unknown: four Newton steps (a
    /// double root's error is twice its step), and at least [`ACCEPT`] of
    /// (1 + |x|), the accuracy the acceptance test asks for.
    fn uncertainty(&mut self, x: &[f64]) -> Vec<f64> {
        let floor: Vec<f64> = x.iter().map(|v| ACCEPT * (1.0 + v.abs())).collect();
        let Some(r) = self.residual(x) else { return floor };
        let Ok((_, step)) = num::gauss_newton_step(self, x, &r, &SEARCH) else { return floor };
        floor.iter().zip(step.iter()).map(|(f, s)| f.max(4.0 * s.abs())).collect()
    }

    /// The linearization at x with its eigenvalues: entries of A (and of
    /// ∂f/∂q) that change by more than their own size when x moves within its
    /// uncertainty are noise and set to zero (at a degenerate point, U = x³ at
    /// 0, Newton stops where A's entry is only its distance from the root).
    fn settle(&mut self, x: &[f64]) -> Result<AtPoint, String> {
        let mut p = self.at(x).ok_or_else(|| "the equations cannot be solved for q'' there".to_string())?;
        let delta = self.uncertainty(x);
        let mut noise_a = DMatrix::<f64>::zeros(p.a.nrows(), p.a.ncols());
        let mut noise_fq = DMatrix::<f64>::zeros(p.fq.nrows(), p.fq.ncols());
        for j in 0..x.len() {
            for sign in [1.0, -1.0] {
                let mut xp = x.to_vec();
                xp[j] += sign * delta[j];
                let Some(pp) = self.at(&xp) else { continue };
                if pp.independent_q != p.independent_q || pp.independent_v != p.independent_v {
                    continue;
                }
                noise_a += (&pp.a - &p.a).abs();
                noise_fq += (&pp.fq - &p.fq).abs();
            }
        }
        p.a.zip_apply(&noise_a, |v, e| {
            if v.abs() <= e {
                *v = 0.0
            }
        });
        p.fq.zip_apply(&noise_fq, |v, e| {
            if v.abs() <= e {
                *v = 0.0
            }
        });
        let second = p.symmetric.then_some(spectrum::SecondOrder { m: &p.mm, fq: &p.fq });
        let (eigenvalues, stability) = spectrum::spectrum(&p.a, second)?;
        p.eigenvalues = eigenvalues;
        p.stability = stability;
        Ok(p)
    }

    /// A and its eigenvalues at the unknowns x.
    fn at(&mut self, x: &[f64]) -> Option<AtPoint> {
        let (q, qd) = self.state(x)?;
        let (nb, qdd, lam) = self.accelerations(&q, &qd)?;
        let n = nb.m.nrows();
        let m = self.c.m;
        // F_q = f_q − (∂M/∂q) q'' + (∂Bᵀ/∂q) λ; C_q = c_q − (∂B/∂q) q''.
        let mut fq = nb.fq.clone();
        for j in 0..nb.mq.len() {
            let col = &nb.mq[j] * &qdd;
            for i in 0..n {
                fq[(i, j)] -= col[i];
            }
        }
        for (k, bqk) in nb.bq.iter().enumerate() {
            fq += bqk * lam[k];
        }
        let mut cq = nb.cq.clone();
        // W = ∂(B q')/∂q (for the velocity constraints) and ∂(B q'')/∂q.
        let vact = DVector::from_iterator(n, self.c.act.iter().map(|&i| qd[i]));
        let mut w = DMatrix::zeros(m, n);
        for (k, bqk) in nb.bq.iter().enumerate() {
            let by_a = bqk.transpose() * &qdd;
            let by_v = bqk.transpose() * &vact;
            for j in 0..n {
                cq[(k, j)] -= by_a[j];
                w[(k, j)] = by_v[j];
            }
        }
        let mut rhs = DMatrix::zeros(n + m, 2 * n);
        rhs.view_mut((0, 0), (n, n)).copy_from(&fq);
        rhs.view_mut((0, n), (n, n)).copy_from(&nb.fv);
        rhs.view_mut((n, 0), (m, n)).copy_from(&cq);
        rhs.view_mut((n, n), (m, n)).copy_from(&nb.cv);
        let g = kkt(&nb).lu().solve(&rhs)?;
        let mut full = DMatrix::zeros(2 * n, 2 * n);
        for i in 0..n {
            full[(i, n + i)] = 1.0;
        }
        full.view_mut((n, 0), (n, 2 * n)).copy_from(&g.rows(0, n));
        // Elimination: δq = P_q δq_I, δq' = Q P_q δq_I + P_v δq'_I, with the
        // dependent coordinates and speeds chosen here (a choice good at the
        // start may be singular at the point: x for a pendulum hanging straight down).
        let phi_q = nb.b.select_rows(self.c.hol.iter());
        let dq = if self.c.hol.is_empty() { Vec::new() } else { pivots(&phi_q, &[], &[])? };
        let dv = if m == 0 { Vec::new() } else { pivots(&nb.b, &dq, &self.setup.avoid)? };
        let (dq, dv) = (&dq, &dv);
        let iq: Vec<usize> = (0..n).filter(|j| !dq.contains(j)).collect();
        let iv: Vec<usize> = (0..n).filter(|j| !dv.contains(j)).collect();
        let mut pq = DMatrix::zeros(n, iq.len());
        for (k, &j) in iq.iter().enumerate() {
            pq[(j, k)] = 1.0;
        }
        if !dq.is_empty() {
            let solved = phi_q.select_columns(dq.iter()).lu().solve(&phi_q.select_columns(iq.iter()))?;
            for (r, &j) in dq.iter().enumerate() {
                for k in 0..iq.len() {
                    pq[(j, k)] = -solved[(r, k)];
                }
            }
        }
        let mut pv = DMatrix::zeros(n, iv.len());
        for (k, &j) in iv.iter().enumerate() {
            pv[(j, k)] = 1.0;
        }
        let mut qm = DMatrix::zeros(n, n);
        if m > 0 {
            let bd = nb.b.select_columns(dv.iter()).lu();
            let sv = bd.solve(&nb.b.select_columns(iv.iter()))?;
            let sw = bd.solve(&w)?;
            for (r, &j) in dv.iter().enumerate() {
                for k in 0..iv.len() {
                    pv[(j, k)] = -sv[(r, k)];
                }
                for k in 0..n {
                    qm[(j, k)] = -sw[(r, k)];
                }
            }
        }
        let (nq, nv) = (iq.len(), iv.len());
        let mut t = DMatrix::zeros(2 * n, nq + nv);
        t.view_mut((0, 0), (n, nq)).copy_from(&pq);
        t.view_mut((n, 0), (n, nq)).copy_from(&(&qm * &pq));
        t.view_mut((n, nq), (n, nv)).copy_from(&pv);
        let rows: Vec<usize> = iq.iter().copied().chain(iv.iter().map(|&j| n + j)).collect();
        let a = (full * t).select_rows(rows.iter());
        // B: the accelerations' response to u, K [∂q''/∂u; ∂λ/∂u] = [∂f/∂u; 0].
        let n_u = nb.fu.ncols();
        let mut b_full = DMatrix::zeros(2 * n, n_u);
        if n_u > 0 {
            let mut rhs_u = DMatrix::zeros(n + m, n_u);
            rhs_u.view_mut((0, 0), (n, n_u)).copy_from(&nb.fu);
            let gu = kkt(&nb).lu().solve(&rhs_u)?;
            b_full.view_mut((n, 0), (n, n_u)).copy_from(&gu.rows(0, n));
        }
        let b = b_full.select_rows(rows.iter());
        if !a.iter().all(|v| v.is_finite()) {
            return None;
        }
        // The second-order problem applies without constraints or velocity terms.
        let symmetric = m == 0 && nb.fv.iter().all(|&v| v == 0.0);
        Some(AtPoint {
            mm: nb.m.clone(),
            fq: fq.clone(),
            symmetric,
            q,
            qd,
            qdd: qdd.iter().copied().collect(),
            lambda: lam.iter().copied().collect(),
            a,
            b,
            eigenvalues: Vec::new(),
            stability: Stability::Marginal,
            independent_q: iq,
            independent_v: iv,
            dependent_q: dq.clone(),
            dependent_v: dv.clone(),
        })
    }
}

impl LeastSquares for Problem<'_> {
    fn residual(&mut self, x: &[f64]) -> Option<DVector<f64>> {
        Problem::residual(self, x)
    }

    fn accept(&mut self, x: &[f64], r: &DVector<f64>, jac: &DMatrix<f64>, step: &DVector<f64>) -> Result<(), String> {
        Problem::accept(self, x, r, jac, step)
    }
}

impl Landscape for Problem<'_> {
    fn solve(&mut self, x0: &[f64]) -> Result<Solved, String> {
        self.gauss_newton(x0)
    }

    fn assess(&mut self, x: &[f64]) -> Assessment {
        let stability = self.settle(x).map_or(Stability::Unstable, |p| p.stability);
        Assessment { stability, unstable_directions: Vec::new() }
    }
}

fn pairs(names: &[String], values: &[f64]) -> String {
    let parts: Vec<String> = names.iter().zip(values).map(|(n, v)| format!("{n}={}", equilibria::short(*v))).collect();
    format!("({})", parts.join(", "))
}

/// Refuses equations that depend on the time: a forced coordinate at its
/// `[forces]` entry, a moving constraint at its entry.
fn check_autonomous(d: &Derivation, pool: &mut Pool, act: &[usize]) -> Result<(), LinearizeError> {
    let t = d.t;
    let undecided = |what: String| LinearizeError::NotAutonomous {
        reason: format!("could not decide whether {what} depends on the time t ({})", probe::UNDECIDED),
    };
    for &i in act {
        let name = &d.model.coordinates[i].name;
        let df = pool.diff(d.forcing[i], t);
        match probe::decide_zero(pool, df) {
            Decision::Zero => {}
            Decision::NonZero => {
                let reason = format!(
                    "the equation of {name} depends on the time t, so there is no fixed point to linearize about"
                );
                let force_t = pool.diff(d.forces[i], t);
                if let (Some(entry), false) =
                    (d.model.forces.get(i).and_then(Option::as_ref), probe::is_zero(pool, force_t))
                {
                    return Err(ModelError::at(entry.span.clone(), reason).into());
                }
                return Err(LinearizeError::NotAutonomous { reason });
            }
            Decision::Undecided => return Err(undecided(format!("the equation of {name}"))),
        }
        for &j in act {
            let dm = pool.diff(d.mass_matrix[i][j], t);
            match probe::decide_zero(pool, dm) {
                Decision::Zero => {}
                Decision::NonZero => {
                    return Err(LinearizeError::NotAutonomous {
                        reason:
                            "the mass matrix M depends on the time t, so there is no fixed point to linearize about"
                                .into(),
                    })
                }
                Decision::Undecided => return Err(undecided("M".into())),
            }
        }
    }
    for c in &d.constraints.list {
        if c.rheonomic != Some(false) {
            return Err(ModelError::at(
                c.span.clone(),
                format!("the constraint '{}' depends on the time t (or could not be shown not to), so there is no fixed point to linearize about", c.name),
            )
            .into());
        }
    }
    Ok(())
}

/// The starting q (every coordinate) and q' from `[initial]`, `at` over q.
fn initial(d: &Derivation, at: &[(String, f64)]) -> Result<(Vec<f64>, Vec<f64>), LinearizeError> {
    let model = &d.model;
    let n = model.n_coords();
    let (mut q, mut qd) = (vec![0.0; n], vec![0.0; n]);
    let env = |name: &str| model.parameter(name);
    for iv in &model.initial {
        let v =
            model.pool.eval(iv.value.expr, &env).map_err(|e| ModelError::at(iv.value.span.clone(), e.to_string()))?;
        if iv.order == 0 {
            q[iv.coord] = v;
        } else {
            qd[iv.coord] = v;
        }
    }
    for (name, v) in at {
        let Some(i) = model.coordinates.iter().position(|c| &c.name == name) else {
            let known: Vec<&str> = model.coordinates.iter().map(|c| c.name.as_str()).collect();
            return Err(ModelError::setting(
                crate::error::Setting::Start { name: name.clone() },
                format!("the model has no coordinate '{name}'"),
            )
            .with_help(format!("its coordinates are: {}", known.join(", ")))
            .into());
        };
        if !v.is_finite() {
            return Err(ModelError::setting(
                crate::error::Setting::Start { name: name.clone() },
                "the value must be finite",
            )
            .into());
        }
        q[i] = *v;
    }
    Ok((q, qd))
}

/// Linearizes the model about the equilibrium or steady motion near the start.
pub fn linearize(d: &Derivation, config: &LinearizeConfig) -> Result<Linearization, LinearizeError> {
    let names: Vec<String> = d.model.coordinates.iter().map(|c| c.name.clone()).collect();
    let big_n = names.len();
    let mut pool = d.pool().clone();
    let mut notes = Vec::new();
    // Idle coordinates: a row of M proven zero.
    let idle: Vec<usize> = (0..big_n)
        .filter(|&i| d.mass_matrix[i].iter().all(|&e| probe::decide_zero(&mut pool, e) == Decision::Zero))
        .collect();
    let act: Vec<usize> = (0..big_n).filter(|i| !idle.contains(i)).collect();
    if !idle.is_empty() {
        let list: Vec<&str> = idle.iter().map(|&i| names[i].as_str()).collect();
        notes.push(format!(
            "idle coordinate{} {} (no inertia: its row of M is zero) left out, at {} start value",
            if idle.len() == 1 { "" } else { "s" },
            list.join(", "),
            if idle.len() == 1 { "its" } else { "their" }
        ));
    }
    check_autonomous(d, &mut pool, &act)?;
    if d.constraints.independent < d.constraints.list.len() {
        let c = &d.constraints.list[0];
        return Err(ModelError::at(
            c.span.clone(),
            "the constraints are not independent (their Jacobian has lower rank), so the dependent coordinates cannot be chosen",
        )
        .into());
    }
    let (mut q_start, qd_start) = initial(d, &config.at)?;
    // What every command checks of its start: inputs finite at t = 0, the
    // constraints defined, holding and with a gradient there.
    d.model.check_values(Some((&q_start, &qd_start)))?;
    d.check_constraints_at(&q_start, &qd_start)?;
    // Rates: cyclic coordinates move in a steady motion.
    let cyclic: Vec<usize> = d.cyclic.iter().copied().filter(|i| act.contains(i)).collect();
    let mut rate = vec![0.0; big_n];
    let mut flagged: Vec<usize> = Vec::new();
    for (name, v) in &config.rates {
        let Some(i) = names.iter().position(|c| c == name) else {
            return Err(LinearizeError::Rate {
                name: name.clone(),
                message: format!("the model has no coordinate '{name}' (its coordinates are: {})", names.join(", ")),
            });
        };
        if config.about != About::Steady {
            return Err(LinearizeError::Rate {
                name: name.clone(),
                message: "a rate applies to a steady motion, not to an equilibrium (every speed is zero there)".into(),
            });
        }
        if !cyclic.contains(&i) {
            return Err(LinearizeError::Rate {
                name: name.clone(),
                message: format!("'{name}' is not cyclic (∂L/∂{name} ≠ 0), so it cannot move at a constant rate"),
            });
        }
        if !v.is_finite() {
            return Err(LinearizeError::Rate { name: name.clone(), message: "the value must be finite".into() });
        }
        rate[i] = *v;
        flagged.push(i);
    }
    let moving: Vec<usize> = match config.about {
        About::Equilibrium => Vec::new(),
        About::Steady => cyclic.clone(),
    };
    for &i in &moving {
        if !flagged.contains(&i) {
            rate[i] = qd_start[i];
        }
    }
    let pos = |i: usize| act.iter().position(|&a| a == i).unwrap_or(0);
    let unknown: Vec<usize> = (0..act.len()).filter(|&k| !moving.contains(&act[k])).collect();
    let speeds: Vec<f64> = act.iter().map(|&i| rate[i]).collect();
    let mut compiled = Compiled::new(d, act.clone())?;
    // Dependent coordinates and speeds, chosen at the start for the search (at
    // the point they are chosen again for the elimination).
    let avoid: Vec<usize> = flagged.iter().map(|&i| pos(i)).collect();
    let dependent = {
        let zero = vec![0.0; big_n];
        let nb = compiled.eval(&q_start, &zero);
        let phi_q = nb.b.select_rows(compiled.hol.iter());
        let dq = if compiled.hol.is_empty() {
            Vec::new()
        } else {
            pivots(&phi_q, &[], &[]).ok_or_else(|| LinearizeError::Singular { at: pairs(&names, &q_start) })?
        };
        if compiled.m == 0 {
            Vec::new()
        } else {
            pivots(&nb.b, &dq, &avoid).ok_or_else(|| LinearizeError::Singular { at: pairs(&names, &q_start) })?
        }
    };
    let unknown_names: Vec<String> = unknown.iter().map(|&k| names[act[k]].clone()).collect();
    let start: Vec<f64> = unknown.iter().map(|&k| q_start[act[k]]).collect();
    let setup = Setup { unknown: unknown.clone(), base_q: q_start.clone(), speeds, dependent, avoid };
    let mut problem = Problem { c: compiled, setup, names: &names };
    let what = match config.about {
        About::Equilibrium => "equilibrium",
        About::Steady => "steady motion",
    };
    // Nothing to solve at the start: a coordinate without inertia there
    // because a parameter is 0 (or, without constraints, M singular) is the
    // cause to name, not the search.
    if problem.residual(&start).is_none() {
        if let Some(idle) = d.no_inertia_at(&act, &q_start, &|p| d.model.parameter(p)) {
            if d.constraints.is_empty() || !idle.zero_parameters.is_empty() {
                let at = format!("the start {}", pairs(&names, &q_start));
                return Err(ModelError::whole(idle.message(&at)).with_help(idle.help()).into());
            }
        }
    }
    let search = equilibria::search(&mut problem, &start, !config.keep_unstable)
        .map_err(|why| LinearizeError::NoPoint { what, start: pairs(&unknown_names, &start), why })?;
    let x = search.found[search.chosen].x.clone();
    if problem.at(&x).is_none() {
        return Err(LinearizeError::Singular { at: pairs(&unknown_names, &x) });
    }
    let point = problem.settle(&x).map_err(|why| LinearizeError::Spectrum { at: pairs(&unknown_names, &x), why })?;
    for &j in &point.dependent_v {
        if flagged.contains(&act[j]) {
            notes.push(format!(
                "the rate of {} follows from the constraints (it is a dependent speed), not from the one given",
                names[act[j]]
            ));
        }
    }
    for (k, &j) in unknown.iter().enumerate() {
        q_start[act[j]] = x[k];
    }
    if search.landing.is_some_and(|i| i != search.chosen) {
        notes.push(format!(
            "Newton's method from the start reached an unstable {what}; the nearest one that is not unstable is linearized instead"
        ));
    }
    // A steady motion keeps the non-cyclic coordinates still.
    for &k in &unknown {
        let i = act[k];
        if point.qd[i].abs() > ACCEPT * (1.0 + point.qd.iter().fold(0.0f64, |m, v| m.max(v.abs()))) {
            return Err(LinearizeError::NoPoint {
                what,
                start: pairs(&unknown_names, &start),
                why: format!(
                    "the constraints make {}' = {} there, so that coordinate does not stand still",
                    names[i],
                    equilibria::short(point.qd[i])
                ),
            });
        }
    }
    if config.about == About::Steady && !moving.is_empty() {
        notes.push(
            "a cyclic coordinate's position does not enter the equations: its column of A is zero, and a change of its rate moves to a neighbouring steady motion, so zero eigenvalues come with each".into(),
        );
    }
    let speed_name = |j: usize| format!("{}'", names[act[j]]);
    let state: Vec<String> = point
        .independent_q
        .iter()
        .map(|&j| names[act[j]].clone())
        .chain(point.independent_v.iter().map(|&j| speed_name(j)))
        .collect();
    let rows = |m: &DMatrix<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows()).map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect()).collect()
    };
    let mut full_qdd = vec![0.0; big_n];
    for (k, &i) in act.iter().enumerate() {
        full_qdd[i] = point.qdd[k];
    }
    // Rounding noise about exact zeros of the point is zero.
    let clean = |v: &mut Vec<f64>| {
        let big = v.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        v.iter_mut().filter(|x| x.abs() <= 1e-14 * big).for_each(|x| *x = 0.0);
    };
    let (mut q, mut qd) = (point.q.clone(), point.qd.clone());
    clean(&mut q);
    clean(&mut qd);
    clean(&mut full_qdd);
    let mut equilibria_found = search.found.clone();
    for e in &mut equilibria_found {
        clean(&mut e.x);
    }
    Ok(Linearization {
        about: config.about,
        coordinates: names.clone(),
        q,
        qd,
        qdd: full_qdd,
        multipliers: d.constraints.list.iter().zip(&point.lambda).map(|(c, &l)| (c.name.clone(), l)).collect(),
        idle: idle.iter().map(|&i| names[i].clone()).collect(),
        moving: moving.iter().map(|&i| (names[i].clone(), point.qd[i])).collect(),
        dependent_coordinates: point.dependent_q.iter().map(|&j| names[act[j]].clone()).collect(),
        dependent_speeds: point.dependent_v.iter().map(|&j| speed_name(j)).collect(),
        state,
        a: rows(&point.a),
        inputs: d.model.inputs.iter().map(|u| u.name.clone()).collect(),
        b: (!d.inputs.is_empty()).then(|| rows(&point.b)),
        eigenvalues: point.eigenvalues,
        stability: point.stability,
        unknowns: unknown_names,
        start,
        equilibria: equilibria_found,
        chosen: search.chosen,
        landing: search.landing,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;

    fn derive(text: &str) -> Derivation {
        Derivation::new(Model::parse(text, &[]).expect("model parses")).expect("derivation")
    }

    const DAMPED: &str = "coordinates = [\"x\"]\nkinetic = \"m*x'^2/2\"\npotential = \"k*x^2/2\"\n\
        dissipation = \"b*x'^2/2\"\n[parameters]\nm = 2.0\nk = 8.0\nb = 0.4\n[initial]\nx = 0.3\n\"x'\" = 0.0\n";

    #[test]
    fn the_damped_oscillator_has_the_textbook_matrix() {
        let l = linearize(&derive(DAMPED), &LinearizeConfig::default()).unwrap();
        let (m, k, b) = (2.0, 8.0, 0.4);
        let want = [[0.0, 1.0], [-k / m, -b / m]];
        for i in 0..2 {
            for j in 0..2 {
                assert!((l.a[i][j] - want[i][j]).abs() < 1e-12, "{:?}", l.a);
            }
        }
        assert_eq!(l.state, ["x", "x'"]);
        assert_eq!(l.stability, Stability::Stable);
        // s = −b/2m ± i sqrt(k/m − b²/4m²).
        let (re, im) = (-b / (2.0 * m), (k / m - b * b / (4.0 * m * m)).sqrt());
        assert!((l.eigenvalues[0].0 - re).abs() < 1e-12 && (l.eigenvalues[0].1 - im).abs() < 1e-12);
        assert!(l.b.is_none() && l.inputs.is_empty());
    }

    #[test]
    fn pivots_prefer_what_is_forced_and_avoid_what_is_asked() {
        let b = DMatrix::from_row_slice(1, 3, &[1.0, 2.0, 0.5]);
        assert_eq!(pivots(&b, &[], &[]), Some(vec![1]));
        assert_eq!(pivots(&b, &[], &[1]), Some(vec![0]));
        assert_eq!(pivots(&b, &[2], &[]), Some(vec![2]));
        let zero = DMatrix::from_row_slice(1, 2, &[0.0, 0.0]);
        assert_eq!(pivots(&zero, &[], &[]), None);
    }
}
