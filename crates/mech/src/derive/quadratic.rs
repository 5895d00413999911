//! Lagrangians quadratic in the velocities, kept in their structure.
//!
//! Almost every mechanical Lagrangian reads L = ½ q'ᵀM(q,t)q' + b(q,t)ᵀq' + L₀(q,t).
//! Held as (M, b, L₀) instead of one long sum, the derivation never has to
//! expand and re-collect the whole of L: the momenta are `M q' + b`, the mass
//! matrix is `M` itself, and the forcing of `M q'' = f` follows from the
//! Christoffel symbols of M, which are sparse (an entry of M depends on few
//! coordinates), so only the few nonzero derivatives are ever formed:
//!
//! ```text
//! f_i = −Σ_{j,k} Γ_i,jk q_j' q_k' − Σ_j (∂M_ij/∂t + ∂b_i/∂q_j − ∂b_j/∂q_i) q_j' − ∂b_i/∂t + ∂L₀/∂q_i
//! Γ_i,jk = ½ (∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i)
//! ```
//!
//! Each coefficient is simplified on its own, while it is small. The particle
//! recipe of the notes (T = ½ Σ m |ẋ|²) lands directly in this form, entry by
//! entry, with the Jacobian dot products shared between particles.

use crate::probe::{self, Subst};
use rustc_hash::FxHashMap;
use std::collections::BTreeMap;
use sym::{ExprId, Pool, Symbol};

/// L = ½ q'ᵀ m q' + bᵀ q' + l0, every part free of velocities.
#[derive(Debug, Clone)]
pub struct Quadratic {
    /// The symmetric matrix M(q, t), entries simplified.
    pub m: Vec<Vec<ExprId>>,
    /// The linear coefficients b(q, t).
    pub b: Vec<ExprId>,
    /// The velocity-free part L₀(q, t).
    pub l0: ExprId,
}

/// The coordinates, velocities and time the forms are written in.
pub struct Vars<'a> {
    /// Coordinates q.
    pub q: &'a [ExprId],
    /// Velocities q'.
    pub qd: &'a [ExprId],
    /// The time.
    pub t: ExprId,
    /// True for the symbols that are variables (not parameters).
    pub is_var: &'a dyn Fn(Symbol) -> bool,
}

impl Quadratic {
    /// The zero form for `n` coordinates.
    pub fn zero(pool: &Pool, n: usize) -> Quadratic {
        Quadratic { m: vec![vec![pool.zero(); n]; n], b: vec![pool.zero(); n], l0: pool.zero() }
    }

    /// Splits `l` into (M, b, L₀) by differentiation, or None when `l` is not
    /// quadratic in the velocities. The split is checked: `l` minus the
    /// rebuilt form must be proven zero ([`probe::is_zero`]); a split that is
    /// not proven is not used, and L is then treated as not quadratic.
    pub fn split(pool: &mut Pool, l: ExprId, v: &Vars) -> Option<Quadratic> {
        let n = v.q.len();
        let zero_vel: Subst = v.qd.iter().map(|&x| (x, pool.zero())).collect();
        let mut form = Quadratic::zero(pool, n);
        let first = sparse_gradient(pool, l, v.qd);
        let velocity_index = coordinate_index(v.qd);
        for i in 0..n {
            if pool.is_zero(first[i]) {
                continue;
            }
            let second = sparse_gradient(pool, first[i], v.qd);
            for j in i..n {
                let d = second[j];
                if pool.is_zero(d) {
                    continue;
                }
                let d = pool.simplify_in(d, v.is_var);
                if !support_of(pool, d, &velocity_index).is_empty() {
                    return None;
                }
                form.m[i][j] = d;
                form.m[j][i] = d;
            }
            let b = pool.substitute(first[i], &zero_vel);
            form.b[i] = pool.simplify_in(b, v.is_var);
        }
        let l0 = pool.substitute(l, &zero_vel);
        form.l0 = pool.simplify_in(l0, v.is_var);
        let rebuilt = form.lagrangian(pool, v.qd);
        let diff = pool.sub(l, rebuilt);
        probe::is_zero(pool, diff).then_some(form)
    }

