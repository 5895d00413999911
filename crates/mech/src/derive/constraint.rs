//! Constraints and their forces with Lagrange multipliers (notes 2.2.1, 2.6.3,
//! appendix A.3): the `[[constraints]]` of a model, their Jacobian `A`, the
//! equations `M q'' = f + Aᵀλ`, and whether a velocity constraint is integrable
//! (holonomic in disguise).
//!
//! A holonomic constraint `f(q, t) = 0` has the row `A = ∂f/∂q` and the time term
//! `a_t = ∂f/∂t`; a velocity constraint `a(q, t)·q' + a_t = 0` has `A = a`. Both
//! are the Pfaffian form `ω = Σ A_i dq_i + a_t dt` on the extended space (q, t).
//! Integrability is Frobenius' condition: `ω ∧ dω = 0` for one form, and for the
//! set `dω_k ∧ ω_1 ∧ … ∧ ω_m = 0` (the distribution the forms annihilate is
//! involutive). Each is a claim of zero, decided as every claim is
//! ([`crate::probe`]): proven by rewriting, refuted at a point, or left
//! undecided (`integrable` is then None and the explanation says so).
//!
//! Entry point: [`derive`], the stage of [`crate::Derivation::new`] between
//! the equations of motion and the verdicts; the tables are read by
//! `model/constraint.rs`, and the numbers of a run are in `run/constrained.rs`.

use super::{Derivation, Symbols};
use crate::error::{ModelError, ModelErrorKind};
use crate::model::{ConstraintKind, Model};
use crate::probe::Decision;
use crate::probe::{self, Subst};
use std::ops::Range;
use sym::{ExprId, NameId, Pool, Symbol};

/// A constraint with what the derivation makes of it.
#[derive(Debug, Clone)]
pub struct Constraint {
    /// Its name.
    pub name: String,
    /// Holonomic or velocity.
    pub kind: ConstraintKind,
    /// The expression as written (f, or a·q' + a_t).
    pub expr: ExprId,
    /// The row of A: ∂f/∂q, or the velocity coefficients a.
    pub jacobian: Vec<ExprId>,
    /// The time term a_t (∂f/∂t for a holonomic constraint).
    pub time_term: ExprId,
    /// The constraint at velocity level, g = A·q' + a_t (= df/dt when holonomic).
    pub velocity_form: ExprId,
    /// The right-hand side c of the acceleration-level constraint A q'' = c.
    pub acceleration_rhs: ExprId,
    /// Whether it depends explicitly on t (None: could not be decided).
    pub rheonomic: Option<bool>,
    /// Whether its force does work (a_t ≠ 0: Σ Q·q' = −λ a_t; None: could not be decided).
    pub does_work: Option<bool>,
    /// Whether it is integrable on its own (holonomic ones are; None: could not be decided).
    pub integrable: Option<bool>,
    /// F(q, t) with dF = ω (the constraint is F = const), when found.
    pub integral: Option<ExprId>,
    /// The teaching text, sentence by sentence.
    pub explanation: Vec<String>,
    /// The Lagrange multiplier's symbol (`lambda_NAME`).
    pub multiplier: ExprId,
    /// Where the constraint's expression is in the model file.
    pub span: Range<usize>,
}

/// The constraints of a derivation and the equations with multipliers.
#[derive(Debug, Clone, Default)]
pub struct Constraints {
    /// The constraints in file order.
    pub list: Vec<Constraint>,
    /// The number of independent constraints (the rank of A at generic points).
    pub independent: usize,
    /// n − independent: the degrees of freedom of the velocities.
    pub degrees_of_freedom: usize,
    /// Whether the velocity constraints together are integrable (None without
    /// any, or when it could not be decided).
    pub integrable: Option<bool>,
    /// E_i − Σ_k λ_k A_ki per coordinate: the equations of motion with multipliers.
    pub multiplier_equations: Vec<ExprId>,
    /// Σ_k λ_k A_ki per coordinate: the generalized constraint force Aᵀλ.
    pub generalized_forces: Vec<ExprId>,
    /// The Cartesian constraint force on each particle, per particle its
    /// components, when it is determined by Q = (∂x/∂q)ᵀF: the positions are the
    /// coordinates themselves, or have as many components as there are
    /// coordinates (n ≤ 3) with ∂x/∂q invertible.
    pub cartesian_forces: Option<Vec<Vec<ExprId>>>,
    /// The teaching text about the set (degrees of freedom, integrability, work).
    pub explanation: Vec<String>,
    /// True when H would be conserved but for the work W of the constraint forces
    /// (L free of t, no dissipation or forces, a constraint with a_t ≠ 0): then
    /// H − W is conserved, and runs audit it.
    pub work_balances_h: bool,
}

impl Constraint {
    /// What the run's `residual_NAME` column shows, as an expression: f for a
    /// holonomic constraint, A q' + a_t for a velocity constraint. The run
    /// computes the same numbers from its compiled geometry
    /// (`run::constrained`'s `residuals`); the exports write this.
    pub fn residual(&self) -> ExprId {
        match self.kind {
            ConstraintKind::Holonomic => self.expr,
            ConstraintKind::Velocity => self.velocity_form,
        }
    }
}

impl Constraints {
    /// True when the model has no constraints.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }
}

impl Derivation {
    /// An error (with the place of the first constraint) for analyses that do not
    /// take constraints into account yet, so that they never answer for the
    /// unconstrained system silently. `what` names the analysis (`lagrange modes`).
    pub fn reject_constraints(&self, what: &str) -> Result<(), ModelError> {
        match self.constraints.list.first() {
            None => Ok(()),
            Some(c) => Err(ModelError::at(
                c.span.clone(),
                format!("{what} does not handle [[constraints]] yet: it would analyse the unconstrained system"),
            )
            .with_kind(ModelErrorKind::Unsupported)
            .with_help("the derivation and simulation enforce constraints with multipliers; or eliminate the constraint by generalized coordinates")),
        }
    }
}

