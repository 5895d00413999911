//! The derivation: from a model to momenta, Euler–Lagrange equations, the mass
//! matrix form `M q'' = f`, cyclic coordinates, the Hamiltonian and Hamilton's
//! equations, as the notes' chapter 2 derives them by hand.
//!
//! Entry point: [`Derivation::new`]. Everything is built in the model's pool, so
//! subexpressions are shared across all results. `M` is never inverted
//! symbolically for the equations of motion; only the Hamiltonian needs
//! `M⁻¹(p − b)`, built block by block (diagonal and small blocks in closed form).

use crate::error::{ModelError, ModelErrorKind};
use crate::model::Model;
use crate::probe::{self, Decision};
use quadratic::{Quadratic, Sparsity, Vars as QVars};
use sym::{ExprId, NameId, Pool, Symbol};

mod body;
pub(crate) mod constraint;
mod hamilton;
mod impact;
mod judge;
mod layout;
mod load;
mod no_inertia;
mod noether;
mod quadratic;
mod shared;
mod solve;
mod verdict;

pub use body::BodyMotion;
pub use constraint::{Constraint, Constraints};
use hamilton::hamiltonian;
pub use impact::ImpactLaw;
use judge::{cyclic_coordinates, judge};
pub use layout::Layout;
pub use no_inertia::NoInertia;
use solve::blocks;
pub use verdict::{
    ConservationReason, ConservedReason, CyclicReason, EnergyReason, Generator, GeneratorKind, HamiltonianReason,
    RateTerm, Verdicts,
};

/// A quantity the derivation shows to be conserved.
#[derive(Debug, Clone)]
pub struct Conserved {
    /// Its name (`p_th`, `H`).
    pub name: String,
    /// The quantity as an expression in (q, q', t).
    pub expr: ExprId,
    /// Why it is conserved.
    pub reason: ConservedReason,
}

/// Everything derived from a model. Expressions live in `model.pool`.
#[derive(Debug, Clone)]
pub struct Derivation {
    /// The model it was derived from (it owns the pool).
    pub(crate) model: Model,
    /// Coordinate symbols q.
    pub(crate) q: Vec<ExprId>,
    /// Velocity symbols q'.
    pub(crate) qd: Vec<ExprId>,
    /// Acceleration symbols q''.
    pub(crate) qdd: Vec<ExprId>,
    /// Momentum symbols p_q.
    pub(crate) p: Vec<ExprId>,
    /// The time symbol.
    pub(crate) t: ExprId,
    /// Kinetic energy T (None when the model gives only a Lagrangian).
    pub(crate) kinetic: Option<ExprId>,
    /// Potential U, possibly velocity-dependent (None for a Lagrangian-only model).
    pub(crate) potential: Option<ExprId>,
    /// The Lagrangian L = T − U.
    pub(crate) lagrangian: ExprId,
    /// Rayleigh's dissipation function R.
    pub(crate) dissipation: Option<ExprId>,
    /// Generalized forces Q (zero where none is given).
    pub(crate) forces: Vec<ExprId>,
    /// Generalized momenta p_q = ∂L/∂q'.
    pub(crate) momenta: Vec<ExprId>,
    /// ∂L/∂q from the shared path's reverse pass ([`shared`]); None on the
    /// expanded path, where differentiating the collected L is cheap.
    pub(crate) coordinate_gradient: Option<Vec<ExprId>>,
    /// E_q = d/dt ∂L/∂q' − ∂L/∂q + ∂R/∂q' − Q_q.
    pub(crate) equations: Vec<ExprId>,
    /// M with E = M q'' − f.
    pub(crate) mass_matrix: Vec<Vec<ExprId>>,
    /// f with E = M q'' − f.
    pub(crate) forcing: Vec<ExprId>,
    /// Indices of cyclic coordinates (∂L/∂q proven to be 0).
    pub(crate) cyclic: Vec<usize>,
    /// Conserved quantities.
    pub(crate) conserved: Vec<Conserved>,
    /// The energy function h = Σ q' ∂L/∂q' − L, in (q, q', t).
    pub(crate) energy_function: ExprId,
    /// The Hamiltonian H(q, p, t), when L is quadratic in the velocities.
    pub(crate) hamiltonian: Option<ExprId>,
    /// The velocities in terms of momenta, q'(q, p, t), when H exists.
    pub(crate) velocities: Option<Vec<ExprId>>,
    /// T + U₀ (U₀ the velocity-independent part of U); None for a Lagrangian-only model.
    pub(crate) energy: Option<ExprId>,
    /// Whether H is the energy T + U₀; None for a Lagrangian-only model.
    pub(crate) hamiltonian_is_energy: Option<bool>,
    /// Whether H is conserved (∂L/∂t = 0, no dissipation, no forces, each proven).
    pub(crate) hamiltonian_conserved: bool,
    /// Hamilton's equations (dq/dt, dp/dt) per coordinate, in (q, p, t).
    pub(crate) hamilton: Option<Vec<(ExprId, ExprId)>>,
    /// Whether L depends explicitly on time; None when ∂L/∂t = 0 could be
    /// neither proven nor refuted.
    pub(crate) explicit_time: Option<bool>,
    /// Explanations of the verdicts.
    pub(crate) verdicts: Verdicts,
    /// Seconds spent from the model to L, M and f (the equations of motion), the
    /// part of [`Derivation::new`] comparable with a CAS that derives only those.
    pub(crate) equations_seconds: f64,
    /// Each rigid body's angular velocity and angular momentum (body frame).
    pub(crate) bodies: Vec<BodyMotion>,
    /// The constraints and the equations with multipliers (empty without `[[constraints]]`).
    pub(crate) constraints: Constraints,
    /// The impact law of each `[[impacts]]` surface.
    pub(crate) impacts: Vec<ImpactLaw>,
    /// The input layout of every compiled expression: `[q, q', t, parameters]`.
    pub(crate) layout: Layout,
    /// The symbols of the model's inputs u (`[inputs]`), in file order.
    pub(crate) inputs: Vec<ExprId>,
    /// B = ∂f/∂u, one row per coordinate (M q'' = f with f = f₀ + B u where f is affine in u).
    pub(crate) input_matrix: Vec<Vec<ExprId>>,
    /// Whether f is proven affine in u (∂B/∂u = 0), so that B u is all of u's part.
    pub(crate) inputs_affine: bool,
}

