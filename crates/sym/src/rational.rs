//! Rational functions: [`Pool::together`] writes an expression as one quotient
//! `N/D` of expanded polynomials and cancels what the two share.
//!
//! The polynomials are in "atoms": symbols, π, function applications, and
//! powers with a non-integer or symbolic exponent, whose insides are themselves
//! put together. A power `u^(p/q)` is split as `u^n·u^f` with `n` an integer and
//! `0 < f < 1`, so `u^(3/2)` and `u^(-1/2)` share the atom `u^(1/2)` and the
//! integer parts join the quotient. The denominator is kept as a product of
//! primitive polynomials (content 1, leading coefficient positive) with
//! exponents, so `-y'^2 - 1` and `y'^2 + 1` are recognized as one factor.
//!
//! Cancellation: the numerator is divided exactly (sparse multivariate
//! division, lexicographic order) by each factor of the denominator as often
//! as it goes (`(x^2 - 1)/(x - 1) → x + 1`), and by the common powers of
//! atoms; the numeric content goes into the numerator's coefficients. When
//! the numerator and a denominator factor are polynomials in one and the same
//! atom, their GCD (Euclid over the rationals) is cancelled too
//! (`(x^2 - 1)/(x^2 + 2*x + 1) → (x - 1)/(x + 1)`). This is not a full
//! multivariate GCD: a factor shared only partly by polynomials in several
//! atoms stays (`(x^2 - y^2)/(x^2 + 2*x*y + y^2)` is not reduced), and two
//! denominator factors are not compared with each other.
//!
//! For deciding zero, [`Pool::together_trig`] goes further: sines and cosines
//! of sums and of integer multiples are expanded by the addition theorems
//! (`sin(a − b) → sin a·cos b − cos a·sin b`, `cos 2u → cos²u − sin²u`), `tan`
//! becomes `sin/cos`, and in the numerator `sin²u` is reduced to `1 − cos²u`
//! and `cosh²u` to `1 + sinh²u`. The reduced numerator is a normal form of the
//! trigonometric polynomials in those atoms (the remainder modulo
//! `sin²u + cos²u − 1`), so an identity such as `sin²u + cos²u = 1` or
//! `sin(a − b) = sin a cos b − cos a sin b` is shown by a numerator of zero.
//!
//! Entry points: [`Pool::together`] and [`Pool::simplify_rational`] (the shorter
//! of `e` and its quotient form), and [`Pool::together_trig`].

use crate::expr::{ExprId, Func, Node, Pool};
use crate::number::{Number, Rational};
use rustc_hash::FxHashMap;
use std::cmp::Ordering;
use std::collections::BTreeMap;

/// Most terms a product of polynomials may have; beyond it the subexpression
/// stays an atom.
const MAX_TERMS: usize = 4096;
/// Most steps of one exact division before it is abandoned as inexact.
const MAX_DIVISION_STEPS: usize = 20_000;
/// Largest integer power of a quotient that is expanded.
const MAX_POWER: i128 = 12;
/// Most terms of an angle whose sine and cosine [`Pool::together_trig`]
/// expands by the addition theorems (the expansion has up to 2^k terms).
const MAX_ANGLE_TERMS: usize = 8;
/// Largest integer multiple `n` of an angle whose sine and cosine are written
/// as polynomials in `sin u` and `cos u` (of degree n).
const MAX_ANGLE_MULTIPLE: i128 = 12;

/// A monomial: atoms with positive exponents, sorted by atom id.
#[derive(Clone, PartialEq, Eq, Hash, Debug, Default)]
struct Mono(Vec<(ExprId, u32)>);

impl Ord for Mono {
    /// Lexicographic order with the atom of smallest id most significant.
    fn cmp(&self, o: &Self) -> Ordering {
        let (a, b) = (&self.0, &o.0);
        for i in 0.. {
            match (a.get(i), b.get(i)) {
                (None, None) => return Ordering::Equal,
                (Some(_), None) => return Ordering::Greater,
                (None, Some(_)) => return Ordering::Less,
                (Some(&(x, m)), Some(&(y, n))) => {
                    if x != y {
                        return if x < y { Ordering::Greater } else { Ordering::Less };
                    }
                    if m != n {
                        return m.cmp(&n);
                    }
                }
            }
        }
        unreachable!("the loop returns")
    }
}