/// The largest residual of a holonomic constraint at the start, relative to
/// the size of its terms ([`probe::terms_size_at`]), that is taken for
/// round-off (and projected away by a run); beyond it the start is refused.
pub const INITIAL_TOLERANCE: f64 = 1e-9;

impl Derivation {
    /// Checks the constraints at a start (q, q') at t = 0 with the parameters at
    /// their values, before anything is solved there: every constraint has a
    /// real value (its row of A too), each holonomic one holds to
    /// [`INITIAL_TOLERANCE`] of its terms' size, and its gradient ∂f/∂q does not
    /// vanish there (a squared constraint's does wherever it holds, which
    /// leaves its force undetermined). Every command that starts from a point
    /// runs this (`simulate`, `report`, `linearize`).
    /// Constraints that are not independent are left to the commands' own
    /// diagnosis, which tells a repeated constraint from a contradiction.
    pub fn check_constraints_at(&self, q: &[f64], qd: &[f64]) -> Result<(), ModelError> {
        if self.constraints.independent < self.constraints.list.len() {
            return Ok(());
        }
        let model = &self.model;
        let names: Vec<&str> = model.coordinates.iter().map(|c| c.name.as_str()).collect();
        let env = |name: &str| {
            if name == "t" {
                return Some(0.0);
            }
            if let Some(k) = names.iter().position(|&c| c == name) {
                return Some(q[k]);
            }
            if let Some(k) = name.strip_suffix('\'').and_then(|c| names.iter().position(|&n| n == c)) {
                return Some(qd[k]);
            }
            model.parameter(name)
        };
        let pool = self.pool();
        let point = || self.point_text(q);
        for c in &self.constraints.list {
            let value = |e: ExprId| pool.eval(e, &env).unwrap_or(f64::NAN);
            let holonomic = c.kind == ConstraintKind::Holonomic;
            let f = if holonomic { value(c.expr) } else { 0.0 };
            let row: Vec<f64> = c.jacobian.iter().map(|&e| value(e)).collect();
            let time_term = value(c.time_term);
            let what = if holonomic { "its gradient ∂f/∂q" } else { "its coefficients of the velocities" };
            let (subject, bad) = if !f.is_finite() {
                (format!("the constraint '{}'", c.name), f)
            } else if let Some(&v) = row.iter().chain([&time_term]).find(|v| !v.is_finite()) {
                (format!("{what} of the constraint '{}'", c.name), v)
            } else {
                (String::new(), 0.0)
            };
            if !subject.is_empty() {
                let how = if bad.is_nan() { "has no real value" } else { "is infinite" };
                return Err(ModelError::at(c.span.clone(), format!("{subject} {how} at the start {}", point()))
                    .with_kind(ModelErrorKind::Start)
                    .with_help("a square root or logarithm of a negative number, or a division by zero, at the start: give [initial] values where the constraint is defined, or write it so that it is"));
            }
            if !holonomic {
                continue;
            }
            let size = probe::terms_size_at(pool, c.expr, &env).unwrap_or(f.abs());
            if f.abs() > INITIAL_TOLERANCE * size {
                return Err(ModelError::at(
                    c.span.clone(),
                    format!(
                        "the initial values violate the constraint '{}': its value at the start {} is {f:.3e}, not 0 (the tolerance is {:.3e}: {INITIAL_TOLERANCE:e} of the size of its terms, {size:.3e})",
                        c.name,
                        point(),
                        INITIAL_TOLERANCE * size,
                    ),
                )
                .with_kind(ModelErrorKind::Start)
                .with_help("give [initial] values that satisfy the constraint (velocities too: A q' + a_t = 0); residuals within the tolerance are round-off and projected away"));
            }
            let vanishes = c.jacobian.iter().all(|&e| probe::zero_to_rounding_at(pool, e, &env).unwrap_or(false));
            if vanishes {
                let power = power_base(pool, c.expr);
                let mut err = ModelError::at(
                    c.span.clone(),
                    format!(
                        "the gradient ∂f/∂q of the constraint '{}' vanishes at the start {}, where the constraint holds: it fixes no direction there, so its force is undetermined",
                        c.name,
                        point()
                    ),
                );
                err = match power {
                    Some(base) => err.with_help(format!(
                        "the constraint is a power of {}, whose gradient is zero wherever it holds: write it unsquared, holonomic = \"{}\"",
                        pool.display(base),
                        pool.display(base)
                    )),
                    None => err.with_help("write the constraint so that its gradient is not zero where it holds (not as a square, a product with a repeated factor or a sum of squares), or start where it is not zero"),
                };
                return Err(err.with_kind(ModelErrorKind::Start));
            }
        }
        Ok(())
    }
}

/// The base g of a constraint written as a power g^n (n > 1), or as a product
/// with such a factor: its gradient n g^(n−1) ∇g vanishes wherever g = 0.
fn power_base(pool: &Pool, e: ExprId) -> Option<ExprId> {
    let repeated = |f: ExprId| match pool.node(f) {
        &sym::Node::Pow(b, x) if pool.as_number(x).is_some_and(|n| n.to_f64() > 1.0) => Some(b),
        _ => None,
    };
    match pool.node(e) {
        sym::Node::Mul(fs) => fs.iter().find_map(|&f| repeated(f)),
        _ => repeated(e),
    }
}