/// The symbols of a derivation and the "is a variable" predicate used for collecting.
struct Symbols {
    names: Vec<String>,
    q: Vec<ExprId>,
    qd: Vec<ExprId>,
    qdd: Vec<ExprId>,
    p: Vec<ExprId>,
    t: ExprId,
    var_names: Vec<NameId>,
    t_name: NameId,
    momentum_names: Vec<NameId>,
}

impl Symbols {
    fn new(pool: &mut Pool, model: &Model) -> Symbols {
        let names: Vec<String> = model.coordinates.iter().map(|c| c.name.clone()).collect();
        let symbols = Symbols {
            q: names.iter().map(|c| pool.var(c, 0)).collect(),
            qd: names.iter().map(|c| pool.var(c, 1)).collect(),
            qdd: names.iter().map(|c| pool.var(c, 2)).collect(),
            p: names.iter().map(|c| pool.symbol(&format!("p_{c}"))).collect(),
            t: pool.symbol("t"),
            var_names: names.iter().map(|c| pool.name(c)).collect(),
            t_name: pool.name("t"),
            momentum_names: names.iter().map(|c| pool.name(&format!("p_{c}"))).collect(),
            names,
        };
        debug_assert!(symbols.names.iter().all(|c| pool.find_name(c).is_some()));
        symbols
    }

    fn is_var(&self, s: Symbol) -> bool {
        s.name == self.t_name || self.var_names.contains(&s.name) || self.momentum_names.contains(&s.name)
    }

    fn n(&self) -> usize {
        self.q.len()
    }
}

/// T, U and L of a model; L also as (M, b, L₀) when it is quadratic in the velocities.
struct Energies {
    kinetic: Option<ExprId>,
    potential: Option<ExprId>,
    lagrangian: ExprId,
    form: Option<Quadratic>,
    sparsity: Option<Sparsity>,
    bodies: Vec<BodyMotion>,
    /// Built by the shared path ([`shared`]): nothing expanded, facts about
    /// long expressions decided without rewriting.
    shared: bool,
}

/// R and Q: what acts on the system besides L.
struct External {
    dissipation: Option<ExprId>,
    forces: Vec<ExprId>,
}

/// The equations of motion: p, `M q'' = f`, E = M q'' − f, and ∂L/∂q.
struct Motion {
    momenta: Vec<ExprId>,
    mass_matrix: Vec<Vec<ExprId>>,
    forcing: Vec<ExprId>,
    equations: Vec<ExprId>,
    dl_dq: Vec<ExprId>,
}

/// The energy function and the verdicts on H.
struct Judged {
    energy_function: ExprId,
    energy: Option<ExprId>,
    hamiltonian_is_energy: Option<bool>,
    hamiltonian_conserved: bool,
    /// H would be conserved but for the constraints' work W: H − W is.
    work_balances_h: bool,
    explicit_time: Option<bool>,
    verdicts: Verdicts,
}

impl Derivation {
    /// Derives everything from a model, in the order of the notes: L, the
    /// equations of motion and the constraints' multiplier equations, what is
    /// conserved and why (the constraint forces included), H and Hamilton's
    /// equations. Each stage makes a value the later ones read; none edits an
    /// earlier one's verdicts. Fails on a singular mass matrix.
    pub fn new(model: Model) -> Result<Derivation, ModelError> {
        if shared::wanted(&model) {
            return Derivation::derive(model, Path::Shared);
        }
        let fallback = model.clone();
        // The expanded path passing its bound is no error: the shared one takes over.
        match Derivation::derive(model, Path::Expanded) {
            Err(e) if e.kind == ModelErrorKind::TooLarge => Derivation::derive(fallback, Path::Shared),
            result => result,
        }
    }

