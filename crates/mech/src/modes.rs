//! Small oscillations and normal modes about an equilibrium, as the notes'
//! Sec. 3.3 computes them by hand.
//!
//! Entry point: [`normal_modes`]. It finds the equilibrium ∂U/∂q = 0 nearest a
//! starting configuration by a damped Newton method on the compiled gradient and
//! Hessian of U, builds `T = M(q₀)` and `U = ∂²U/∂q∂q (q₀)`, and solves the
//! generalized symmetric eigenproblem `U a = Ω² T a` by a Cholesky factor of T
//! and a symmetric eigensolver, normalizing each mode shape to `aᵀ T a = 1`.
//! Zero modes are told apart: a free motion (U does not change along the mode,
//! as for the translation of a molecule) is reported, a vanishing curvature that
//! is not a symmetry (U = q⁴) is a degenerate equilibrium and an error.
//!
//! For up to three coordinates at an equilibrium with exact (integer)
//! coordinates, the secular equation `det(U − Ω²T) = 0` is also built
//! symbolically and solved exactly where it factors (trial roots, then the
//! quadratic formula).
//!
//! The potential is `U = −L(q, q' = 0)`: for particle models their potential
//! energy, for a `lagrangian` string its velocity-independent part (with
//! moving constraints this includes −T₀, the effective potential).

use crate::derive::Derivation;
use crate::equilibria::{self, Assessment, Equilibrium, EquilibriumReport, Landscape, Solved, Stability};
use crate::error::ModelError;
use crate::probe::{self, Decision, Subst, UNDECIDED};
use crate::report::Ordered;
use serde::Serialize;
use sym::{ExprId, Pool, Tape};

mod secular;
use secular::symbolic_modes;

/// Newton iterations before "no equilibrium nearby".
const MAX_NEWTON: usize = 200;
/// Eigenvalues of U below this fraction of the largest are zero modes.
const ZERO_MODE: f64 = 1e-9;
/// Largest system whose secular equation is built symbolically.
const MAX_SYMBOLIC: usize = 3;
/// Equilibrium coordinates below this fraction of the largest (or of 1) are
/// rounding noise about an exact zero, and printed as 0 (a few ulps of the
/// Newton iteration's last step).
const EQUILIBRIUM_ROUND_OFF: f64 = 1e-14;
/// Mode-shape components below this fraction of the largest are zero: the
/// eigenvectors carry a few hundred ulps of noise from the solver.
const SHAPE_ROUND_OFF: f64 = 1e-13;
/// Components within this fraction of the largest count as tied for the sign
/// convention (the first of them is made positive), so the sign does not
/// follow rounding noise.
const SHAPE_TIE: f64 = 1e-9;
/// A zero mode is a free motion when U changes along it by less than this
/// fraction of the energy and curvature scales: U is then flat there, not quartic.
const FLAT_ALONG_MODE: f64 = 1e-9;
/// An equilibrium coordinate within this relative distance of an integer is
/// taken as that integer for the closed form (T and U evaluated exactly there).
const EXACT_EQUILIBRIUM: f64 = 1e-9;
/// Largest integer equilibrium coordinate the closed form substitutes.
const MAX_EXACT_EQUILIBRIUM: f64 = 1e6;
/// A closed-form Ω² must agree with the numeric one to this fraction of the
/// largest Ω², or the closed form is withheld.
const ROOTS_AGREE: f64 = 1e-8;

/// Options of [`normal_modes`].
#[derive(Debug, Clone, Default)]
pub struct ModesConfig {
    /// Starting values for some coordinates (`--at q=v`); the others start at
    /// their `[initial]` value.
    pub at: Vec<(String, f64)>,
    /// Keep the equilibrium Newton's method lands on from the start even when
    /// it is unstable; otherwise a stable one near the start is looked for and
    /// preferred (both are listed in [`Modes::equilibria`]).
    pub keep_unstable: bool,
}

/// What kind of motion a normal mode is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModeKind {
    /// An oscillation with frequency Ω > 0.
    Oscillation,
    /// Ω = 0 and U does not change along the mode: a free motion (translation, rotation).
    Free,
    /// Ω² < 0: the equilibrium is unstable along this mode.
    Unstable,
}

/// One normal mode.
#[derive(Debug, Clone)]
pub struct Mode {
    /// Ω², the eigenvalue of `U a = Ω² T a`.
    pub omega_squared: f64,
    /// Ω (0 for a free mode, None for an unstable one).
    pub frequency: Option<f64>,
    /// The kind of motion.
    pub kind: ModeKind,
    /// The amplitude per coordinate, with `aᵀ T a = 1` and its largest component positive.
    pub shape: Vec<f64>,
}

/// The secular equation and the frequencies in closed form.
#[derive(Debug, Clone)]
pub struct SymbolicModes {
    /// The pool of these expressions: the derivation's, extended.
    pub pool: Pool,
    /// T at the equilibrium, in the parameters.
    pub t_matrix: Vec<Vec<ExprId>>,
    /// U at the equilibrium, in the parameters.
    pub u_matrix: Vec<Vec<ExprId>>,
    /// The symbol standing for Ω in `secular`.
    pub omega: ExprId,
    /// det(U − Ω²T), a polynomial in Ω².
    pub secular: ExprId,
    /// Ω² in closed form, ascending as the numeric ones (None where it does not factor).
    pub omega_squared: Option<Vec<ExprId>>,
    /// Ω in closed form, ascending.
    pub frequencies: Option<Vec<ExprId>>,
}