/// Derives the constraints of a model on its equations of motion `E`: each
/// constraint's row of A, time term, velocity and acceleration forms,
/// integrability and teaching text; the set's rank; the equations with
/// multipliers `E − Aᵀλ` and, where they are determined, the Cartesian
/// constraint forces. A stage of [`crate::Derivation::new`], run before any
/// verdict: the verdicts then read what the constraint forces do
/// ([`Constraints::work`], [`momentum_kept`]), and [`Constraints::explained`]
/// adds their sentences.
pub(super) fn derive(
    pool: &mut Pool,
    model: &Model,
    s: &Symbols,
    equations: &[ExprId],
) -> Result<Constraints, ModelError> {
    if model.constraints.is_empty() {
        return Ok(Constraints::default());
    }
    let mut set = derive_all(pool, s, &model.constraints)?;
    // Equations with multipliers: E_i − Σ_k λ_k A_ki = 0.
    for (i, &equation) in equations.iter().enumerate() {
        let terms: Vec<ExprId> = set.list.iter().map(|c| pool.mul2(c.multiplier, c.jacobian[i])).collect();
        let force = pool.add(&terms);
        set.generalized_forces.push(force);
        let eq = pool.sub(equation, force);
        set.multiplier_equations.push(eq);
    }
    set.cartesian_forces = cartesian_forces(model, &s.q, &set.generalized_forces)
        .or_else(|| cartesian_forces_square(pool, model, &s.q, &set.generalized_forces));
    Ok(set)
}

/// The constraints whose forces do work (a_t proven nonzero) and those for
/// which that could not be decided: what the verdict on H reads.
pub(super) struct Work {
    pub(super) working: Vec<String>,
    pub(super) undecided: Vec<String>,
}

impl Constraints {
    /// Which constraint forces do work ([`Work`]).
    pub(super) fn work(&self) -> Work {
        let names = |does_work: Option<bool>| {
            self.list.iter().filter(|c| c.does_work == does_work).map(|c| c.name.clone()).collect()
        };
        Work { working: names(Some(true)), undecided: names(None) }
    }

    /// The set with the sentences of the verdicts that its forces changed:
    /// the momenta of cyclic coordinates they take away (`lost`, from
    /// [`momentum_kept`]), whether `H − W` is what a run audits, and that
    /// Hamilton's equations (when there are any) are for L alone.
    pub(super) fn explained(mut self, lost: Vec<String>, work_balances_h: bool, hamilton: bool) -> Constraints {
        if self.is_empty() {
            return self;
        }
        self.explanation.extend(lost);
        if hamilton {
            self.explanation
                .push("Hamilton's equations are given for L alone: with the constraints, p' = −∂H/∂q + Aᵀλ.".into());
        }
        self.work_balances_h = work_balances_h;
        self
    }
}

/// Whether the momentum of the cyclic coordinate `i` (named `q`) stays
/// conserved under the constraint forces: only when its column of A is proven
/// zero. A point showing an entry nonzero, or an entry that could not be
/// decided, gives the sentence saying why it is not claimed.
pub(super) fn momentum_kept(pool: &mut Pool, set: &Constraints, i: usize, q: &str) -> Result<(), String> {
    let mut acted = Vec::new();
    let mut unknown = Vec::new();
    for k in &set.list {
        match probe::decide_zero(pool, k.jacobian[i]) {
            Decision::Zero => {}
            Decision::NonZero => acted.push(k.name.as_str()),
            Decision::Undecided => unknown.push(k.name.as_str()),
        }
    }
    if !acted.is_empty() {
        Err(format!(
            "{q} is cyclic, but the constraint force of {} acts on it (its column of A is not zero), so p_{q} is not conserved.",
            acted.join(", ")
        ))
    } else if !unknown.is_empty() {
        Err(format!(
            "{q} is cyclic, but whether the constraint force of {} acts on it could not be decided (its column of A is neither proven zero nor shown nonzero at a probe point), so p_{q} is not claimed conserved.",
            unknown.join(", ")
        ))
    } else {
        Ok(())
    }
}

