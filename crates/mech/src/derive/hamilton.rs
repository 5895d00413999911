//! Hamilton's side of a derivation: H(q, p, t), q'(q, p, t) and Hamilton's
//! equations by the Legendre transform, for a Lagrangian quadratic in the
//! velocities, with M inverted block by block (`solve.rs`) where it is small
//! enough to print; otherwise none, and the verdicts say why.

use super::quadratic::{Quadratic, Sparsity};
use super::solve::{adjugate, blocks, largest_block, solve_symbolic};
use super::{simplify_bounded, Energies, External, HamiltonianReason, Motion, Symbols, Verdicts, MAX_PRINTED_TREE};
use crate::probe::Subst;
use sym::{ExprId, Pool, Symbol};

/// H(q, p, t), q'(q, p, t) and Hamilton's equations by the Legendre transform,
/// for L quadratic in q'; otherwise none, with the reason in the verdicts.
pub(super) fn hamiltonian(
    pool: &mut Pool,
    s: &Symbols,
    e: &Energies,
    m: &Motion,
    ext: &External,
    verdicts: &mut Verdicts,
    is_var: &dyn Fn(Symbol) -> bool,
) -> Option<Legendre> {
    if e.shared && e.form.is_some() {
        // M⁻¹ written out would grow with the cube of a full block, and with
        // every level of the tree: the shared path does not invert M.
        let coupled = largest_block(pool, &m.mass_matrix);
        verdicts.hamiltonian.push(HamiltonianReason::TooLong { coupled });
        return None;
    }
    let Some((form, sparsity)) = e.form.as_ref().zip(e.sparsity.as_ref()) else {
        verdicts.hamiltonian.push(HamiltonianReason::NotQuadratic);
        return None;
    };
    let sys = System { q: &s.q, qd: &s.qd, p: &s.p, form, sparsity, dissipation: ext.dissipation, forces: &ext.forces };
    let found = legendre(pool, &sys, is_var);
    if found.is_none() {
        let coupled = largest_block(pool, &m.mass_matrix);
        verdicts.hamiltonian.push(HamiltonianReason::TooLong { coupled });
    }
    found
}

/// The parts of a derivation the Legendre transform reads.
pub(super) struct System<'a> {
    q: &'a [ExprId],
    qd: &'a [ExprId],
    p: &'a [ExprId],
    form: &'a Quadratic,
    sparsity: &'a Sparsity,
    dissipation: Option<ExprId>,
    forces: &'a [ExprId],
}

/// H(q, p, t), q'(q, p, t) and Hamilton's equations, for L quadratic in the
/// velocities: L = ½q'ᵀMq' + bᵀq' + L₀ gives H = ½(p − b)ᵀM⁻¹(p − b) − L₀.
/// None when the result would be too long to print.
pub(super) struct Legendre {
    /// H(q, p, t).
    pub(super) hamiltonian: ExprId,
    /// q'(q, p, t), one per coordinate.
    pub(super) velocities: Vec<ExprId>,
    /// Hamilton's equations (q', p') of each coordinate.
    pub(super) equations: Vec<(ExprId, ExprId)>,
}

pub(super) fn legendre(pool: &mut Pool, s: &System, is_var: &dyn Fn(Symbol) -> bool) -> Option<Legendre> {
    let n = s.q.len();
    let (b, l0) = (&s.form.b, s.form.l0);
    let shifted: Vec<ExprId> = (0..n).map(|i| pool.sub(s.p[i], b[i])).collect();
    let no_b = b.iter().all(|&x| pool.is_zero(x));
    // With M⁻¹ in closed form (blocks of at most 3 coordinates) and b = 0, H is
    // Σ c_ij p_i p_j − L₀ with each coefficient simplified on its own, and so are
    // q' and ṗ: nothing long is ever expanded.
    if let (true, Some(inv)) = (no_b, small_block_inverse(pool, &s.form.m, is_var)) {
        return Some(legendre_structured(pool, s, &inv, is_var));
    }
    let v = solve_symbolic(pool, &s.form.m, &shifted, is_var)?;
    if v.iter().any(|&x| pool.tree_size(x) > MAX_PRINTED_TREE) {
        return None;
    }
    let terms: Vec<ExprId> = (0..n).map(|i| pool.mul2(shifted[i], v[i])).collect();
    let half = pool.rational(1, 2);
    let kin = pool.add(&terms);
    let kin = pool.mul2(half, kin);
    let h = pool.sub(kin, l0);
    let h = simplify_bounded(pool, h, is_var);
    let vel_subst: Subst = (0..n).map(|i| (s.qd[i], v[i])).collect();
    let mut eqs = Vec::with_capacity(n);
    for i in 0..n {
        let dh = pool.diff(h, s.q[i]);
        let mut dp_terms = vec![pool.neg(dh)];
        dp_terms.push(nonconservative(pool, s, i, &vel_subst));
        let dp = pool.add(&dp_terms);
        let dp = simplify_bounded(pool, dp, is_var);
        if pool.tree_size(dp) > MAX_PRINTED_TREE {
            return None;
        }
        eqs.push((v[i], dp));
    }
    Some(Legendre { hamiltonian: h, velocities: v, equations: eqs })
}