/// Small oscillations about an equilibrium.
#[derive(Debug, Clone)]
pub struct Modes {
    /// Coordinate names.
    pub coordinates: Vec<String>,
    /// Where Newton's method started.
    pub start: Vec<f64>,
    /// The equilibrium q₀.
    pub equilibrium: Vec<f64>,
    /// Newton iterations taken.
    pub newton_iterations: usize,
    /// |∂U/∂q| at the equilibrium.
    pub gradient_norm: f64,
    /// U(q₀).
    pub potential: f64,
    /// T = M(q₀).
    pub t_matrix: Vec<Vec<f64>>,
    /// U = ∂²U/∂q∂q at q₀.
    pub u_matrix: Vec<Vec<f64>>,
    /// The modes by ascending Ω².
    pub modes: Vec<Mode>,
    /// True when no Ω² is negative.
    pub stable: bool,
    /// The closed forms, when the system is small and the equilibrium exact.
    pub symbolic: Option<SymbolicModes>,
    /// The damped motion, when the model has Rayleigh's dissipation function.
    pub damping: Option<Damping>,
    /// Remarks for the reader (what was neglected, why no closed form).
    pub notes: Vec<String>,
    /// Every equilibrium the search met near the start, with its stability
    /// (Newton's landing point from the start first).
    pub equilibria: Vec<Equilibrium>,
    /// Which of `equilibria` is analysed here.
    pub chosen: usize,
    /// Which of `equilibria` Newton's method reached from the start, if any.
    pub landing: Option<usize>,
    /// T₀ = T(q, q' = 0), printed, when it is not zero: U is then the effective
    /// potential U − T₀ of moving constraints, not the model's U.
    pub effective_potential: Option<String>,
}

/// The small motion with friction: T (q − q₀)'' + C (q − q₀)' + U (q − q₀) = 0,
/// whose solutions go as e^{st} with det(s²T + sC + U) = 0.
#[derive(Debug, Clone)]
pub struct Damping {
    /// C = ∂²R/∂q'∂q' at q₀ and q' = 0.
    pub c_matrix: Vec<Vec<f64>>,
    /// The 2n roots s = (Re s, Im s): decay rate −Re s, damped frequency |Im s|;
    /// by decay rate, then by Im s descending (a conjugate pair + before −).
    pub eigenvalues: Vec<(f64, f64)>,
}

impl Modes {
    /// The normal frequencies Ω, ascending (None for an unstable mode).
    pub fn frequencies(&self) -> Vec<Option<f64>> {
        self.modes.iter().map(|m| m.frequency).collect()
    }
}

/// The hint of a refusal because the model is not conservative.
const NEEDS_CONSERVATIVE: &str = "small oscillations need L = T − U with T quadratic in q' and U(q) not depending on t";

/// Why there are no normal modes to report.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ModesError {
    /// The model itself is wrong (missing initial values, unknown `--at` name),
    /// or a place in it keeps small oscillations out (a `[forces]` entry).
    #[error("{0}")]
    Model(ModelError),
    /// The model is not a conservative system about a fixed equilibrium.
    #[error("{reason}")]
    NotConservative {
        /// Which part of the model prevents it.
        reason: String,
    },
    /// Newton's method found no point with ∂U/∂q = 0.
    #[error("no equilibrium near {start}: {why}")]
    NoEquilibrium {
        /// The starting configuration, as `q=v` pairs.
        start: String,
        /// What went wrong (diverged, did not converge).
        why: String,
    },
    /// The kinetic-energy matrix is not positive definite at the equilibrium.
    #[error("the kinetic-energy matrix T = M(q₀) is not positive definite at the equilibrium {at}")]
    SingularKinetic {
        /// The equilibrium, as `q=v` pairs.
        at: String,
    },
    /// A coordinate has no inertia at the equilibrium because a parameter is 0
    /// (a mass, a moment, a length): the kinetic-energy matrix is singular.
    #[error("{message}")]
    NoInertia {
        /// The sentence ([`crate::NoInertia::message`]).
        message: String,
        /// What to do ([`crate::NoInertia::help`]).
        help: String,
    },
    /// A zero mode along which U is not constant: the oscillation is not harmonic.
    #[error("the equilibrium at {at} is degenerate: U has no curvature along the mode {shape}, yet U changes along it, so small oscillations there are not harmonic")]
    Degenerate {
        /// The equilibrium, as `q=v` pairs.
        at: String,
        /// The flat direction, as `q=v` pairs.
        shape: String,
    },
    /// The eigenvalues of the damped system could not be computed (the QR
    /// iteration did not converge within its bound).
    #[error("the eigenvalues of the damped system at {at} cannot be computed: {why}")]
    NoEigenvalues {
        /// The equilibrium, as `q=v` pairs.
        at: String,
        /// Why not.
        why: num::EigenError,
    },
}

impl ModesError {
    /// A hint on how to fix it.
    pub fn help(&self) -> Option<String> {
        match self {
            ModesError::Model(e) => e.help.clone(),
            ModesError::NotConservative { .. } => Some(NEEDS_CONSERVATIVE.into()),
            ModesError::NoEquilibrium { .. } => Some(
                "start elsewhere (give the coordinates other starting values), or check that U has a minimum".into(),
            ),
            ModesError::NoInertia { help, .. } => Some(help.clone()),
            ModesError::SingularKinetic { .. } => {
                Some("the coordinates are singular there (like polar coordinates at r = 0); choose others".into())
            }
            ModesError::Degenerate { .. } => {
                Some("the leading term of U about this point is of higher than second order (like q^4)".into())
            }
            ModesError::NoEigenvalues { .. } => None,
        }
    }
}

impl From<ModelError> for ModesError {
    fn from(e: ModelError) -> Self {
        ModesError::Model(e)
    }
}

/// U, ∂U/∂q and the upper triangle of ∂²U/∂q∂q, compiled.
struct Potential {
    tape: Tape,
    n: usize,
    inputs: Vec<f64>,
    out: Vec<f64>,
}

impl Potential {
    /// Evaluates at q: (U, gradient, Hessian).
    fn eval(&mut self, q: &[f64]) -> (f64, Vec<f64>, nalgebra::DMatrix<f64>) {
        let n = self.n;
        self.inputs[..n].copy_from_slice(q);
        self.tape.eval(&self.inputs, &mut self.out);
        let g = self.out[1..=n].to_vec();
        let mut h = nalgebra::DMatrix::zeros(n, n);
        let mut k = n + 1;
        for i in 0..n {
            for j in i..n {
                h[(i, j)] = self.out[k];
                h[(j, i)] = self.out[k];
                k += 1;
            }
        }
        (self.out[0], g, h)
    }

    fn value(&mut self, q: &[f64]) -> f64 {
        self.eval(q).0
    }
}