    /// Adds another form entry by entry, simplifying entries both have.
    pub fn add(&mut self, pool: &mut Pool, other: &Quadratic, is_var: &dyn Fn(Symbol) -> bool) {
        let merge = |pool: &mut Pool, a: ExprId, b: ExprId| -> ExprId {
            if pool.is_zero(a) {
                b
            } else if pool.is_zero(b) {
                a
            } else {
                let s = pool.add2(a, b);
                pool.simplify_in(s, is_var)
            }
        };
        let n = self.b.len();
        for i in 0..n {
            for j in 0..n {
                self.m[i][j] = merge(pool, self.m[i][j], other.m[i][j]);
            }
            self.b[i] = merge(pool, self.b[i], other.b[i]);
        }
        self.l0 = merge(pool, self.l0, other.l0);
    }

    /// ½ q'ᵀ M q' + bᵀ q' + L₀ as one sum (½ M_ii q_i'² and M_ij q_i' q_j' for i < j).
    pub fn lagrangian(&self, pool: &mut Pool, qd: &[ExprId]) -> ExprId {
        let mut terms = self.quadratic_terms(pool, qd);
        for (i, &b) in self.b.iter().enumerate() {
            if !pool.is_zero(b) {
                terms.push(pool.mul2(b, qd[i]));
            }
        }
        terms.push(self.l0);
        pool.add(&terms)
    }

    /// The terms of ½ q'ᵀ M q'.
    pub fn quadratic_terms(&self, pool: &mut Pool, qd: &[ExprId]) -> Vec<ExprId> {
        let n = qd.len();
        let half = pool.rational(1, 2);
        let mut terms = Vec::new();
        for i in 0..n {
            for j in i..n {
                let entry = self.m[i][j];
                if pool.is_zero(entry) {
                    continue;
                }
                let term = if i == j {
                    let sq = pool.powi(qd[i], 2);
                    pool.mul(&[half, entry, sq])
                } else {
                    pool.mul(&[entry, qd[i], qd[j]])
                };
                terms.push(term);
            }
        }
        terms
    }

    /// The momenta p_i = Σ_j M_ij q_j' + b_i.
    pub fn momenta(&self, pool: &mut Pool, qd: &[ExprId]) -> Vec<ExprId> {
        let n = qd.len();
        (0..n)
            .map(|i| {
                let mut terms: Vec<ExprId> = Vec::with_capacity(n + 1);
                for j in 0..n {
                    if !pool.is_zero(self.m[i][j]) {
                        terms.push(pool.mul2(self.m[i][j], qd[j]));
                    }
                }
                terms.push(self.b[i]);
                pool.add(&terms)
            })
            .collect()
    }

    /// The energy function h = Σ q'·p − L = ½ q'ᵀ M q' − L₀.
    pub fn energy_function(&self, pool: &mut Pool, qd: &[ExprId]) -> ExprId {
        let mut terms = self.quadratic_terms(pool, qd);
        terms.push(pool.neg(self.l0));
        pool.add(&terms)
    }

    /// Which coordinates each part depends on, found once for the forcing,
    /// ∂L/∂q and Hamilton's equations. One walk per nonzero entry of M, so a
    /// diagonal M of a thousand coordinates costs a thousand walks, not a
    /// billion tests.
    pub fn sparsity(&self, pool: &mut Pool, q: &[ExprId]) -> Sparsity {
        let n = q.len();
        let mut support: Vec<Vec<Vec<usize>>> = vec![vec![Vec::new(); n]; n];
        let mut depends: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        let index = coordinate_index(q);
        for j in 0..n {
            for k in j..n {
                let e = self.m[j][k];
                if pool.as_number(e).is_some() {
                    continue;
                }
                let s = support_of(pool, e, &index);
                for &c in &s {
                    depends[c].push((j, k));
                }
                support[k][j] = s.clone();
                support[j][k] = s;
            }
        }
        let grad_l0 = sparse_gradient(pool, self.l0, q);
        Sparsity { support, depends, grad_l0 }
    }