    /// [`Derivation::new`] along one path.
    fn derive(mut model: Model, path: Path) -> Result<Derivation, ModelError> {
        let started = crate::clock::Instant::now();
        // The pool is taken out of the model while the model's other parts are read.
        let mut pool_owned = std::mem::take(&mut model.pool);
        let pool = &mut pool_owned;
        let s = Symbols::new(pool, &model);
        let is_var = |x: Symbol| s.is_var(x);

        let shared = path == Path::Shared;
        let start = pool.work();
        let stage_limit = match (shared, model.constraints.is_empty()) {
            (true, _) => WORK_LIMIT,
            (false, true) => EXPANDED_WORK_LIMIT,
            (false, false) => EXPANDED_CONSTRAINED_WORK_LIMIT,
        };
        pool.set_work_limit(Some(start + stage_limit));
        let within = within_work_limit;
        let frames = crate::model::frames::frames(pool, &model.bodies, &s.q, &s.qd);
        let (energies, ext, motion) = if shared {
            let mut energies = shared::energies(pool, &model, &s, &frames);
            let ext = external(pool, &model, &s, &frames, true, &is_var);
            let motion = shared::motion(pool, &s, &mut energies, &ext);
            (energies, ext, motion)
        } else {
            let energies = energies(pool, &model, &s, &frames, &is_var);
            within(pool, &model)?;
            let ext = external(pool, &model, &s, &frames, false, &is_var);
            let motion = equations_of_motion(pool, &s, &energies, &ext, &is_var);
            within(pool, &model)?;
            pool.set_work_limit(Some(start + WORK_LIMIT));
            (energies, ext, motion)
        };
        within(pool, &model)?;
        let equations_seconds = started.elapsed().as_secs_f64();
        check_regular(pool, &model, &motion.mass_matrix)?;
        let constraints = constraint::derive(pool, &model, &s, &motion.equations)?;
        within(pool, &model)?;
        let impacts = impact::derive(pool, &model, &s.q, &s.qd, s.t, &motion.mass_matrix, &mut |pool, e| {
            if shared {
                simplify_bounded(pool, e, &is_var)
            } else {
                pool.simplify_in(e, &is_var)
            }
        })?;
        let cyclic = cyclic_coordinates(pool, &s, &motion, &ext, &constraints, shared);
        let mut conserved = cyclic.conserved;
        within(pool, &model)?;
        let mut judged = judge(pool, &model, &s, &energies, &motion, &ext, &constraints, &is_var);
        within(pool, &model)?;
        judged.verdicts.cyclic = cyclic.reasons;
        if judged.hamiltonian_conserved {
            conserved.push(Conserved {
                name: "H".into(),
                expr: judged.energy_function,
                reason: match judged.hamiltonian_is_energy {
                    Some(true) => ConservedReason::EnergyConserved,
                    Some(false) => ConservedReason::HamiltonianConserved,
                    None => ConservedReason::HamiltonianConservedEnergyUnknown,
                },
            });
        }
        // Noether: the point symmetries of L, on the expanded path, within a
        // bound of its own (a proof made before the bound stays a proof).
        if !shared && pool.work() - start + noether::SEARCH_WORK < WORK_LIMIT {
            pool.set_work_limit(Some(pool.work() + noether::SEARCH_WORK));
            let found = noether::symmetries(
                pool,
                &model,
                &s,
                &motion,
                &ext,
                &constraints,
                &energies.bodies,
                &cyclic.indices,
                &conserved,
                &is_var,
            );
            conserved.extend(found);
            pool.set_work_limit(Some(start + WORK_LIMIT));
        }
        let legendre = hamiltonian(pool, &s, &energies, &motion, &ext, &mut judged.verdicts, &is_var);
        let constraints = constraints.explained(cyclic.lost, judged.work_balances_h, legendre.is_some());
        let (hamiltonian, velocities, hamilton) = match legendre {
            Some(l) => (Some(l.hamiltonian), Some(l.velocities), Some(l.equations)),
            None => (None, None, None),
        };
        let inputs: Vec<ExprId> = model.inputs.iter().map(|u| pool.symbol(&u.name)).collect();
        let input_matrix: Vec<Vec<ExprId>> = motion
            .forcing
            .iter()
            .map(|&f| {
                inputs
                    .iter()
                    .map(|&u| {
                        let b = pool.diff(f, u);
                        if shared {
                            simplify_bounded(pool, b, &is_var)
                        } else {
                            pool.simplify_in(b, &is_var)
                        }
                    })
                    .collect()
            })
            .collect();
        let inputs_affine = input_matrix.iter().flatten().all(|&b| {
            inputs.iter().all(|&u| {
                let d = pool.diff(b, u);
                decide(pool, d, shared).is_zero()
            })
        });
        within(pool, &model)?;
        let layout = Layout::new(pool, &s.q, &s.qd, s.t, &model.parameters);
        model.pool = pool_owned;
        let Symbols { q, qd, qdd, p, t, .. } = s;
        let mut derivation = Derivation {
            model,
            q,
            qd,
            qdd,
            p,
            t,
            kinetic: energies.kinetic,
            potential: energies.potential,
            lagrangian: energies.lagrangian,
            dissipation: ext.dissipation,
            forces: ext.forces,
            momenta: motion.momenta,
            coordinate_gradient: shared.then_some(motion.dl_dq),
            equations: motion.equations,
            mass_matrix: motion.mass_matrix,
            forcing: motion.forcing,
            cyclic: cyclic.indices,
            conserved,
            energy_function: judged.energy_function,
            hamiltonian,
            velocities,
            energy: judged.energy,
            hamiltonian_is_energy: judged.hamiltonian_is_energy,
            hamiltonian_conserved: judged.hamiltonian_conserved,
            hamilton,
            explicit_time: judged.explicit_time,
            verdicts: judged.verdicts,
            bodies: energies.bodies,
            equations_seconds,
            constraints,
            impacts,
            layout,
            inputs,
            input_matrix,
            inputs_affine,
        };
        within_work_limit(&derivation.model.pool, &derivation.model)?;
        // The bound is the derivation's: analyses rewrite in copies of the pool.
        derivation.model.pool.set_work_limit(None);
        Ok(derivation)
    }