/// T = M(q₀) is not positive definite at q₀ (`at`, as text): a coordinate
/// without inertia because a parameter is 0 when that is the cause, else the
/// coordinates' singularity.
fn singular_kinetic(d: &Derivation, q0: &[f64], at: &str) -> ModesError {
    let all: Vec<usize> = (0..d.q.len()).collect();
    match d.no_inertia_at(&all, q0, &|p| d.model.parameter(p)) {
        Some(idle) if !idle.zero_parameters.is_empty() => {
            ModesError::NoInertia { message: idle.message(&format!("the equilibrium {at}")), help: idle.help() }
        }
        _ => ModesError::SingularKinetic { at: at.to_string() },
    }
}

fn pairs(names: &[String], values: &[f64]) -> String {
    let parts: Vec<String> = names.iter().zip(values).map(|(n, v)| format!("{n}={}", short(*v))).collect();
    format!("({})", parts.join(", "))
}

/// A number with 6 significant digits, trailing zeros dropped.
pub(crate) fn short(v: f64) -> String {
    equilibria::short(v)
}

/// The velocity-independent potential U(q) = −L(q, 0) and the checks that
/// small oscillations apply.
/// Also T₀ = T(q, q' = 0), printed, when it is not proven zero: U is then the
/// effective potential U − T₀.
fn potential_of(d: &Derivation, pool: &mut Pool) -> Result<(ExprId, Vec<String>, Option<String>), ModesError> {
    let mut notes = Vec::new();
    let not_conservative = |reason: String| Err(ModesError::NotConservative { reason });
    match d.explicit_time {
        Some(false) => {}
        Some(true) => {
            return not_conservative(
                "L depends explicitly on the time t, so there is no fixed equilibrium to oscillate about".into(),
            )
        }
        None => {
            return not_conservative(format!(
                "could not decide whether L depends explicitly on the time t ({UNDECIDED}); small oscillations need it shown free of t"
            ))
        }
    }
    for (i, &f) in d.forces().iter().enumerate() {
        let reason = match probe::decide_zero(pool, f) {
            Decision::Zero => continue,
            Decision::NonZero => {
                "the model has generalized forces [forces], which are not derived from a potential".to_string()
            }
            Decision::Undecided => {
                format!("could not decide whether the generalized force {} is zero ({UNDECIDED})", pool.display(f))
            }
        };
        // A force comes from its `[forces]` entry: the refusal points at it.
        return match d.model.forces.get(i).and_then(Option::as_ref) {
            Some(entry) => {
                Err(ModesError::Model(ModelError::at(entry.span.clone(), reason).with_help(NEEDS_CONSERVATIVE)))
            }
            None => not_conservative(reason),
        };
    }
    if d.dissipation.is_some() {
        notes.push("the normal modes are the undamped ones (R left out); the damped motion's roots s include R".into());
    }
    let zero_vel: Subst = d.qd.iter().map(|&v| (v, pool.zero())).collect();
    // Terms linear in the velocities, b(q)·q', act like a magnetic field (gyroscopic
    // forces) unless b is a gradient; small oscillations as in the notes need none.
    for i in 0..d.q.len() {
        let b = pool.substitute(d.momenta[i], &zero_vel);
        let name = &d.model.coordinates[i].name;
        match probe::decide_zero(pool, b) {
            Decision::Zero => {}
            Decision::NonZero => {
                return not_conservative(format!(
                    "L has a term linear in the velocity {name}' (∂L/∂{name}' at rest is {}): gyroscopic forces are not covered",
                    pool.display(b)
                ))
            }
            Decision::Undecided => {
                return not_conservative(format!(
                    "could not decide whether L has a term linear in the velocity {name}' (∂L/∂{name}' at rest is {}; {UNDECIDED})",
                    pool.display(b)
                ))
            }
        }
    }
    let effective = match d.kinetic {
        Some(t) => {
            let t0 = pool.substitute(t, &zero_vel);
            let t0 = pool.simplify(t0);
            match probe::decide_zero(pool, t0) {
                Decision::Zero => None,
                _ => Some(pool.display(t0).to_string()),
            }
        }
        None => None,
    };
    if let Some(t0) = &effective {
        notes.push(format!(
            "U here is the effective potential U − T₀ = −L(q, q' = 0), not derive's U: T has the part T₀ = {t0} that does not vanish at rest (a moving constraint), and it counts as potential energy"
        ));
    }
    let l0 = pool.substitute(d.lagrangian, &zero_vel);
    let u = pool.neg(l0);
    Ok((pool.simplify(u), notes, effective))
}

