//! The verdicts of a derivation, each made once: the cyclic coordinates and
//! the momenta they conserve, the energy function h, whether H is conserved
//! and whether it is the energy T + U₀, with the reasons the notes give. The
//! constraints are derived before: their forces are part of each verdict.

use super::constraint::{self, Constraints};
use super::quadratic::Quadratic;
use super::{
    decide, simplify_bounded, ConservationReason, Conserved, ConservedReason, CyclicReason, Energies, EnergyReason,
    External, Judged, Motion, RateTerm, Symbols, Verdicts,
};
use crate::model::Model;
use crate::probe::{self, Decision, Subst};
use sym::{ExprId, Pool, Symbol};

/// The cyclic coordinates and what they conserve.
pub(super) struct Cyclic {
    /// The indices of the coordinates whose ∂L/∂q is proven 0.
    pub(super) indices: Vec<usize>,
    /// Their momenta that are conserved.
    pub(super) conserved: Vec<Conserved>,
    /// Coordinates and momenta that could not be decided.
    pub(super) reasons: Vec<CyclicReason>,
    /// Why a constraint force takes a cyclic coordinate's momentum away, one
    /// sentence per momentum (the constraints' explanation).
    pub(super) lost: Vec<String>,
}

/// Cyclic coordinates (∂L/∂q proven to be 0) and the momenta that are
/// conserved: those on which dissipation, a generalized force and every
/// constraint force are proven absent. A coordinate whose ∂L/∂q (or whose R
/// and Q) could not be decided gets a reason instead of a claim.
pub(super) fn cyclic_coordinates(
    pool: &mut Pool,
    s: &Symbols,
    m: &Motion,
    ext: &External,
    constraints: &Constraints,
    shared: bool,
) -> Cyclic {
    let mut cyclic = Vec::new();
    let mut conserved = Vec::new();
    let mut reasons = Vec::new();
    let mut lost = Vec::new();
    // On the shared path most ∂L/∂q are refuted by numbers: all at once.
    let refuted = if shared { probe::refuted_each(pool, &m.dl_dq) } else { vec![false; s.n()] };
    for i in 0..s.n() {
        let coordinate = s.names[i].clone();
        if refuted[i] {
            continue;
        }
        match decide(pool, m.dl_dq[i], shared) {
            Decision::Zero => {}
            Decision::NonZero => continue,
            Decision::Undecided => {
                reasons.push(CyclicReason::Undecided { coordinate });
                continue;
            }
        }
        cyclic.push(i);
        let damping = match ext.dissipation {
            Some(r) => {
                let d = pool.diff(r, s.qd[i]);
                decide(pool, d, shared)
            }
            None => Decision::Zero,
        };
        let forcing = decide(pool, ext.forces[i], shared);
        match (damping, forcing) {
            (Decision::Zero, Decision::Zero) => match constraint::momentum_kept(pool, constraints, i, &coordinate) {
                Ok(()) => conserved.push(Conserved {
                    name: format!("p_{coordinate}"),
                    expr: m.momenta[i],
                    reason: ConservedReason::Cyclic { coordinate },
                }),
                Err(why) => lost.push(why),
            },
            (Decision::NonZero, _) | (_, Decision::NonZero) => {}
            _ => reasons.push(CyclicReason::MomentumUndecided { coordinate }),
        }
    }
    Cyclic { indices: cyclic, conserved, reasons, lost }
}