    /// The impact law of each `[[impacts]]` surface, in file order.
    pub fn impacts(&self) -> &[ImpactLaw] {
        &self.impacts
    }

    /// The symbols of the model's inputs u, in file order (empty without `[inputs]`).
    pub fn inputs(&self) -> &[ExprId] {
        &self.inputs
    }

    /// B = ∂f/∂u, one row per coordinate and one column per input.
    pub fn input_matrix(&self) -> &[Vec<ExprId>] {
        &self.input_matrix
    }

    /// Whether f is proven affine in the inputs (f = f₀ + B u with B free of u).
    pub fn inputs_affine(&self) -> bool {
        self.inputs_affine
    }

    /// The model it was derived from (it owns the pool).
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Coordinate symbols q.
    pub fn q(&self) -> &[ExprId] {
        &self.q
    }

    /// Velocity symbols q'.
    pub fn qd(&self) -> &[ExprId] {
        &self.qd
    }

    /// Acceleration symbols q''.
    pub fn qdd(&self) -> &[ExprId] {
        &self.qdd
    }

    /// Momentum symbols p_q.
    pub fn p(&self) -> &[ExprId] {
        &self.p
    }

    /// The time symbol.
    pub fn t(&self) -> ExprId {
        self.t
    }

    /// Kinetic energy T (None when the model gives only a Lagrangian).
    pub fn kinetic(&self) -> Option<ExprId> {
        self.kinetic
    }

    /// Potential U, possibly velocity-dependent (None for a Lagrangian-only model).
    pub fn potential(&self) -> Option<ExprId> {
        self.potential
    }

    /// The Lagrangian L = T − U.
    pub fn lagrangian(&self) -> ExprId {
        self.lagrangian
    }

    /// Rayleigh's dissipation function R.
    pub fn dissipation(&self) -> Option<ExprId> {
        self.dissipation
    }

    /// Generalized forces Q (zero where none is given).
    pub fn forces(&self) -> &[ExprId] {
        &self.forces
    }

    /// Generalized momenta p_q = ∂L/∂q'.
    pub fn momenta(&self) -> &[ExprId] {
        &self.momenta
    }

    /// E_q = d/dt ∂L/∂q' − ∂L/∂q + ∂R/∂q' − Q_q.
    pub fn equations(&self) -> &[ExprId] {
        &self.equations
    }

    /// M with E = M q'' − f.
    pub fn mass_matrix(&self) -> &[Vec<ExprId>] {
        &self.mass_matrix
    }

    /// f with E = M q'' − f.
    pub fn forcing(&self) -> &[ExprId] {
        &self.forcing
    }

    /// Indices of cyclic coordinates (∂L/∂q proven to be 0; a coordinate for
    /// which that could not be decided is not among them, and the verdicts'
    /// `cyclic` reasons name it).
    pub fn cyclic(&self) -> &[usize] {
        &self.cyclic
    }

    /// Conserved quantities.
    pub fn conserved(&self) -> &[Conserved] {
        &self.conserved
    }

    /// The energy function h = Σ q' ∂L/∂q' − L, in (q, q', t).
    pub fn energy_function(&self) -> ExprId {
        self.energy_function
    }

    /// The Hamiltonian H(q, p, t), when L is quadratic in the velocities.
    pub fn hamiltonian(&self) -> Option<ExprId> {
        self.hamiltonian
    }

    /// The velocities in terms of momenta, q'(q, p, t), when H exists.
    pub fn velocities(&self) -> Option<&[ExprId]> {
        self.velocities.as_deref()
    }

    /// T + U₀ (U₀ the velocity-independent part of U); None for a Lagrangian-only model.
    pub fn energy(&self) -> Option<ExprId> {
        self.energy
    }

    /// Whether H is the energy T + U₀; None for a Lagrangian-only model.
    pub fn hamiltonian_is_energy(&self) -> Option<bool> {
        self.hamiltonian_is_energy
    }

    /// Whether H is proven conserved (∂L/∂t = 0, no dissipation, no forces).
    pub fn hamiltonian_conserved(&self) -> bool {
        self.hamiltonian_conserved
    }

    /// Hamilton's equations (dq/dt, dp/dt) per coordinate, in (q, p, t).
    pub fn hamilton(&self) -> Option<&[(ExprId, ExprId)]> {
        self.hamilton.as_deref()
    }