/// Finds the equilibrium near the starting point and the normal modes about it.
pub fn normal_modes(d: &Derivation, config: &ModesConfig) -> Result<Modes, ModesError> {
    let n = d.q.len();
    let names: Vec<String> = d.model.coordinates.iter().map(|c| c.name.clone()).collect();
    let start = starting_point(d, config)?;
    // The derivation's pool is frozen: U, its derivatives and the closed forms
    // are built in a copy, which the symbolic result keeps.
    let mut pool_owned = d.pool().clone();
    let pool = &mut pool_owned;
    let (u, mut notes, effective_potential) = potential_of(d, pool)?;

    // Compile U, ∇U and the upper triangle of the Hessian.
    let grad: Vec<ExprId> = d.q.iter().map(|&q| pool.diff(u, q)).collect();
    let mut roots = vec![u];
    roots.extend(&grad);
    let mut hess = vec![vec![pool.zero(); n]; n];
    for i in 0..n {
        for j in i..n {
            let h = pool.diff(grad[i], d.q[j]);
            hess[i][j] = h;
            hess[j][i] = h;
            roots.push(h);
        }
    }
    let (input_ids, input_values) = (d.layout.symbols(), d.layout.values());
    let tape = Tape::compile(pool, &roots, input_ids)
        .map_err(|e| ModesError::NotConservative { reason: format!("U cannot be evaluated: {e}") })?;
    let n_out = roots.len();
    let mut pot = Potential { tape, n, inputs: input_values.clone(), out: vec![0.0; n_out] };

    // T = M(q), compiled beside U: the search asks for both at each point it finds.
    let m_roots: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    let mtape = Tape::compile(pool, &m_roots, input_ids)
        .map_err(|e| ModesError::NotConservative { reason: format!("T cannot be evaluated: {e}") })?;
    let mut land = ModesLandscape { pot: &mut pot, mtape, inputs: input_values, names: &names };
    let search = equilibria::search(&mut land, &start, !config.keep_unstable)
        .map_err(|why| ModesError::NoEquilibrium { start: pairs(&names, &start), why })?;
    let chosen = &search.found[search.chosen];
    let (mut q0, iterations, gnorm) = (chosen.x.clone(), chosen.iterations, chosen.residual);
    if search.landing.is_some_and(|i| i != search.chosen) {
        notes.push(
            "Newton's method from the start reached an unstable equilibrium; the stable one nearest the start is analysed instead".into(),
        );
    }
    // Rounding noise about an exact zero is zero (q = -1e-16 reads as a result).
    let q_big = q0.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    q0.iter_mut().filter(|v| v.abs() <= EQUILIBRIUM_ROUND_OFF * q_big).for_each(|v| *v = 0.0);
    let mvals = land.kinetic(&q0);
    let (u0, _, hmat) = land.pot.eval(&q0);
    let mut equilibria_found = search.found.clone();
    for e in &mut equilibria_found {
        let big = e.x.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        e.x.iter_mut().filter(|v| v.abs() <= EQUILIBRIUM_ROUND_OFF * big).for_each(|v| *v = 0.0);
    }
    let tmat = nalgebra::DMatrix::from_row_slice(n, n, &mvals);
    let at = pairs(&names, &q0);
    if !tmat.iter().all(|v| v.is_finite()) || !hmat.iter().all(|v| v.is_finite()) {
        return Err(ModesError::NoEquilibrium {
            start: pairs(&names, &start),
            why: format!("T or U is not finite at {at}"),
        });
    }

    // U a = λ T a  ⇔  (L⁻¹ U L⁻ᵀ) y = λ y with T = L Lᵀ and a = L⁻ᵀ y.
    let chol = tmat.clone().cholesky().ok_or_else(|| singular_kinetic(d, &q0, &at))?;
    let l = chol.l();
    let l_inv = l.clone().try_inverse().ok_or_else(|| singular_kinetic(d, &q0, &at))?;
    let s = &l_inv * &hmat * l_inv.transpose();
    let s = (&s + s.transpose()) * 0.5;
    let eig = s.symmetric_eigen();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let lam_scale = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // The curvature met on the way is the scale for "zero": at a degenerate
    // bottom (U = q⁴) every eigenvalue vanishes, so the equilibrium's own are no scale.
    let (_, _, h_start) = pot.eval(&start);
    let start_scale = (&l_inv * h_start * l_inv.transpose()).amax();
    let zero_scale = if start_scale.is_finite() { lam_scale.max(start_scale) } else { lam_scale };
    let energy_scale = 1.0 + u0.abs();
    let mut modes = Vec::with_capacity(n);
    for &k in &order {
        let y = eig.eigenvectors.column(k).into_owned();
        let a = l_inv.transpose() * y;
        let mut shape: Vec<f64> = a.iter().copied().collect();
        // The largest component positive (ties: the first); rounding noise is zero.
        let big = shape.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        shape.iter_mut().filter(|v| v.abs() <= SHAPE_ROUND_OFF * big).for_each(|v| *v = 0.0);
        if let Some(first) = shape.iter().find(|v| v.abs() > big * (1.0 - SHAPE_TIE)) {
            if *first < 0.0 {
                shape.iter_mut().for_each(|v| *v = -*v);
            }
        }
        let lam = eig.eigenvalues[k];
        let (omega_squared, frequency, kind) = if lam.abs() <= ZERO_MODE * zero_scale.max(f64::MIN_POSITIVE) {
            // Free motion or a flat, non-harmonic bottom: test U along the mode.
            let step = 0.1 * (1.0 + q0.iter().fold(0.0f64, |m, v| m.max(v.abs()))) / big.max(f64::MIN_POSITIVE);
            let mut flat = true;
            for sgn in [-1.0, 1.0, -0.1, 0.1] {
                let q: Vec<f64> = q0.iter().zip(&shape).map(|(q, a)| q + sgn * step * a).collect();
                let du = pot.value(&q) - u0;
                let curv_scale = 0.5 * lam_scale * (sgn * step).powi(2);
                if du.is_nan() || du.abs() > FLAT_ALONG_MODE * (energy_scale + curv_scale) {
                    flat = false;
                }
            }
            if !flat {
                return Err(ModesError::Degenerate { at, shape: pairs(&names, &shape) });
            }
            (0.0, Some(0.0), ModeKind::Free)
        } else if lam > 0.0 {
            (lam, Some(lam.sqrt()), ModeKind::Oscillation)
        } else {
            (lam, None, ModeKind::Unstable)
        };
        modes.push(Mode { omega_squared, frequency, kind, shape });
    }
    let stable = modes.iter().all(|m| m.kind != ModeKind::Unstable);
    if modes.iter().any(|m| m.kind == ModeKind::Free) {
        notes.push(
            "a zero mode (Ω = 0) is a free motion: U does not change along it (a translation or rotation of the whole system); its normal coordinate moves uniformly, Q = A t + B".into(),
        );
    }

    let symbolic = if n <= MAX_SYMBOLIC {
        let r = symbolic_modes(d, pool_owned, &hess, &q0, &modes);
        if let Err(why) = &r {
            notes.push(format!("no closed form: {why}"));
        }
        r.ok()
    } else {
        None
    };

    let to_rows =
        |m: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> { (0..n).map(|i| (0..n).map(|j| m[(i, j)]).collect()).collect() };
    let damping = match d.dissipation {
        Some(r) => Some(damped(d, r, &q0, &tmat, &hmat)?),
        None => None,
    };
    Ok(Modes {
        coordinates: names,
        start,
        equilibrium: q0,
        newton_iterations: iterations,
        gradient_norm: gnorm,
        potential: u0,
        t_matrix: to_rows(&tmat),
        u_matrix: to_rows(&hmat),
        modes,
        stable,
        symbolic,
        damping,
        notes,
        equilibria: equilibria_found,
        chosen: search.chosen,
        landing: search.landing,
        effective_potential,
    })
}