/// −∂R/∂q_i' + Q_i written in (q, p, t) by the velocity substitution.
pub(super) fn nonconservative(pool: &mut Pool, s: &System, i: usize, vel_subst: &Subst) -> ExprId {
    let mut terms = Vec::new();
    if let Some(r) = s.dissipation {
        let dr = pool.diff(r, s.qd[i]);
        let dr = pool.substitute(dr, vel_subst);
        terms.push(pool.neg(dr));
    }
    terms.push(pool.substitute(s.forces[i], vel_subst));
    pool.add(&terms)
}

/// H = Σ_{i≤j} c_ij p_i p_j − L₀ with c_ii = ½(M⁻¹)_ii, c_ij = (M⁻¹)_ij, for b = 0.
pub(super) fn legendre_structured(
    pool: &mut Pool,
    s: &System,
    inv: &[Vec<ExprId>],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Legendre {
    let n = s.q.len();
    let half = pool.rational(1, 2);
    // The coefficients of H, one per pair of momenta M couples.
    let mut pairs: Vec<(usize, usize, ExprId)> = Vec::new();
    for i in 0..n {
        for j in i..n {
            if pool.is_zero(inv[i][j]) {
                continue;
            }
            let c = if i == j { pool.mul2(half, inv[i][i]) } else { inv[i][j] };
            pairs.push((i, j, c));
        }
    }
    let mut h_terms: Vec<ExprId> = Vec::with_capacity(pairs.len() + 1);
    for &(i, j, c) in &pairs {
        let mono = if i == j { pool.powi(s.p[i], 2) } else { pool.mul2(s.p[i], s.p[j]) };
        h_terms.push(pool.mul2(c, mono));
    }
    h_terms.push(pool.neg(s.form.l0));
    let h = pool.add(&h_terms);
    let v: Vec<ExprId> = (0..n)
        .map(|i| {
            let coupled: Vec<usize> = (0..n).filter(|&j| !pool.is_zero(inv[i][j])).collect();
            let terms: Vec<ExprId> = coupled.into_iter().map(|j| pool.mul2(inv[i][j], s.p[j])).collect();
            pool.add(&terms)
        })
        .collect();
    // ṗ_k = −∂H/∂q_k = ½ q'ᵀ (∂M/∂q_k) q' + ∂L₀/∂q_k with q' = M⁻¹p, since
    // ∂M⁻¹/∂q = −M⁻¹ (∂M/∂q) M⁻¹: only the few nonzero ∂M_ij/∂q_k are formed.
    let vel_subst: Subst = (0..n).map(|i| (s.qd[i], v[i])).collect();
    let mut eqs = Vec::with_capacity(n);
    let (depends, grad_l0) = (&s.sparsity.depends, &s.sparsity.grad_l0);
    for k in 0..n {
        let mut terms = Vec::new();
        for &(i, j) in &depends[k] {
            let d = pool.diff(s.form.m[i][j], s.q[k]);
            let d = if i == j { pool.mul2(half, d) } else { d };
            let d = pool.simplify_in(d, is_var);
            if !pool.is_zero(d) {
                terms.push(pool.mul(&[d, v[i], v[j]]));
            }
        }
        let dl0 = grad_l0[k];
        let extra = nonconservative(pool, s, k, &vel_subst);
        let rest = pool.add2(dl0, extra);
        terms.push(pool.simplify_in(rest, is_var));
        eqs.push((v[k], pool.add(&terms)));
    }
    Legendre { hamiltonian: h, velocities: v, equations: eqs }
}

/// M⁻¹ entry by entry when every block M couples has at most 3 coordinates
/// (1×1 blocks divide; 2×2 and 3×3 use the adjugate over the simplified
/// determinant), each entry simplified; None for larger blocks.
pub(super) fn small_block_inverse(
    pool: &mut Pool,
    m: &[Vec<ExprId>],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Option<Vec<Vec<ExprId>>> {
    let n = m.len();
    let blocks = blocks(pool, m);
    if blocks.iter().any(|idx| idx.len() > 3) {
        return None;
    }
    let mut inv = vec![vec![pool.zero(); n]; n];
    for idx in blocks {
        let a: Vec<Vec<ExprId>> = idx.iter().map(|&i| idx.iter().map(|&j| m[i][j]).collect()).collect();
        if idx.len() == 1 {
            let one = pool.one();
            inv[idx[0]][idx[0]] = pool.div(one, a[0][0]);
            continue;
        }
        let (adj, det) = adjugate(pool, &a, is_var);
        for (r, &i) in idx.iter().enumerate() {
            for (c, &j) in idx.iter().enumerate().skip(r) {
                // Common monomial factors of the (factored) cofactor and
                // determinant cancel in the canonical product.
                inv[i][j] = pool.div(adj[r][c], det);
                inv[j][i] = inv[i][j];
            }
        }
    }
    Some(inv)
}