impl PartialOrd for Mono {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Mono {
    fn atom(a: ExprId) -> Mono {
        Mono(vec![(a, 1)])
    }

    fn times(&self, o: &Mono) -> Mono {
        let (a, b) = (&self.0, &o.0);
        let mut out = Vec::with_capacity(a.len() + b.len());
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            match (a.get(i), b.get(j)) {
                (Some(&(x, m)), Some(&(y, n))) if x == y => {
                    out.push((x, m + n));
                    i += 1;
                    j += 1;
                }
                (Some(&(x, m)), Some(&(y, _))) if x < y => {
                    out.push((x, m));
                    i += 1;
                }
                (Some(&p), None) => {
                    out.push(p);
                    i += 1;
                }
                (_, Some(&q)) => {
                    out.push(q);
                    j += 1;
                }
                (None, None) => unreachable!("the loop condition"),
            }
        }
        Mono(out)
    }

    /// `self / o` when `o` divides `self`.
    fn over(&self, o: &Mono) -> Option<Mono> {
        let mut out = Vec::with_capacity(self.0.len());
        let mut j = 0;
        for &(x, m) in &self.0 {
            match o.0.get(j) {
                Some(&(y, n)) if y == x => {
                    if n > m {
                        return None;
                    }
                    if m > n {
                        out.push((x, m - n));
                    }
                    j += 1;
                }
                Some(&(y, _)) if y < x => return None,
                _ => out.push((x, m)),
            }
        }
        (j == o.0.len()).then_some(Mono(out))
    }

    fn exponent(&self, a: ExprId) -> u32 {
        self.0.iter().find(|p| p.0 == a).map_or(0, |p| p.1)
    }
}

/// A polynomial: nonzero coefficients by monomial.
type Poly = BTreeMap<Mono, Number>;

fn constant(n: Number) -> Poly {
    let mut p = Poly::new();
    if !n.is_zero() {
        p.insert(Mono::default(), n);
    }
    p
}

fn atom_poly(a: ExprId) -> Poly {
    let mut p = Poly::new();
    p.insert(Mono::atom(a), Number::ONE);
    p
}

fn add_term(p: &mut Poly, m: Mono, c: Number) {
    if c.is_zero() {
        return;
    }
    match p.get_mut(&m) {
        Some(v) => {
            let s = v.plus(c);
            if s.is_zero() {
                p.remove(&m);
            } else {
                *v = s;
            }
        }
        None => {
            p.insert(m, c);
        }
    }
}

fn poly_add(a: &Poly, b: &Poly) -> Poly {
    let mut out = a.clone();
    for (m, &c) in b {
        add_term(&mut out, m.clone(), c);
    }
    out
}

fn poly_mul(a: &Poly, b: &Poly) -> Option<Poly> {
    if a.len().saturating_mul(b.len()) > MAX_TERMS {
        return None;
    }
    let mut out = Poly::new();
    for (m, &c) in a {
        for (n, &d) in b {
            add_term(&mut out, m.times(n), c.times(d));
        }
    }
    Some(out)
}

fn poly_pow(a: &Poly, n: u32) -> Option<Poly> {
    let mut out = constant(Number::ONE);
    for _ in 0..n {
        out = poly_mul(&out, a)?;
    }
    Some(out)
}

fn scale(a: &Poly, c: Number) -> Poly {
    a.iter().map(|(m, &d)| (m.clone(), d.times(c))).filter(|(_, d)| !d.is_zero()).collect()
}

fn has_float(a: &Poly) -> bool {
    a.values().any(|c| matches!(c, Number::Float(_)))
}

fn recip(n: Number) -> Number {
    match n {
        Number::Rational(r) => r.recip().map_or(Number::float(f64::INFINITY), Number::Rational),
        Number::Float(x) => Number::float(1.0 / x),
    }
}