/// The search's view of U: Newton on ∇U = 0, and the stability from the
/// eigenvalues of `U a = Ω² T a` (a negative one is unstable; its shape is the
/// direction to look for a stable equilibrium in).
struct ModesLandscape<'a> {
    pot: &'a mut Potential,
    mtape: Tape,
    inputs: Vec<f64>,
    names: &'a [String],
}

impl ModesLandscape<'_> {
    /// M(q), row by row.
    fn kinetic(&mut self, q: &[f64]) -> Vec<f64> {
        let n = q.len();
        self.inputs[..n].copy_from_slice(q);
        let mut out = vec![0.0; n * n];
        self.mtape.eval(&self.inputs, &mut out);
        out
    }
}

impl Landscape for ModesLandscape<'_> {
    fn solve(&mut self, x0: &[f64]) -> Result<Solved, String> {
        newton(self.pot, x0, self.names).map(|(x, iterations, residual)| Solved { x, iterations, residual })
    }

    fn assess(&mut self, x: &[f64]) -> Assessment {
        let n = x.len();
        let unknown = Assessment { stability: Stability::Unstable, unstable_directions: Vec::new() };
        let t = nalgebra::DMatrix::from_row_slice(n, n, &self.kinetic(x));
        let (_, _, h) = self.pot.eval(x);
        if !t.iter().chain(h.iter()).all(|v| v.is_finite()) {
            return unknown;
        }
        let Some(chol) = t.cholesky() else { return unknown };
        let Some(l_inv) = chol.l().try_inverse() else { return unknown };
        let s = &l_inv * h * l_inv.transpose();
        let eig = ((&s + s.transpose()) * 0.5).symmetric_eigen();
        let scale = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        let unstable_directions: Vec<Vec<f64>> = (0..n)
            .filter(|&k| eig.eigenvalues[k] < -ZERO_MODE * scale)
            .map(|k| (l_inv.transpose() * eig.eigenvectors.column(k)).iter().copied().collect())
            .collect();
        let stability = if unstable_directions.is_empty() { Stability::Stable } else { Stability::Unstable };
        Assessment { stability, unstable_directions }
    }
}

/// C = ∂²R/∂q'∂q' at (q₀, q' = 0) and the roots of det(s²T + sC + U) = 0, the
/// eigenvalues of the first-order system [[0, 1], [−T⁻¹U, −T⁻¹C]].
fn damped(
    d: &Derivation,
    r: ExprId,
    q0: &[f64],
    tmat: &nalgebra::DMatrix<f64>,
    hmat: &nalgebra::DMatrix<f64>,
) -> Result<Damping, ModesError> {
    let n = q0.len();
    let mut pool = d.pool().clone();
    let mut roots = Vec::with_capacity(n * n);
    for i in 0..n {
        let ri = pool.diff(r, d.qd[i]);
        for j in 0..n {
            roots.push(pool.diff(ri, d.qd[j]));
        }
    }
    let at = || pairs(&d.model.coordinates.iter().map(|c| c.name.clone()).collect::<Vec<_>>(), q0);
    let mut tape = Tape::compile(&pool, &roots, d.layout.symbols())
        .map_err(|e| ModesError::NotConservative { reason: format!("R cannot be evaluated: {e}") })?;
    let mut inputs = d.layout.values();
    inputs[..n].copy_from_slice(q0);
    inputs[n..2 * n].iter_mut().for_each(|v| *v = 0.0);
    let mut c = vec![0.0; n * n];
    tape.eval(&inputs, &mut c);
    let cmat = nalgebra::DMatrix::from_row_slice(n, n, &c);
    if !cmat.iter().all(|v| v.is_finite()) {
        return Err(ModesError::NoEquilibrium {
            start: at(), why: format!("∂²R/∂q'∂q' is not finite at {}", at())
        });
    }
    let t_inv = tmat.clone().try_inverse().ok_or_else(|| singular_kinetic(d, q0, &at()))?;
    let mut a = nalgebra::DMatrix::<f64>::zeros(2 * n, 2 * n);
    for i in 0..n {
        a[(i, n + i)] = 1.0;
    }
    let (k, damp) = (-(&t_inv * hmat), -(&t_inv * &cmat));
    a.view_mut((n, 0), (n, n)).copy_from(&k);
    a.view_mut((n, n), (n, n)).copy_from(&damp);
    let scale = a.amax().max(f64::MIN_POSITIVE);
    // Our QR iteration (num::eigenvalues), not nalgebra's Schur, which panics
    // on a nilpotent A (a free coordinate without damping).
    let rows_a: Vec<f64> = (0..2 * n).flat_map(|i| (0..2 * n).map(move |j| (i, j))).map(|(i, j)| a[(i, j)]).collect();
    let computed = num::eigenvalues(2 * n, &rows_a).map_err(|why| ModesError::NoEigenvalues { at: at(), why })?;
    let mut eigenvalues: Vec<(f64, f64)> = computed
        .into_iter()
        .map(|(re, im)| {
            // Rounding noise about a real root (or a zero decay) is zero.
            let im = if im.abs() <= 1e-12 * scale { 0.0 } else { im };
            let re = if re.abs() <= 1e-12 * scale { 0.0 } else { re };
            (re, im)
        })
        .collect();
    eigenvalues.sort_by(|x, y| (-x.0).total_cmp(&-y.0).then(y.1.total_cmp(&x.1)));
    let rows = (0..n).map(|i| (0..n).map(|j| cmat[(i, j)]).collect()).collect();
    Ok(Damping { c_matrix: rows, eigenvalues })
}