    /// ∂L/∂q_i for every coordinate, assembled from the parts that depend on
    /// q_i: ½ Σ ∂M_jk/∂q_i q_j' q_k' + Σ ∂b_j/∂q_i q_j' + ∂L₀/∂q_i.
    pub fn coordinate_gradient(&self, pool: &mut Pool, q: &[ExprId], qd: &[ExprId], sp: &Sparsity) -> Vec<ExprId> {
        let n = q.len();
        let (depends, grad_l0) = (&sp.depends, &sp.grad_l0);
        let index = coordinate_index(q);
        let mut b_terms: Vec<Vec<ExprId>> = vec![Vec::new(); n];
        for (j, &b) in self.b.iter().enumerate() {
            if pool.as_number(b).is_some() {
                continue;
            }
            for c in support_of(pool, b, &index) {
                let d = pool.diff(b, q[c]);
                b_terms[c].push(pool.mul2(d, qd[j]));
            }
        }
        let half = pool.rational(1, 2);
        (0..n)
            .map(|i| {
                let mut terms = std::mem::take(&mut b_terms[i]);
                for &(j, k) in &depends[i] {
                    let d = pool.diff(self.m[j][k], q[i]);
                    let term = if j == k {
                        let sq = pool.powi(qd[j], 2);
                        pool.mul(&[half, d, sq])
                    } else {
                        pool.mul(&[d, qd[j], qd[k]])
                    };
                    terms.push(term);
                }
                terms.push(grad_l0[i]);
                pool.add(&terms)
            })
            .collect()
    }

    /// The velocity-dependent and conservative part of the forcing, row by
    /// row: f_i with M q'' = f for this L alone (no dissipation or forces).
    /// Coefficients are simplified one by one; rows are sums of distinct
    /// velocity monomials and need no simplification as a whole.
    pub fn forcing(&self, pool: &mut Pool, v: &Vars, sp: &Sparsity) -> Vec<ExprId> {
        let n = v.q.len();
        let (support, depends, grad_l0) = (&sp.support, &sp.depends, &sp.grad_l0);
        let explicit_m =
            (0..n).any(|j| (j..n).any(|k| pool.as_number(self.m[j][k]).is_none() && !pool.free_of(self.m[j][k], v.t)));
        let has_b = self.b.iter().any(|&b| !pool.is_zero(b));
        let neg_half = pool.rational(-1, 2);

        let mut rows = Vec::with_capacity(n);
        for i in 0..n {
            // Coefficient terms of q_j' q_k' (j ≤ k) in Σ_jk (∂M_ij/∂q_k − ½ ∂M_jk/∂q_i) q_j' q_k'.
            let mut quad: BTreeMap<(usize, usize), Vec<ExprId>> = BTreeMap::new();
            for j in 0..n {
                for &k in &support[i][j] {
                    let d = pool.diff(self.m[i][j], v.q[k]);
                    quad.entry((j.min(k), j.max(k))).or_default().push(d);
                }
            }
            for &(j, k) in &depends[i] {
                let d = pool.diff(self.m[j][k], v.q[i]);
                // The ordered pairs (j, k) and (k, j) both carry −½ ∂M_jk/∂q_i.
                let term = if j == k { pool.mul2(neg_half, d) } else { pool.neg(d) };
                quad.entry((j, k)).or_default().push(term);
            }
            let mut terms = Vec::new();
            for ((j, k), parts) in quad {
                let c = pool.add(&parts);
                // One derivative of a simplified entry is left as it is; sums
                // of several may combine.
                let c = if parts.len() > 1 && !pool.is_zero(c) { pool.simplify_in(c, v.is_var) } else { c };
                if pool.is_zero(c) {
                    continue;
                }
                let mono = if j == k { pool.powi(v.qd[j], 2) } else { pool.mul2(v.qd[j], v.qd[k]) };
                let t = pool.mul2(c, mono);
                terms.push(pool.neg(t));
            }
            // Linear terms: Σ_j (∂M_ij/∂t + ∂b_i/∂q_j − ∂b_j/∂q_i) q_j'.
            if explicit_m || has_b {
                for j in 0..n {
                    let mut parts = Vec::new();
                    if explicit_m {
                        parts.push(pool.diff(self.m[i][j], v.t));
                    }
                    if has_b {
                        parts.push(pool.diff(self.b[i], v.q[j]));
                        let d = pool.diff(self.b[j], v.q[i]);
                        parts.push(pool.neg(d));
                    }
                    let c = pool.add(&parts);
                    if pool.is_zero(c) {
                        continue;
                    }
                    let c = pool.simplify_in(c, v.is_var);
                    if !pool.is_zero(c) {
                        let t = pool.mul2(c, v.qd[j]);
                        terms.push(pool.neg(t));
                    }
                }
            }
            // Velocity-free terms: −∂b_i/∂t + ∂L₀/∂q_i.
            let db = pool.diff(self.b[i], v.t);
            let dl = grad_l0[i];
            let rest = pool.sub(dl, db);
            let rest = pool.simplify_in(rest, v.is_var);
            terms.push(rest);
            rows.push(pool.add(&terms));
        }
        rows
    }
}

