//! Calculus on expressions: partial derivatives, total time derivatives,
//! substitution, and the queries they need (free symbols, dependence, size).
//!
//! Entry points: [`Pool::diff`], [`Pool::time_derivative`], [`Pool::substitute`].
//! Derivatives are memoized per (expression, variable) in the pool, so deriving
//! many expressions from one shares the work the way the DAG shares
//! subexpressions; subexpressions whose symbol filter rules the variable out
//! are skipped (their derivative is zero, their substitution themselves).

use crate::expr::{ExprId, Func, NameId, Node, Pool, Symbol};
use crate::number::Number;
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::BinaryHeap;

impl Pool {
    /// The partial derivative ∂e/∂x, where `x` is a symbol node (`q`, `q'`, `t`, …).
    /// Symbols other than `x` are independent of it: `diff(q', q) = 0`.
    pub fn diff(&mut self, e: ExprId, x: ExprId) -> ExprId {
        debug_assert!(matches!(self.node(x), Node::Sym(_)), "diff with respect to a non-symbol");
        // Most subexpressions do not contain x, and their symbol filters say so.
        if !self.may_contain(e, x) {
            return self.zero();
        }
        if let Some(&d) = self.diff_cache.get(&(e, x)) {
            return d;
        }
        let d = match *self.node(e) {
            Node::Num(_) | Node::Pi => self.zero(),
            Node::Sym(_) => {
                if e == x {
                    self.one()
                } else {
                    self.zero()
                }
            }
            Node::Add(ref ts) => {
                let ts = ts.clone();
                let ds: Vec<ExprId> = ts.iter().map(|&t| self.diff(t, x)).collect();
                self.add(&ds)
            }
            Node::Mul(ref fs) => {
                let fs = fs.clone();
                let ds: Vec<ExprId> = fs.iter().map(|&f| self.diff(f, x)).collect();
                self.product_rule(&fs, &ds)
            }
            Node::Pow(b, p) => {
                let db = self.diff(b, x);
                let dp = self.diff(p, x);
                let mut terms = Vec::with_capacity(2);
                if !self.is_zero(db) {
                    // p * b^(p-1) * b'
                    let m1 = self.minus_one();
                    let pm1 = self.add2(p, m1);
                    let bp = self.pow(b, pm1);
                    terms.push(self.mul(&[p, bp, db]));
                }
                if !self.is_zero(dp) {
                    // b^p * log(b) * p'
                    let lb = self.func(Func::Log, b);
                    terms.push(self.mul(&[e, lb, dp]));
                }
                self.add(&terms)
            }
            Node::Func(f, u) => {
                let du = self.diff(u, x);
                if self.is_zero(du) {
                    self.zero()
                } else {
                    let outer = self.func_derivative(f, u);
                    self.mul2(outer, du)
                }
            }
            Node::Atan2(y, xx) => {
                // d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
                let dy = self.diff(y, x);
                let dx = self.diff(xx, x);
                let a = self.mul2(xx, dy);
                let b = self.mul2(y, dx);
                let num = self.sub(a, b);
                let x2 = self.powi(xx, 2);
                let y2 = self.powi(y, 2);
                let den = self.add2(x2, y2);
                self.div(num, den)
            }
        };
        self.diff_cache.insert((e, x), d);
        d
    }

    /// The derivative of the product of `factors` whose own derivatives are
    /// `derivatives`: Σ_i f_1 ⋯ f_i' ⋯ f_k, skipping the zero f_i'.
    pub(crate) fn product_rule(&mut self, factors: &[ExprId], derivatives: &[ExprId]) -> ExprId {
        let mut terms = Vec::new();
        for (i, &d) in derivatives.iter().enumerate() {
            if self.is_zero(d) {
                continue;
            }
            let mut prod: Vec<ExprId> = factors.to_vec();
            prod[i] = d;
            terms.push(self.mul(&prod));
        }
        self.add(&terms)
    }