/// `a / d` when `d` divides `a` exactly (both exact).
fn exact_div(a: &Poly, d: &Poly) -> Option<Poly> {
    let (lm, &lc) = d.last_key_value()?;
    let mut rem = a.clone();
    let mut quot = Poly::new();
    let inv = recip(lc);
    let mut steps = 0;
    while let Some((m, &c)) = rem.last_key_value() {
        steps += 1;
        if steps > MAX_DIVISION_STEPS || rem.len() > MAX_TERMS {
            return None;
        }
        let qm = m.over(lm)?;
        let qc = c.times(inv);
        for (n, &e) in d {
            add_term(&mut rem, n.times(&qm), qc.times(e).negated());
        }
        add_term(&mut quot, qm, qc);
    }
    Some(quot)
}

fn int_gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Splits `a` (nonzero) into content `c`, common monomial `m` and primitive
/// part `p` (`a = c·m·p`; p has content 1 and a positive leading coefficient,
/// or leading coefficient 1 when a coefficient is a float).
fn split(a: &Poly) -> (Number, Mono, Poly) {
    let mut common: Option<Mono> = None;
    for m in a.keys() {
        common = Some(match common {
            None => m.clone(),
            Some(prev) => Mono(
                prev.0.into_iter().filter_map(|(x, e)| Some((x, e.min(m.exponent(x)))).filter(|p| p.1 > 0)).collect(),
            ),
        });
    }
    let common = common.unwrap_or_default();
    let lead = a.last_key_value().map_or(Number::ONE, |p| *p.1);
    let content = if has_float(a) {
        // A subnormal lead has no finite reciprocal: dividing by it would make
        // the coefficients infinite (x^5e-324 became x^inf), so it stays.
        if lead.to_f64().recip().is_finite() {
            lead
        } else {
            Number::ONE
        }
    } else {
        let (mut num, mut den) = (0i128, 1i128);
        let mut exact = true;
        for c in a.values() {
            let r = c.as_rational().unwrap_or(Rational::ONE);
            num = int_gcd(num, r.numer());
            let g = int_gcd(den, r.denom()).max(1);
            match (den / g).checked_mul(r.denom()) {
                Some(l) => den = l,
                None => exact = false,
            }
        }
        match Rational::new(if lead.is_negative() { -num } else { num }, den) {
            Some(r) if exact && !r.is_zero() => Number::Rational(r),
            _ => lead,
        }
    };
    let inv = recip(content);
    let p = a
        .iter()
        .map(|(m, &c)| (m.over(&common).expect("the common monomial divides every term"), c.times(inv)))
        .collect();
    (content, common, p)
}

/// A quotient: an expanded numerator over a monic product of primitive
/// polynomials (single atoms among them) with exponents.
#[derive(Clone, Debug)]
struct Frac {
    num: Poly,
    den: Vec<(Poly, u32)>,
}

impl Frac {
    fn poly(num: Poly) -> Frac {
        Frac { num, den: Vec::new() }
    }
}

fn den_expand(d: &[(Poly, u32)]) -> Option<Poly> {
    let mut out = constant(Number::ONE);
    for (b, k) in d {
        out = poly_mul(&out, &poly_pow(b, *k)?)?;
    }
    Some(out)
}

fn den_exponent(d: &[(Poly, u32)], b: &Poly) -> u32 {
    d.iter().find(|p| p.0 == *b).map_or(0, |p| p.1)
}