    /// Whether L depends explicitly on time: Some(false) when ∂L/∂t is proven
    /// to be 0, Some(true) when a point shows it is not, None when neither.
    pub fn explicit_time(&self) -> Option<bool> {
        self.explicit_time
    }

    /// Explanations of the verdicts.
    pub fn verdicts(&self) -> &Verdicts {
        &self.verdicts
    }

    /// Seconds spent from the model to L, M and f (the equations of motion), the
    /// part of [`Derivation::new`] comparable with a CAS that derives only those.
    pub fn equations_seconds(&self) -> f64 {
        self.equations_seconds
    }

    /// Each rigid body's angular velocity and angular momentum (body frame).
    pub fn bodies(&self) -> &[BodyMotion] {
        &self.bodies
    }

    /// The constraints and the equations with multipliers (empty without `[[constraints]]`).
    pub fn constraints(&self) -> &Constraints {
        &self.constraints
    }

    /// The input layout of every compiled expression: `[q, q', t, parameters]`.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The pool holding every expression.
    pub fn pool(&self) -> &Pool {
        &self.model.pool
    }

    /// The coordinate names.
    pub fn coordinate_names(&self) -> Vec<&str> {
        self.model.coordinates.iter().map(|c| c.name.as_str()).collect()
    }

    /// The coordinates at `q` as messages show them: `(x = 0.6, y = -0.8)`.
    pub(crate) fn point_text(&self, q: &[f64]) -> String {
        let parts: Vec<String> =
            self.coordinate_names().iter().zip(q).map(|(n, v)| format!("{n} = {}", num::Shortest(*v))).collect();
        format!("({})", parts.join(", "))
    }

    /// True when M is diagonal (each coordinate's acceleration appears in its own equation only).
    pub fn mass_matrix_is_diagonal(&self) -> bool {
        let n = self.q.len();
        (0..n).all(|i| (0..n).all(|j| i == j || self.model.pool.is_zero(self.mass_matrix[i][j])))
    }
}

/// T and U from particles, bodies, `kinetic` and `potential`, or L itself. When L
/// is quadratic in the velocities (almost always) it is also held as (M, b, L₀),
/// from which the rest is built without expanding L whole.
fn energies(
    pool: &mut Pool,
    model: &Model,
    s: &Symbols,
    frames: &[crate::model::frames::Frame],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Energies {
    let (q, qd, t) = (&s.q, &s.qd, s.t);
    let vars_q = QVars { q, qd, t, is_var };
    let mut bodies = Vec::new();
    let (kinetic, potential, lagrangian, form) = if let Some(l) = &model.lagrangian {
        let l = pool.simplify_in(l.expr, is_var);
        let form = Quadratic::split(pool, l, &vars_q);
        (None, None, l, form)
    } else {
        let mut u_terms = Vec::new();
        for part in &model.particles {
            if let Some(g) = &model.gravity {
                u_terms.push(g.potential(pool, part.mass, &part.position));
            }
            if let Some(u) = part.potential {
                u_terms.push(u);
            }
        }
        // The bodies' T enters the form coefficient by coefficient; its sum,
        // with the model's own `kinetic`, is what the model's T is shown as.
        let mut k_terms = Vec::new();
        let mut body_parts = quadratic::Parts::new(s.n());
        for (body, frame) in model.bodies.iter().zip(frames) {
            let terms = body::terms(pool, body, frame, q, qd, t, model.gravity.as_ref());
            k_terms.push(terms.kinetic);
            u_terms.extend(terms.potential);
            body::kinetic_form(pool, body, frame, &vars_q, &mut body_parts);
            bodies.push(body::motion(pool, body, frame, &terms, is_var));
        }
        let body_form = (!model.bodies.is_empty()).then(|| body_parts.finish(pool, is_var));
        if let Some(k) = &model.kinetic {
            k_terms.push(k.expr);
        }
        if let Some(u) = &model.potential {
            u_terms.push(u.expr);
        }
        let uu = pool.add(&u_terms);
        let uu = pool.simplify_in(uu, is_var);
        let k = if k_terms.is_empty() {
            None
        } else {
            let k = pool.add(&k_terms);
            Some(pool.simplify_in(k, is_var))
        };
        // The parts of L not yet in a form: the model's `kinetic`, and −U.
        let user_kinetic = model.kinetic.as_ref().map_or_else(|| pool.zero(), |k| k.expr);
        let rest = pool.sub(user_kinetic, uu);
        let rest = pool.simplify_in(rest, is_var);
        if pool.work_exhausted() {
            // The derivation stops at its next check; nothing more is worth building.
            let tt = k.unwrap_or_else(|| pool.zero());
            let l = pool.sub(tt, uu);
            (Some(tt), Some(uu), l, None)
        } else if model.particles.is_empty() {
            let tt = k.unwrap_or_else(|| pool.zero());
            let l = pool.sub(tt, uu);
            let l = pool.simplify_in(l, is_var);
            let form = Quadratic::split(pool, rest, &vars_q).map(|mut f| {
                if let Some(body_form) = &body_form {
                    f.add(pool, body_form, is_var);
                }
                f
            });
            (Some(tt), Some(uu), l, form)
        } else {
            let masses: Vec<(ExprId, Vec<ExprId>)> =
                model.particles.iter().map(|p| (p.mass, p.position.clone())).collect();
            let particle_form = quadratic::particles(pool, &masses, &vars_q);
            let t_particles = particle_form.lagrangian(pool, qd);
            let tt = match k {
                Some(k) => pool.add2(t_particles, k),
                None => t_particles,
            };
            let form = Quadratic::split(pool, rest, &vars_q).map(|rest_form| {
                let mut f = particle_form;
                if let Some(body_form) = &body_form {
                    f.add(pool, body_form, is_var);
                }
                f.add(pool, &rest_form, is_var);
                f
            });
            let l = match &form {
                Some(f) => f.lagrangian(pool, qd),
                None => {
                    let l = pool.sub(tt, uu);
                    pool.simplify_in(l, is_var)
                }
            };
            (Some(tt), Some(uu), l, form)
        }
    };
    let sparsity = form.as_ref().map(|f| f.sparsity(pool, q));
    Energies { kinetic, potential, lagrangian, form, sparsity, bodies, shared: false }
}

/// The most work ([`Pool::work`]: nodes built, weighted by their operands) a
/// derivation may do. A chain of 20 rods, each hinged on the previous one,
/// does about 26·10⁶ in about a second, 25 rods take five; at 30 the expanded
/// coefficients of M (a sum over the links below, each term a product of
/// sums) pass the bound. Past it the expressions are too long to
/// derive in reasonable time and memory, and the derivation stops with an error
/// rather than running for minutes.
pub const WORK_LIMIT: u64 = 64_000_000;

/// The work the expanded path may spend on L, M and f before the derivation
/// starts again on the shared path ([`shared`]), about a fifth of a second.
/// Every model of the notes and the guide stays far below it (a few 10⁴);
/// the UR5 arm (2.4·10⁶) stays below it too, and its collected M makes a
/// right-hand side twice as fast as the shared path's (3.7 against 6.8 µs);
/// a chain of fifteen rods, or the Panda arm, passes it, and the shared path
/// derives them in milliseconds.
const EXPANDED_WORK_LIMIT: u64 = 4_000_000;

/// [`EXPANDED_WORK_LIMIT`] for a model with constraints, whose multipliers the
/// expanded path eliminates on short collected expressions: the benchmark
/// bicycle (four bodies, two rolling wheels) spends 1.4·10⁷ on its equations
/// of motion and stays on the expanded path.
const EXPANDED_CONSTRAINED_WORK_LIMIT: u64 = 16_000_000;

/// The two ways to derive: expanding and simplifying each coefficient (short,
/// collected results) or keeping one shared DAG (results that grow gently with
/// the model).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Path {
    Expanded,
    Shared,
}

