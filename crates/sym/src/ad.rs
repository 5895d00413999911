//! Derivatives of large shared expressions in one pass over their DAG.
//!
//! [`Pool::diff`] differentiates by one symbol at a time: the momenta of a
//! model with n coordinates cost n passes over L. For the long expressions of
//! large mechanisms (a hundred links, a robot) two classic passes build every
//! derivative that is needed with work proportional to the DAG, as automatic
//! differentiation does on programs:
//!
//! - [`Pool::tangent`] (forward mode): Σ_x ∂e/∂x·ẋ for given seeds ẋ, for
//!   many roots at once; with q → q' and t → 1 it is the total time derivative
//!   at q'' = 0, used for velocities and for d/dt ∂L/∂q'.
//! - [`Pool::gradient`] (reverse mode): ∂e/∂x for every x of a list, by
//!   adjoints that flow from e down to its leaves once; used for p = ∂L/∂q' and
//!   ∂L/∂q.
//!
//! Both produce expressions in the pool's canonical form, never simplified:
//! their size follows the DAG's, not the tree's.

use crate::expr::{ExprId, Func, Node, Pool};
use rustc_hash::FxHashMap;

impl Pool {
    /// For each root e, Σ_x ∂e/∂x · seeds[x], the symbols x not in `seeds`
    /// held constant. Subexpressions shared between the roots get one tangent.
    pub fn tangent(&mut self, roots: &[ExprId], seeds: &FxHashMap<ExprId, ExprId>) -> Vec<ExprId> {
        let zero = self.zero();
        let mut tan: FxHashMap<ExprId, ExprId> = FxHashMap::default();
        for id in self.reachable(roots) {
            let d = match self.node(id).clone() {
                Node::Num(_) | Node::Pi => zero,
                Node::Sym(_) => seeds.get(&id).copied().unwrap_or(zero),
                Node::Add(ts) => {
                    let ds: Vec<ExprId> = ts.iter().map(|t| tan[t]).filter(|&d| d != zero).collect();
                    self.add(&ds)
                }
                Node::Mul(fs) => {
                    let ds: Vec<ExprId> = fs.iter().map(|f| tan[f]).collect();
                    self.product_rule(&fs, &ds)
                }
                Node::Pow(b, p) => {
                    let (db, dp) = (tan[&b], tan[&p]);
                    self.pow_partials(id, b, p).into_iter().zip([db, dp]).fold(zero, |acc, (part, d)| match part {
                        Some(part) if d != zero => {
                            let t = self.mul2(part, d);
                            self.add2(acc, t)
                        }
                        _ => acc,
                    })
                }
                Node::Func(f, u) => {
                    let du = tan[&u];
                    if du == zero {
                        zero
                    } else {
                        let outer = self.func_derivative(f, u);
                        self.mul2(outer, du)
                    }
                }
                Node::Atan2(y, x) => {
                    let (dy, dx) = (tan[&y], tan[&x]);
                    if dy == zero && dx == zero {
                        zero
                    } else {
                        let [py, px] = self.atan2_partials(y, x);
                        let a = self.mul2(py, dy);
                        let b = self.mul2(px, dx);
                        self.add2(a, b)
                    }
                }
            };
            tan.insert(id, d);
        }
        roots.iter().map(|r| tan[r]).collect()
    }

    /// ∂e/∂x for each symbol x of `vars`, by reverse accumulation: each node's
    /// adjoint ∂e/∂node is the sum of its parents' adjoints times the local
    /// partials, formed once, and only on nodes that depend on some x.
    pub fn gradient(&mut self, e: ExprId, vars: &[ExprId]) -> Vec<ExprId> {
        let order = self.reachable(&[e]);
        // Which nodes depend on a variable (children come first in `order`).
        let mut depends: FxHashMap<ExprId, bool> = FxHashMap::default();
        for &id in &order {
            let d = match self.node(id) {
                Node::Num(_) | Node::Pi => false,
                Node::Sym(_) => vars.contains(&id),
                node => self.children(node).iter().any(|c| depends[c]),
            };
            depends.insert(id, d);
        }
        let mut parts: FxHashMap<ExprId, Vec<ExprId>> = FxHashMap::default();
        let mut adjoint: FxHashMap<ExprId, ExprId> = FxHashMap::default();
        if depends[&e] {
            parts.insert(e, vec![self.one()]);
        }
        for &id in order.iter().rev() {
            let Some(terms) = parts.remove(&id) else { continue };
            let adj = self.add(&terms);
            adjoint.insert(id, adj);
            let mut push = |child: ExprId, local: ExprId, pool: &mut Pool| {
                if depends[&child] {
                    let c = pool.mul2(adj, local);
                    parts.entry(child).or_default().push(c);
                }
            };
            match self.node(id).clone() {
                Node::Num(_) | Node::Pi | Node::Sym(_) => {}
                Node::Add(ts) => {
                    for t in ts.iter() {
                        if depends[t] {
                            parts.entry(*t).or_default().push(adj);
                        }
                    }
                }
                Node::Mul(fs) => {
                    for i in 0..fs.len() {
                        if !depends[&fs[i]] {
                            continue;
                        }
                        let others: Vec<ExprId> =
                            fs.iter().enumerate().filter(|&(j, _)| j != i).map(|(_, &f)| f).collect();
                        let local = self.mul(&others);
                        push(fs[i], local, self);
                    }
                }
                Node::Pow(b, p) => {
                    let [pb, pp] = self.pow_partials(id, b, p);
                    if let Some(pb) = pb {
                        push(b, pb, self);
                    }
                    if let Some(pp) = pp {
                        push(p, pp, self);
                    }
                }
                Node::Func(f, u) => {
                    let outer = self.func_derivative(f, u);
                    push(u, outer, self);
                }
                Node::Atan2(y, x) => {
                    let [py, px] = self.atan2_partials(y, x);
                    push(y, py, self);
                    push(x, px, self);
                }
            }
        }
        vars.iter().map(|v| adjoint.get(v).copied().unwrap_or_else(|| self.zero())).collect()
    }