/// Cancels what `num` shares with `den`.
fn reduce(mut num: Poly, den: Vec<(Poly, u32)>) -> Frac {
    if num.is_empty() {
        return Frac::poly(num);
    }
    let mut out: Vec<(Poly, u32)> = Vec::with_capacity(den.len());
    let mut work = den;
    while let Some((b, mut k)) = work.pop() {
        if b.len() == 1 {
            // A single atom (bases are monic and primitive).
            let (m, _) = b.first_key_value().expect("one term");
            if let [(a, 1)] = m.0[..] {
                let e = num.keys().map(|n| n.exponent(a)).min().unwrap_or(0);
                let t = e.min(k);
                if t > 0 {
                    let by = Mono(vec![(a, t)]);
                    num = num.into_iter().map(|(n, c)| (n.over(&by).expect("common power"), c)).collect();
                    k -= t;
                }
            }
        } else if !has_float(&b) && !has_float(&num) {
            while k > 0 {
                match exact_div(&num, &b) {
                    Some(q) => {
                        num = q;
                        k -= 1;
                    }
                    None => break,
                }
            }
            // A common factor short of all of b: split b = g·(b/g) and go on.
            if k > 0 {
                if let Some((g, rest, q)) = common_factor(&num, &b) {
                    num = q;
                    let (c, m, rest) = split(&rest);
                    // b is primitive, so c is ±1 by Gauss's lemma; scale all the same.
                    let ck = (0..k).fold(Number::ONE, |acc, _| acc.times(c));
                    num = scale(&num, recip(ck));
                    work.extend(m.0.iter().map(|&(x, e)| (atom_poly(x), e * k)));
                    if rest.len() > 1 || rest.keys().any(|key| !key.0.is_empty()) {
                        work.push((rest, k));
                    }
                    if k > 1 {
                        work.push((g, k - 1));
                    }
                    continue;
                }
            }
        }
        if k > 0 {
            match out.iter_mut().find(|p| p.0 == b) {
                Some(p) => p.1 += k,
                None => out.push((b, k)),
            }
        }
    }
    Frac { num, den: out }
}

/// The atom a polynomial is univariate in (`None` for a constant or several atoms).
fn main_atom(p: &Poly) -> Option<ExprId> {
    let mut atom = None;
    for m in p.keys() {
        match m.0[..] {
            [] => {}
            [(a, _)] if atom.is_none() || atom == Some(a) => atom = Some(a),
            _ => return None,
        }
    }
    atom
}

/// The remainder of `p` divided by `d` (univariate in the same atom, exact).
fn univariate_rem(p: &Poly, d: &Poly) -> Option<Poly> {
    let (lm, &lc) = d.last_key_value()?;
    let inv = recip(lc);
    let mut rem = p.clone();
    for _ in 0..MAX_DIVISION_STEPS {
        let Some((m, &c)) = rem.last_key_value() else { return Some(rem) };
        let Some(qm) = m.over(lm) else { return Some(rem) };
        let qc = c.times(inv);
        for (n, &e) in d {
            add_term(&mut rem, n.times(&qm), qc.times(e).negated());
        }
        if has_float(&rem) {
            return None;
        }
    }
    None
}

/// A nontrivial common factor `g` of `num` and the primitive `b` when both
/// are polynomials in one and the same atom (Euclid over the rationals), with
/// `b/g` and `num/g`. `g` is primitive with a positive leading coefficient.
fn common_factor(num: &Poly, b: &Poly) -> Option<(Poly, Poly, Poly)> {
    let x = main_atom(b)?;
    if main_atom(num) != Some(x) {
        return None;
    }
    let (mut r0, mut r1) = (b.clone(), num.clone());
    while !r1.is_empty() {
        let r = univariate_rem(&r0, &r1)?;
        (r0, r1) = (r1, r);
    }
    let (_, _, g) = split(&r0);
    if g.len() < 2 || g == *b {
        return None;
    }
    let rest = exact_div(b, &g)?;
    let q = exact_div(num, &g)?;
    Some((g, rest, q))
}

fn frac_add(a: &Frac, b: &Frac) -> Option<Frac> {
    let mut lcm = a.den.clone();
    for (base, k) in &b.den {
        match lcm.iter_mut().find(|p| p.0 == *base) {
            Some(p) => p.1 = p.1.max(*k),
            None => lcm.push((base.clone(), *k)),
        }
    }
    let cofactor = |d: &[(Poly, u32)]| -> Vec<(Poly, u32)> {
        lcm.iter().map(|(base, k)| (base.clone(), k - den_exponent(d, base))).filter(|p| p.1 > 0).collect()
    };
    let na = poly_mul(&a.num, &den_expand(&cofactor(&a.den))?)?;
    let nb = poly_mul(&b.num, &den_expand(&cofactor(&b.den))?)?;
    Some(reduce(poly_add(&na, &nb), lcm))
}

fn frac_mul(a: &Frac, b: &Frac) -> Option<Frac> {
    let num = poly_mul(&a.num, &b.num)?;
    let mut den = a.den.clone();
    for (base, k) in &b.den {
        match den.iter_mut().find(|p| p.0 == *base) {
            Some(p) => p.1 += k,
            None => den.push((base.clone(), *k)),
        }
    }
    Some(reduce(num, den))
}

