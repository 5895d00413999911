//! Simplification beyond the constructors' canonical form: expansion,
//! trigonometric combination, factoring common terms, and collecting in a set
//! of variables.
//!
//! Entry points: [`Pool::simplify`] (generic) and [`Pool::simplify_in`] (collect
//! the coefficients of the given variables, as the notes write equations of
//! motion: `(mA + mB)*lA^2*a'' + …`), and [`Pool::is_identically_zero`], which
//! tries these rewrites and the quotient form to show that an expression is 0. Both keep the shorter of the input and the
//! rewritten form (and, where a sum stands in a denominator, the single
//! quotient of [`Pool::together`]), so simplification never makes an
//! expression longer, and every rewrite is an identity (the property tests
//! check values at random points).

use crate::expr::{ExprId, Func, Node, Pool, Symbol};
use crate::number::{Number, Rational};
use rustc_hash::FxHashMap;

/// Most terms an expansion may produce before it gives up and keeps the product.
const MAX_EXPANDED_TERMS: usize = 4096;
/// Cache keys of the memoized rewrites.
const EXPAND: u8 = 0;
const TRIG: u8 = 1;
const FACTOR: u8 = 2;
/// Whether a node has a negative power of a sum inside (stored as 1 or 0).
const QUOTIENT: u8 = 3;

/// Largest power of a sum that is expanded.
const MAX_EXPANDED_POWER: i128 = 12;

impl Pool {
    /// The terms of a sum (a non-sum is one term).
    pub fn terms(&self, e: ExprId) -> Vec<ExprId> {
        match self.node(e) {
            Node::Add(ts) => ts.to_vec(),
            _ => vec![e],
        }
    }

    /// The factors of a product (a non-product is one factor).
    pub fn factors(&self, e: ExprId) -> Vec<ExprId> {
        match self.node(e) {
            Node::Mul(fs) => fs.to_vec(),
            _ => vec![e],
        }
    }

    /// Distributes products over sums and expands small integer powers of sums,
    /// within a budget of terms (beyond it the product is kept as it is).
    pub fn expand(&mut self, e: ExprId) -> ExprId {
        self.cached(EXPAND, e, &mut |pool, id| pool.expand_node(id))
    }

    /// `rewrite` memoized per node: a rewrite is a pure function of the id, so
    /// the many overlapping expressions of a derivation share the work. Each
    /// node is rebuilt from its rewritten children, then rewritten itself; the
    /// walk stops at nodes already in the memo.
    fn cached(&mut self, kind: u8, e: ExprId, f: &mut dyn FnMut(&mut Pool, ExprId) -> ExprId) -> ExprId {
        if let Some(&r) = self.rewrite_cache.get(&(kind, e)) {
            return r;
        }
        // Post-order walk: (id, children done).
        let mut stack = vec![(e, false)];
        while let Some((id, ready)) = stack.pop() {
            if self.rewrite_cache.contains_key(&(kind, id)) {
                continue;
            }
            if !ready {
                stack.push((id, true));
                for c in self.children(self.node(id)) {
                    if !self.rewrite_cache.contains_key(&(kind, c)) {
                        stack.push((c, false));
                    }
                }
                continue;
            }
            let cache = std::mem::take(&mut self.rewrite_cache);
            let rebuilt = self.rebuild(id, |c| cache[&(kind, c)]);
            self.rewrite_cache = cache;
            // Past the work limit a node is kept as rebuilt (still equal to `id`).
            let out = if self.work_exhausted() { rebuilt } else { f(self, rebuilt) };
            self.rewrite_cache.insert((kind, id), out);
        }
        self.rewrite_cache[&(kind, e)]
    }