/// A quadratic form gathered term by term (the rigid bodies' parts), each
/// coefficient simplified once when the form is finished.
pub struct Parts {
    m: Vec<Vec<Vec<ExprId>>>,
    b: Vec<Vec<ExprId>>,
    l0: Vec<ExprId>,
}

impl Parts {
    /// No terms yet, for `n` coordinates.
    pub fn new(n: usize) -> Parts {
        Parts { m: vec![vec![Vec::new(); n]; n], b: vec![Vec::new(); n], l0: Vec::new() }
    }

    /// Adds `e` to M_ij (and M_ji).
    pub fn push_m(&mut self, i: usize, j: usize, e: ExprId) {
        self.m[i.min(j)][i.max(j)].push(e);
    }

    /// Adds `e` to b_i.
    pub fn push_b(&mut self, i: usize, e: ExprId) {
        self.b[i].push(e);
    }

    /// Adds `e` to L₀.
    pub fn push_l0(&mut self, e: ExprId) {
        self.l0.push(e);
    }

    /// The form, each coefficient the simplified sum of its terms.
    pub fn finish(self, pool: &mut Pool, is_var: &dyn Fn(Symbol) -> bool) -> Quadratic {
        let n = self.b.len();
        let sum = |pool: &mut Pool, terms: &[ExprId]| -> ExprId {
            if terms.is_empty() {
                return pool.zero();
            }
            let s = pool.add(terms);
            pool.simplify_in(s, is_var)
        };
        let mut form = Quadratic::zero(pool, n);
        for i in 0..n {
            for j in i..n {
                let e = sum(pool, &self.m[i][j]);
                form.m[i][j] = e;
                form.m[j][i] = e;
            }
            form.b[i] = sum(pool, &self.b[i]);
        }
        form.l0 = sum(pool, &self.l0);
        form
    }
}

/// Coordinate symbol → its index.
fn coordinate_index(q: &[ExprId]) -> FxHashMap<ExprId, usize> {
    q.iter().enumerate().map(|(i, &x)| (x, i)).collect()
}

/// The coordinates an expression depends on, ascending (one walk of its DAG).
fn support_of(pool: &Pool, e: ExprId, index: &FxHashMap<ExprId, usize>) -> Vec<usize> {
    let mut s: Vec<usize> = pool.reachable(&[e]).into_iter().filter_map(|id| index.get(&id).copied()).collect();
    s.sort_unstable();
    s
}