fn frac_inv(a: &Frac) -> Option<Frac> {
    if a.num.is_empty() {
        return None;
    }
    let (c, m, p) = split(&a.num);
    let num = scale(&den_expand(&a.den)?, recip(c));
    let mut den: Vec<(Poly, u32)> = m.0.iter().map(|&(x, e)| (atom_poly(x), e)).collect();
    if p.len() > 1 || p.keys().any(|k| !k.0.is_empty()) {
        den.push((p, 1));
    }
    Some(reduce(num, den))
}

fn frac_powi(a: &Frac, n: i128) -> Option<Frac> {
    if n.abs() > MAX_POWER {
        return None;
    }
    let base = if n < 0 { frac_inv(a)? } else { a.clone() };
    let k = n.unsigned_abs() as u32;
    let num = poly_pow(&base.num, k)?;
    let den = base.den.iter().map(|(b, e)| (b.clone(), e * k)).collect();
    Some(Frac { num, den })
}

/// The memos of one call of [`Pool::together`] or [`Pool::together_trig`].
#[derive(Default)]
struct Memo {
    fracs: FxHashMap<ExprId, Frac>,
    exprs: FxHashMap<ExprId, ExprId>,
    /// Expand sines and cosines and reduce `sin²` ([`Pool::together_trig`]).
    trig: bool,
}

/// `(cos θ, sin θ)` of an angle as quotients.
type CosSin = (Frac, Frac);

/// `cos(a + b)` and `sin(a + b)` from those of `a` and `b`.
fn angle_sum(a: &CosSin, b: &CosSin) -> Option<CosSin> {
    let cc = frac_mul(&a.0, &b.0)?;
    let ss = frac_mul(&a.1, &b.1)?;
    let sc = frac_mul(&a.1, &b.0)?;
    let cs = frac_mul(&a.0, &b.1)?;
    let minus_ss = Frac { num: scale(&ss.num, Number::MINUS_ONE), den: ss.den };
    Some((frac_add(&cc, &minus_ss)?, frac_add(&sc, &cs)?))
}

impl Pool {
    /// `e` as one quotient `N/D`, with sums of quotients put over a common
    /// denominator, numerator and denominator expanded, and common factors
    /// cancelled (see the module documentation for what is cancelled).
    /// Subexpressions whose expansion would exceed a budget stay as they are.
    pub fn together(&mut self, e: ExprId) -> ExprId {
        if self.work_exhausted() {
            return e;
        }
        let mut memo = Memo::default();
        self.together_memo(e, &mut memo)
    }

    /// Like [`Pool::together`], with sines and cosines expanded and `sin²`
    /// reduced (see the module documentation): the quotient of a trigonometric
    /// identity's two sides' difference has the numerator 0. The form is made
    /// for deciding zero, not for reading.
    pub fn together_trig(&mut self, e: ExprId) -> ExprId {
        if self.work_exhausted() {
            return e;
        }
        let mut memo = Memo { trig: true, ..Memo::default() };
        self.together_memo(e, &mut memo)
    }

    /// The shorter of `e` and [`Pool::together`]`(e)`, preferring `e` on a tie.
    pub fn simplify_rational(&mut self, e: ExprId) -> ExprId {
        let t = self.together(e);
        if self.tree_size(t) < self.tree_size(e) {
            t
        } else {
            e
        }
    }

    fn together_memo(&mut self, e: ExprId, memo: &mut Memo) -> ExprId {
        if let Some(&x) = memo.exprs.get(&e) {
            return x;
        }
        let mut f = self.frac_of(e, memo);
        if memo.trig {
            if let Some(num) = self.reduce_squares(&f.num) {
                f.num = num;
            }
        }
        let x = self.frac_expr(&f);
        memo.exprs.insert(e, x);
        x
    }

    /// The quotient form of `e`. Children have smaller ids than their parents,
    /// so visiting the subexpressions by increasing id needs no recursion.
    fn frac_of(&mut self, e: ExprId, memo: &mut Memo) -> Frac {
        if let Some(f) = memo.fracs.get(&e) {
            return f.clone();
        }
        let mut order = self.reachable(&[e]);
        order.sort_unstable();
        for id in order {
            if memo.fracs.contains_key(&id) {
                continue;
            }
            let f = self.frac_node(id, memo).unwrap_or_else(|| Frac::poly(atom_poly(id)));
            memo.fracs.insert(id, f);
        }
        memo.fracs[&e].clone()
    }