/// Decides a zero: by rewriting on the expanded path; on the shared path
/// without expanding long expressions ([`shared::decide_zero`]).
fn decide(pool: &mut Pool, e: ExprId, shared: bool) -> Decision {
    if shared {
        shared::decide_zero(pool, e)
    } else {
        probe::decide_zero(pool, e)
    }
}

/// An error, located at the first body (or at L, T or the first particle), when
/// the derivation has done more than [`WORK_LIMIT`] work: its rewrites have
/// stopped, so nothing it would go on to claim could be trusted.
fn within_work_limit(pool: &Pool, model: &Model) -> Result<(), ModelError> {
    if !pool.work_exhausted() {
        return Ok(());
    }
    let span = model.bodies.first().map(|b| b.span.clone()).or_else(|| energy_span(model));
    let message = format!(
        "the derivation stopped at its bound of {} million steps of expression building: the expressions of this model grow too long to derive in reasonable time and memory",
        WORK_LIMIT / 1_000_000
    );
    let help = "long chains of bodies, each turning relative to the one before, and long products of sums make the expressions grow quickly; a shorter chain, or a Lagrangian written out by hand, stays within the bound";
    Err(ModelError::located(span, message).with_help(help).with_kind(ModelErrorKind::TooLarge))
}

/// Rayleigh's R and the generalized forces Q (`[forces]` and the loads' virtual
/// work; zero where neither gives one), simplified.
fn external(
    pool: &mut Pool,
    model: &Model,
    s: &Symbols,
    frames: &[crate::model::frames::Frame],
    shared: bool,
    is_var: &dyn Fn(Symbol) -> bool,
) -> External {
    let simplify = |pool: &mut Pool, e: ExprId| {
        if shared {
            simplify_bounded(pool, e, is_var)
        } else {
            pool.simplify_in(e, is_var)
        }
    };
    let dissipation = model.dissipation.as_ref().map(|r| simplify(pool, r.expr));
    let from_loads = load::generalized_forces(pool, &model.loads, frames, &s.q, &s.qd);
    let forces = model
        .forces
        .iter()
        .zip(from_loads)
        .map(|(f, l)| {
            let f = match f {
                Some(f) => pool.add2(f.expr, l),
                None => l,
            };
            simplify(pool, f)
        })
        .collect();
    External { dissipation, forces }
}