/// Where each part of a [`Quadratic`] depends on the coordinates.
pub struct Sparsity {
    /// `support[j][k]`: the coordinates M_jk depends on, ascending.
    pub support: Vec<Vec<Vec<usize>>>,
    /// For each coordinate, the entries (j ≤ k) of M that depend on it.
    pub depends: Vec<Vec<(usize, usize)>>,
    /// ∂L₀/∂q_i for every coordinate.
    pub grad_l0: Vec<ExprId>,
}

/// Dot products of Jacobian columns, each with the masses that share it.
type Groups = Vec<(ExprId, Vec<ExprId>)>;

/// ∂e/∂x_i for every symbol x_i of `q` (coordinates or velocities). A long sum (the potential of a thousand
/// springs) is split by the coordinates each term contains, so each term is
/// differentiated only by its own coordinates: O(size), not O(n·size).
pub fn sparse_gradient(pool: &mut Pool, e: ExprId, q: &[ExprId]) -> Vec<ExprId> {
    let n = q.len();
    let terms: Vec<ExprId> = match pool.node(e) {
        sym::Node::Add(terms) => terms.to_vec(),
        _ => vec![e],
    };
    let index = coordinate_index(q);
    let mut parts: Vec<Vec<ExprId>> = vec![Vec::new(); n];
    for term in terms.iter() {
        for c in support_of(pool, *term, &index) {
            parts[c].push(pool.diff(*term, q[c]));
        }
    }
    parts.iter().map(|p| pool.add(p)).collect()
}