    fn expand_node(&mut self, id: ExprId) -> ExprId {
        match self.node(id).clone() {
            Node::Mul(fs) => {
                if !fs.iter().any(|&f| matches!(self.node(f), Node::Add(_))) {
                    return id;
                }
                let mut acc: Vec<ExprId> = vec![self.one()];
                for f in fs.iter() {
                    let ts = self.terms(*f);
                    if acc.len() * ts.len() > MAX_EXPANDED_TERMS {
                        return id;
                    }
                    let mut next = Vec::with_capacity(acc.len() * ts.len());
                    for &a in &acc {
                        for &t in &ts {
                            next.push(self.mul2(a, t));
                        }
                    }
                    if self.work_exhausted() {
                        return id;
                    }
                    acc = next;
                }
                self.add(&acc)
            }
            Node::Pow(b, p) => {
                let n = match self.as_number(p) {
                    Some(Number::Rational(r)) if r.is_integer() && r.numer() > 1 => r.numer(),
                    _ => return id,
                };
                if n > MAX_EXPANDED_POWER || !matches!(self.node(b), Node::Add(_)) {
                    return id;
                }
                let ts = self.terms(b);
                let mut acc = ts.clone();
                for _ in 1..n {
                    if acc.len() * ts.len() > MAX_EXPANDED_TERMS {
                        return id;
                    }
                    let mut next = Vec::with_capacity(acc.len() * ts.len());
                    for &a in &acc {
                        for &t in &ts {
                            next.push(self.mul2(a, t));
                        }
                    }
                    let sum = self.add(&next);
                    acc = self.terms(sum);
                }
                self.add(&acc)
            }
            _ => id,
        }
    }

    /// Combines trigonometric terms of every sum in `e`:
    /// `c·R·sin²u + c·R·cos²u → c·R`, `c·R − c·R·sin²u → c·R·cos²u`,
    /// `cos u·cos v ± sin u·sin v → cos(u ∓ v)`, `sin u·cos v ± cos u·sin v → sin(u ± v)`.
    pub fn combine_trig(&mut self, e: ExprId) -> ExprId {
        self.cached(TRIG, e, &mut |pool, id| match pool.node(id) {
            Node::Add(_) => pool.combine_trig_sum(id),
            _ => id,
        })
    }

    fn combine_trig_sum(&mut self, sum: ExprId) -> ExprId {
        // One pass over a growing list: a combined pair is marked dead and its
        // result appended (and itself examined later), so the cost is linear in
        // the number of terms times the factors per term.
        let mut terms = self.terms(sum);
        let mut alive = vec![true; terms.len()];
        let mut index: FxHashMap<ExprId, Vec<usize>> = FxHashMap::default();
        for (i, &t) in terms.iter().enumerate() {
            index.entry(t).or_default().push(i);
        }
        let mut i = 0;
        // Past the work limit the rest stays as it is (the sum is unchanged).
        while i < terms.len() && !self.work_exhausted() {
            if alive[i] {
                if let Some((j, with)) = self.trig_partner(terms[i], i, &index, &alive) {
                    alive[i] = false;
                    alive[j] = false;
                    terms.push(with);
                    alive.push(true);
                    index.entry(with).or_default().push(terms.len() - 1);
                }
            }
            i += 1;
        }
        let out: Vec<ExprId> = terms.iter().zip(&alive).filter(|(_, &a)| a).map(|(&t, _)| t).collect();
        self.add(&out)
    }

    /// A live term `j ≠ i` that combines with `term`, and what the pair becomes.
    fn trig_partner(
        &mut self,
        term: ExprId,
        i: usize,
        index: &FxHashMap<ExprId, Vec<usize>>,
        alive: &[bool],
    ) -> Option<(usize, ExprId)> {
        let find = |id: ExprId| index.get(&id).and_then(|v| v.iter().copied().find(|&j| j != i && alive[j]));
        for f in self.factors(term) {
            let (base, exp) = self.base_exp(f);
            let Node::Func(g, u) = *self.node(base) else { continue };
            if !matches!(g, Func::Sin | Func::Cos) {
                continue;
            }
            let other = if g == Func::Sin { Func::Cos } else { Func::Sin };
            // Pythagorean identities, for a square (or higher power).
            if self.as_number(exp).is_some_and(|n| n.to_f64() >= 2.0) {
                let sq = self.powi(base, -2);
                let rest = self.mul2(term, sq);
                let ob = self.func(other, u);
                let osq = self.powi(ob, 2);
                let partner = self.mul2(rest, osq);
                if let Some(j) = find(partner) {
                    return Some((j, rest));
                }
                // c·R·sin² − c·R = −c·R·cos²
                let neg_rest = self.neg(rest);
                if let Some(j) = find(neg_rest) {
                    let v = self.mul2(neg_rest, osq);
                    return Some((j, v));
                }
            }
            // Angle sums, for factors of exponent one.
            if exp != self.one() {
                continue;
            }
            for f2 in self.factors(term) {
                let Node::Func(Func::Cos, v) = *self.node(f2) else { continue };
                if v == u || f2 == f {
                    continue;
                }
                let inv = self.mul2(f, f2);
                let inv = self.powi(inv, -1);
                let rest = self.mul2(term, inv);
                let su = self.func(other, u);
                let sv = self.func(Func::Sin, v);
                let partner = self.mul(&[rest, su, sv]);
                let neg_partner = self.neg(partner);
                // g = cos: cos u cos v + sin u sin v = cos(u − v)
                // g = sin: sin u cos v + cos u sin v = sin(u + v)
                let (plus_arg, minus_arg) =
                    if g == Func::Cos { (self.sub(u, v), self.add2(u, v)) } else { (self.add2(u, v), self.sub(u, v)) };
                for (candidate, arg) in [(partner, plus_arg), (neg_partner, minus_arg)] {
                    if let Some(j) = find(candidate) {
                        let c = self.func(g, arg);
                        return Some((j, self.mul2(rest, c)));
                    }
                }
            }
        }
        None
    }