/// The momenta and the Euler–Lagrange equations in the form `M q'' = f`.
fn equations_of_motion(
    pool: &mut Pool,
    s: &Symbols,
    e: &Energies,
    ext: &External,
    is_var: &dyn Fn(Symbol) -> bool,
) -> Motion {
    let (n, q, qd, t) = (s.n(), &s.q, &s.qd, s.t);
    let (dissipation, forces) = (ext.dissipation, &ext.forces);
    let mut mass_matrix = vec![vec![pool.zero(); n]; n];
    let mut forcing = Vec::with_capacity(n);
    let mut dl_dq: Vec<ExprId> = Vec::with_capacity(n);
    let momenta: Vec<ExprId>;
    if let (Some(form), Some(sp)) = (&e.form, &e.sparsity) {
        let vars_q = QVars { q, qd, t, is_var };
        momenta = form.momenta(pool, qd).into_iter().map(|p| polish(pool, p, is_var)).collect();
        mass_matrix.clone_from(&form.m);
        let rows = form.forcing(pool, &vars_q, sp);
        dl_dq = form.coordinate_gradient(pool, q, qd, sp);
        for (i, row) in rows.into_iter().enumerate() {
            // Dissipation and generalized forces: −∂R/∂q_i' + Q_i.
            let mut extra = vec![forces[i]];
            if let Some(r) = dissipation {
                let d = pool.diff(r, qd[i]);
                extra.push(pool.neg(d));
            }
            let extra = pool.add(&extra);
            let f = if pool.is_zero(extra) {
                row
            } else {
                let extra = pool.simplify_in(extra, is_var);
                pool.add2(row, extra)
            };
            forcing.push(f);
        }
    } else {
        momenta = (0..n)
            .map(|i| {
                let d = pool.diff(e.lagrangian, qd[i]);
                pool.simplify_in(d, is_var)
            })
            .collect();
        // M_ij = ∂p_i/∂q_j' and f_i = −(E_i at q'' = 0), each simplified while
        // small.
        for i in 0..n {
            for j in 0..n {
                mass_matrix[i][j] = if j < i {
                    mass_matrix[j][i]
                } else {
                    let m = pool.diff(momenta[i], qd[j]);
                    pool.simplify_in(m, is_var)
                };
            }
            // d/dt p_i without its q'' terms: Σ ∂p_i/∂q_k q_k' + ∂p_i/∂t.
            let mut terms: Vec<ExprId> = Vec::with_capacity(n + 4);
            for k in 0..n {
                let d = pool.diff(momenta[i], q[k]);
                if !pool.is_zero(d) {
                    terms.push(pool.mul2(d, qd[k]));
                }
            }
            terms.push(pool.diff(momenta[i], t));
            let dl = pool.diff(e.lagrangian, q[i]);
            dl_dq.push(dl);
            terms.push(pool.neg(dl));
            if let Some(r) = dissipation {
                terms.push(pool.diff(r, qd[i]));
            }
            terms.push(pool.neg(forces[i]));
            let rest = pool.add(&terms);
            let f = pool.neg(rest);
            forcing.push(simplify_bounded(pool, f, is_var));
        }
    }
    let equations = assemble_equations(pool, &mass_matrix, &forcing, &s.qdd);
    Motion { momenta, mass_matrix, forcing, equations, dl_dq }
}

/// E_i = Σ M_ij q_j'' − f_i, assembled from M and f so that the long
/// equations are never expanded as a whole.
fn assemble_equations(pool: &mut Pool, mass_matrix: &[Vec<ExprId>], forcing: &[ExprId], qdd: &[ExprId]) -> Vec<ExprId> {
    (0..forcing.len())
        .map(|i| {
            let mut terms: Vec<ExprId> = Vec::with_capacity(qdd.len() + 1);
            for (&m, &a) in mass_matrix[i].iter().zip(qdd) {
                if !pool.is_zero(m) {
                    terms.push(pool.mul2(m, a));
                }
            }
            terms.push(pool.neg(forcing[i]));
            pool.add(&terms)
        })
        .collect()
}