/// T of point masses by the notes' recipe: with x_k(q, t),
/// T = ½ Σ_k m_k |Σ_i ∂x_k/∂q_i q_i' + ∂x_k/∂t|², as a quadratic form:
/// M_ij = Σ_k m_k ∂x_k/∂q_i · ∂x_k/∂q_j, b_i = Σ_k m_k ∂x_k/∂q_i · ∂x_k/∂t,
/// L₀ = T₀ = ½ Σ_k m_k |∂x_k/∂t|².
///
/// Particles whose Jacobian columns give the same dot product (the links of
/// a chain all share the upper links' columns) are grouped first, so each
/// dot product is simplified once and multiplied by the sum of the masses.
pub fn particles(pool: &mut Pool, particles: &[(ExprId, Vec<ExprId>)], v: &Vars) -> Quadratic {
    let n = v.q.len();
    // For each entry: dot product → masses sharing it, in first-seen order.
    let mut m_groups: Vec<Vec<Groups>> = vec![vec![Vec::new(); n]; n];
    let mut b_groups: Vec<Groups> = vec![Vec::new(); n];
    let mut t0_groups: Groups = Vec::new();
    fn group(groups: &mut Groups, dot: ExprId, mass: ExprId) {
        match groups.iter_mut().find(|(d, _)| *d == dot) {
            Some((_, masses)) => masses.push(mass),
            None => groups.push((dot, vec![mass])),
        }
    }
    // Dot products of Jacobian columns, shared between particles: the links of
    // a chain have equal columns for the coordinates they share.
    type Column = [ExprId; 3];
    let mut dots: FxHashMap<(Column, Column), ExprId> = FxHashMap::default();
    let mut dot = |pool: &mut Pool, a: Column, b: Column| -> ExprId {
        *dots.entry((a, b)).or_insert_with(|| {
            let parts: Vec<ExprId> = (0..3).map(|d| pool.mul2(a[d], b[d])).collect();
            pool.add(&parts)
        })
    };
    let zero = pool.zero();
    for (mass, position) in particles {
        let column = |pool: &mut Pool, x: ExprId| -> Column {
            let mut c = [zero; 3];
            for (d, &xd) in position.iter().enumerate() {
                c[d] = pool.diff(xd, x);
            }
            c
        };
        let jac: Vec<Column> = v.q.iter().map(|&qi| column(pool, qi)).collect();
        let dxdt = column(pool, v.t);
        let moving: Vec<usize> = (0..n).filter(|&i| jac[i] != [zero; 3]).collect();
        for (a, &i) in moving.iter().enumerate() {
            for &j in &moving[a..] {
                let d = dot(pool, jac[i], jac[j]);
                if !pool.is_zero(d) {
                    group(&mut m_groups[i][j], d, *mass);
                }
            }
            if dxdt != [zero; 3] {
                let d = dot(pool, jac[i], dxdt);
                if !pool.is_zero(d) {
                    group(&mut b_groups[i], d, *mass);
                }
            }
        }
        if dxdt != [zero; 3] {
            let d = dot(pool, dxdt, dxdt);
            if !pool.is_zero(d) {
                group(&mut t0_groups, d, *mass);
            }
        }
    }
    let assemble = |pool: &mut Pool, groups: &[(ExprId, Vec<ExprId>)]| -> ExprId {
        let parts: Vec<ExprId> = groups
            .iter()
            .map(|(dot, masses)| {
                let dot = pool.simplify_in(*dot, v.is_var);
                let total = pool.add(masses);
                pool.mul2(total, dot)
            })
            .collect();
        match parts.len() {
            0 => pool.zero(),
            1 => parts[0],
            _ => {
                let sum = pool.add(&parts);
                pool.simplify_in(sum, v.is_var)
            }
        }
    };
    let mut form = Quadratic::zero(pool, n);
    for i in 0..n {
        for j in i..n {
            let e = assemble(pool, &m_groups[i][j]);
            form.m[i][j] = e;
            form.m[j][i] = e;
        }
        form.b[i] = assemble(pool, &b_groups[i]);
    }
    let t0 = assemble(pool, &t0_groups);
    let half = pool.rational(1, 2);
    form.l0 = pool.mul2(half, t0);
    form
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Setup {
        pool: Pool,
        q: Vec<ExprId>,
        qd: Vec<ExprId>,
        t: ExprId,
    }

    fn setup(names: &[&str]) -> Setup {
        let mut pool = Pool::default();
        let q = names.iter().map(|c| pool.var(c, 0)).collect();
        let qd = names.iter().map(|c| pool.var(c, 1)).collect();
        let t = pool.symbol("t");
        Setup { pool, q, qd, t }
    }

    fn is_var(s: Symbol) -> bool {
        let _ = s;
        true
    }

    /// f_i by the textbook route: f = −(d/dt ∂L/∂q' − ∂L/∂q) at q'' = 0.
    fn brute_force_forcing(s: &mut Setup, l: ExprId) -> Vec<ExprId> {
        let n = s.q.len();
        (0..n)
            .map(|i| {
                let pool = &mut s.pool;
                let p = pool.diff(l, s.qd[i]);
                let mut terms = Vec::new();
                for k in 0..n {
                    let d = pool.diff(p, s.q[k]);
                    terms.push(pool.mul2(d, s.qd[k]));
                }
                terms.push(pool.diff(p, s.t));
                let dl = pool.diff(l, s.q[i]);
                terms.push(pool.neg(dl));
                let sum = pool.add(&terms);
                pool.neg(sum)
            })
            .collect()
    }

    #[test]
    fn split_recovers_the_parts_and_the_forcing_matches_euler_lagrange() {
        let mut s = setup(&["x", "y", "z"]);
        // M depends on q and t, b on q and t (a magnetic-like term), L₀ on q and t.
        let l = s
            .pool
            .parse(
                "(2 + sin(y)^2)*x'^2/2 + x*z*x'*y' + exp(t/3)*y'^2 + (1 + x^2)*z'^2/2 \
                 + cos(t)*y*x' - x*z' + t*x*y - y^4/4 + z*sin(t)",
            )
            .unwrap();
        let v = Vars { q: &s.q, qd: &s.qd, t: s.t, is_var: &is_var };
        let form = Quadratic::split(&mut s.pool, l, &v).expect("quadratic");
        let expected = brute_force_forcing(&mut s, l);
        let v = Vars { q: &s.q, qd: &s.qd, t: s.t, is_var: &is_var };
        let sp = form.sparsity(&mut s.pool, &s.q);
        let rows = form.forcing(&mut s.pool, &v, &sp);
        for (got, want) in rows.into_iter().zip(expected) {
            let d = s.pool.sub(got, want);
            assert!(probe::is_zero(&mut s.pool, d), "{}", s.pool.display(d));
        }
        let momenta = form.momenta(&mut s.pool, &s.qd);
        for (i, p) in momenta.into_iter().enumerate() {
            let want = s.pool.diff(l, s.qd[i]);
            let d = s.pool.sub(p, want);
            assert!(probe::is_zero(&mut s.pool, d));
        }
        let h = form.energy_function(&mut s.pool, &s.qd);
        let mut terms: Vec<ExprId> = (0..3)
            .map(|i| {
                let p = s.pool.diff(l, s.qd[i]);
                s.pool.mul2(s.qd[i], p)
            })
            .collect();
        terms.push(s.pool.neg(l));
        let want = s.pool.add(&terms);
        let d = s.pool.sub(h, want);
        assert!(probe::is_zero(&mut s.pool, d));
    }

    #[test]
    fn split_refuses_what_is_not_quadratic() {
        let mut s = setup(&["x"]);
        for text in ["sqrt(1 + x'^2)", "x'^4", "x'^3*x", "exp(x')"] {
            let l = s.pool.parse(text).unwrap();
            let v = Vars { q: &s.q, qd: &s.qd, t: s.t, is_var: &is_var };
            assert!(Quadratic::split(&mut s.pool, l, &v).is_none(), "{text}");
        }
    }

    #[test]
    fn particles_give_the_kinetic_energy_of_the_recipe() {
        // A pendulum hanging from a point moving along x as a(t), plus a free mass.
        let mut s = setup(&["th", "u"]);
        let positions = [["a0*cos(w*t) + l*sin(th)", "-l*cos(th)"], ["u", "l*th"]];
        let masses = ["m", "M"];
        let parts: Vec<(ExprId, Vec<ExprId>)> = masses
            .iter()
            .zip(positions)
            .map(|(m, pos)| {
                let m = s.pool.parse(m).unwrap();
                let pos = pos.iter().map(|x| s.pool.parse(x).unwrap()).collect();
                (m, pos)
            })
            .collect();
        let v = Vars { q: &s.q, qd: &s.qd, t: s.t, is_var: &is_var };
        let form = particles(&mut s.pool, &parts, &v);
        let t_form = form.lagrangian(&mut s.pool, &s.qd);
        // T = ½ Σ m |dx/dt|² with the total time derivative, written out.
        let mut terms = Vec::new();
        for (m, pos) in &parts {
            for &x in pos {
                let mut rate = vec![s.pool.diff(x, s.t)];
                for k in 0..2 {
                    let d = s.pool.diff(x, s.q[k]);
                    rate.push(s.pool.mul2(d, s.qd[k]));
                }
                let rate = s.pool.add(&rate);
                let sq = s.pool.powi(rate, 2);
                let half = s.pool.rational(1, 2);
                terms.push(s.pool.mul(&[half, *m, sq]));
            }
        }
        let want = s.pool.add(&terms);
        let d = s.pool.sub(t_form, want);
        assert!(probe::is_zero(&mut s.pool, d), "{}", s.pool.display(d));
        // The shared dot product: M_th,th = m l² + M l², one simplified entry.
        assert_eq!(s.pool.display(form.m[0][0]).to_string(), "l^2*(M + m)");
    }
}