fn derive_all(pool: &mut Pool, d: &Symbols, specs: &[crate::model::ConstraintSpec]) -> Result<Constraints, ModelError> {
    let n = d.q.len();
    let names = &d.names;
    let var_names: Vec<NameId> = names.iter().map(|c| pool.name(c)).collect();
    let t_name = pool.name("t");
    let is_var = |s: Symbol| s.name == t_name || var_names.contains(&s.name);
    let zero_vel: Subst = d.qd.iter().map(|&v| (v, pool.zero())).collect();
    let mut list = Vec::new();
    for spec in specs {
        let e = spec.expr.expr;
        let span = spec.expr.span.clone();
        let (jacobian, time_term) = match spec.kind {
            ConstraintKind::Holonomic => {
                let jac: Vec<ExprId> =
                    d.q.iter()
                        .map(|&q| {
                            let j = pool.diff(e, q);
                            pool.simplify_in(j, &is_var)
                        })
                        .collect();
                let at = pool.diff(e, d.t);
                (jac, pool.simplify_in(at, &is_var))
            }
            ConstraintKind::Velocity => {
                // Linear in q': every second velocity derivative vanishes.
                for i in 0..n {
                    let di = pool.diff(e, d.qd[i]);
                    for j in i..n {
                        let dij = pool.diff(di, d.qd[j]);
                        let (vi, vj) = (&names[i], &names[j]);
                        let problem = match probe::decide_zero(pool, dij) {
                            Decision::Zero => continue,
                            Decision::NonZero => format!("is not linear in the velocities: ∂²/∂{vi}'∂{vj}' ≠ 0"),
                            Decision::Undecided => format!(
                                "could not be shown linear in the velocities: ∂²/∂{vi}'∂{vj}' = {} ({})",
                                pool.display(dij),
                                probe::UNDECIDED
                            ),
                        };
                        return Err(ModelError::at(span, format!("the velocity constraint '{}' {problem}", spec.name))
                            .with_help(
                                "a velocity constraint has the form a(q, t)·q' + a_t = 0 (Pfaffian); Lagrange multipliers need it linear in q'",
                            ));
                    }
                }
                let jac: Vec<ExprId> =
                    d.qd.iter()
                        .map(|&v| {
                            let j = pool.diff(e, v);
                            let j = pool.substitute(j, &zero_vel);
                            pool.simplify_in(j, &is_var)
                        })
                        .collect();
                let at = pool.substitute(e, &zero_vel);
                (jac, pool.simplify_in(at, &is_var))
            }
        };
        let jacobian: Vec<ExprId> = jacobian.into_iter().map(|j| probe::zero_if_proven(pool, j)).collect();
        let time_term = probe::zero_if_proven(pool, time_term);
        if jacobian.iter().all(|&j| pool.is_zero(j)) {
            let msg = match spec.kind {
                ConstraintKind::Holonomic => format!(
                    "the holonomic constraint '{}' does not depend on the coordinates: it restricts nothing (or is never satisfied)",
                    spec.name
                ),
                ConstraintKind::Velocity => format!(
                    "the velocity constraint '{}' contains no velocity: write a condition on the coordinates as `holonomic`",
                    spec.name
                ),
            };
            let kind = match spec.kind {
                ConstraintKind::Holonomic => ModelErrorKind::DoesNothing,
                ConstraintKind::Velocity => ModelErrorKind::Invalid,
            };
            return Err(ModelError::at(span, msg).with_kind(kind));
        }
        // g = A·q' + a_t and A q'' = c = −(Σ ∂g/∂q_j q_j' + ∂g/∂t).
        let mut g_terms: Vec<ExprId> = (0..n).map(|i| pool.mul2(jacobian[i], d.qd[i])).collect();
        g_terms.push(time_term);
        let velocity_form = pool.add(&g_terms);
        let mut c_terms: Vec<ExprId> = (0..n)
            .map(|j| {
                let dg = pool.diff(velocity_form, d.q[j]);
                pool.mul2(dg, d.qd[j])
            })
            .collect();
        c_terms.push(pool.diff(velocity_form, d.t));
        let c_sum = pool.add(&c_terms);
        let c_neg = pool.neg(c_sum);
        let acceleration_rhs = pool.simplify_in(c_neg, &is_var);
        let de_dt = pool.diff(e, d.t);
        let rheonomic = probe::decide_zero(pool, de_dt).known().map(|zero| !zero);
        let does_work = probe::decide_zero(pool, time_term).known().map(|zero| !zero);
        let multiplier = pool.symbol(&format!("lambda_{}", spec.name));
        list.push(Constraint {
            name: spec.name.clone(),
            kind: spec.kind,
            expr: e,
            jacobian,
            time_term,
            velocity_form,
            acceleration_rhs,
            rheonomic,
            does_work,
            integrable: None,
            integral: None,
            explanation: Vec::new(),
            multiplier,
            span,
        });
    }

    // Integrability, one by one and as a set.
    let forms: Vec<Vec<ExprId>> =
        list.iter().map(|c| c.jacobian.iter().copied().chain([c.time_term]).collect()).collect();
    let mut z: Vec<ExprId> = d.q.clone();
    z.push(d.t);
    for k in 0..list.len() {
        if list[k].kind == ConstraintKind::Holonomic {
            list[k].integrable = Some(true);
            list[k].integral = Some(list[k].expr);
            continue;
        }
        let closed = is_closed(pool, &forms[k], &z);
        let integrable = if closed { Some(true) } else { involutive(pool, &forms[k..=k], &z, &[0], 1) };
        list[k].integrable = integrable;
        if closed {
            list[k].integral = integral(pool, &forms[k], &z, &is_var);
        }
    }
    let velocity_idx: Vec<usize> = (0..list.len()).filter(|&k| list[k].kind == ConstraintKind::Velocity).collect();
    let (independent, rank_proven) = rank(pool, &list.iter().map(|c| c.jacobian.clone()).collect::<Vec<_>>());
    // The set: the forms of all constraints (holonomic ones are exact) annihilate
    // a distribution that must be involutive.
    let all: Vec<usize> = (0..list.len()).collect();
    let set_integrable = if velocity_idx.is_empty() { None } else { involutive(pool, &forms, &z, &all, independent) };

    // The teaching text.
    for c in &mut list {
        let e = pool.display(c.expr).to_string();
        let mut s = Vec::new();
        match c.kind {
            ConstraintKind::Holonomic => {
                s.push(format!("{}: {e} = 0 restricts the configuration: it is holonomic.", c.name));
            }
            ConstraintKind::Velocity => match (c.integrable, c.integral) {
                (Some(true), Some(f)) => s.push(format!(
                    "{}: {e} = 0 restricts the velocities, but it is integrable: it says d/dt ({}) = 0, the holonomic constraint {} = const in disguise.",
                    c.name,
                    pool.display(f),
                    pool.display(f)
                )),
                (Some(true), None) => s.push(format!(
                    "{}: {e} = 0 restricts the velocities, and it is integrable (ω ∧ dω = 0, Frobenius): an integrating factor makes it exact, so it is holonomic in disguise; its integral was not found in closed form.",
                    c.name
                )),
                (None, _) => s.push(format!(
                    "{}: {e} = 0 restricts the velocities; whether it is integrable could not be decided (ω ∧ dω is neither proven zero nor shown nonzero at a probe point), so it is not claimed holonomic or nonholonomic.",
                    c.name
                )),
                _ => s.push(format!(
                    "{}: {e} = 0 restricts the velocities and, on its own, is not integrable: ω ∧ dω ≠ 0 (Frobenius), so no f(q, t) = 0 is equivalent to it. It is nonholonomic: it does not reduce the configurations that can be reached.",
                    c.name
                )),
            },
        }
        let time = match c.rheonomic {
            Some(true) => "It depends explicitly on the time (rheonomic)".to_string(),
            Some(false) => "It does not depend on the time (scleronomic)".to_string(),
            None => format!("Whether it depends explicitly on the time could not be decided ({})", probe::UNDECIDED),
        };
        let work = match c.does_work {
            Some(true) => "its force does work on the system (a_t ≠ 0)".to_string(),
            Some(false) => "its force does no work".to_string(),
            None => format!("whether its force does work could not be decided (a_t: {})", probe::UNDECIDED),
        };
        // A moving constraint whose a_t is 0 (x' − t·y') needs no word on work.
        s.push(if (c.rheonomic, c.does_work) == (Some(true), Some(false)) {
            format!("{time}.")
        } else {
            format!("{time}; {work}.")
        });
        c.explanation = s;
    }
    let m = list.len();
    let n_holonomic = list.iter().filter(|c| c.kind == ConstraintKind::Holonomic).count();
    let mut explanation = vec![format!(
        "{n} coordinate{} and {independent} independent constraint{}{}: {} degree{} of freedom remain{}.",
        if n == 1 { "" } else { "s" },
        if independent == 1 { "" } else { "s" },
        if independent < m { format!(" (of {m})") } else { String::new() },
        n.saturating_sub(independent),
        if n.saturating_sub(independent) == 1 { "" } else { "s" },
        if n.saturating_sub(independent) == 1 { "s" } else { "" },
    )];
    if !rank_proven {
        explanation.push(format!(
            "That only {independent} of the {m} constraints {are} independent is what the probe points show: not every {k}×{k} minor of A could be proven zero, so this count (and the degrees of freedom) is not certain.",
            are = if independent == 1 { "is" } else { "are" },
            k = independent + 1
        ));
    }
    if n_holonomic < m && set_integrable == Some(false) {
        explanation.push(format!(
            "The nonholonomic constraints restrict the velocities only: the configuration still needs {} coordinate{} (n minus the holonomic constraints), but only {} independent velocities are free.",
            n - n_holonomic.min(n),
            if n - n_holonomic.min(n) == 1 { "" } else { "s" },
            n.saturating_sub(independent)
        ));
    }
    if velocity_idx.len() >= 2 {
        explanation.push(match set_integrable {
            Some(true) => "Together the velocity constraints are integrable: the space they leave free is involutive (dω_k ∧ ω_1 ∧ … ∧ ω_m = 0 for each k).".into(),
            Some(false) => "Together the velocity constraints are not integrable: Lie brackets of motions they allow leave the allowed space (dω_k ∧ ω_1 ∧ … ∧ ω_m ≠ 0).".into(),
            None => "Whether the velocity constraints together are integrable could not be decided (dω_k ∧ ω_1 ∧ … ∧ ω_m is neither proven zero nor shown nonzero at a probe point).".into(),
        });
    }
    explanation.push("The equations of motion read M q'' = f + Aᵀλ, with A the constraint Jacobian (one row per constraint) and λ the multipliers; Aᵀλ is the generalized constraint force.".into());
    Ok(Constraints {
        list,
        independent,
        degrees_of_freedom: n.saturating_sub(independent),
        integrable: set_integrable,
        multiplier_equations: Vec::new(),
        generalized_forces: Vec::new(),
        cartesian_forces: None,
        explanation,
        work_balances_h: false,
    })
}