/// An error, located at L or T, when M is singular: then the equations of
/// motion do not determine every acceleration. M is singular when one of its
/// blocks is (a chain of masses has a thousand 1×1 blocks, not one 1000×1000
/// matrix to factor).
fn check_regular(pool: &mut Pool, model: &Model, mass_matrix: &[Vec<ExprId>]) -> Result<(), ModelError> {
    let singular = blocks(pool, mass_matrix).iter().any(|idx| {
        let block: Vec<Vec<ExprId>> = idx.iter().map(|&i| idx.iter().map(|&j| mass_matrix[i][j]).collect()).collect();
        probe::is_singular(pool, &block)
    });
    if !singular {
        return Ok(());
    }
    // Coordinates whose row of M is zero: no inertia at all (a thin rod's
    // spin about its own axis, a coordinate that never moves anything).
    let idle: Vec<usize> = (0..mass_matrix.len())
        .filter(|&i| mass_matrix[i].iter().all(|&m| probe::decide_zero(pool, m) == Decision::Zero))
        .collect();
    let names: Vec<String> = idle.iter().map(|&i| format!("'{}'", model.coordinates[i].name)).collect();
    let body = model.bodies.iter().find(|b| b.orientation.angles().iter().any(|a| idle.contains(a)));
    let span = body
        .map(|b| b.span.clone())
        .or_else(|| energy_span(model))
        .or_else(|| model.bodies.first().map(|b| b.span.clone()));
    let message = match names.as_slice() {
        [] => "the mass matrix ∂²L/∂q'∂q' is singular: the equations of motion do not determine every acceleration"
            .to_string(),
        [one] => format!(
            "the mass matrix ∂²L/∂q'∂q' is singular: the coordinate {one} has no inertia (its velocity does not appear in T), so the equations of motion do not determine its acceleration"
        ),
        many => format!(
            "the mass matrix ∂²L/∂q'∂q' is singular: the coordinates {} have no inertia (their velocities do not appear in T), so the equations of motion do not determine their accelerations",
            many.join(", ")
        ),
    };
    let help = match body {
        Some(_) => "a body with a zero principal moment (a thin rod about its axis) has no inertia for a spin about that axis: leave that angle out of the coordinates, or give the body its moment",
        None => "each coordinate needs its own kinetic energy; a coordinate whose velocity never appears, or two that only appear as one combination, leave the motion undetermined",
    };
    Err(ModelError::located(span, message).with_help(help).with_kind(ModelErrorKind::SingularMassMatrix))
}

/// Largest tree size of an expression that is simplified (beyond it, expansion
/// would cost more than it saves).
const MAX_SIMPLIFIED_TREE: u64 = 1500;

/// Largest tree size of Hamilton's equations that is reported symbolically.
const MAX_PRINTED_TREE: u64 = 20_000;

/// Largest tree size of a momentum that is polished by simplification.
const MAX_POLISHED_TREE: u64 = 80;

/// Simplifies a result that is already collected when it is small enough for
/// the factored form to be worth its cost.
fn polish(pool: &mut Pool, e: ExprId, is_var: &dyn Fn(Symbol) -> bool) -> ExprId {
    if pool.tree_size(e) > MAX_POLISHED_TREE {
        e
    } else {
        pool.simplify_in(e, is_var)
    }
}

/// Simplifies expressions of moderate size and keeps large ones as they are.
fn simplify_bounded(pool: &mut Pool, e: ExprId, is_var: &dyn Fn(Symbol) -> bool) -> ExprId {
    if pool.tree_size(e) > MAX_SIMPLIFIED_TREE {
        e
    } else {
        pool.simplify_in(e, is_var)
    }
}

/// Where the model states its energy: the Lagrangian, else the kinetic
/// energy, else its first particle.
fn energy_span(model: &Model) -> Option<std::ops::Range<usize>> {
    model
        .lagrangian
        .as_ref()
        .or(model.kinetic.as_ref())
        .map(|l| l.span.clone())
        .or_else(|| model.particles.first().map(|p| p.span.clone()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::probe::Subst;

    /// Hamilton's equations as built (structured for small blocks) agree with
    /// q' = ∂H/∂p and ṗ = −∂H/∂q − ∂R/∂q' + Q differentiated from H itself.
    #[test]
    fn hamilton_equations_are_the_derivatives_of_h() {
        let triple = r#"
coordinates = ["a", "b", "c", "x"]
gravity = "g"
dissipation = "k*x'^2/2"
[parameters]
m1 = 1.0
m2 = 2.0
m3 = 1.5
l1 = 1.0
l2 = 0.7
l3 = 1.3
g = 9.81
k = 0.3
[[particles]]
mass = "m1"
position = ["l1*sin(a)", "-l1*cos(a)"]
[[particles]]
mass = "m2"
position = ["l1*sin(a) + l2*sin(b)", "-l1*cos(a) - l2*cos(b)"]
[[particles]]
mass = "m3"
position = ["l1*sin(a) + l2*sin(b) + l3*sin(c)", "-l1*cos(a) - l2*cos(b) - l3*cos(c)"]
[[particles]]
mass = "m1"
position = ["x", "x^2/2"]
"#;
        let model = Model::parse(triple, &[]).unwrap();
        let d = Derivation::new(model).unwrap();
        let h = d.hamiltonian.expect("H");
        let eqs = d.hamilton.clone().expect("Hamilton's equations");
        let velocities = d.velocities.clone().unwrap();
        let mut scratch = d.pool().clone();
        let pool = &mut scratch;
        let subst: Subst = d.qd.iter().copied().zip(velocities).collect();
        for (k, (dq, dp)) in eqs.into_iter().enumerate() {
            let want_dq = pool.diff(h, d.p[k]);
            let e = pool.sub(dq, want_dq);
            assert!(probe::is_zero(pool, e), "q'{k}");
            let dh = pool.diff(h, d.q[k]);
            let dr = match d.dissipation {
                Some(r) => {
                    let dr = pool.diff(r, d.qd[k]);
                    pool.substitute(dr, &subst)
                }
                None => pool.zero(),
            };
            let sum = pool.add(&[dp, dh, dr]);
            assert!(probe::is_zero(pool, sum), "p'{k}: {}", pool.display(sum));
        }
    }
}