/// The starting configuration: `[initial]` values (0 where missing), overridden by `--at`.
fn starting_point(d: &Derivation, config: &ModesConfig) -> Result<Vec<f64>, ModesError> {
    let model = &d.model;
    let n = model.n_coords();
    let mut q = vec![0.0; n];
    let env = |name: &str| model.parameter(name);
    for iv in model.initial.iter().filter(|iv| iv.order == 0) {
        let v =
            model.pool.eval(iv.value.expr, &env).map_err(|e| ModelError::at(iv.value.span.clone(), e.to_string()))?;
        q[iv.coord] = v;
    }
    for (name, v) in &config.at {
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
    Ok(q)
}

/// The equilibrium search: `num::newton` on ∇U = 0 with the Hessian as
/// Jacobian (|∇U|² as merit function; a flat direction, such as a free
/// translation, gets no step), with its defaults but [`MAX_NEWTON`] iterations.
/// Returns the point, the iterations and |∇U| there, or why it found none.
fn newton(pot: &mut Potential, start: &[f64], names: &[String]) -> Result<(Vec<f64>, usize, f64), String> {
    let n = start.len();
    let fail = |why: String| why;
    let gradient = |q: &[f64], g: &mut [f64], jac: &mut [f64]| {
        let (_, grad, hess) = pot.eval(q);
        g.copy_from_slice(&grad);
        for i in 0..n {
            for j in 0..n {
                jac[i * n + j] = hess[(i, j)];
            }
        }
    };
    let config = num::NewtonConfig { max_iterations: MAX_NEWTON, ..num::NewtonConfig::default() };
    match num::newton(gradient, start, &config) {
        Ok(sol) => Ok((sol.x, sol.iterations, sol.residual)),
        Err(num::NewtonError::NotFinite { x, .. }) => {
            Err(fail(format!("U or its derivatives are not finite at {}", pairs(names, &x))))
        }
        Err(num::NewtonError::Stalled { x, residual }) => {
            Err(fail(format!("Newton's method stalls at {} with |∂U/∂q| = {}", pairs(names, &x), short(residual))))
        }
        Err(num::NewtonError::RunAway { x }) => {
            Err(fail(format!("Newton's method runs away (to {})", pairs(names, &x))))
        }
        Err(num::NewtonError::NoConvergence { residual, .. }) => Err(fail(format!(
            "Newton's method did not converge in {MAX_NEWTON} iterations (|∂U/∂q| = {})",
            short(residual)
        ))),
    }
}

/// A name for Ω that is not one of the model's names.
fn fresh_name(d: &Derivation, base: &str) -> String {
    let mut name = base.to_string();
    while d.model.parameters.iter().any(|p| p.name == name) || d.model.coordinates.iter().any(|c| c.name == name) {
        name.push('_');
    }
    name
}

/// The modes as the JSON contract `lagrange.modes/1`.
#[derive(Debug, Clone, Serialize)]
pub struct ModesReport {
    /// Always `lagrange.modes/1`.
    pub format: &'static str,
    /// The model's name.
    pub name: String,
    /// q₀ by coordinate.
    pub equilibrium: Ordered<f64>,
    /// T = M(q₀).
    #[serde(rename = "T")]
    pub t_matrix: Vec<Vec<f64>>,
    /// U = ∂²U/∂q∂q at q₀.
    #[serde(rename = "U")]
    pub u_matrix: Vec<Vec<f64>>,
    /// Ω ascending (null for an unstable mode).
    pub frequencies: Vec<Option<f64>>,
    /// Mode shapes, one per frequency, normalized to aᵀTa = 1.
    pub modes: Vec<Vec<f64>>,
    /// True when no Ω² is negative.
    pub stable: bool,
    /// Ω² ascending (negative for an unstable mode).
    pub omega_squared: Vec<f64>,
    /// The kind of each mode: oscillation, free, unstable.
    pub kinds: Vec<ModeKind>,
    /// The secular equation det(U − Ω²T) = 0 in the expression language (Ω is `Om`), or null.
    pub secular_equation: Option<String>,
    /// Ω in closed form, ascending, or null.
    pub exact_frequencies: Option<Vec<String>>,
    /// Newton iterations used to find the equilibrium.
    pub newton_iterations: usize,
    /// C = ∂²R/∂q'∂q' at q₀, or null without dissipation.
    #[serde(rename = "C")]
    pub c_matrix: Option<Vec<Vec<f64>>>,
    /// The damped motion's roots s of det(s²T + sC + U) = 0 (e^{st}), or null
    /// without dissipation.
    pub damped: Option<Vec<DampedRoot>>,
    /// Every equilibrium met near the start with its stability; `chosen` marks
    /// the one analysed, `landing` the one Newton's method reached from the start.
    pub equilibria: Vec<EquilibriumReport>,
    /// T₀ = T(q, q' = 0) when it is not zero: then `U` (and U(q₀)) is the
    /// effective potential U − T₀, not the model's U; null otherwise.
    pub effective_potential: Option<String>,
    /// U(q₀), the (effective) potential at the equilibrium.
    pub potential: f64,
}

/// One root s of the damped motion.
#[derive(Debug, Clone, Serialize)]
pub struct DampedRoot {
    /// Re s.
    pub re: f64,
    /// Im s.
    pub im: f64,
    /// −Re s: how fast the motion decays (negative: grows).
    pub decay_rate: f64,
    /// |Im s|: the damped angular frequency (0 for an overdamped root).
    pub frequency: f64,
}

impl ModesReport {
    /// The report of computed modes.
    pub fn new(d: &Derivation, m: &Modes) -> ModesReport {
        let sym = m.symbolic.as_ref();
        ModesReport {
            format: "lagrange.modes/1",
            name: d.model.name.clone(),
            equilibrium: Ordered(m.coordinates.iter().cloned().zip(m.equilibrium.iter().copied()).collect()),
            t_matrix: m.t_matrix.clone(),
            u_matrix: m.u_matrix.clone(),
            frequencies: m.frequencies(),
            modes: m.modes.iter().map(|x| x.shape.clone()).collect(),
            stable: m.stable,
            omega_squared: m.modes.iter().map(|x| x.omega_squared).collect(),
            kinds: m.modes.iter().map(|x| x.kind).collect(),
            secular_equation: sym.map(|s| format!("{} = 0", s.pool.display(s.secular))),
            exact_frequencies: sym
                .and_then(|s| s.frequencies.as_ref().map(|f| (f, &s.pool)))
                .map(|(f, pool)| f.iter().map(|&e| pool.display(e).to_string()).collect()),
            newton_iterations: m.newton_iterations,
            c_matrix: m.damping.as_ref().map(|x| x.c_matrix.clone()),
            damped: m.damping.as_ref().map(|x| {
                x.eigenvalues
                    .iter()
                    .map(|&(re, im)| DampedRoot { re, im, decay_rate: -re, frequency: im.abs() })
                    .collect()
            }),
            equilibria: EquilibriumReport::list(&m.coordinates, &m.equilibria, m.chosen, m.landing),
            effective_potential: m.effective_potential.clone(),
            potential: m.potential,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;

    fn derive(text: &str, set: &[(&str, f64)]) -> Derivation {
        let set: Vec<(String, f64)> = set.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        let model = Model::parse(text, &set).expect("model parses");
        Derivation::new(model).expect("derivation")
    }

    fn example(name: &str) -> String {
        let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    #[track_caller]
    fn check_frequencies(m: &Modes, expect: &[f64]) {
        let got: Vec<f64> = m.frequencies().into_iter().map(|f| f.expect("stable")).collect();
        assert_eq!(got.len(), expect.len());
        for (g, e) in got.iter().zip(expect) {
            assert!((g - e).abs() <= 1e-10 * (1.0 + e.abs()), "got {got:?}, expected {expect:?}");
        }
    }

    #[test]
    fn a_free_undamped_coordinate_beside_a_damped_one_has_its_double_zero() {
        // C vanishes along x (R = x'^4/4): A has the nilpotent block of a free
        // particle, which nalgebra's Schur could not take.
        let text = "coordinates = [\"x\", \"y\"]\nlagrangian = \"x'^2/2 + y'^2/2 - y^2/2\"\ndissipation = \"x'^4/4 + y'^2/10\"\n";
        let d = derive(text, &[]);
        let m = normal_modes(&d, &ModesConfig::default()).unwrap();
        let ev = m.damping.expect("damped").eigenvalues;
        let zeros = ev.iter().filter(|e| e.0.hypot(e.1) <= 1e-6).count();
        assert_eq!(zeros, 2, "{ev:?}");
        // y: s² + 0.2 s + 1 = 0.
        let w = (1.0f64 - 0.01).sqrt();
        for want in [(-0.1, w), (-0.1, -w)] {
            assert!(ev.iter().any(|e| (e.0 - want.0).hypot(e.1 - want.1) <= 1e-12), "{ev:?}");
        }
    }

    /// Every mode solves U a = Ω² T a with aᵀ T a = 1, and modes are T-orthogonal.
    #[track_caller]
    fn check_eigen(m: &Modes) {
        let n = m.coordinates.len();
        let t = nalgebra::DMatrix::from_fn(n, n, |i, j| m.t_matrix[i][j]);
        let u = nalgebra::DMatrix::from_fn(n, n, |i, j| m.u_matrix[i][j]);
        let scale = u.amax().max(t.amax());
        for (i, a) in m.modes.iter().enumerate() {
            let av = nalgebra::DVector::from_column_slice(&a.shape);
            let r = &u * &av - &t * &av * a.omega_squared;
            assert!(r.amax() <= 1e-9 * scale * (1.0 + av.amax()), "mode {i}: residual {}", r.amax());
            for (j, b) in m.modes.iter().enumerate() {
                let bv = nalgebra::DVector::from_column_slice(&b.shape);
                let dot = (av.transpose() * &t * bv)[(0, 0)];
                let expect = if i == j { 1.0 } else { 0.0 };
                assert!((dot - expect).abs() < 1e-9, "aᵀTa[{i}][{j}] = {dot}");
            }
        }
    }

    #[test]
    fn coupled_oscillators_match_the_notes() {
        let d = derive(&example("coupled_oscillators"), &[]);
        let m = normal_modes(&d, &ModesConfig::default()).unwrap();
        // m = k = 1, k12 = 0.625: Ω₁ = sqrt(k/m) = 1, Ω₂ = sqrt((k + 2k12)/m) = 1.5 (Fig. 3.3).
        check_frequencies(&m, &[1.0, 1.5]);
        check_eigen(&m);
        // Symmetric and antisymmetric modes, each normalized: (1, 1)/√2, (1, −1)/√2.
        let h = std::f64::consts::FRAC_1_SQRT_2;
        for (a, e) in m.modes[0].shape.iter().zip([h, h]) {
            assert!((a - e).abs() < 1e-12);
        }
        assert!((m.modes[1].shape[0] - h).abs() < 1e-12 && (m.modes[1].shape[1] + h).abs() < 1e-12);
        assert!(m.stable);
        let s = m.symbolic.as_ref().expect("a 2x2 secular equation");
        assert!(s.frequencies.is_some(), "the quadratic formula gives closed forms");
    }

    #[test]
    fn triatomic_molecule_has_a_free_translation_and_the_notes_frequencies() {
        let d = derive(&example("triatomic"), &[]);
        let m = normal_modes(&d, &ModesConfig::default()).unwrap();
        let (mm, big, k) = (16.0f64, 12.0f64, 1.0f64);
        check_frequencies(&m, &[0.0, (k / mm).sqrt(), (k / mm * (1.0 + 2.0 * mm / big)).sqrt()]);
        check_eigen(&m);
        assert_eq!(m.modes[0].kind, ModeKind::Free);
        assert!(m.stable);
        // The notes' V: translation (1,1,1)/sqrt(M+2m); Ω₂ mode (1,0,−1)/sqrt(2m).
        let tr = 1.0 / (big + 2.0 * mm).sqrt();
        for a in &m.modes[0].shape {
            assert!((a - tr).abs() < 1e-12);
        }
        let s2 = 1.0 / (2.0 * mm).sqrt();
        let expect = [s2, 0.0, -s2];
        for (a, e) in m.modes[1].shape.iter().zip(expect) {
            assert!((a - e).abs() < 1e-12, "{:?}", m.modes[1].shape);
        }
        // Exact: Ω² = 0, k/m, k/m (1 + 2m/M).
        let s = m.symbolic.as_ref().unwrap_or_else(|| panic!("no symbolic modes: {:?}", m.notes));
        let om2 = s.omega_squared.as_ref().expect("the cubic factors");
        let pool = &s.pool;
        let mut expect_exprs = Vec::new();
        let mut p = pool.clone();
        for text in ["0", "k/m", "k/m*(1 + 2*m/M)"] {
            expect_exprs.push(p.parse(text).unwrap());
        }
        for (&got, &want) in om2.iter().zip(&expect_exprs) {
            let diff = p.sub(got, want);
            assert!(probe::is_zero(&mut p, diff), "Ω² = {} is not {}", p.display(got), p.display(want));
        }
    }

    #[test]
    fn double_pendulum_about_its_lowest_position() {
        let d = derive(&example("double_pendulum"), &[]);
        let at = vec![("a".to_string(), 0.1), ("b".to_string(), -0.2)];
        let m = normal_modes(&d, &ModesConfig { at, ..Default::default() }).unwrap();
        assert!(m.equilibrium.iter().all(|q| q.abs() < 1e-12), "{:?}", m.equilibrium);
        // Equal masses and lengths: Ω² = (2 ∓ √2) g/l.
        let g = 9.81f64;
        check_frequencies(&m, &[((2.0 - 2f64.sqrt()) * g).sqrt(), ((2.0 + 2f64.sqrt()) * g).sqrt()]);
        check_eigen(&m);
        assert!(m.symbolic.as_ref().and_then(|s| s.frequencies.as_ref()).is_some());
    }

    #[test]
    fn double_pendulum_upside_down_is_unstable() {
        let d = derive(&example("double_pendulum"), &[]);
        let m = normal_modes(&d, &ModesConfig::default()).unwrap();
        let pi = std::f64::consts::PI;
        assert!(m.equilibrium.iter().all(|q| (q - pi).abs() < 1e-9), "{:?}", m.equilibrium);
        assert!(!m.stable);
        assert_eq!(m.modes[0].kind, ModeKind::Unstable);
    }

    #[test]
    fn chain_of_fifty_masses() {
        let d = derive(&example("chain50"), &[]);
        let m = normal_modes(&d, &ModesConfig::default()).unwrap();
        let n = 50.0;
        let expect: Vec<f64> =
            (1..=50).map(|j| 2.0 * (j as f64 * std::f64::consts::PI / (2.0 * (n + 1.0))).sin()).collect();
        check_frequencies(&m, &expect);
        check_eigen(&m);
        assert!(m.symbolic.is_none());
    }

    #[test]
    fn bad_equilibria_are_errors() {
        let flat =
            "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"x^4\"\n[initial]\nx = 1.0\n\"x'\" = 0.0\n";
        let d = derive(flat, &[]);
        let e = normal_modes(&d, &ModesConfig::default()).unwrap_err();
        assert!(matches!(e, ModesError::Degenerate { .. }), "{e}");

        let none = "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"x\"\n[initial]\nx = 1.0\n\"x'\" = 0.0\n";
        let d = derive(none, &[]);
        let e = normal_modes(&d, &ModesConfig::default()).unwrap_err();
        assert!(matches!(e, ModesError::NoEquilibrium { .. }), "{e}");

        let d = derive(&example("kepler"), &[]);
        let e = normal_modes(&d, &ModesConfig::default()).unwrap_err();
        assert!(matches!(e, ModesError::NoEquilibrium { .. }), "{e}");
    }

    /// A `[forces]` entry keeps small oscillations out; the refusal points at
    /// the entry's value (the second coordinate's, the first's being zero).
    #[test]
    fn a_generalized_force_is_refused_at_its_entry() {
        let text = "coordinates = [\"x\", \"y\"]\nkinetic = \"(x'^2 + y'^2)/2\"\npotential = \"(x^2 + y^2)/2\"\n\
                    [forces]\nx = \"0\"\ny = \"-y'\"\n[initial]\nx = 0.0\ny = 0.0\n\"x'\" = 0.0\n\"y'\" = 0.0\n";
        let d = derive(text, &[]);
        let e = normal_modes(&d, &ModesConfig::default()).unwrap_err();
        let ModesError::Model(m) = e else { panic!("expected a located model error, got {e:?}") };
        assert!(m.message.contains("not derived from a potential"), "{}", m.message);
        let span = m.span.expect("the error has a place");
        assert_eq!(&text[span.clone()], "\"-y'\"");
        assert_eq!(span.start, text.find("y = \"-y'").unwrap() + 4);
        assert!(m.help.is_some());
    }

    /// The notes' case (iii): started in the Ω₃ mode, the molecule stays in it:
    /// the other normal coordinates Q = aᵀT(q − q₀) stay zero.
    #[test]
    fn a_simulation_started_in_a_mode_stays_in_it() {
        let text = example("triatomic");
        let d = derive(&text, &[]);
        let m = normal_modes(&d, &ModesConfig::default()).unwrap();
        let amp = 0.05;
        for (k, mode) in m.modes.iter().enumerate().skip(1) {
            let head = text.split("[initial]").next().unwrap();
            let mut model = head.to_string();
            model.push_str("[initial]\n");
            for (i, c) in m.coordinates.iter().enumerate() {
                model.push_str(&format!("{c} = {}\n\"{c}'\" = 0.0\n", m.equilibrium[i] + amp * mode.shape[i]));
            }
            let sim = derive(&model, &[]);
            let config = crate::RunConfig { until: 60.0, rtol: 1e-11, atol: 1e-13, ..Default::default() };
            let n = m.coordinates.len();
            let t = nalgebra::DMatrix::from_fn(n, n, |i, j| m.t_matrix[i][j]);
            let mut worst: f64 = 0.0;
            let mut main_err: f64 = 0.0;
            let omega = mode.frequency.unwrap();
            crate::simulate(&sim, &config, |row| {
                let dq = nalgebra::DVector::from_iterator(n, row.q.iter().zip(&m.equilibrium).map(|(a, b)| a - b));
                for (j, other) in m.modes.iter().enumerate() {
                    let av = nalgebra::DVector::from_column_slice(&other.shape);
                    let qj = (av.transpose() * &t * &dq)[(0, 0)];
                    if j == k {
                        main_err = main_err.max((qj - amp * (omega * row.t).cos()).abs());
                    } else {
                        worst = worst.max(qj.abs());
                    }
                }
                std::ops::ControlFlow::Continue(())
            })
            .unwrap();
            assert!(worst < 1e-8, "mode {k}: other normal coordinates reach {worst}");
            assert!(main_err < 1e-7, "mode {k}: Q_k departs from A cos(Ωt) by {main_err}");
        }
    }
}
