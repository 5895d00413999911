//! Exact integration of a polynomial density over a box.
//!
//! [`as_polynomial`] decides whether an expression is a polynomial in the
//! integration variables x, y, z (after expansion: every term a coefficient
//! free of x, y, z times x^i y^j z^k with natural exponents) and returns its
//! monomials; [`integrate_monomials`] integrates such a polynomial, times an
//! extra monomial weight, over a box, monomial by monomial:
//! ∫ x^i dx from x0 to x1 = (x1^(i+1) − x0^(i+1))/(i+1).

use sym::{ExprId, Node, Number, Pool};

/// One term of a polynomial: a coefficient free of x, y, z and the exponents of x, y, z.
pub type Monomial = (ExprId, [u32; 3]);

/// Highest exponent accepted per variable (a guard against absurd input).
const MAX_DEGREE: i128 = 64;

/// The monomials of `e` as a polynomial in `vars` (the symbol nodes of x, y, z),
/// or `None` when `e` is not a polynomial in them.
pub fn as_polynomial(pool: &mut Pool, e: ExprId, vars: [ExprId; 3]) -> Option<Vec<Monomial>> {
    let expanded = pool.expand(e);
    let mut out: Vec<Monomial> = Vec::new();
    for term in pool.terms(expanded) {
        let mut coeff = Vec::new();
        let mut exps = [0u32; 3];
        for f in pool.factors(term) {
            if vars.iter().all(|&v| pool.free_of(f, v)) {
                coeff.push(f);
                continue;
            }
            let (base, exp) = pool.base_exp(f);
            let k = vars.iter().position(|&v| v == base)?;
            let n = match pool.node(exp) {
                Node::Num(Number::Rational(r)) if r.is_integer() && !r.is_negative() && r.numer() <= MAX_DEGREE => {
                    r.numer() as u32
                }
                _ => return None,
            };
            exps[k] += n;
        }
        let c = pool.mul(&coeff);
        match out.iter_mut().find(|(_, e)| *e == exps) {
            Some((prev, _)) => *prev = pool.add2(*prev, c),
            None => out.push((c, exps)),
        }
    }
    Some(out)
}

/// ∫ over the box `region` (per axis [lower, upper]) of the polynomial times
/// x^w0 y^w1 z^w2, exactly.
pub fn integrate_monomials(pool: &mut Pool, poly: &[Monomial], weight: [u32; 3], region: &[[ExprId; 2]; 3]) -> ExprId {
    let mut terms = Vec::with_capacity(poly.len());
    for &(c, exps) in poly {
        let mut factors = vec![c];
        for axis in 0..3 {
            let n = i64::from(exps[axis] + weight[axis]) + 1;
            let [lo, hi] = region[axis];
            let up = pool.powi(hi, n);
            let down = pool.powi(lo, n);
            let diff = pool.sub(up, down);
            let inv = pool.rational(1, n);
            factors.push(pool.mul2(inv, diff));
        }
        terms.push(pool.mul(&factors));
    }
    pool.add(&terms)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars(pool: &mut Pool) -> [ExprId; 3] {
        [pool.symbol("x"), pool.symbol("y"), pool.symbol("z")]
    }

    #[track_caller]
    fn check_polynomial(text: &str, expect: Option<usize>) {
        let mut pool = Pool::default();
        let v = vars(&mut pool);
        let e = pool.parse(text).unwrap();
        assert_eq!(as_polynomial(&mut pool, e, v).map(|p| p.len()), expect, "{text}");
    }

    #[test]
    fn recognizes_polynomials() {
        check_polynomial("rho", Some(1));
        check_polynomial("rho*(1 + x/a)", Some(2));
        check_polynomial("(x + y)^2*k", Some(3));
        check_polynomial("x*y*z/(a*b)", Some(1));
        check_polynomial("exp(x)", None);
        check_polynomial("1/x", None);
        check_polynomial("sqrt(x)", None);
        check_polynomial("sin(a)*x^3", Some(1));
        check_polynomial("x^a", None);
    }

    #[track_caller]
    fn check_integral(density: &str, weight: [u32; 3], region: [[&str; 2]; 3], expect: &str) {
        let mut pool = Pool::default();
        let v = vars(&mut pool);
        let e = pool.parse(density).unwrap();
        let poly = as_polynomial(&mut pool, e, v).unwrap();
        let region = region.map(|r| r.map(|s| pool.parse(s).unwrap()));
        let i = integrate_monomials(&mut pool, &poly, weight, &region);
        let i = pool.simplify(i);
        assert_eq!(pool.display(i).to_string(), expect, "{density} {weight:?}");
    }

    #[test]
    fn integrates_over_boxes() {
        let unit = [["0", "a"], ["0", "b"], ["0", "c"]];
        check_integral("rho", [0, 0, 0], unit, "a*b*c*rho");
        check_integral("rho*(1 + x/a)", [0, 0, 0], unit, "3*a*b*c*rho/2");
        check_integral("rho*(1 + x/a)", [1, 0, 0], unit, "5*a^2*b*c*rho/6");
        check_integral("x*y", [0, 0, 0], [["-1", "1"], ["0", "2"], ["0", "1"]], "0");
    }
}