    /// Pulls the factors common to every term of each sum out of it
    /// (`a*x^2 + a*x*y → a*x*(x + y)`), including a common rational content.
    pub fn factor_terms(&mut self, e: ExprId) -> ExprId {
        self.cached(FACTOR, e, &mut |pool, id| match pool.node(id) {
            Node::Add(_) => pool.factor_sum(id),
            _ => id,
        })
    }

    fn factor_sum(&mut self, sum: ExprId) -> ExprId {
        // A purely numeric content distributes back (2*(x + y) is 2*x + 2*y
        // in canonical form), so only symbolic common factors stay outside.
        let parts = self.factor_sum_parts(sum);
        self.mul(&parts)
    }

    /// Pulls the factors common to the terms of `e` out, at the top level only.
    pub fn factor_outer(&mut self, e: ExprId) -> ExprId {
        match self.node(e) {
            Node::Add(_) => self.factor_sum(e),
            _ => e,
        }
    }

    /// The factors common to every term of `sum` followed by the reduced sum
    /// (just `[sum]` when nothing is common).
    fn factor_sum_parts(&mut self, sum: ExprId) -> Vec<ExprId> {
        let terms = self.terms(sum);
        if terms.len() < 2 {
            return vec![sum];
        }
        // Rational content: gcd of numerators over lcm of denominators.
        let mut content: Option<Rational> = None;
        let mut exact = true;
        for &t in &terms {
            match self.split_coeff(t).0 {
                Number::Rational(r) => {
                    content = Some(match content {
                        None => Rational::new(r.numer().abs(), r.denom()).unwrap_or(Rational::ONE),
                        Some(c) => rational_gcd(c, r),
                    })
                }
                Number::Float(_) => exact = false,
            }
        }
        let content = if exact { content.unwrap_or(Rational::ONE) } else { Rational::ONE };
        // Common bases with the smallest numeric exponent.
        let mut common: Option<FxHashMap<ExprId, Rational>> = None;
        for &t in &terms {
            let mut here: FxHashMap<ExprId, Rational> = FxHashMap::default();
            for f in self.factors(t) {
                if self.as_number(f).is_some() {
                    continue;
                }
                let (b, p) = self.base_exp(f);
                if let Some(Number::Rational(r)) = self.as_number(p) {
                    here.insert(b, r);
                }
            }
            common = Some(match common {
                None => here,
                Some(prev) => prev
                    .into_iter()
                    .filter_map(|(b, r)| {
                        let r2 = *here.get(&b)?;
                        // Only pull out powers with the same sign of exponent.
                        if r.is_negative() != r2.is_negative() {
                            return None;
                        }
                        Some((b, if r.is_negative() { r.max(r2) } else { r.min(r2) }))
                    })
                    .collect(),
            });
        }
        let common = common.unwrap_or_default();
        if common.is_empty() && content.is_one() && !self.is_negated(sum) {
            return vec![sum];
        }
        let mut factors: Vec<ExprId> = vec![self.number(Number::Rational(content))];
        let mut bases: Vec<(ExprId, Rational)> = common.into_iter().collect();
        bases.sort_by(|a, b| self.cmp(a.0, b.0));
        for (b, r) in bases {
            let p = self.number(Number::Rational(r));
            factors.push(self.pow(b, p));
        }
        let g = self.mul(&factors);
        let ginv = self.powi(g, -1);
        let reduced: Vec<ExprId> = terms.iter().map(|&t| self.mul2(t, ginv)).collect();
        let mut inner = self.add(&reduced);
        // Pull a leading minus out: -g*(a + b), not g*(-a - b).
        if self.is_negated(inner) {
            inner = self.neg(inner);
            factors[0] = self.number(Number::Rational(content.checked_neg().unwrap_or(content)));
        }
        factors.push(inner);
        factors
    }