    /// The quotient form of one node from those of its children (`None` when
    /// a budget is exceeded or a division by zero would be written).
    fn frac_node(&mut self, id: ExprId, memo: &mut Memo) -> Option<Frac> {
        Some(match self.node(id).clone() {
            Node::Num(n) => Frac::poly(constant(n)),
            Node::Pi | Node::Sym(_) => Frac::poly(atom_poly(id)),
            Node::Add(ts) => {
                let mut acc = memo.fracs[&ts[0]].clone();
                for t in &ts[1..] {
                    acc = frac_add(&acc, &memo.fracs[t])?;
                }
                acc
            }
            Node::Mul(fs) => {
                let mut acc = memo.fracs[&fs[0]].clone();
                for f in &fs[1..] {
                    acc = frac_mul(&acc, &memo.fracs[f])?;
                }
                acc
            }
            Node::Pow(b, x) => match self.as_number(x) {
                Some(Number::Rational(r)) if r.is_integer() => frac_powi(&memo.fracs[&b], r.numer())?,
                Some(Number::Rational(r)) => {
                    // u^(n + f) = u^n · u^f with 0 < f < 1.
                    let n = r.numer().div_euclid(r.denom());
                    let frac = Rational::new(r.numer().rem_euclid(r.denom()), r.denom())?;
                    let base = self.together_memo(b, memo);
                    let fx = self.number(Number::Rational(frac));
                    let atom = self.pow(base, fx);
                    let whole = frac_powi(&memo.fracs[&b], n)?;
                    frac_mul(&Frac::poly(atom_poly(atom)), &whole)?
                }
                _ => {
                    let base = self.together_memo(b, memo);
                    let exp = self.together_memo(x, memo);
                    let atom = self.pow(base, exp);
                    Frac::poly(atom_poly(atom))
                }
            },
            Node::Func(f, a) => {
                let a = self.together_memo(a, memo);
                if memo.trig {
                    if let Some(expanded) = self.trig_frac(f, a) {
                        return Some(expanded);
                    }
                    let value = self.func(f, a);
                    return Some(self.signed_atom(value));
                }
                let atom = self.func(f, a);
                Frac::poly(atom_poly(atom))
            }
            Node::Atan2(y, x) => {
                let y = self.together_memo(y, memo);
                let x = self.together_memo(x, memo);
                let atom = self.atan2(y, x);
                Frac::poly(atom_poly(atom))
            }
        })
    }

    /// A function value as a quotient: a number, or ± an atom (the
    /// constructors write `sin(−u)` as `−sin(u)`).
    fn signed_atom(&mut self, value: ExprId) -> Frac {
        if let Some(n) = self.as_number(value) {
            return Frac::poly(constant(n));
        }
        let (c, atom) = self.split_coeff(value);
        Frac::poly(scale(&atom_poly(atom), c))
    }

    /// `sin`, `cos` or `tan` of the (put together) angle `a` by the addition
    /// theorems, when `a` is a sum or an integer multiple; None when there is
    /// nothing to expand or the expansion exceeds its budget.
    fn trig_frac(&mut self, f: Func, a: ExprId) -> Option<Frac> {
        if !matches!(f, Func::Sin | Func::Cos | Func::Tan) {
            return None;
        }
        let terms = self.terms(a);
        let multiple = |pool: &mut Pool, t: ExprId| match pool.split_coeff(t) {
            (Number::Rational(r), rest) if r.is_integer() && r.numer().abs() >= 2 && rest != pool.one() => {
                Some((r.numer(), rest))
            }
            _ => None,
        };
        let expands = terms.len() > 1 || f == Func::Tan || multiple(self, a).is_some();
        if !expands || terms.len() > MAX_ANGLE_TERMS {
            return None;
        }
        let mut total: Option<CosSin> = None;
        for t in terms {
            let part = match multiple(self, t) {
                Some((n, u)) if n.abs() <= MAX_ANGLE_MULTIPLE => {
                    let base = self.cos_sin_atoms(u);
                    let mut acc = base.clone();
                    for _ in 1..n.abs() {
                        acc = angle_sum(&acc, &base)?;
                    }
                    if n < 0 {
                        acc.1 = Frac { num: scale(&acc.1.num, Number::MINUS_ONE), den: acc.1.den };
                    }
                    acc
                }
                _ => self.cos_sin_atoms(t),
            };
            total = Some(match total {
                None => part,
                Some(acc) => angle_sum(&acc, &part)?,
            });
        }
        let (cos, sin) = total?;
        match f {
            Func::Sin => Some(sin),
            Func::Cos => Some(cos),
            _ => frac_mul(&sin, &frac_inv(&cos)?),
        }
    }