/// dω = 0, proven (every ∂ω_j/∂z_i − ∂ω_i/∂z_j reduces to 0).
fn is_closed(pool: &mut Pool, form: &[ExprId], z: &[ExprId]) -> bool {
    let dim = z.len();
    for i in 0..dim {
        for j in i + 1..dim {
            let a = pool.diff(form[j], z[i]);
            let b = pool.diff(form[i], z[j]);
            let w = pool.sub(a, b);
            if !probe::is_zero(pool, w) {
                return false;
            }
        }
    }
    true
}

/// The 2-forms dω_k (antisymmetric matrices over z) of the given forms.
fn exterior_derivatives(pool: &mut Pool, forms: &[Vec<ExprId>], z: &[ExprId]) -> Vec<Vec<ExprId>> {
    let dim = z.len();
    forms
        .iter()
        .map(|form| {
            let mut w = vec![pool.zero(); dim * dim];
            for i in 0..dim {
                for j in i + 1..dim {
                    let a = pool.diff(form[j], z[i]);
                    let b = pool.diff(form[i], z[j]);
                    let v = pool.sub(a, b);
                    w[i * dim + j] = v;
                    w[j * dim + i] = pool.neg(v);
                }
            }
            w
        })
        .collect()
}

/// Most components of the (m+2)-forms dω_k ∧ ω_1 ∧ … ∧ ω_m that Frobenius'
/// test decides one by one; beyond it integrability is left undecided.
const MAX_WEDGE_COMPONENTS: usize = 4096;

