//! The kinematics of a model's bodies: each body's axes (the rotation D from
//! space to body components), angular velocity and reference point, followed
//! through the tree from the roots (see [`crate::model::body`]). The derivation
//! builds T, U, L and the loads' virtual work on them, and rolling constraints
//! the contact point's velocity.

use crate::euler;
use crate::model::{Body, Orientation};
use sym::{ExprId, Pool};

/// A body's axes and reference point, followed through the tree from its root.
#[derive(Debug, Clone)]
pub(crate) struct Frame {
    /// The rotation from space components to body components (rows: the body axes).
    pub d: euler::ExprMatrix,
    /// The angular velocity, body components.
    pub omega: [ExprId; 3],
    /// The reference point in space.
    pub origin: [ExprId; 3],
    /// `(axis, angle)` when D is one turn about a coordinate axis (planar
    /// turns about that axis all the way from the root), so that a child's
    /// turn about the same axis composes to one angle sum, not a product.
    pub turn: Option<(usize, ExprId)>,
}

/// A body-components vector in space components: `Dᵀ v`.
pub(crate) fn to_space(pool: &mut Pool, d: &euler::ExprMatrix, v: &[ExprId; 3]) -> [ExprId; 3] {
    std::array::from_fn(|i| {
        let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(d[k][i], v[k])).collect();
        pool.add(&terms)
    })
}

/// The frame of every body, parents first (the model lists them so):
/// `D = D_rel·D_parent`, `ω = D_rel·ω_parent + ω_rel`, `x = x_parent + D_parentᵀ·position`.
pub(crate) fn frames(pool: &mut Pool, bodies: &[Body], q: &[ExprId], qd: &[ExprId]) -> Vec<Frame> {
    let mut out: Vec<Frame> = Vec::with_capacity(bodies.len());
    for body in bodies {
        let (zero, one) = (pool.zero(), pool.one());
        let (d_rel, w_rel) = relative_turn(pool, body, q, qd);
        let own_turn = match body.orientation {
            Orientation::Planar { angle, axis } => Some((axis, q[angle])),
            _ => None,
        };
        let frame = match body.parent.map(|p| out[p].clone()) {
            None => {
                let identity = std::array::from_fn(|i| std::array::from_fn(|j| if i == j { one } else { zero }));
                Frame { d: d_rel.unwrap_or(identity), omega: w_rel, origin: body.position, turn: own_turn }
            }
            Some(parent) => {
                // Turns about one axis add their angles: R(θ)·R(φ) = R(θ + φ). Kept
                // as one sum, a chain of k rods has D in cos and sin of one angle
                // each, where the product's expansion has 2^k terms.
                let turn = match (own_turn, parent.turn, &d_rel) {
                    (Some((axis, angle)), Some((parent_axis, parent_angle)), _) if axis == parent_axis => {
                        Some((axis, pool.add2(parent_angle, angle)))
                    }
                    (None, parent_turn, None) => parent_turn,
                    _ => None,
                };
                let (d, carried) = match (&d_rel, turn) {
                    (Some(d_rel), Some((axis, angle))) => {
                        (euler::turn_expr(pool, axis, angle), mat_vec(pool, d_rel, &parent.omega))
                    }
                    (Some(d_rel), None) => {
                        (euler::mat_mul(pool, d_rel, &parent.d), mat_vec(pool, d_rel, &parent.omega))
                    }
                    (None, _) => (parent.d, parent.omega),
                };
                let omega = std::array::from_fn(|k| pool.add2(carried[k], w_rel[k]));
                let origin = std::array::from_fn(|i| {
                    let mut terms = vec![parent.origin[i]];
                    terms.extend((0..3).map(|k| pool.mul2(parent.d[k][i], body.position[k])));
                    pool.add(&terms)
                });
                Frame { d, omega, origin, turn }
            }
        };
        out.push(frame);
    }
    out
}

/// A body's turn relative to its parent's axes (or space's): the rotation
/// D_rel from the parent's components to the body's (None for no turn of its
/// own) and the angular velocity ω_rel it adds, body components.
pub(crate) fn relative_turn(
    pool: &mut Pool,
    body: &Body,
    q: &[ExprId],
    qd: &[ExprId],
) -> (Option<euler::ExprMatrix>, [ExprId; 3]) {
    let zero = pool.zero();
    match body.orientation {
        Orientation::Euler { angles: [a, b, c], sequence } => (
            Some(euler::rotation_of(pool, sequence, [q[a], q[b], q[c]])),
            euler::angular_velocity_of(pool, sequence, [q[a], q[b], q[c]], [qd[a], qd[b], qd[c]]),
        ),
        Orientation::Planar { angle, axis } => {
            let mut w = [zero; 3];
            w[axis] = qd[angle];
            (Some(euler::turn_expr(pool, axis, q[angle])), w)
        }
        Orientation::Hinge { angle, axis } => {
            (Some(hinge(pool, axis, q[angle])), axis.map(|n| pool.mul2(n, qd[angle])))
        }
        Orientation::Fixed => (None, [zero; 3]),
    }
}

/// The turn by `angle` about the unit vector n, space → body components:
/// D = cos θ·1 + (1 − cos θ) n nᵀ − sin θ [n]ₓ (the notes' R_z for n = z).
fn hinge(pool: &mut Pool, n: [ExprId; 3], angle: ExprId) -> euler::ExprMatrix {
    let (s, c) = (pool.func(sym::Func::Sin, angle), pool.func(sym::Func::Cos, angle));
    let one = pool.one();
    let one_minus_c = pool.sub(one, c);
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let mut terms = vec![pool.mul(&[one_minus_c, n[i], n[j]])];
            if i == j {
                terms.push(c);
            }
            // [n]ₓ[i][j] = −ε_ijk n_k; −sin θ [n]ₓ adds sin θ ε_ijk n_k.
            if i != j {
                let k = 3 - i - j;
                let sign = if (j + 3 - i) % 3 == 1 { 1 } else { -1 };
                let term = pool.mul2(s, n[k]);
                terms.push(if sign > 0 { term } else { pool.neg(term) });
            }
            pool.add(&terms)
        })
    })
}

/// M v for a 3×3 matrix of expressions.
pub(crate) fn mat_vec(pool: &mut Pool, m: &euler::ExprMatrix, v: &[ExprId; 3]) -> [ExprId; 3] {
    std::array::from_fn(|i| {
        let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(m[i][j], v[j])).collect();
        pool.add(&terms)
    })
}

/// The velocity of a point given in space as functions of (q, t):
/// v = Σ ∂x/∂q_i q_i' + ∂x/∂t, per component.
pub(crate) fn velocity(pool: &mut Pool, x: &[ExprId; 3], q: &[ExprId], qd: &[ExprId], t: ExprId) -> [ExprId; 3] {
    std::array::from_fn(|k| {
        let mut terms: Vec<ExprId> = q
            .iter()
            .zip(qd)
            .map(|(&qi, &vi)| {
                let dx = pool.diff(x[k], qi);
                pool.mul2(dx, vi)
            })
            .collect();
        terms.push(pool.diff(x[k], t));
        pool.add(&terms)
    })
}
