//! The secular equation det(U − Ω²T) = 0 of up to three coordinates, built
//! symbolically at an equilibrium with exact coordinates and solved exactly
//! where it factors (trial roots, then the quadratic formula), each root
//! matched to a numeric frequency.

use super::{fresh_name, short, Mode, SymbolicModes, EXACT_EQUILIBRIUM, MAX_EXACT_EQUILIBRIUM, ROOTS_AGREE};
use crate::derive::Derivation;
use crate::probe::{self, Subst};
use sym::{ExprId, Node, Pool};

/// The secular equation det(U − Ω²T) and, where it factors, its roots.
pub(super) fn symbolic_modes(
    d: &Derivation,
    mut pool_owned: Pool,
    hess: &[Vec<ExprId>],
    q0: &[f64],
    modes: &[Mode],
) -> Result<SymbolicModes, String> {
    let n = q0.len();
    let lam_name = fresh_name(d, "lam");
    let om_name = fresh_name(d, "Om");
    let params: Vec<String> = d.model.parameters.iter().map(|p| p.name.clone()).collect();
    let param_only = |pool: &Pool, e: ExprId| -> bool {
        pool.reachable(&[e]).into_iter().all(|id| match pool.node(id) {
            Node::Sym(s) => params.iter().any(|p| p == pool.name_str(s.name)),
            _ => true,
        })
    };
    // T and U as they are (constant for a quadratic U), else at the
    // equilibrium, which must then be exact: 0, ±1, ... (not a float).
    let mut subst = Subst::default();
    let pool = &mut pool_owned;
    let constant = d.mass_matrix.iter().chain(hess).flatten().all(|&e| param_only(pool, e));
    if !constant {
        for (i, &v) in q0.iter().enumerate() {
            let r = v.round();
            if (v - r).abs() > EXACT_EQUILIBRIUM * (1.0 + v.abs()) || r.abs() > MAX_EXACT_EQUILIBRIUM {
                return Err(format!(
                    "T and U depend on the coordinates, and the equilibrium {} = {} is not an exact integer",
                    d.model.coordinates[i].name,
                    short(v)
                ));
            }
            subst.insert(d.q[i], pool.int(r as i64));
        }
    }
    let mut tm = vec![vec![pool.zero(); n]; n];
    let mut um = vec![vec![pool.zero(); n]; n];
    for i in 0..n {
        for j in 0..n {
            let t = pool.substitute(d.mass_matrix[i][j], &subst);
            tm[i][j] = pool.simplify(t);
            let u = pool.substitute(hess[i][j], &subst);
            um[i][j] = pool.simplify(u);
        }
    }
    if !tm.iter().chain(&um).flatten().all(|&e| param_only(pool, e)) {
        return Err("T or U at the equilibrium still depends on the coordinates".into());
    }
    let lam = pool.symbol(&lam_name);
    let om = pool.symbol(&om_name);
    let a: Vec<Vec<ExprId>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let lt = pool.mul2(lam, tm[i][j]);
                    pool.sub(um[i][j], lt)
                })
                .collect()
        })
        .collect();
    let det = determinant(pool, &a);
    let det = pool.expand(det);
    // Coefficients c_k of λ^k: c_k = (1/k!) d^k det/dλ^k at λ = 0.
    let mut coeffs = Vec::with_capacity(n + 1);
    let mut dk = det;
    let mut fact = 1i64;
    let at_zero: Subst = [(lam, pool.zero())].into_iter().collect();
    for k in 0..=n {
        if k > 0 {
            dk = pool.diff(dk, lam);
            fact *= k as i64;
        }
        let c = pool.substitute(dk, &at_zero);
        let inv = pool.rational(1, fact);
        let c = pool.mul2(inv, c);
        let c = pool.simplify(c);
        coeffs.push(probe::zero_if_proven(pool, c));
    }
    // The secular polynomial in Ω.
    let om2 = pool.powi(om, 2);
    let terms: Vec<ExprId> = coeffs
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let p = pool.powi(om2, k as i64);
            pool.mul2(c, p)
        })
        .collect();
    let secular = pool.add(&terms);
    let mut candidates = vec![pool.zero()];
    for i in 0..n {
        if !probe::is_zero(pool, tm[i][i]) {
            candidates.push(pool.div(um[i][i], tm[i][i]));
        }
        for j in 0..n {
            if i == j {
                continue;
            }
            for sign in [1i64, -1] {
                let s = pool.int(sign);
                let uij = pool.mul2(s, um[i][j]);
                let tij = pool.mul2(s, tm[i][j]);
                let num = pool.add2(um[i][i], uij);
                let den = pool.add2(tm[i][i], tij);
                if !probe::is_zero(pool, den) {
                    candidates.push(pool.div(num, den));
                }
            }
        }
    }
    let roots = solve(pool, coeffs, &candidates);
    let (omega_squared, frequencies) = match roots {
        Some(roots) => match_roots(d, pool, roots, modes),
        None => (None, None),
    };
    Ok(SymbolicModes { pool: pool_owned, t_matrix: tm, u_matrix: um, omega: om, secular, omega_squared, frequencies })
}