    /// f'(u) for the language's functions.
    pub(crate) fn func_derivative(&mut self, f: Func, u: ExprId) -> ExprId {
        let one = self.one();
        match f {
            Func::Sin => self.func(Func::Cos, u),
            Func::Cos => {
                let s = self.func(Func::Sin, u);
                self.neg(s)
            }
            Func::Tan => {
                let c = self.func(Func::Cos, u);
                self.powi(c, -2)
            }
            Func::Asin | Func::Acos => {
                let u2 = self.powi(u, 2);
                let d = self.sub(one, u2);
                let mhalf = self.rational(-1, 2);
                let r = self.pow(d, mhalf);
                if f == Func::Asin {
                    r
                } else {
                    self.neg(r)
                }
            }
            Func::Atan => {
                let u2 = self.powi(u, 2);
                let d = self.add2(one, u2);
                self.powi(d, -1)
            }
            Func::Sinh => self.func(Func::Cosh, u),
            Func::Cosh => self.func(Func::Sinh, u),
            Func::Tanh => {
                let c = self.func(Func::Cosh, u);
                self.powi(c, -2)
            }
            Func::Exp => self.func(Func::Exp, u),
            Func::Log => self.powi(u, -1),
            Func::Abs => {
                // sign(u) = u/|u| (undefined at 0, like the function's derivative).
                let a = self.func(Func::Abs, u);
                self.div(u, a)
            }
        }
    }

    /// The total time derivative of `e`: every symbol whose name satisfies
    /// `moves` is a function of time (its velocity is the same name with one more
    /// prime), and `time`, if given, is the explicit time.
    ///
    /// `d/dt f(q, q', t) = Σ ∂f/∂q·q' + Σ ∂f/∂q'·q'' + ∂f/∂t`.
    pub fn time_derivative(&mut self, e: ExprId, time: Option<ExprId>, moves: &dyn Fn(NameId) -> bool) -> ExprId {
        let mut terms = Vec::new();
        for s in self.symbols(e) {
            if !moves(s.name) {
                continue;
            }
            let sid = self.sym(s);
            let d = self.diff(e, sid);
            if self.is_zero(d) {
                continue;
            }
            let next = self.sym(Symbol { name: s.name, order: s.order.saturating_add(1) });
            terms.push(self.mul2(d, next));
        }
        if let Some(t) = time {
            terms.push(self.diff(e, t));
        }
        self.add(&terms)
    }

    /// The ids reachable from `roots`, children before parents (ascending ids).
    pub fn reachable(&self, roots: &[ExprId]) -> Vec<ExprId> {
        self.reachable_until(roots, |_| false)
    }

    /// [`Pool::reachable`] without the nodes `known` says are known already
    /// (nor what lies below them, unless reached another way): a walk that
    /// grows a tape over many roots visits each node once.
    pub fn reachable_until(&self, roots: &[ExprId], known: impl Fn(ExprId) -> bool) -> Vec<ExprId> {
        // Children have smaller ids than their parents, so popping the largest
        // id first sees every copy of an id in a row, after all its parents:
        // a heap deduplicates without hashing.
        let mut roots = roots.to_vec();
        roots.sort_unstable();
        roots.dedup();
        let mut heap = BinaryHeap::from(roots);
        let mut out: Vec<ExprId> = Vec::new();
        let mut last = None;
        while let Some(id) = heap.pop() {
            // Asked once per id, not once per edge into it.
            if last == Some(id) {
                continue;
            }
            last = Some(id);
            if known(id) {
                continue;
            }
            out.push(id);
            match self.node(id) {
                Node::Num(_) | Node::Pi | Node::Sym(_) => {}
                Node::Add(ts) | Node::Mul(ts) => heap.extend(ts.iter().copied()),
                &Node::Pow(a, b) | &Node::Atan2(a, b) => {
                    heap.push(a);
                    heap.push(b);
                }
                &Node::Func(_, a) => heap.push(a),
            }
        }
        out.reverse();
        out
    }

    /// The symbols occurring in `e`, in canonical order.
    pub fn symbols(&self, e: ExprId) -> Vec<Symbol> {
        let mut out: Vec<Symbol> = self.reachable(&[e]).into_iter().filter_map(|id| self.as_symbol(id)).collect();
        out.sort_by(|a, b| {
            crate::expr::natural_cmp(self.name_str(a.name), self.name_str(b.name)).then(a.order.cmp(&b.order))
        });
        out
    }

