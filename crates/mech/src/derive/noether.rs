//! Noether's theorem (notes §2.4): conserved quantities from continuous point
//! symmetries of L. Homogeneity of space gives momentum, isotropy angular
//! momentum; the cyclic coordinates ([`super::judge`]) are the simplest case.
//!
//! Entry point: [`symmetries`]. Each candidate generator ξ(q, t) is a rigid
//! translation of the whole system along x, y or z, a rotation about x, y or z
//! through the origin (both written in the model's coordinates by solving
//! Σ_j ∂r_i/∂q_j ξ_j = δr_i for every particle and body, once, with one
//! right-hand side per candidate), or a shift of one coordinate or of two
//! together. A candidate is a symmetry when δL = Σ ∂L/∂q·ξ + ∂L/∂q'·ξ' equals
//! dF/dt for some F(q, t) (F = 0, or found by integrating δL's coefficients
//! term by term), proven with the zero test of the verdicts, and when neither
//! the constraint forces, dissipation nor generalized forces act along ξ.
//! Then Q = Σ p·ξ − F is conserved. An undecided test claims nothing. Hidden
//! symmetries (the Runge–Lenz vector) are not searched for.

use super::constraint::Constraints;
use super::{decide, BodyMotion, Conserved, ConservedReason, External, Motion, Symbols};
use crate::derive::verdict::{Generator, GeneratorKind};
use crate::model::Model;
use crate::probe::{Decision, Subst};
use sym::{ExprId, Pool, Symbol};

/// The most coordinates searched: beyond, the kinematics' linear system and
/// the pairs of shifts grow quadratically and the derivation's cost is
/// elsewhere (a chain of fifty links has no rigid symmetry to find).
const MAX_COORDINATES: usize = 24;

/// The most coordinates for which pairs of shifts (q_i ± q_j) are tried.
const MAX_PAIRED: usize = 12;

/// The largest tree an entry of the eliminated kinematics may grow to before
/// the candidates that need it are given up.
const MAX_ENTRY_TREE: u64 = 400;

/// The work ([`Pool::work`]) the search may spend; past it, it stops with what
/// it has proven (a proof made before the bound stays a proof).
pub(super) const SEARCH_WORK: u64 = 3_000_000;

