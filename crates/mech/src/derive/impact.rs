//! The impact law of each `[[impacts]]` surface φ(q, t) ≥ 0: its gradient
//! ∇φ = ∂φ/∂q, its rate ∂φ/∂t (a moving surface), and the normal velocity
//! v_n = ∇φ·q' + ∂φ/∂t with which the motion meets it.
//!
//! At an impact the finite forces do nothing in the instant it lasts; an
//! impulse along the surface's normal in configuration space, M⁻¹∇φ Λ, turns
//! v_n⁻ into −e v_n⁻ (Newton's law), so that
//!
//! q'⁺ = q'⁻ − (1 + e) M⁻¹∇φ v_n⁻ / (∇φᵀ M⁻¹ ∇φ).
//!
//! M is never inverted symbolically: a run solves with its numbers at the
//! impact (`run/impacts.rs`). The law needs M free of the velocities, L
//! quadratic in them, as every model of particles and bodies is.

use crate::error::ModelError;
use crate::model::Model;
use sym::{ExprId, Pool};

/// The law of one unilateral contact, in the derivation's pool.
#[derive(Debug, Clone)]
pub struct ImpactLaw {
    /// The impact's name.
    pub name: String,
    /// φ(q, t).
    pub surface: ExprId,
    /// ∂φ/∂q_i, one per coordinate.
    pub gradient: Vec<ExprId>,
    /// ∂φ/∂t (zero for a surface at rest).
    pub rate: ExprId,
    /// v_n = ∇φ·q' + ∂φ/∂t.
    pub normal_velocity: ExprId,
    /// Newton's coefficient of restitution e.
    pub restitution: ExprId,
}

/// The laws of the model's impacts; an error when M depends on the velocities.
pub(super) fn derive(
    pool: &mut Pool,
    model: &Model,
    q: &[ExprId],
    qd: &[ExprId],
    t: ExprId,
    mass_matrix: &[Vec<ExprId>],
    simplify: &mut dyn FnMut(&mut Pool, ExprId) -> ExprId,
) -> Result<Vec<ImpactLaw>, ModelError> {
    let Some(first) = model.impacts.first() else { return Ok(Vec::new()) };
    if mass_matrix.iter().flatten().any(|&m| qd.iter().any(|&v| !pool.free_of(m, v))) {
        return Err(ModelError::at(
            first.name_span.clone(),
            "impacts need a mass matrix M free of the velocities (L quadratic in q'), and this model's depends on them",
        )
        .with_help(
            "Newton's impact law q'⁺ = q'⁻ − (1 + e) M⁻¹∇φ v_n/(∇φᵀM⁻¹∇φ) holds for L = ½ q'ᵀM(q)q' + b·q' − U",
        ));
    }
    let mut laws = Vec::with_capacity(model.impacts.len());
    for spec in &model.impacts {
        let phi = spec.surface.expr;
        let gradient: Vec<ExprId> = q
            .iter()
            .map(|&qi| {
                let g = pool.diff(phi, qi);
                simplify(pool, g)
            })
            .collect();
        let rate = pool.diff(phi, t);
        let rate = simplify(pool, rate);
        let mut terms: Vec<ExprId> = gradient.iter().zip(qd).map(|(&g, &v)| pool.mul2(g, v)).collect();
        terms.push(rate);
        let normal_velocity = pool.add(&terms);
        let normal_velocity = simplify(pool, normal_velocity);
        laws.push(ImpactLaw {
            name: spec.name.clone(),
            surface: phi,
            gradient,
            rate,
            normal_velocity,
            restitution: spec.restitution.expr,
        });
    }
    Ok(laws)
}