/// Frobenius for the forms `forms[k]` (k in `which`): every
/// dω_k ∧ ω_1 ∧ … ∧ ω_m vanishes. Some(true) when each component is proven
/// zero and the forms are independent (`rank` = m: for dependent forms the
/// wedge vanishes whatever dω is), Some(false) when a point shows a component
/// nonzero, None otherwise.
fn involutive(pool: &mut Pool, forms: &[Vec<ExprId>], z: &[ExprId], which: &[usize], rank: usize) -> Option<bool> {
    let dim = z.len();
    let chosen: Vec<Vec<ExprId>> = which.iter().map(|&k| forms[k].clone()).collect();
    let m = chosen.len();
    let dws = exterior_derivatives(pool, &chosen, z);
    if dws.iter().flatten().all(|&w| pool.is_zero(w)) {
        // Closed forms are locally exact: each is df = 0 for some f.
        return Some(true);
    }
    let subsets = increasing_subsets(dim, m + 2, MAX_WEDGE_COMPONENTS)?;
    let mut proven = true;
    for dw in &dws {
        for idx in &subsets {
            // (dω ∧ Ω)_I = Σ_{a<b in I} ± dω_ab · det Ω[:, I ∖ {a, b}].
            let mut terms = Vec::new();
            for pa in 0..idx.len() {
                for pb in pa + 1..idx.len() {
                    let w = dw[idx[pa] * dim + idx[pb]];
                    if pool.is_zero(w) {
                        continue;
                    }
                    let rest: Vec<usize> =
                        idx.iter().enumerate().filter(|&(p, _)| p != pa && p != pb).map(|(_, &c)| c).collect();
                    let minor: Vec<Vec<ExprId>> =
                        chosen.iter().map(|row| rest.iter().map(|&c| row[c]).collect()).collect();
                    let det = determinant(pool, &minor);
                    let term = pool.mul2(w, det);
                    terms.push(if (pa + pb) % 2 == 1 { term } else { pool.neg(term) });
                }
            }
            let component = pool.add(&terms);
            match probe::decide_zero(pool, component) {
                Decision::Zero => {}
                Decision::NonZero => return Some(false),
                Decision::Undecided => proven = false,
            }
        }
    }
    (proven && rank == m).then_some(true)
}

/// The increasing k-subsets of 0..n, or None when there are more than `limit`.
fn increasing_subsets(n: usize, k: usize, limit: usize) -> Option<Vec<Vec<usize>>> {
    let mut out = Vec::new();
    if k > n {
        return Some(out);
    }
    let mut idx: Vec<usize> = (0..k).collect();
    loop {
        if out.len() == limit {
            return None;
        }
        out.push(idx.clone());
        // The last position that can still move right.
        let Some(p) = (0..k).rev().find(|&p| idx[p] < n - k + p) else { return Some(out) };
        idx[p] += 1;
        for q in p + 1..k {
            idx[q] = idx[q - 1] + 1;
        }
    }
}

/// The determinant of a small square matrix of expressions (Laplace expansion
/// along the first row; the wedge products above need m ≤ a few).
fn determinant(pool: &mut Pool, a: &[Vec<ExprId>]) -> ExprId {
    match a.len() {
        0 => pool.one(),
        1 => a[0][0],
        n => {
            let mut terms = Vec::with_capacity(n);
            for c in 0..n {
                if pool.is_zero(a[0][c]) {
                    continue;
                }
                let minor: Vec<Vec<ExprId>> = a[1..]
                    .iter()
                    .map(|row| row.iter().enumerate().filter(|&(j, _)| j != c).map(|(_, &x)| x).collect())
                    .collect();
                let d = determinant(pool, &minor);
                let t = pool.mul2(a[0][c], d);
                terms.push(if c % 2 == 0 { t } else { pool.neg(t) });
            }
            pool.add(&terms)
        }
    }
}

/// Most minors whose vanishing [`rank`] decides to prove a rank below full.
const MAX_RANK_MINORS: usize = 1024;

/// The rank of A and whether it is proven. At generic points the numeric rank
/// is a lower bound (a minor clearly nonzero at a point); a rank below full
/// is proven only when every larger minor reduces to 0.
fn rank(pool: &mut Pool, rows: &[Vec<ExprId>]) -> (usize, bool) {
    let r = generic_rank(pool, rows);
    let (m, n) = (rows.len(), rows.first().map_or(0, Vec::len));
    if r >= m.min(n) {
        return (r, true);
    }
    let (Some(row_sets), Some(col_sets)) =
        (increasing_subsets(m, r + 1, MAX_RANK_MINORS), increasing_subsets(n, r + 1, MAX_RANK_MINORS))
    else {
        return (r, false);
    };
    if row_sets.len() * col_sets.len() > MAX_RANK_MINORS {
        return (r, false);
    }
    for rs in &row_sets {
        for cs in &col_sets {
            let minor: Vec<Vec<ExprId>> = rs.iter().map(|&i| cs.iter().map(|&j| rows[i][j]).collect()).collect();
            let det = determinant(pool, &minor);
            if !probe::is_zero(pool, det) {
                return (r, false);
            }
        }
    }
    (r, true)
}

/// The rank of the matrix of expressions at generic (random) points.
pub(crate) fn generic_rank(pool: &Pool, rows: &[Vec<ExprId>]) -> usize {
    let m = rows.len();
    let n = rows.first().map_or(0, Vec::len);
    let roots: Vec<ExprId> = rows.iter().flatten().copied().collect();
    let Some(samples) = probe::finite_samples(pool, &roots, 4, 0x5eed_00a4) else { return m };
    let mut rank = 0;
    for out in &samples {
        let a = nalgebra::DMatrix::from_row_slice(m, n, out);
        rank = rank.max(a.rank(1e-9 * a.amax().max(f64::MIN_POSITIVE)));
    }
    if rank == 0 {
        m.min(n)
    } else {
        rank
    }
}

/// F with dF = ω for a closed form, by the homotopy formula
/// F(z) = ∫₀¹ Σ ω_i(s z) z_i ds, the integral taken by Boole's rule (exact for
/// integrands of degree ≤ 5 in s), and kept only if ∂F/∂z_i = ω_i checks out.
fn integral(pool: &mut Pool, form: &[ExprId], z: &[ExprId], is_var: &dyn Fn(Symbol) -> bool) -> Option<ExprId> {
    let weights = [7, 32, 12, 32, 7];
    let mut terms = Vec::new();
    for (k, &w) in weights.iter().enumerate() {
        let s = pool.rational(k as i64, 4);
        let scaled: Subst = z.iter().map(|&zi| (zi, pool.mul2(s, zi))).collect();
        let g: Vec<ExprId> = form
            .iter()
            .zip(z)
            .map(|(&a, &zi)| {
                let a_s = pool.substitute(a, &scaled);
                pool.mul2(a_s, zi)
            })
            .collect();
        let g = pool.add(&g);
        let c = pool.rational(w, 90);
        terms.push(pool.mul2(c, g));
    }
    let f = pool.add(&terms);
    let f = pool.simplify_in(f, is_var);
    if pool.is_zero(f) {
        return None;
    }
    for (i, &zi) in z.iter().enumerate() {
        let df = pool.diff(f, zi);
        let r = pool.sub(df, form[i]);
        if !probe::is_zero(pool, r) {
            return None;
        }
    }
    Some(f)
}