    /// The partials of `e = b^p` with respect to b and p: p·b^(p−1), and
    /// b^p·log(b) unless p is a number (then None: the exponent is constant).
    fn pow_partials(&mut self, e: ExprId, b: ExprId, p: ExprId) -> [Option<ExprId>; 2] {
        let m1 = self.minus_one();
        let pm1 = self.add2(p, m1);
        let bp = self.pow(b, pm1);
        let db = self.mul2(p, bp);
        let dp = if self.as_number(p).is_some() {
            None
        } else {
            let lb = self.func(Func::Log, b);
            Some(self.mul2(e, lb))
        };
        [Some(db), dp]
    }

    /// ∂atan2(y, x)/∂y = x/(x² + y²) and ∂/∂x = −y/(x² + y²).
    fn atan2_partials(&mut self, y: ExprId, x: ExprId) -> [ExprId; 2] {
        let x2 = self.powi(x, 2);
        let y2 = self.powi(y, 2);
        let r2 = self.add2(x2, y2);
        let py = self.div(x, r2);
        let my = self.neg(y);
        let px = self.div(my, r2);
        [py, px]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval_at(pool: &Pool, e: ExprId, vals: &[(&str, f64)]) -> f64 {
        pool.eval(e, &|n: &str| vals.iter().find(|(k, _)| *k == n).map(|(_, v)| *v)).unwrap()
    }

    const TEXTS: [&str; 6] = [
        "m*(l*cos(a)*a' + l*cos(a + b)*(a' + b'))^2/2 + g*cos(a)*cos(b)",
        "x^3*y' + sqrt(1 + x^2)*exp(-y)*atan2(y, x + 2)",
        "(x + y)^(x/3 + 1) * log(2 + y^2) + sin(x*y)^2",
        "tan(x)/(1 + y^2) - asin(x/3) + cosh(y)*atan(x*y)",
        "x*x'*y*y' + (x'*y)^2",
        "q",
    ];

    /// Reverse mode and forward mode agree with one `diff` per symbol, at points.
    #[test]
    fn gradient_and_tangent_agree_with_diff() {
        let vals = [("a", 0.3), ("b", -0.7), ("a'", 1.1), ("b'", 0.4), ("m", 1.3), ("l", 0.8), ("g", 9.8)];
        let vals2 = [("x", 0.4), ("y", 0.9), ("x'", -0.6), ("y'", 1.7), ("q", 0.2)];
        let all: Vec<(&str, f64)> = vals.iter().chain(vals2.iter()).copied().collect();
        let names = ["a", "b", "a'", "b'", "x", "y", "x'", "y'", "q"];
        for text in TEXTS {
            let mut pool = Pool::default();
            let e = pool.parse(text).unwrap();
            let vars: Vec<ExprId> = names
                .iter()
                .map(|n| match n.strip_suffix('\'') {
                    Some(base) => pool.var(base, 1),
                    None => pool.symbol(n),
                })
                .collect();
            let grad = pool.gradient(e, &vars);
            let mut seeds = FxHashMap::default();
            let mut expected_tangent = 0.0;
            for (k, &x) in vars.iter().enumerate() {
                let d = pool.diff(e, x);
                let (a, b) = (eval_at(&pool, grad[k], &all), eval_at(&pool, d, &all));
                assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{text}: d/d{}: {a} vs {b}", names[k]);
                let seed = 0.25 + k as f64;
                seeds.insert(x, pool.float(seed));
                expected_tangent += seed * b;
            }
            let tan = pool.tangent(&[e], &seeds)[0];
            let got = eval_at(&pool, tan, &all);
            assert!((got - expected_tangent).abs() <= 1e-11 * (1.0 + expected_tangent.abs()), "{text}: {got}");
        }
    }

    /// A chain of shared sums: the gradient stays linear in the chain's length
    /// where the tree of the expression grows as its square.
    #[test]
    fn gradient_of_a_shared_chain_stays_small() {
        let mut pool = Pool::default();
        let n = 200;
        let xs: Vec<ExprId> = (0..n).map(|i| pool.symbol(&format!("x{i}"))).collect();
        let mut s = pool.zero();
        let mut terms = Vec::new();
        for &x in &xs {
            let c = pool.func(Func::Cos, x);
            s = pool.add2(s, c);
            terms.push(pool.func(Func::Sin, s));
        }
        let e = pool.add(&terms);
        let before = pool.len();
        let grad = pool.gradient(e, &xs);
        assert!(pool.len() - before < 40 * n * n / 10, "built {} nodes", pool.len() - before);
        let vals: Vec<(String, f64)> = (0..n).map(|i| (format!("x{i}"), 0.01 * i as f64)).collect();
        let env = |name: &str| vals.iter().find(|(k, _)| k == name).map(|(_, v)| *v);
        // ∂e/∂x_k = −sin(x_k) Σ_{j≥k} cos(s_j).
        let mut acc = 0.0;
        let mut sums = Vec::new();
        let mut s = 0.0;
        for (_, v) in &vals {
            s += f64::cos(*v);
            sums.push(s);
        }
        for k in (0..n).rev() {
            acc += sums[k].cos();
            let want = -vals[k].1.sin() * acc;
            let got = pool.eval(grad[k], &env).unwrap();
            assert!((got - want).abs() < 1e-9 * (1.0 + want.abs()), "x{k}: {got} vs {want}");
        }
    }
}