/// The energy function h = Σ q' ∂L/∂q' − L and the verdicts on it: whether H is
/// conserved (dH/dt = −∂L/∂t − Σ q'·∂R/∂q' + Σ Q·q' − λ·a_t, each term named
/// that is there; with only the constraints' work in the way, H − W is) and
/// whether it is the energy T + U₀.
#[allow(clippy::too_many_arguments)]
pub(super) fn judge(
    pool: &mut Pool,
    model: &Model,
    s: &Symbols,
    e: &Energies,
    m: &Motion,
    ext: &External,
    constraints: &Constraints,
    is_var: &dyn Fn(Symbol) -> bool,
) -> Judged {
    let (n, qd) = (s.n(), &s.qd);
    let energy_function = match &e.form {
        Some(form) => form.energy_function(pool, qd),
        None => {
            let mut h_terms: Vec<ExprId> = (0..n).map(|i| pool.mul2(qd[i], m.momenta[i])).collect();
            h_terms.push(pool.neg(e.lagrangian));
            let h_sum = pool.add(&h_terms);
            if e.shared {
                simplify_bounded(pool, h_sum, is_var)
            } else {
                pool.simplify_in(h_sum, is_var)
            }
        }
    };
    // Each term of dH/dt: H is conserved only when all three are proven 0.
    let dl_dt = pool.diff(e.lagrangian, s.t);
    let time = decide(pool, dl_dt, e.shared);
    let dissipation = match ext.dissipation {
        Some(r) => decide(pool, r, e.shared),
        None => Decision::Zero,
    };
    let forces: Vec<Decision> = (0..n).map(|i| decide(pool, ext.forces[i], e.shared)).collect();
    let forced: Vec<usize> = (0..n).filter(|&i| forces[i].is_nonzero()).collect();
    let force = if !forced.is_empty() {
        Decision::NonZero
    } else if forces.iter().all(|f| f.is_zero()) {
        Decision::Zero
    } else {
        Decision::Undecided
    };
    let explicit_time = time.known().map(|zero| !zero);
    let terms =
        [(RateTerm::ExplicitTime, time), (RateTerm::Dissipation, dissipation), (RateTerm::GeneralizedForces, force)];
    let unconstrained_conserved = terms.iter().all(|(_, d)| d.is_zero());
    let mut verdicts = Verdicts::default();
    if time.is_nonzero() {
        verdicts.conservation.push(ConservationReason::ExplicitTime);
    }
    if dissipation.is_nonzero() {
        verdicts.conservation.push(ConservationReason::Dissipation);
    }
    if !forced.is_empty() {
        let coordinates = forced.iter().map(|&i| s.names[i].clone()).collect();
        verdicts.conservation.push(ConservationReason::GeneralizedForces { coordinates });
    }
    let shown: Vec<RateTerm> = terms.iter().filter(|(_, d)| d.is_nonzero()).map(|&(t, _)| t).collect();
    if !shown.is_empty() {
        verdicts.conservation.push(ConservationReason::Rate { terms: shown });
    }
    let undecided: Vec<RateTerm> = terms.iter().filter(|(_, d)| *d == Decision::Undecided).map(|&(t, _)| t).collect();
    if !undecided.is_empty() {
        verdicts.conservation.push(ConservationReason::Undecided { terms: undecided });
    }
    // Without the other terms, the constraints' work decides.
    let work = constraints.work();
    let (hamiltonian_conserved, work_balances_h) = match unconstrained_conserved {
        false => (false, false),
        true if !work.working.is_empty() => {
            verdicts.conservation.push(ConservationReason::ConstraintWork { constraints: work.working });
            verdicts.conservation.push(ConservationReason::WorkBalance);
            (false, true)
        }
        true if !work.undecided.is_empty() => {
            verdicts.conservation.push(ConservationReason::ConstraintWorkUndecided { constraints: work.undecided });
            (false, false)
        }
        true => {
            verdicts.conservation.push(ConservationReason::Conserved);
            if !constraints.is_empty() {
                verdicts.conservation.push(ConservationReason::ConstraintsDoNoWork);
            }
            (true, false)
        }
    };
    let (energy, hamiltonian_is_energy) = match (e.kinetic, e.potential) {
        (Some(tt), Some(uu)) => {
            let zero_vel: Subst = qd.iter().map(|&v| (v, pool.zero())).collect();
            let u0 = pool.substitute(uu, &zero_vel);
            let en = pool.add2(tt, u0);
            // T and U are simplified each; their sum is, too, while it is small.
            let en = if model.particles.is_empty() && !e.shared { simplify_bounded(pool, en, is_var) } else { en };
            // With U free of the velocities, L's form holds T's b and L₀ = T₀ − U:
            // T is homogeneous of degree 2 exactly when b = 0 and T₀ = L₀ + U = 0,
            // and h − E = −bᵀq' − 2T₀, so h = E exactly then. Deciding that on the
            // form's simplified coefficients spares proving two long sums equal.
            let homogeneous = match &e.form {
                Some(form) if qd.iter().all(|&v| pool.free_of(uu, v)) => Some(homogeneity(pool, form, uu, e.shared)),
                _ => None,
            };
            let same = match homogeneous {
                Some(decision) => decision.known(),
                None => {
                    let d = pool.sub(energy_function, en);
                    decide(pool, d, e.shared).known()
                }
            };
            explain_energy(pool, &mut verdicts, same, homogeneous, tt, uu, u0, qd, e.shared);
            (Some(en), same)
        }
        _ => {
            verdicts.energy.push(EnergyReason::OnlyLagrangian);
            (None, None)
        }
    };
    Judged {
        energy_function,
        energy,
        hamiltonian_is_energy,
        hamiltonian_conserved,
        work_balances_h,
        explicit_time,
        verdicts,
    }
}