/// The Cartesian constraint forces, when the coordinates are the particles'
/// Cartesian components themselves (position = ["x", "y"]): then the force on
/// a particle is the generalized force on its coordinates.
fn cartesian_forces(model: &Model, q: &[ExprId], generalized: &[ExprId]) -> Option<Vec<Vec<ExprId>>> {
    let particles = &model.particles;
    if particles.is_empty() {
        return None;
    }
    let mut used = vec![false; q.len()];
    let mut forces = Vec::new();
    for part in particles {
        let mut f = Vec::new();
        for &x in &part.position {
            let i = q.iter().position(|&q| q == x)?;
            if used[i] {
                return None;
            }
            used[i] = true;
            f.push(generalized[i]);
        }
        forces.push(f);
    }
    used.iter().all(|&u| u).then_some(forces)
}

/// The Cartesian constraint forces when the particles' components x(q, t) are as
/// many as the coordinates (n ≤ 3) and ∂x/∂q is invertible: Q = (∂x/∂q)ᵀ F then
/// determines F = (∂x/∂q)⁻ᵀ Q, by the adjugate over the simplified determinant.
fn cartesian_forces_square(
    pool: &mut Pool,
    model: &Model,
    q: &[ExprId],
    generalized: &[ExprId],
) -> Option<Vec<Vec<ExprId>>> {
    let n = q.len();
    let xs: Vec<ExprId> = model.particles.iter().flat_map(|p| p.position.iter().copied()).collect();
    if model.particles.is_empty() || xs.len() != n || n > 3 {
        return None;
    }
    let names: Vec<NameId> = model.coordinates.iter().map(|c| pool.name(&c.name)).collect();
    let t_name = pool.name("t");
    let is_var = |s: Symbol| s.name == t_name || names.contains(&s.name);
    // jt[i][a] = ∂x_a/∂q_i: the matrix of Q = Jᵀ F.
    let jt: Vec<Vec<ExprId>> = (0..n).map(|i| xs.iter().map(|&x| pool.diff(x, q[i])).collect()).collect();
    if probe::is_singular(pool, &jt) {
        return None;
    }
    let minor = |pool: &mut Pool, rows: [usize; 2], cols: [usize; 2]| {
        let x = pool.mul2(jt[rows[0]][cols[0]], jt[rows[1]][cols[1]]);
        let y = pool.mul2(jt[rows[0]][cols[1]], jt[rows[1]][cols[0]]);
        pool.sub(x, y)
    };
    // adj[a][i] = cofactor C_ia of jt.
    let mut adj = vec![vec![pool.zero(); n]; n];
    let det = match n {
        1 => {
            adj[0][0] = pool.one();
            jt[0][0]
        }
        2 => {
            adj[0][0] = jt[1][1];
            adj[1][1] = jt[0][0];
            adj[0][1] = pool.neg(jt[0][1]);
            adj[1][0] = pool.neg(jt[1][0]);
            minor(pool, [0, 1], [0, 1])
        }
        _ => {
            let others = |i: usize| -> [usize; 2] {
                match i {
                    0 => [1, 2],
                    1 => [0, 2],
                    _ => [0, 1],
                }
            };
            for a in 0..3 {
                for i in 0..3 {
                    let c = minor(pool, others(i), others(a));
                    adj[a][i] = if (a + i) % 2 == 0 { c } else { pool.neg(c) };
                }
            }
            let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(jt[0][j], adj[j][0])).collect();
            pool.add(&terms)
        }
    };
    let det = pool.simplify_in(det, &is_var);
    let mut flat = Vec::with_capacity(n);
    for row in adj.iter().take(n) {
        let terms: Vec<ExprId> = (0..n).map(|i| pool.mul2(row[i], generalized[i])).collect();
        let num = pool.add(&terms);
        let num = pool.simplify_in(num, &is_var);
        let f = pool.div(num, det);
        flat.push(pool.simplify_in(f, &is_var));
    }
    let mut forces = Vec::new();
    let mut k = 0;
    for p in &model.particles {
        forces.push(flat[k..k + p.position.len()].to_vec());
        k += p.position.len();
    }
    Some(forces)
}

#[cfg(test)]
mod tests {
    use crate::test_models::derive;
    use crate::{Derivation, Model};

    #[test]
    fn the_cartesian_force_of_a_bead_on_a_rotating_wire() {
        let d = derive(
            "coordinates = [\"r\", \"ph\"]\n[parameters]\nm = 1.0\nom = 2.0\n[[particles]]\nmass = \"m\"\nposition = [\"r*cos(ph)\", \"r*sin(ph)\"]\n[[constraints]]\nholonomic = \"ph - om*t\"\n",
        );
        let f = d.constraints.cartesian_forces.as_ref().expect("2 components for 2 coordinates");
        let shown: Vec<String> = f[0].iter().map(|&e| d.pool().display(e).to_string()).collect();
        // Perpendicular to the wire, of size λ/r (the torque λ over the arm r).
        assert_eq!(shown, ["-lambda_c1*sin(ph)/r", "lambda_c1*cos(ph)/r"]);
    }