    /// True when `e` does not contain the symbol `x`.
    pub fn free_of(&self, e: ExprId, x: ExprId) -> bool {
        if !matches!(self.node(x), Node::Sym(_)) {
            return !self.reachable(&[e]).contains(&x);
        }
        // Only subexpressions whose symbol filter admits x can contain it.
        let mut seen: FxHashSet<ExprId> = FxHashSet::default();
        let mut stack = vec![e];
        while let Some(id) = stack.pop() {
            if id == x {
                return false;
            }
            if !self.may_contain(id, x) || !seen.insert(id) {
                continue;
            }
            stack.extend(self.children(self.node(id)));
        }
        true
    }

    /// The number of distinct nodes of `e` (its size as a DAG).
    pub fn size(&self, e: ExprId) -> usize {
        self.reachable(&[e]).len()
    }

    /// Replaces every occurrence of the keys of `map` in `e` by their values and
    /// rebuilds the result in canonical form.
    pub fn substitute(&mut self, e: ExprId, map: &FxHashMap<ExprId, ExprId>) -> ExprId {
        // Subexpressions free of every key (by their symbol filters) stay as they are.
        let keys_mask = map.keys().fold(0u64, |m, &k| match self.node(k) {
            Node::Sym(_) => m | self.sym_mask(k),
            _ => u64::MAX,
        });
        let mut done: FxHashMap<ExprId, ExprId> = FxHashMap::default();
        // Post-order walk: (id, children done).
        let mut stack = vec![(e, false)];
        while let Some((id, ready)) = stack.pop() {
            if done.contains_key(&id) {
                continue;
            }
            if let Some(&v) = map.get(&id) {
                done.insert(id, v);
                continue;
            }
            if self.sym_mask(id) & keys_mask == 0 {
                done.insert(id, id);
                continue;
            }
            if !ready {
                stack.push((id, true));
                stack.extend(self.children(self.node(id)).into_iter().map(|c| (c, false)));
                continue;
            }
            let new = self.rebuild(id, |c| done[&c]);
            done.insert(id, new);
        }
        done[&e]
    }

    /// Substitutes numbers for symbols (`g → 9.81`), exact where the value is.
    pub fn substitute_numbers(&mut self, e: ExprId, values: &[(ExprId, Number)]) -> ExprId {
        let map: FxHashMap<ExprId, ExprId> = values.iter().map(|&(s, v)| (s, self.number(v))).collect();
        self.substitute(e, &map)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_and_chain_rules() {
        let mut p = Pool::default();
        let x = p.symbol("x");
        let y = p.symbol("y");
        let s = p.func(Func::Sin, x);
        let e = p.mul(&[s, s, y]); // y*sin(x)^2
        let d = p.diff(e, x);
        let c = p.func(Func::Cos, x);
        let two = p.int(2);
        let expect = p.mul(&[two, c, s, y]);
        assert_eq!(d, expect);
        let z = p.symbol("z");
        assert_eq!(p.diff(e, z), p.zero());
    }

    #[test]
    fn time_derivative_uses_velocities_and_explicit_time() {
        let mut p = Pool::default();
        let q = p.symbol("q");
        let t = p.symbol("t");
        let om = p.symbol("om");
        let arg = p.mul2(om, t);
        let c = p.func(Func::Cos, arg);
        let e = p.mul2(q, c); // q*cos(om*t)
        let qname = p.name("q");
        let d = p.time_derivative(e, Some(t), &|n| n == qname);
        let qd = p.velocity("q");
        let s = p.func(Func::Sin, arg);
        let a = p.mul2(qd, c);
        let b = p.mul(&[om, q, s]);
        let expect = p.sub(a, b);
        assert_eq!(d, expect);
    }

    #[test]
    fn substitution_recanonicalizes() {
        let mut p = Pool::default();
        let x = p.symbol("x");
        let y = p.symbol("y");
        let e = p.sub(x, y);
        let map: FxHashMap<ExprId, ExprId> = [(y, x)].into_iter().collect();
        assert_eq!(p.substitute(e, &map), p.zero());
    }
}