/// Whether T is homogeneous of degree 2 in the velocities, read from L's
/// form when U is free of them: b = 0 and T₀ = L₀ + U = 0, each coefficient
/// decided on its own.
pub(super) fn homogeneity(pool: &mut Pool, form: &Quadratic, potential: ExprId, shared: bool) -> Decision {
    let t0 = pool.add2(form.l0, potential);
    let mut all_zero = true;
    for &b in form.b.iter().chain([&t0]) {
        match decide(pool, b, shared) {
            Decision::NonZero => return Decision::NonZero,
            d => all_zero &= d.is_zero(),
        }
    }
    if all_zero {
        Decision::Zero
    } else {
        Decision::Undecided
    }
}

/// Explains whether h equals T + U₀, the way the notes do: a time-dependent
/// transformation x(q, t) makes T inhomogeneous in q'; a velocity-dependent
/// potential adds terms to h.
#[allow(clippy::too_many_arguments)]
pub(super) fn explain_energy(
    pool: &mut Pool,
    verdicts: &mut Verdicts,
    same: Option<bool>,
    homogeneous: Option<Decision>,
    kinetic: ExprId,
    potential: ExprId,
    u0: ExprId,
    qd: &[ExprId],
    shared: bool,
) {
    // T homogeneous of degree 2 in q' ⇔ Σ q' ∂T/∂q' = 2T.
    let homogeneous = homogeneous.unwrap_or_else(|| {
        let mut terms: Vec<ExprId> = qd
            .iter()
            .map(|&v| {
                let d = pool.diff(kinetic, v);
                pool.mul2(v, d)
            })
            .collect();
        let two = pool.int(2);
        let two_t = pool.mul2(two, kinetic);
        terms.push(pool.neg(two_t));
        let euler = pool.add(&terms);
        decide(pool, euler, shared)
    });
    verdicts.energy.push(match homogeneous {
        Decision::Zero => EnergyReason::KineticHomogeneous,
        Decision::NonZero => EnergyReason::KineticNotHomogeneous,
        Decision::Undecided => EnergyReason::HomogeneityUndecided,
    });
    let velocity_part = pool.sub(potential, u0);
    match decide(pool, velocity_part, shared) {
        Decision::Zero => {}
        Decision::NonZero => verdicts.energy.push(EnergyReason::VelocityDependentPotential),
        Decision::Undecided => verdicts.energy.push(EnergyReason::VelocityDependenceUndecided),
    }
    verdicts.energy.push(match same {
        Some(true) => EnergyReason::IsEnergy,
        Some(false) => EnergyReason::NotEnergy,
        None => EnergyReason::EnergyUndecided,
    });
}