    #[track_caller]
    fn check_integrable(coords: &str, constraint: &str, expect: Option<&str>) {
        let text = format!(
            "coordinates = [{coords}]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nvelocity = \"{constraint}\"\n"
        );
        let d = derive(&text);
        let c = &d.constraints.list[0];
        match expect {
            Some(integral) => {
                assert_eq!(c.integrable, Some(true), "{constraint}");
                let got = c.integral.map(|f| d.pool().display(f).to_string());
                assert_eq!(got.as_deref(), Some(integral), "{constraint}");
            }
            None => assert_eq!(c.integrable, Some(false), "{constraint}"),
        }
    }

    #[test]
    fn integrability_of_single_velocity_constraints() {
        check_integrable("\"x\", \"y\"", "x' - y'", Some("x - y"));
        check_integrable("\"x\", \"y\"", "y*x' + x*y'", Some("x*y"));
        check_integrable("\"x\", \"y\"", "2*x*x' + 2*y*y'", Some("x^2 + y^2"));
    }

    #[test]
    fn an_integrating_factor_is_integrable_without_an_integral() {
        // y dx − x dy: not closed, but y⁻² makes it d(x/y).
        let d = derive(
            "coordinates = [\"x\", \"y\"]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nvelocity = \"y*x' - x*y'\"\n",
        );
        assert_eq!(d.constraints.list[0].integrable, Some(true));
    }

    const DISK: &str = r#"
coordinates = ["x", "y", "ph", "ps"]
kinetic = "m/2*(x'^2 + y'^2) + I/2*ps'^2 + J/2*ph'^2"
[parameters]
m = 1.0
I = 0.5
J = 0.25
R = 1.0
[[constraints]]
velocity = "x' - R*cos(ph)*ps'"
[[constraints]]
velocity = "y' - R*sin(ph)*ps'"
"#;

    #[test]
    fn the_rolling_disk_is_nonholonomic() {
        let d = derive(DISK);
        let c = &d.constraints;
        assert_eq!(c.list[0].integrable, Some(false));
        assert_eq!(c.list[1].integrable, Some(false));
        assert_eq!(c.integrable, Some(false));
        assert_eq!(c.independent, 2);
        assert_eq!(c.degrees_of_freedom, 2);
        // Only p_ph survives: the constraint forces act on x, y and ps.
        let names: Vec<&str> = d.conserved.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["p_ph", "H"]);
    }

    #[test]
    fn a_set_can_be_integrable_when_its_members_are_not() {
        // dz − y dx alone is not integrable (ω ∧ dω = dz∧dx∧dy), but with dy = 0
        // the free directions shrink to ∂x + y ∂z: y = c and z − c x = const.
        let d = derive(
            "coordinates = [\"x\", \"y\", \"z\"]\nkinetic = \"x'^2/2 + y'^2/2 + z'^2/2\"\n[[constraints]]\nvelocity = \"z' - y*x'\"\n[[constraints]]\nvelocity = \"y'\"\n",
        );
        let c = &d.constraints;
        assert_eq!(c.list[0].integrable, Some(false));
        assert_eq!(c.list[1].integrable, Some(true));
        assert_eq!(d.pool().display(c.list[1].integral.unwrap()).to_string(), "y");
        assert_eq!(c.integrable, Some(true));
        assert_eq!(c.degrees_of_freedom, 1);
    }

    #[test]
    fn a_rheonomic_constraint_does_work() {
        let d = derive(
            "coordinates = [\"r\", \"ph\"]\nkinetic = \"m/2*(r'^2 + r^2*ph'^2)\"\n[parameters]\nm = 1.0\nom = 2.0\n[[constraints]]\nholonomic = \"ph - om*t\"\n",
        );
        let c = &d.constraints.list[0];
        assert_eq!((c.rheonomic, c.does_work), (Some(true), Some(true)));
        assert!(!d.hamiltonian_conserved);
        assert_eq!(d.pool().display(c.time_term).to_string(), "-om");
    }

    #[test]
    fn a_constant_time_term_does_work_without_time_dependence() {
        // x' = 1: ∂/∂t of the constraint is 0, but a_t = −1, so its force does work.
        let d = derive(
            "coordinates = [\"x\", \"y\"]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nvelocity = \"x' - 1\"\n",
        );
        let c = &d.constraints.list[0];
        assert_eq!((c.rheonomic, c.does_work), (Some(false), Some(true)));
        assert!(c.explanation[1].contains("its force does work"), "{:?}", c.explanation);
        assert!(!d.hamiltonian_conserved);
    }

    #[track_caller]
    fn check_rank(second: &str, independent: usize, proven: bool) {
        let text = format!(
            "coordinates = [\"x\", \"y\"]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nholonomic = \"x - y\"\n[[constraints]]\nholonomic = \"{second}\"\n"
        );
        let d = derive(&text);
        assert_eq!(d.constraints.independent, independent, "{second}");
        let uncertain = d.constraints.explanation.iter().any(|s| s.contains("is not certain"));
        assert_eq!(!uncertain, proven, "{second}: {:?}", d.constraints.explanation);
    }

    #[test]
    fn a_rank_below_full_is_claimed_only_when_proven() {
        check_rank("x + y", 2, true);
        check_rank("2*x - 2*y", 1, true);
        // The second row differs from the first by a term that underflows at every point.
        check_rank("x - y + exp(-1000000*y^2)", 1, false);
    }

    #[test]
    fn a_nonlinear_velocity_constraint_is_rejected() {
        let text =
            "coordinates = [\"x\", \"y\"]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nvelocity = \"x'^2 - y'\"\n";
        let err = Derivation::new(Model::parse(text, &[]).unwrap()).unwrap_err();
        assert!(err.message.contains("not linear"), "{}", err.message);
        assert_eq!(err.span.map(|s| &text[s]), Some("\"x'^2 - y'\""));
    }
}