    /// `(cos u, sin u)` of one angle as atoms (numbers where they fold).
    fn cos_sin_atoms(&mut self, u: ExprId) -> CosSin {
        let c = self.func(Func::Cos, u);
        let s = self.func(Func::Sin, u);
        (self.signed_atom(c), self.signed_atom(s))
    }

    /// The numerator with `sin²u` replaced by `1 − cos²u` and `cosh²u` by
    /// `1 + sinh²u` in every monomial (the remainder modulo the Pythagorean
    /// identities); None beyond the budget of terms.
    fn reduce_squares(&mut self, p: &Poly) -> Option<Poly> {
        let mut out = Poly::new();
        for (m, &c) in p {
            let mut kept = Vec::with_capacity(m.0.len());
            let mut factor = constant(Number::ONE);
            for &(a, k) in &m.0 {
                let swap = match *self.node(a) {
                    Node::Func(Func::Sin, u) if k >= 2 => Some((Func::Cos, u, Number::MINUS_ONE)),
                    Node::Func(Func::Cosh, u) if k >= 2 => Some((Func::Sinh, u, Number::ONE)),
                    _ => None,
                };
                let Some((other, u, sign)) = swap else {
                    kept.push((a, k));
                    continue;
                };
                if k % 2 == 1 {
                    kept.push((a, 1));
                }
                // 1 ∓ other(u)²
                let o = self.func(other, u);
                let o = self.signed_atom(o).num;
                let square = poly_mul(&o, &o)?;
                let pythagoras = poly_add(&constant(Number::ONE), &scale(&square, sign));
                factor = poly_mul(&factor, &poly_pow(&pythagoras, k / 2)?)?;
            }
            kept.sort_unstable_by_key(|p| p.0);
            let mut mono = Poly::new();
            mono.insert(Mono(kept), c);
            out = poly_add(&out, &poly_mul(&mono, &factor)?);
            if out.len() > MAX_TERMS {
                return None;
            }
        }
        Some(out)
    }

    fn poly_expr(&mut self, p: &Poly) -> ExprId {
        let mut terms = Vec::with_capacity(p.len());
        for (m, &c) in p {
            let mut fs = Vec::with_capacity(m.0.len() + 1);
            fs.push(self.number(c));
            for &(a, k) in &m.0 {
                let k = self.int(i64::from(k));
                fs.push(self.pow(a, k));
            }
            terms.push(self.mul(&fs));
        }
        self.add(&terms)
    }