/// Orders the exact roots like the numeric Ω² and takes their square roots;
/// None when they do not match (a closed form must agree with the numbers).
pub(super) fn match_roots(
    d: &Derivation,
    pool: &mut Pool,
    roots: Vec<ExprId>,
    modes: &[Mode],
) -> (Option<Vec<ExprId>>, Option<Vec<ExprId>>) {
    let env = |name: &str| d.model.parameter(name);
    let mut valued = Vec::new();
    for r in roots {
        match pool.eval(r, &env) {
            Ok(v) if v.is_finite() => valued.push((v, r)),
            _ => return (None, None),
        }
    }
    valued.sort_by(|a, b| a.0.total_cmp(&b.0));
    let scale = modes.iter().fold(0.0f64, |m, x| m.max(x.omega_squared.abs())).max(f64::MIN_POSITIVE);
    if valued.len() != modes.len()
        || valued.iter().zip(modes).any(|((v, _), m)| (v - m.omega_squared).abs() > ROOTS_AGREE * scale)
    {
        return (None, None);
    }
    let sq: Vec<ExprId> = valued.iter().map(|&(_, r)| r).collect();
    let om: Vec<ExprId> = sq
        .iter()
        .map(|&r| {
            let s = pool.sqrt(r);
            pool.simplify(s)
        })
        .collect();
    (Some(sq), Some(om))
}

/// Roots of Σ c_k λ^k: trial roots first (deflating by each one found), then
/// the formula for degree ≤ 2. None when a cubic has no trial root.
pub(super) fn solve(pool: &mut Pool, mut c: Vec<ExprId>, candidates: &[ExprId]) -> Option<Vec<ExprId>> {
    while c.len() > 1 && probe::is_zero(pool, *c.last()?) {
        c.pop();
    }
    let deg = c.len() - 1;
    match deg {
        0 => return Some(Vec::new()),
        1 => {
            let r = pool.div(c[0], c[1]);
            let r = pool.neg(r);
            return Some(vec![pool.simplify(r)]);
        }
        _ => {}
    }
    for &r in candidates {
        let mut terms = Vec::new();
        for (k, &ck) in c.iter().enumerate() {
            let p = pool.powi(r, k as i64);
            terms.push(pool.mul2(ck, p));
        }
        let value = pool.add(&terms);
        if probe::is_zero(pool, value) {
            // Synthetic division: c(λ) = (λ − r) b(λ).
            let mut b = vec![pool.zero(); deg];
            b[deg - 1] = c[deg];
            for k in (1..deg).rev() {
                let rb = pool.mul2(r, b[k]);
                let s = pool.add2(c[k], rb);
                b[k - 1] = pool.simplify(s);
            }
            let mut rest = solve(pool, b, candidates)?;
            rest.push(pool.simplify(r));
            return Some(rest);
        }
    }
    if deg == 2 {
        let (a, b, cc) = (c[2], c[1], c[0]);
        let b2 = pool.powi(b, 2);
        let four = pool.int(4);
        let fac = pool.mul(&[four, a, cc]);
        let disc = pool.sub(b2, fac);
        let disc = pool.simplify(disc);
        let sq = pool.sqrt(disc);
        let two = pool.int(2);
        let two_a = pool.mul2(two, a);
        let mb = pool.neg(b);
        let r1 = pool.sub(mb, sq);
        let r1 = pool.div(r1, two_a);
        let r2 = pool.add2(mb, sq);
        let r2 = pool.div(r2, two_a);
        return Some(vec![r1, r2]);
    }
    None
}

/// det A by cofactor expansion (n ≤ 3).
pub(super) fn determinant(pool: &mut Pool, a: &[Vec<ExprId>]) -> ExprId {
    let n = a.len();
    match n {
        0 => pool.one(),
        1 => a[0][0],
        _ => {
            let mut terms = Vec::with_capacity(n);
            for j in 0..n {
                let minor: Vec<Vec<ExprId>> = a[1..]
                    .iter()
                    .map(|row| row.iter().enumerate().filter(|&(k, _)| k != j).map(|(_, &x)| x).collect())
                    .collect();
                let m = determinant(pool, &minor);
                let mut t = pool.mul2(a[0][j], m);
                if j % 2 == 1 {
                    t = pool.neg(t);
                }
                terms.push(t);
            }
            pool.add(&terms)
        }
    }
}