/// The conserved quantities of the point symmetries of L, not already in
/// `existing` (cyclic momenta, H). Searched only on the expanded path and
/// for at most [`MAX_COORDINATES`] coordinates.
#[allow(clippy::too_many_arguments)]
pub(super) fn symmetries(
    pool: &mut Pool,
    model: &Model,
    s: &Symbols,
    m: &Motion,
    ext: &External,
    constraints: &Constraints,
    bodies: &[BodyMotion],
    cyclic: &[usize],
    existing: &[Conserved],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Vec<Conserved> {
    let n = s.n();
    if n == 0 || n > MAX_COORDINATES {
        return Vec::new();
    }
    let mut candidates = rigid_candidates(pool, model, s, bodies, is_var);
    candidates.extend(shift_candidates(pool, model, s, m, cyclic));
    let mut found: Vec<Conserved> = Vec::new();
    // Coordinates whose own shift is a symmetry: a pair with one of them adds
    // nothing (q_i ± q_j is a symmetry only if both are, and then its Q is the sum).
    let mut shifted: Vec<usize> = cyclic.to_vec();
    for c in candidates {
        if pool.work_exhausted() {
            break;
        }
        if c.coordinates.len() > 1 && c.coordinates.iter().any(|i| shifted.contains(i)) {
            continue;
        }
        let Some((q_expr, f)) = noether_charge(pool, s, m, ext, constraints, &c.xi, is_var) else {
            continue;
        };
        if is_constant(pool, s, q_expr) || already_known(pool, q_expr, existing.iter().chain(&found)) {
            continue;
        }
        let generator = Generator {
            kind: c.kind,
            axis: c.axis.map(str::to_string),
            coordinates: c.coordinates.iter().map(|&i| s.names[i].clone()).collect(),
            xi: (0..n)
                .filter(|&j| !pool.is_zero(c.xi[j]))
                .map(|j| (s.names[j].clone(), pool.display(c.xi[j]).to_string()))
                .collect(),
            moved: match (model.particles.is_empty(), model.bodies.len()) {
                (false, 0) => "every particle",
                (false, _) => "every particle and body",
                (true, 1) => "the body",
                (true, _) => "every body",
            }
            .to_string(),
        };
        if let [i] = c.coordinates[..] {
            shifted.push(i);
        }
        let name = fresh_name(model, existing.iter().chain(&found), &c.name);
        let f = (!pool.is_zero(f)).then(|| pool.display(f).to_string());
        found.push(Conserved { name, expr: q_expr, reason: ConservedReason::Symmetry { generator, f } });
    }
    found
}

/// A candidate generator: ξ per coordinate and what it is.
struct Candidate {
    kind: GeneratorKind,
    axis: Option<&'static str>,
    coordinates: Vec<usize>,
    xi: Vec<ExprId>,
    name: String,
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Translations and rotations of every particle and body, in the model's
/// coordinates: the solutions of the kinematics' linear system, where it has
/// one. A body's reference point moves as a particle does, and its turn is
/// its angular velocity with ξ for q': ω(ξ) = 0 for a translation, and for a
/// rotation about e, ω(ξ) = e (body components: e's along the body axes). A
/// body placed on another body keeps the search to shifts.
fn rigid_candidates(
    pool: &mut Pool,
    model: &Model,
    s: &Symbols,
    bodies: &[BodyMotion],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Vec<Candidate> {
    if model.particles.is_empty() && model.bodies.is_empty() {
        return Vec::new();
    }
    if model.bodies.iter().any(|b| b.parent.is_some()) || bodies.len() != model.bodies.len() {
        return Vec::new();
    }
    // All positions in one dimension: 2 for the plane, 3 for space.
    let mut dims = model.particles.iter().map(|p| p.position.len()).chain(model.bodies.iter().map(|b| b.dimension));
    let Some(dim) = dims.next() else { return Vec::new() };
    if dim < 2 || dims.any(|d| d != dim) {
        return Vec::new();
    }
    // The points that move: particles' and bodies' reference points.
    let mut points: Vec<Vec<ExprId>> = model.particles.iter().map(|p| p.position.clone()).collect();
    points.extend(bodies.iter().map(|b| b.position[..dim].to_vec()));
    // The right-hand sides δr (and each body's ω): translations along each
    // axis, rotations about z (in the plane) or about each axis (in space).
    let zero = pool.zero();
    let one = pool.one();
    let mut rhs: Vec<(GeneratorKind, usize, Vec<ExprId>)> = Vec::new();
    for (k, _) in AXES.iter().enumerate().take(dim) {
        let mut col = Vec::new();
        for _ in &points {
            col.extend((0..dim).map(|c| if c == k { one } else { zero }));
        }
        col.extend(bodies.iter().flat_map(|_| [zero; 3]));
        rhs.push((GeneratorKind::Translation, k, col));
    }
    let axes: &[usize] = if dim == 2 { &[2] } else { &[0, 1, 2] };
    for &k in axes {
        let mut col = Vec::new();
        for r in &points {
            let at = |c: usize| if c < dim { r[c] } else { zero };
            // e_k × r.
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            let mut d = [zero; 3];
            d[a] = pool.neg(at(b));
            d[b] = at(a);
            col.extend(d[..dim].iter().copied());
        }
        // e_k in body components: its component along each body axis.
        col.extend(bodies.iter().flat_map(|b| [b.axes[0][k], b.axes[1][k], b.axes[2][k]]));
        rhs.push((GeneratorKind::Rotation, k, col));
    }
    // The rows: ∂r/∂q per point component, and ξ_angle = 0 for bodies' angles.
    let mut rows: Vec<Vec<ExprId>> = Vec::new();
    for r in &points {
        for &x in r {
            rows.push(s.q.iter().map(|&q| pool.diff(x, q)).collect());
        }
    }
    for b in bodies {
        for &w in &b.omega {
            rows.push(s.qd.iter().map(|&v| pool.diff(w, v)).collect());
        }
    }
    let columns: Vec<Vec<ExprId>> = rhs.iter().map(|(_, _, c)| c.clone()).collect();
    let solutions = solve(pool, &rows, &columns, is_var);
    let mut out = Vec::new();
    for ((kind, k, col), xi) in rhs.into_iter().zip(solutions) {
        let Some(xi) = xi else { continue };
        // The solution is checked on the original rows, whatever the elimination did.
        let solves = rows.iter().zip(&col).all(|(row, &b)| {
            let terms: Vec<ExprId> = row.iter().zip(&xi).map(|(&a, &x)| pool.mul2(a, x)).collect();
            let lhs = pool.add(&terms);
            let d = pool.sub(lhs, b);
            decide(pool, d, false).is_zero()
        });
        if !solves || xi.iter().all(|&x| pool.is_zero(x)) {
            continue;
        }
        let name = match kind {
            GeneratorKind::Translation => format!("P_{}", AXES[k]),
            _ => format!("L_{}", AXES[k]),
        };
        out.push(Candidate { kind, axis: Some(AXES[k]), coordinates: Vec::new(), xi, name });
    }
    out
}

/// Solves `rows · ξ = column` for each column by Gauss–Jordan elimination
/// with exact pivots (a number first, else an entry free of the coordinates,
/// else one proven nonzero): ξ per column, free unknowns 0, or None where the
/// system has no solution that could be shown, or the entries grew too long.
fn solve(
    pool: &mut Pool,
    rows: &[Vec<ExprId>],
    columns: &[Vec<ExprId>],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Vec<Option<Vec<ExprId>>> {
    let n = rows.first().map_or(0, Vec::len);
    let k = columns.len();
    // The augmented matrix [A | b_1 … b_k].
    let mut a: Vec<Vec<ExprId>> = rows
        .iter()
        .enumerate()
        .map(|(r, row)| row.iter().copied().chain(columns.iter().map(|c| c[r])).collect())
        .collect();
    let mut pivots: Vec<(usize, usize)> = Vec::new();
    let mut used = vec![false; a.len()];
    for col in 0..n {
        let rank = |pool: &mut Pool, e: ExprId| -> Option<u8> {
            if pool.is_zero(e) {
                None
            } else if pool.as_number(e).is_some() {
                Some(0)
            } else if pool.symbols(e).iter().all(|&x| !is_var(x)) {
                Some(1)
            } else if decide(pool, e, false) == Decision::NonZero {
                Some(2)
            } else {
                None
            }
        };
        let mut best: Option<(u8, usize)> = None;
        for r in 0..a.len() {
            if used[r] {
                continue;
            }
            if let Some(score) = rank(pool, a[r][col]) {
                if best.is_none_or(|(b, _)| score < b) {
                    best = Some((score, r));
                }
            }
        }
        let Some((_, p)) = best else {
            // No pivot: the column must vanish in every unused row for ξ_col = 0 to do.
            if (0..a.len()).any(|r| !used[r] && decide(pool, a[r][col], false) != Decision::Zero) {
                return vec![None; k];
            }
            continue;
        };
        used[p] = true;
        let pivot = a[p][col];
        for c in 0..n + k {
            let v = pool.div(a[p][c], pivot);
            a[p][c] = pool.simplify_in(v, is_var);
        }
        for r in 0..a.len() {
            if r == p || pool.is_zero(a[r][col]) {
                continue;
            }
            let factor = a[r][col];
            for c in 0..n + k {
                if pool.is_zero(a[p][c]) {
                    continue;
                }
                let prod = pool.mul2(factor, a[p][c]);
                let v = pool.sub(a[r][c], prod);
                a[r][c] = pool.simplify_in(v, is_var);
                if pool.tree_size(a[r][c]) > MAX_ENTRY_TREE {
                    return vec![None; k];
                }
            }
        }
        pivots.push((p, col));
    }
    (0..k)
        .map(|j| {
            // An unused row left with a nonzero right-hand side: no solution.
            let consistent = (0..a.len()).all(|r| used[r] || decide(pool, a[r][n + j], false).is_zero());
            consistent.then(|| {
                let mut xi = vec![pool.zero(); n];
                for &(p, col) in &pivots {
                    xi[col] = a[p][n + j];
                }
                xi
            })
        })
        .collect()
}

/// Shifts of one coordinate that is not cyclic (a symmetry only up to a total
/// derivative, as for a charge in a magnetic field), and for a model without
/// particles or bodies, of two coordinates together (q_i + q_j or q_i − q_j,
/// as for two bodies written in their own coordinates).
fn shift_candidates(pool: &mut Pool, model: &Model, s: &Symbols, m: &Motion, cyclic: &[usize]) -> Vec<Candidate> {
    let n = s.n();
    let free: Vec<usize> = (0..n).filter(|i| !cyclic.contains(i)).collect();
    let unit = |pool: &mut Pool, pairs: &[(usize, i64)]| -> Vec<ExprId> {
        let mut xi = vec![pool.zero(); n];
        for &(i, c) in pairs {
            xi[i] = pool.int(c);
        }
        xi
    };
    let mut out = Vec::new();
    for &i in &free {
        // ∂L/∂q_i must at least be a total derivative: affine in the velocities.
        if !may_be_total_derivative(pool, s, m.dl_dq[i]) {
            continue;
        }
        let xi = unit(pool, &[(i, 1)]);
        let name = format!("N_{}", s.names[i]);
        out.push(Candidate { kind: GeneratorKind::Shift, axis: None, coordinates: vec![i], xi, name });
    }
    if model.particles.is_empty() && model.bodies.is_empty() && n <= MAX_PAIRED {
        for (a, &i) in free.iter().enumerate() {
            for &j in &free[a + 1..] {
                for sign in [1, -1] {
                    let terms = if sign == 1 {
                        [m.dl_dq[i], m.dl_dq[j]]
                    } else {
                        let neg = pool.neg(m.dl_dq[j]);
                        [m.dl_dq[i], neg]
                    };
                    let sum = pool.add(&terms);
                    if !may_be_total_derivative(pool, s, sum) {
                        continue;
                    }
                    let xi = unit(pool, &[(i, 1), (j, sign)]);
                    let (a, b) = (&s.names[i], &s.names[j]);
                    let name = if sign == 1 { format!("N_{a}_plus_{b}") } else { format!("N_{a}_minus_{b}") };
                    out.push(Candidate { kind: GeneratorKind::Shift, axis: None, coordinates: vec![i, j], xi, name });
                }
            }
        }
    }
    out
}

/// False when `e` is shown not to be affine in the velocities (a total
/// derivative dF(q, t)/dt is): its second derivative in some pair of
/// velocities is refuted to be 0. True also when that is undecided: the
/// later, exact test decides.
fn may_be_total_derivative(pool: &mut Pool, s: &Symbols, e: ExprId) -> bool {
    if pool.is_zero(e) {
        return false;
    }
    for &v in &s.qd {
        let d = pool.diff(e, v);
        if pool.is_zero(d) {
            continue;
        }
        for &w in &s.qd {
            let dd = pool.diff(d, w);
            if !pool.is_zero(dd) && crate::probe::decide_zero_without_rewriting(pool, dd).is_nonzero() {
                return false;
            }
        }
    }
    true
}

/// Q = Σ p·ξ − F and F, when ξ is proven a symmetry: δL = dF/dt, A ξ = 0 for
/// every constraint, and Σ (Q_j − ∂R/∂q'_j) ξ_j = 0. None when any of these is
/// refuted or undecided.
fn noether_charge(
    pool: &mut Pool,
    s: &Symbols,
    m: &Motion,
    ext: &External,
    constraints: &Constraints,
    xi: &[ExprId],
    is_var: &dyn Fn(Symbol) -> bool,
) -> Option<(ExprId, ExprId)> {
    let n = s.n();
    // The constraint forces do no work along ξ.
    for c in &constraints.list {
        let terms: Vec<ExprId> = c.jacobian.iter().zip(xi).map(|(&a, &x)| pool.mul2(a, x)).collect();
        let along = pool.add(&terms);
        if !decide(pool, along, false).is_zero() {
            return None;
        }
    }
    // Nor do dissipation and generalized forces.
    let mut work = Vec::with_capacity(n);
    for j in 0..n {
        if pool.is_zero(xi[j]) {
            continue;
        }
        let mut q_j = ext.forces[j];
        if let Some(r) = ext.dissipation {
            let d = pool.diff(r, s.qd[j]);
            q_j = pool.sub(q_j, d);
        }
        work.push(pool.mul2(q_j, xi[j]));
    }
    let work = pool.add(&work);
    if !decide(pool, work, false).is_zero() {
        return None;
    }
    // δL = Σ ∂L/∂q_j ξ_j + p_j ξ_j', ξ' the total derivative of ξ(q, t).
    let mut terms = Vec::new();
    for j in 0..n {
        if pool.is_zero(xi[j]) {
            continue;
        }
        terms.push(pool.mul2(m.dl_dq[j], xi[j]));
        let rate = total_derivative(pool, s, xi[j]);
        if !pool.is_zero(rate) {
            terms.push(pool.mul2(m.momenta[j], rate));
        }
    }
    let delta = pool.add(&terms);
    let f = match decide(pool, delta, false) {
        Decision::Zero => pool.zero(),
        Decision::Undecided => return None,
        Decision::NonZero => {
            let f = potential_of(pool, s, delta, is_var)?;
            let rate = total_derivative(pool, s, f);
            let rest = pool.sub(delta, rate);
            if !decide(pool, rest, false).is_zero() {
                return None;
            }
            f
        }
    };
    let mut charge: Vec<ExprId> = (0..n).map(|j| pool.mul2(m.momenta[j], xi[j])).collect();
    charge.push(pool.neg(f));
    let charge = pool.add(&charge);
    Some((pool.simplify_in(charge, is_var), f))
}

/// dE/dt along the motion for E(q, q', t) free of the accelerations:
/// Σ ∂E/∂q q' + ∂E/∂t.
fn total_derivative(pool: &mut Pool, s: &Symbols, e: ExprId) -> ExprId {
    let mut terms = Vec::with_capacity(s.n() + 1);
    for (&q, &v) in s.q.iter().zip(&s.qd) {
        let d = pool.diff(e, q);
        if !pool.is_zero(d) {
            terms.push(pool.mul2(d, v));
        }
    }
    terms.push(pool.diff(e, s.t));
    pool.add(&terms)
}

/// F(q, t) with dF/dt = δL, when δL = Σ g_j q_j' + g_t and each g, less what
/// the earlier variables' integrals already give, integrates term by term
/// (sums of monomials in the variable); None otherwise. The caller checks
/// dF/dt = δL exactly.
fn potential_of(pool: &mut Pool, s: &Symbols, delta: ExprId, is_var: &dyn Fn(Symbol) -> bool) -> Option<ExprId> {
    let at_rest: Subst = s.qd.iter().map(|&v| (v, pool.zero())).collect();
    let mut vars: Vec<(ExprId, ExprId)> = s.q.iter().zip(&s.qd).map(|(&q, &v)| (q, pool.diff(delta, v))).collect();
    vars.push((s.t, pool.substitute(delta, &at_rest)));
    let mut f = pool.zero();
    for (x, g) in vars {
        if s.qd.iter().any(|&v| !pool.free_of(g, v)) {
            // δL not affine in the velocities: not a total derivative of F(q, t).
            let g = pool.simplify_in(g, is_var);
            if s.qd.iter().any(|&v| !pool.free_of(g, v)) {
                return None;
            }
        }
        let known = pool.diff(f, x);
        let rest = pool.sub(g, known);
        let rest = pool.simplify_in(rest, is_var);
        if pool.is_zero(rest) {
            continue;
        }
        let part = integrate(pool, rest, x)?;
        f = pool.add2(f, part);
    }
    Some(pool.simplify_in(f, is_var))
}

/// ∫ e dx for a sum of terms each free of x or a product with one factor x^k
/// (k ≠ −1); None for anything else.
fn integrate(pool: &mut Pool, e: ExprId, x: ExprId) -> Option<ExprId> {
    let e = pool.expand(e);
    let mut parts = Vec::new();
    for term in pool.terms(e) {
        if pool.free_of(term, x) {
            parts.push(pool.mul2(term, x));
            continue;
        }
        let factors = pool.factors(term);
        let (with_x, without): (Vec<ExprId>, Vec<ExprId>) = factors.into_iter().partition(|&f| !pool.free_of(f, x));
        let [power] = with_x[..] else { return None };
        let (base, exp) = pool.base_exp(power);
        if base != x {
            return None;
        }
        let k = pool.as_number(exp)?.as_rational()?;
        let k1 = k.checked_add(sym::Rational::ONE)?;
        if k1.is_zero() {
            return None;
        }
        let k1_expr = pool.number(sym::Number::Rational(k1));
        let raised = pool.pow(x, k1_expr);
        let coeff = pool.mul(&without);
        let over = pool.div(raised, k1_expr);
        parts.push(pool.mul2(coeff, over));
    }
    Some(pool.add(&parts))
}

/// True when Q is proven free of q, q' and t: a constant, no news.
fn is_constant(pool: &mut Pool, s: &Symbols, e: ExprId) -> bool {
    s.q.iter().chain(&s.qd).chain([&s.t]).all(|&x| {
        let d = pool.diff(e, x);
        decide(pool, d, false).is_zero()
    })
}

/// True when Q or −Q is proven equal to a quantity already listed.
fn already_known<'a>(pool: &mut Pool, e: ExprId, known: impl Iterator<Item = &'a Conserved>) -> bool {
    for c in known {
        let d = pool.sub(e, c.expr);
        if decide(pool, d, false).is_zero() {
            return true;
        }
        let s = pool.add2(e, c.expr);
        if decide(pool, s, false).is_zero() {
            return true;
        }
    }
    false
}

/// `wanted`, or `wanted2`, `wanted3`, … when a coordinate, parameter, input
/// or listed quantity already has that name.
fn fresh_name<'a>(model: &Model, known: impl Iterator<Item = &'a Conserved> + Clone, wanted: &str) -> String {
    let taken = |name: &str| {
        model.coordinates.iter().any(|c| c.name == name || format!("p_{}", c.name) == name)
            || model.parameters.iter().any(|p| p.name == name)
            || model.inputs.iter().any(|u| u.name == name)
            || known.clone().any(|c| c.name == name)
            || name == "H"
            || name == "E"
            || name == "t"
    };
    if !taken(wanted) {
        return wanted.to_string();
    }
    (2..).map(|k| format!("{wanted}{k}")).find(|name| !taken(name)).unwrap_or_else(|| wanted.to_string())
}

#[cfg(test)]
mod tests {
    use super::integrate;
    use crate::derive::{ConservedReason, Derivation};
    use crate::model::Model;
    use crate::probe;
    use sym::Pool;

    /// The names of the conserved quantities the symmetry search adds to `model`.
    #[track_caller]
    fn check(model: &str, expect: &[&str]) {
        let d = Derivation::new(Model::parse(model, &[]).expect("a model")).expect("a derivation");
        let names: Vec<&str> = d
            .conserved()
            .iter()
            .filter(|c| matches!(c.reason, ConservedReason::Symmetry { .. }))
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(names, expect);
    }

    /// ∫ e dx is found, and its derivative is e again; or it is not found.
    #[track_caller]
    fn check_integral(e: &str, x: &str, found: bool) {
        let mut pool = Pool::default();
        let e = pool.parse(e).unwrap();
        let x = pool.symbol(x);
        match integrate(&mut pool, e, x) {
            Some(f) => {
                assert!(found, "{} integrated", pool.display(e));
                let d = pool.diff(f, x);
                let rest = pool.sub(d, e);
                assert!(probe::is_zero(&mut pool, rest), "∫ = {}", pool.display(f));
            }
            None => assert!(!found, "{} not integrated", pool.display(e)),
        }
    }

    #[test]
    fn integrals_of_sums_of_powers() {
        check_integral("3*x^2*y + y", "x", true);
        check_integral("-B*Q/2", "x", true);
        check_integral("x^(1/2) + t", "x", true);
        check_integral("1/x", "x", false);
        check_integral("sin(x)", "x", false);
    }

    const SPRING: &str = r#"
coordinates = ["x1", "y1", "z1", "x2", "y2", "z2"]
[parameters]
m1 = 1.0
m2 = 2.0
k = 3.0
[[particles]]
mass = "m1"
position = ["x1", "y1", "z1"]
potential = "k*((x1 - x2)^2 + (y1 - y2)^2 + (z1 - z2)^2)/2"
[[particles]]
mass = "m2"
position = ["x2", "y2", "z2"]
"#;

    #[test]
    fn two_masses_on_a_spring_in_space_have_all_six() {
        check(SPRING, &["P_x", "P_y", "P_z", "L_x", "L_y", "L_z"]);
        // Gravity along −z: P_z less the impulse (F = −M g t), and L_z only.
        let heavy = SPRING.replace("[parameters]", "gravity = \"g\"\n[parameters]\ng = 9.81");
        check(&heavy, &["P_x", "P_y", "P_z", "L_z"]);
    }

    #[test]
    fn dissipation_along_the_generator_breaks_it() {
        // Drag on the first mass along x only: P_x is lost, and every rotation
        // that moves x1 (about y and z); P_y, P_z and L_x stay.
        let dragged = SPRING.replace("[parameters]", "dissipation = \"c*x1'^2/2\"\n[parameters]\nc = 0.1");
        check(&dragged, &["P_y", "P_z", "L_x"]);
    }

    #[test]
    fn a_name_taken_by_the_model_is_not_reused() {
        let clash = SPRING.replace("k = 3.0", "k = 3.0\nP_x = 1.0");
        check(&clash, &["P_x2", "P_y", "P_z", "L_x", "L_y", "L_z"]);
    }

    #[test]
    fn a_pendulum_hung_from_a_point_has_none() {
        check(
            r#"
coordinates = ["ph"]
gravity = "g"
[parameters]
g = 9.81
[[particles]]
mass = 1
position = ["sin(ph)", "-cos(ph)"]
"#,
            &[],
        );
    }

    #[test]
    fn an_undecided_change_of_l_claims_nothing() {
        // ∂L/∂x = 2000000*x*exp(-1000000*x^2) is 0 to the last bit at every
        // probe point, and no rewriting removes it: neither proven nor refuted.
        check(
            r#"
coordinates = ["x"]
kinetic = "x'^2/2"
potential = "exp(-1000000*x^2)"
"#,
            &[],
        );
    }
}