    /// Groups the terms of `e` (a sum) by their dependence on the variables
    /// (symbols for which `is_var` holds) and factors each group's coefficient:
    /// `lA^2*mA*a'^2/2 + lA^2*mB*a'^2/2 → lA^2*(mA + mB)*a'^2/2`.
    pub fn collect(&mut self, e: ExprId, is_var: &dyn Fn(Symbol) -> bool) -> ExprId {
        let terms = self.terms(e);
        if terms.len() < 2 {
            return e;
        }
        // Which factors depend on a variable, memoized over the shared subexpressions.
        let mut depends: FxHashMap<ExprId, bool> = FxHashMap::default();
        let mut groups: Vec<(ExprId, Vec<ExprId>)> = Vec::new();
        let mut index: FxHashMap<ExprId, usize> = FxHashMap::default();
        for t in terms {
            let mut var_part = Vec::new();
            let mut coeff = Vec::new();
            for f in self.factors(t) {
                if self.depends_on(f, is_var, &mut depends) {
                    var_part.push(f);
                } else {
                    coeff.push(f);
                }
            }
            let key = self.mul(&var_part);
            let c = self.mul(&coeff);
            match index.get(&key) {
                Some(&i) => groups[i].1.push(c),
                None => {
                    index.insert(key, groups.len());
                    groups.push((key, vec![c]));
                }
            }
        }
        let mut out = Vec::with_capacity(groups.len());
        for (key, cs) in groups {
            let c = self.add(&cs);
            let mut parts = self.factor_sum_parts(c);
            parts.push(key);
            out.push(self.mul(&parts));
        }
        self.add(&out)
    }

    /// True when `e` contains a symbol for which `is_var` holds (`memo` keeps
    /// the answers for subexpressions).
    fn depends_on(&self, e: ExprId, is_var: &dyn Fn(Symbol) -> bool, memo: &mut FxHashMap<ExprId, bool>) -> bool {
        if let Some(&d) = memo.get(&e) {
            return d;
        }
        let d = match self.node(e) {
            Node::Num(_) | Node::Pi => false,
            Node::Sym(s) => is_var(*s),
            Node::Add(xs) | Node::Mul(xs) => xs.iter().any(|&x| self.depends_on(x, is_var, memo)),
            &Node::Pow(a, b) | &Node::Atan2(a, b) => {
                self.depends_on(a, is_var, memo) || self.depends_on(b, is_var, memo)
            }
            &Node::Func(_, a) => self.depends_on(a, is_var, memo),
        };
        memo.insert(e, d);
        d
    }

    /// Expands, combines trigonometric terms and factors common terms, and
    /// returns the shorter of that and `e` (and of [`Pool::together`]`(e)` when
    /// `e` divides by a sum).
    pub fn simplify(&mut self, e: ExprId) -> ExprId {
        let x = self.expand(e);
        let x = self.combine_trig(x);
        let x = self.factor_terms(x);
        let best = self.shorter(e, x);
        self.shorter_together(best, e)
    }

    /// The shorter of `best` and `together(e)`, tried only when `e` has a
    /// negative power of a sum (elsewhere it has nothing to combine).
    fn shorter_together(&mut self, best: ExprId, e: ExprId) -> ExprId {
        if !self.has_quotient_of_sums(e) {
            return best;
        }
        let t = self.together(e);
        self.shorter(best, t)
    }