    /// `N/D` as an expression, the numerator written `c·m·(primitive sum)`.
    fn frac_expr(&mut self, f: &Frac) -> ExprId {
        if f.num.is_empty() {
            return self.zero();
        }
        let (mut c, m, p) = split(&f.num);
        let mut p = self.poly_expr(&p);
        if self.is_negated(p) {
            p = self.neg(p);
            c = c.negated();
        }
        let mut fs = vec![self.number(c), p];
        for &(a, k) in &m.0 {
            let k = self.int(i64::from(k));
            fs.push(self.pow(a, k));
        }
        for (b, k) in &f.den {
            let b = self.poly_expr(b);
            let k = self.int(-i64::from(*k));
            fs.push(self.pow(b, k));
        }
        self.mul(&fs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check(text: &str, expect: &str) {
        let mut pool = Pool::default();
        let e = pool.parse(text).unwrap();
        let t = pool.together(e);
        assert_eq!(pool.display(t).to_string(), expect, "together({text})");
    }

    #[test]
    fn classic_quotients() {
        check("1/a + 1/b", "(a + b)/(a*b)");
        check("(x^2 - 1)/(x - 1)", "x + 1");
        check("x/(x*y)", "1/y");
        check("1/(1 + 1/x)", "x/(x + 1)");
        check("(1/x - 1/y)/(1/x + 1/y)", "-(x - y)/(x + y)");
        check("x/2 + x/3", "5*x/6");
    }

    #[test]
    fn univariate_common_factors() {
        check("(x^2 - 1)/(x^2 + 2*x + 1)", "(x - 1)/(x + 1)");
        check("1/(x - 1) - 2/(x^2 - 1)", "1/(x + 1)");
        check("(x^3 - x)/(x^2 - 2*x + 1)^2", "x*(x + 1)/(x - 1)^3");
        check("(x^2 - 1)/(x^2 + 1)", "(x^2 - 1)/(x^2 + 1)");
    }

    #[test]
    fn catenary_and_brachistochrone_accelerations() {
        check("-1/(y*(y'^2/(y'^2 + 1) - 1))", "(y'^2 + 1)/y");
        check("-(y'^2 - y'^2/(y'^2 + 1) - y'^4/(y'^2 + 1) - 1)/(y*(2*y'^2/(y'^2 + 1) - 2))", "-(y'^2 + 1)/(2*y)");
    }

    /// Found by fuzzing: the exponent 5e-324 (subnormal) was divided by
    /// itself as a float content, and the power came back as `m^inf`.
    #[test]
    fn a_subnormal_coefficient_is_not_divided_out() {
        check("m^sin(4.9e-324)/(m1 + 0.2*m^sin(4.9e-324))", "5.0*m^5e-324/(1.0*m^5e-324 + 5.0*m1)");
        check("5e-324*x + 5e-324", "5e-324*x + 5e-324");
    }

    #[test]
    fn roots_share_an_atom() {
        check("1/sqrt(u) - u^(-3/2)", "(u - 1)/u^(3/2)");
        check("sqrt(1/x + 1)", "sqrt((x + 1)/x)");
    }

    #[test]
    fn zero_and_large_inputs() {
        // The parser refuses a division by zero; built directly, it stays.
        let mut pool = Pool::default();
        let x = pool.symbol("x");
        let zero = pool.sub(x, x);
        let e = pool.div(x, zero);
        let t = pool.together(e);
        assert_eq!(pool.display(t).to_string(), "0^(-1)*x");
        check("(x + y)^40/(x + y)", "(x + y)^39");
    }

    #[track_caller]
    fn check_trig(text: &str, expect: &str) {
        let mut pool = Pool::default();
        let e = pool.parse(text).unwrap();
        let t = pool.together_trig(e);
        assert_eq!(pool.display(t).to_string(), expect, "together_trig({text})");
    }

    #[test]
    fn trigonometric_identities_have_a_zero_numerator() {
        check_trig("sin(u)^2 + cos(u)^2 - 1", "0");
        check_trig("sin(a - b) - sin(a)*cos(b) + cos(a)*sin(b)", "0");
        check_trig("cos(2*u) - cos(u)^2 + sin(u)^2", "0");
        check_trig("sin(3*u) - 3*sin(u) + 4*sin(u)^3", "0");
        check_trig("tan(u)*cos(u) - sin(u)", "0");
        check_trig("1/cos(u)^2 - tan(u)^2 - 1", "0");
        check_trig("cosh(u)^2 - sinh(u)^2 - 1", "0");
        check_trig("exp(sin(u)^2 + cos(u)^2) - exp(1)", "0");
        check_trig("m*l^2*(sin(q)^2 + cos(q)^2)*q'^2/2 - m*l^2*q'^2/2", "0");
    }

    #[test]
    fn trigonometric_non_identities_stay_nonzero() {
        check_trig("sin(u)^2 - cos(u)^2", "-2*cos(u)^2 + 1");
        check_trig("sin(2*u) - 2*sin(u)", "2*sin(u)*(cos(u) - 1)");
        check_trig("sin(u)^2", "-cos(u)^2 + 1");
    }
}
