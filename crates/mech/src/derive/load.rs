//! Loads as generalized forces, by virtual work (see [`crate::model::load`]):
//! a force F at r gives `Q_j = F·∂r/∂q_j`, a torque τ on a body
//! `Q_j = τ·∂ω/∂q'_j`, both in one set of components (a body's loads are
//! turned into space or body components with its rotation D).

use super::body::Frame;
use crate::model::{Load, LoadKind};
use sym::{ExprId, Pool};

/// The generalized force of every coordinate from the loads (zero without any).
pub(crate) fn generalized_forces(
    pool: &mut Pool,
    loads: &[Load],
    frames: &[Frame],
    q: &[ExprId],
    qd: &[ExprId],
) -> Vec<ExprId> {
    let mut terms: Vec<Vec<ExprId>> = vec![Vec::new(); q.len()];
    for load in loads {
        let frame = load.body.map(|b| &frames[b]);
        match (&load.kind, frame) {
            (LoadKind::Force { at }, frame) => {
                // The point and the force in space components.
                let (r, f) = match frame {
                    None => (*at, load.vector),
                    Some(fr) => {
                        let offset = to_space(pool, &fr.d, at);
                        let r = std::array::from_fn(|i| pool.add2(fr.origin[i], offset[i]));
                        let f = if load.body_axes { to_space(pool, &fr.d, &load.vector) } else { load.vector };
                        (r, f)
                    }
                };
                for (j, &qj) in q.iter().enumerate() {
                    for i in 0..3 {
                        if pool.is_zero(f[i]) {
                            continue;
                        }
                        let dr = pool.diff(r[i], qj);
                        terms[j].push(pool.mul2(f[i], dr));
                    }
                }
            }
            (LoadKind::Torque, Some(fr)) => {
                // τ in body components, against ω in body components.
                let tau = if load.body_axes { load.vector } else { from_space(pool, &fr.d, &load.vector) };
                for (j, &vj) in qd.iter().enumerate() {
                    for k in 0..3 {
                        if pool.is_zero(tau[k]) {
                            continue;
                        }
                        let dw = pool.diff(fr.omega[k], vj);
                        terms[j].push(pool.mul2(tau[k], dw));
                    }
                }
            }
            (LoadKind::Torque, None) => unreachable!("a torque's body is checked when the model is read"),
        }
    }
    terms.into_iter().map(|t| pool.add(&t)).collect()
}

/// Dᵀ v: body components to space components.
fn to_space(pool: &mut Pool, d: &crate::euler::ExprMatrix, v: &[ExprId; 3]) -> [ExprId; 3] {
    std::array::from_fn(|i| {
        let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(d[k][i], v[k])).collect();
        pool.add(&terms)
    })
}

/// D v: space components to body components.
fn from_space(pool: &mut Pool, d: &crate::euler::ExprMatrix, v: &[ExprId; 3]) -> [ExprId; 3] {
    std::array::from_fn(|i| {
        let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(d[i][k], v[k])).collect();
        pool.add(&terms)
    })
}