    /// True when a negative power of a sum occurs in `e` (memoized per node).
    fn has_quotient_of_sums(&mut self, e: ExprId) -> bool {
        let mut stack = vec![(e, false)];
        while let Some((id, ready)) = stack.pop() {
            if self.rewrite_cache.contains_key(&(QUOTIENT, id)) {
                continue;
            }
            let children = self.children(self.node(id));
            if !ready {
                stack.push((id, true));
                stack.extend(children.iter().map(|&c| (c, false)));
                continue;
            }
            let here = match self.node(id) {
                &Node::Pow(b, x) => {
                    matches!(self.node(b), Node::Add(_)) && self.as_number(x).is_some_and(|n| n.is_negative())
                }
                _ => false,
            };
            let any = here || children.iter().any(|c| self.rewrite_cache[&(QUOTIENT, *c)] == self.one());
            let flag = if any { self.one() } else { self.zero() };
            self.rewrite_cache.insert((QUOTIENT, id), flag);
        }
        self.rewrite_cache[&(QUOTIENT, e)] == self.one()
    }

    /// Like [`Pool::simplify`], but collects the coefficients of the variables
    /// (symbols for which `is_var` holds) instead of factoring whole sums.
    pub fn simplify_in(&mut self, e: ExprId, is_var: &dyn Fn(Symbol) -> bool) -> ExprId {
        let expanded = self.expand(e);
        let trig = self.combine_trig(expanded);
        let collected = self.collect(trig, is_var);
        // Factoring only the outer sum: inner sums are already in the form the
        // expressions they came from were simplified to.
        let mut best = e;
        for candidate in [collected, self.factor_outer(collected), self.factor_outer(e)] {
            best = self.shorter(best, candidate);
        }
        self.shorter_together(best, e)
    }

    /// True when exact rewriting shows that `e` is identically zero (wherever it
    /// is defined): its canonical form, its expansion with trigonometric terms
    /// combined, or its quotient form with sines and cosines expanded
    /// ([`Pool::together_trig`]) is 0. False only means that no rewrite showed
    /// it: zero-equivalence is undecidable in general, so false is not "nonzero".
    pub fn is_identically_zero(&mut self, e: ExprId) -> bool {
        if self.is_zero(e) {
            return true;
        }
        let expanded = self.expand(e);
        if self.is_zero(expanded) {
            return true;
        }
        let combined = self.combine_trig(expanded);
        if self.is_zero(combined) {
            return true;
        }
        let quotient = self.together_trig(e);
        self.is_zero(quotient)
    }

    /// The shorter of two equal expressions, preferring the first on a tie.
    fn shorter(&self, a: ExprId, b: ExprId) -> ExprId {
        if self.tree_size(b) < self.tree_size(a) {
            b
        } else {
            a
        }
    }
}

fn int_gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// gcd of two rationals: gcd of numerators over lcm of denominators (positive).
fn rational_gcd(a: Rational, b: Rational) -> Rational {
    let n = int_gcd(a.numer(), b.numer());
    let g = int_gcd(a.denom(), b.denom()).max(1);
    let lcm = (a.denom() / g).checked_mul(b.denom());
    match lcm.and_then(|l| Rational::new(n, l)) {
        Some(r) if !r.is_zero() => r,
        _ => Rational::ONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool_with(names: &[&str]) -> (Pool, Vec<ExprId>) {
        let mut p = Pool::default();
        let ids = names.iter().map(|n| p.symbol(n)).collect();
        (p, ids)
    }

    #[test]
    fn pythagoras_in_kinetic_energy() {
        let (mut p, v) = pool_with(&["l", "q"]);
        let (l, q) = (v[0], v[1]);
        let qd = p.velocity("q");
        let c = p.func(Func::Cos, q);
        let s = p.func(Func::Sin, q);
        let xd = p.mul(&[l, c, qd]);
        let yd = p.mul(&[l, s, qd]);
        let x2 = p.powi(xd, 2);
        let y2 = p.powi(yd, 2);
        let sum = p.add2(x2, y2);
        let got = p.simplify(sum);
        let l2 = p.powi(l, 2);
        let qd2 = p.powi(qd, 2);
        assert_eq!(got, p.mul2(l2, qd2));
    }

    #[test]
    fn angle_difference() {
        let (mut p, v) = pool_with(&["a", "b"]);
        let (a, b) = (v[0], v[1]);
        let ca = p.func(Func::Cos, a);
        let cb = p.func(Func::Cos, b);
        let sa = p.func(Func::Sin, a);
        let sb = p.func(Func::Sin, b);
        let t1 = p.mul2(ca, cb);
        let t2 = p.mul2(sa, sb);
        let e = p.add2(t1, t2);
        let got = p.simplify(e);
        let d = p.sub(a, b);
        assert_eq!(got, p.func(Func::Cos, d));
        let e2 = {
            let x = p.mul2(sa, cb);
            let y = p.mul2(ca, sb);
            p.sub(x, y)
        };
        let got2 = p.simplify(e2);
        assert_eq!(got2, p.func(Func::Sin, d));
    }

    #[test]
    fn expansion_and_factoring() {
        let (mut p, v) = pool_with(&["x", "y"]);
        let (x, y) = (v[0], v[1]);
        let s = p.add2(x, y);
        let sq = p.powi(s, 2);
        let e = p.expand(sq);
        assert_eq!(p.terms(e).len(), 3);
        let two = p.int(2);
        let t = p.mul(&[two, x, y]);
        let x2 = p.powi(x, 2);
        let f = p.add2(t, x2);
        let got = p.factor_terms(f);
        let two_y = p.mul2(two, y);
        let inner = p.add2(x, two_y);
        assert_eq!(got, p.mul2(x, inner));
    }

    #[test]
    fn quotients_of_sums_are_put_together() {
        let mut p = Pool::default();
        let e = p.parse("-1/(y*(y'^2/(y'^2 + 1) - 1))").unwrap();
        let got = p.simplify(e);
        assert_eq!(p.display(got).to_string(), "(y'^2 + 1)/y");
        let yname = p.name("y");
        let got = p.simplify_in(e, &|s| s.name == yname);
        assert_eq!(p.display(got).to_string(), "(y'^2 + 1)/y");
        // Without a sum in a denominator there is nothing to put together.
        let e = p.parse("1/a + 1/b").unwrap();
        assert_eq!(p.simplify(e), e);
    }

    #[track_caller]
    fn check_zero(text: &str, expect: bool) {
        let mut p = Pool::default();
        let e = p.parse(text).unwrap();
        assert_eq!(p.is_identically_zero(e), expect, "{text}");
    }

    #[test]
    fn identities_are_shown_to_be_zero() {
        check_zero("x - x", true);
        check_zero("(x + y)^2 - x^2 - 2*x*y - y^2", true);
        check_zero("l^2*q'^2*(sin(q)^2 + cos(q)^2) - l^2*q'^2", true);
        check_zero("1/(x - 1) - 2/(x^2 - 1) - 1/(x + 1)", true);
        check_zero("cos(a - b) - cos(a)*cos(b) - sin(a)*sin(b)", true);
        check_zero("mu*r^2/(mu*r^2) - 1", true);
        // Not identities, and things no rewrite here shows (false is not "nonzero").
        check_zero("sin(x)^2 - cos(x)^2", false);
        check_zero("exp(-1000000*x^2)*x", false);
        check_zero("sqrt(x^2) - x", false);
    }

    #[test]
    fn past_the_work_limit_rewrites_leave_expressions_as_they_are() {
        let (mut pool, _) = pool_with(&["a", "b", "c"]);
        let e = pool.parse("(a + b)^2*(b + c)^2 - (a*b + a*c + b^2 + b*c)^2").unwrap();
        let fresh = pool.clone();
        assert!(pool.clone().is_identically_zero(e), "within the limit the identity is proven");
        pool.set_work_limit(Some(pool.work()));
        assert!(!pool.work_exhausted());
        let _ = pool.parse("a + b + c").unwrap();
        assert!(pool.work_exhausted());
        assert_eq!(pool.expand(e), e);
        assert!(!pool.is_identically_zero(e), "past it nothing is rewritten");
        pool.set_work_limit(None);
        assert!(!pool.work_exhausted());
        assert!(fresh.work() <= pool.work());
    }

    #[test]
    fn collect_groups_parameter_coefficients() {
        let mut p = Pool::default();
        p.set_rank("a", 2);
        let (ma, mb, a) = (p.symbol("mA"), p.symbol("mB"), p.symbol("a"));
        let ad = p.velocity("a");
        let ad2 = p.powi(ad, 2);
        let t1 = p.mul2(ma, ad2);
        let t2 = p.mul2(mb, ad2);
        let t3 = p.mul2(ma, a);
        let e = p.add(&[t1, t2, t3]);
        let aname = p.name("a");
        let got = p.collect(e, &|s| s.name == aname);
        let m = p.add2(ma, mb);
        let g1 = p.mul2(m, ad2);
        let expect = p.add2(g1, t3);
        assert_eq!(got, expect);
    }
}
