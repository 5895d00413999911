//! Numeric evaluation of many expressions at once over their shared
//! subexpressions: a flat instruction tape.
//!
//! [`Tape::compile`] walks the nodes reachable from the roots in arena order
//! (children first), emits one instruction per operation into a single list of
//! slots, and removes repeated instructions (common-subexpression elimination on
//! top of the DAG's sharing). [`Tape::eval`] then runs the list with no
//! allocation: this is the hot path of `simulate`. [`Pool::eval`] is the
//! convenience for one expression with named inputs.

use crate::expr::{ExprId, Func, Node, Pool};
use crate::number::Number;
use rustc_hash::FxHashMap;

/// Why an expression could not be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// A symbol had no value.
    #[error("no value for '{name}'")]
    Unbound {
        /// The symbol as text (`q'`).
        name: String,
    },
}

/// One tape instruction; operands are slot indices, the result goes to the
/// instruction's own slot. `jit.rs` translates the same list to native code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Op {
    Input(u32),
    Const(u64),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Recip(u32),
    Square(u32),
    Powi(u32, i32),
    Powf(u32, u32),
    Sqrt(u32),
    Func(Func, u32),
    Atan2(u32, u32),
}

/// A compiled list of instructions computing several expressions from a fixed
/// list of input symbols. See the module documentation.
#[derive(Clone, Debug)]
pub struct Tape {
    ops: Vec<Op>,
    outputs: Vec<u32>,
    n_inputs: usize,
    slots: Vec<f64>,
}

struct Builder<'a> {
    pool: &'a Pool,
    ops: Vec<Op>,
    dedup: FxHashMap<Op, u32>,
    slot_of: FxHashMap<ExprId, u32>,
}

impl Builder<'_> {
    fn emit(&mut self, op: Op) -> u32 {
        if let Some(&s) = self.dedup.get(&op) {
            return s;
        }
        let s = self.ops.len() as u32;
        self.ops.push(op);
        self.dedup.insert(op, s);
        s
    }

    fn constant(&mut self, x: f64) -> u32 {
        self.emit(Op::Const(x.to_bits()))
    }

    /// `base^n` for an integer n, by the cheapest instruction.
    fn powi(&mut self, base: u32, n: i64) -> u32 {
        match n {
            0 => self.constant(1.0),
            1 => base,
            2 => self.emit(Op::Square(base)),
            -1 => self.emit(Op::Recip(base)),
            n if n < 0 => match n.checked_neg() {
                Some(m) => {
                    let p = self.powi(base, m);
                    self.emit(Op::Recip(p))
                }
                // i64::MIN has no positive counterpart.
                None => {
                    let e = self.constant(n as f64);
                    self.emit(Op::Powf(base, e))
                }
            },
            n => match i32::try_from(n) {
                Ok(k) => self.emit(Op::Powi(base, k)),
                Err(_) => {
                    let e = self.constant(n as f64);
                    self.emit(Op::Powf(base, e))
                }
            },
        }
    }

    fn node(&mut self, id: ExprId) -> u32 {
        let slot = match self.pool.node(id) {
            Node::Num(n) => self.constant(n.to_f64()),
            Node::Pi => self.constant(std::f64::consts::PI),
            Node::Sym(_) => unreachable!("inputs are bound before the walk"),
            Node::Add(ts) => {
                // Subtract negated terms instead of multiplying them by -1.
                let mut acc: Option<u32> = None;
                let mut negs = Vec::new();
                for &t in ts.iter() {
                    match self.negated(t) {
                        Some(s) => negs.push(s),
                        None => {
                            let s = self.slot_of[&t];
                            acc = Some(match acc {
                                Some(a) => self.emit(Op::Add(a, s)),
                                None => s,
                            });
                        }
                    }
                }
                let mut acc = match acc {
                    Some(a) => a,
                    None => {
                        let first = negs.remove(0);
                        self.emit(Op::Neg(first))
                    }
                };
                for s in negs {
                    acc = self.emit(Op::Sub(acc, s));
                }
                acc
            }
            Node::Mul(fs) => {
                // Numerator and denominator products, then one division.
                let mut num: Option<u32> = None;
                let mut den: Option<u32> = None;
                let mut sign = 1.0;
                for &f in fs.iter() {
                    if let Some(n) = self.pool.as_number(f) {
                        if n.to_f64() == -1.0 {
                            sign = -sign;
                            continue;
                        }
                    }
                    let (slot, into_den) = match self.pool.node(f) {
                        Node::Pow(b, e) => match self.pool.as_number(*e) {
                            Some(Number::Rational(r)) if r.is_integer() && r.is_negative() => {
                                let n = i64::try_from(-r.numer()).unwrap_or(i64::MAX);
                                let b = self.slot_of[b];
                                (self.powi(b, n), true)
                            }
                            _ => (self.slot_of[&f], false),
                        },
                        _ => (self.slot_of[&f], false),
                    };
                    let target = if into_den { &mut den } else { &mut num };
                    *target = Some(match *target {
                        Some(a) => self.emit(Op::Mul(a, slot)),
                        None => slot,
                    });
                }
                let mut v = match (num, den) {
                    (Some(n), Some(d)) => self.emit(Op::Div(n, d)),
                    (Some(n), None) => n,
                    (None, Some(d)) => self.emit(Op::Recip(d)),
                    (None, None) => self.constant(1.0),
                };
                if sign < 0.0 {
                    v = self.emit(Op::Neg(v));
                }
                v
            }
            Node::Pow(b, e) => {
                let bs = self.slot_of[b];
                match self.pool.as_number(*e) {
                    Some(Number::Rational(r)) if r.is_integer() => {
                        self.powi(bs, i64::try_from(r.numer()).unwrap_or(i64::MAX))
                    }
                    Some(Number::Rational(r)) if r.denom() == 2 && r.numer().abs() == 1 => {
                        let s = self.emit(Op::Sqrt(bs));
                        if r.is_negative() {
                            self.emit(Op::Recip(s))
                        } else {
                            s
                        }
                    }
                    Some(Number::Rational(r)) if r.denom() == 2 && r.numer().abs() < 64 => {
                        // x^(k/2) = sqrt(x)^k
                        let s = self.emit(Op::Sqrt(bs));
                        self.powi(s, r.numer() as i64)
                    }
                    _ => {
                        let es = self.slot_of[e];
                        self.emit(Op::Powf(bs, es))
                    }
                }
            }
            Node::Func(f, u) => {
                let us = self.slot_of[u];
                self.emit(Op::Func(*f, us))
            }
            Node::Atan2(y, x) => {
                let (ys, xs) = (self.slot_of[y], self.slot_of[x]);
                self.emit(Op::Atan2(ys, xs))
            }
        };
        self.slot_of.insert(id, slot);
        slot
    }

    /// Emits every node reachable from `roots` that has no slot yet.
    fn walk(&mut self, roots: &[ExprId]) -> Result<(), EvalError> {
        let pool = self.pool;
        for id in pool.reachable_until(roots, |id| self.slot_of.contains_key(&id)) {
            if let Node::Sym(s) = pool.node(id) {
                return Err(EvalError::Unbound { name: pool.symbol_text(*s) });
            }
            self.node(id);
        }
        Ok(())
    }

    /// The slot of `-t` when `t` is a term with coefficient -1 (so `a - b` is a Sub).
    fn negated(&mut self, t: ExprId) -> Option<u32> {
        let Node::Mul(fs) = self.pool.node(t) else { return None };
        if self.pool.as_number(fs[0])?.to_f64() != -1.0 {
            return None;
        }
        let rest: Vec<ExprId> = fs[1..].to_vec();
        if rest.len() == 1 {
            return Some(self.slot_of[&rest[0]]);
        }
        // The positive product is not a node of the pool; build it from slots.
        let mut acc = self.slot_of[&rest[0]];
        for f in &rest[1..] {
            let s = self.slot_of[f];
            acc = self.emit(Op::Mul(acc, s));
        }
        Some(acc)
    }
}

impl Tape {
    /// Compiles `roots` as functions of `inputs` (symbol nodes, in the order the
    /// values will be passed to [`Tape::eval`]). Fails when a root contains a
    /// symbol that is not an input.
    pub fn compile(pool: &Pool, roots: &[ExprId], inputs: &[ExprId]) -> Result<Tape, EvalError> {
        Tape::compile_with_definitions(pool, &[], roots, inputs)
    }

    /// [`Tape::compile`] with definitions: each `(symbol, expr)` binds the
    /// symbol to the value of `expr`, which may use the inputs and the symbols
    /// defined before it. A recursive algorithm written as a sequence of
    /// assignments (the articulated-body algorithm of `mech`) keeps its sums
    /// and products apart this way, where the pool would flatten them into
    /// one sum per output.
    pub fn compile_with_definitions(
        pool: &Pool,
        definitions: &[(ExprId, ExprId)],
        roots: &[ExprId],
        inputs: &[ExprId],
    ) -> Result<Tape, EvalError> {
        let mut b = Builder { pool, ops: Vec::new(), dedup: FxHashMap::default(), slot_of: FxHashMap::default() };
        for (k, &i) in inputs.iter().enumerate() {
            let s = b.emit(Op::Input(k as u32));
            b.slot_of.insert(i, s);
        }
        // Only the definitions the roots use, found from the last one back.
        let mut needed: rustc_hash::FxHashSet<ExprId> =
            if definitions.is_empty() { Default::default() } else { pool.reachable(roots).into_iter().collect() };
        let mut used = vec![false; definitions.len()];
        for (k, &(symbol, expr)) in definitions.iter().enumerate().rev() {
            if needed.contains(&symbol) {
                used[k] = true;
                needed.extend(pool.reachable(&[expr]));
            }
        }
        for (&(symbol, expr), _) in definitions.iter().zip(&used).filter(|(_, &u)| u) {
            b.walk(&[expr])?;
            let slot = b.slot_of[&expr];
            b.slot_of.insert(symbol, slot);
        }
        b.walk(roots)?;
        let outputs = roots.iter().map(|r| b.slot_of[r]).collect();
        let slots = vec![0.0; b.ops.len()];
        Ok(Tape { ops: b.ops, outputs, n_inputs: inputs.len(), slots })
    }

    /// The number of inputs expected by [`Tape::eval`].
    pub fn n_inputs(&self) -> usize {
        self.n_inputs
    }

    /// The number of outputs written by [`Tape::eval`].
    pub fn n_outputs(&self) -> usize {
        self.outputs.len()
    }

    /// The number of instructions (a measure of the cost of one evaluation).
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// True when the tape has no instruction.
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Whether every instruction is analytic where it is defined: no `abs`,
    /// whose kink a Taylor series cannot see coming (a series of `|u|` is the
    /// series of `±u` and stays so across u = 0).
    pub fn is_analytic(&self) -> bool {
        !self.ops.iter().any(|op| matches!(op, Op::Func(Func::Abs, _)))
    }

    /// The instructions, in order: instruction `i` writes slot `i`, and its
    /// operands are earlier slots; `Input(k)` has `k < n_inputs`.
    pub(crate) fn ops(&self) -> &[Op] {
        &self.ops
    }

    /// The slot of each output, in root order.
    pub(crate) fn output_slots(&self) -> &[u32] {
        &self.outputs
    }

    /// Evaluates every root. `inputs.len()` must be [`Tape::n_inputs`] and
    /// `outputs.len()` [`Tape::n_outputs`].
    pub fn eval(&mut self, inputs: &[f64], outputs: &mut [f64]) {
        debug_assert_eq!(inputs.len(), self.n_inputs);
        debug_assert_eq!(outputs.len(), self.outputs.len());
        let v = &mut self.slots;
        for (i, op) in self.ops.iter().enumerate() {
            let x = match *op {
                Op::Input(k) => inputs[k as usize],
                Op::Const(bits) => f64::from_bits(bits),
                Op::Add(a, b) => v[a as usize] + v[b as usize],
                Op::Sub(a, b) => v[a as usize] - v[b as usize],
                Op::Mul(a, b) => v[a as usize] * v[b as usize],
                Op::Div(a, b) => v[a as usize] / v[b as usize],
                Op::Neg(a) => -v[a as usize],
                Op::Recip(a) => 1.0 / v[a as usize],
                Op::Square(a) => v[a as usize] * v[a as usize],
                Op::Powi(a, n) => v[a as usize].powi(n),
                Op::Powf(a, b) => v[a as usize].powf(v[b as usize]),
                Op::Sqrt(a) => v[a as usize].sqrt(),
                Op::Func(f, a) => f.apply(v[a as usize]),
                Op::Atan2(a, b) => v[a as usize].atan2(v[b as usize]),
            };
            v[i] = x;
        }
        for (o, &s) in outputs.iter_mut().zip(&self.outputs) {
            *o = v[s as usize];
        }
    }
}

impl Pool {
    /// Evaluates `e`, asking `env` for the value of each symbol by its text
    /// (`q`, `q'`, `p_q`, `t`, parameter names).
    pub fn eval(&self, e: ExprId, env: &dyn Fn(&str) -> Option<f64>) -> Result<f64, EvalError> {
        let inputs: Vec<ExprId> =
            self.reachable(&[e]).into_iter().filter(|&id| matches!(self.node(id), Node::Sym(_))).collect();
        let mut values = Vec::with_capacity(inputs.len());
        for &i in &inputs {
            let name = self.symbol_text(self.as_symbol(i).expect("filtered to symbols"));
            match env(&name) {
                Some(v) => values.push(v),
                None => return Err(EvalError::Unbound { name }),
            }
        }
        let mut tape = Tape::compile(self, &[e], &inputs)?;
        let mut out = [0.0];
        tape.eval(&values, &mut out);
        Ok(out[0])
    }

    /// The value of `e` when it is a constant power or function value that has
    /// none: NaN from finite operands (`sqrt(-1)`, `asin(2)`), or a pole (`0^-1`,
    /// `log(0)`). An overflow (`exp(1000)`, `10^400` as a float) is a large
    /// value, not an undefined one: None. The parser refuses text with an
    /// undefined constant, so that no simplification can drop it (`0*log(0)`).
    pub fn undefined_value(&self, e: ExprId) -> Option<f64> {
        let (operands, pole): (&[ExprId], bool) = match self.node(e) {
            Node::Pow(b, x) => (&[*b, *x], self.is_zero(*b)),
            Node::Func(f, a) => (std::slice::from_ref(a), *f == Func::Log),
            _ => return None,
        };
        if self.sym_mask(e) != 0 {
            return None;
        }
        let value = |id: ExprId| self.eval(id, &|_| None).ok();
        if !operands.iter().all(|&o| value(o).is_some_and(f64::is_finite)) {
            return None;
        }
        let v = value(e)?;
        (v.is_nan() || (v.is_infinite() && pole)).then_some(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Definitions are computed in order, each from the inputs and the ones
    /// before it; one the roots do not use costs no instruction; a symbol
    /// that is neither an input nor defined is an error.
    #[test]
    fn definitions_stand_for_their_expressions() {
        let mut p = Pool::default();
        let (x, a, b, unused) = (p.symbol("x"), p.symbol("a"), p.symbol("b"), p.symbol("unused"));
        let one = p.one();
        let x_plus_1 = p.add2(x, one);
        let sin_x = p.func(Func::Sin, x);
        let a_squared = p.powi(a, 2);
        let b_expr = p.mul2(a_squared, sin_x);
        let unused_expr = p.func(Func::Exp, b);
        let root = p.add2(b, a);
        let defs = [(a, x_plus_1), (b, b_expr), (unused, unused_expr)];
        let mut tape = Tape::compile_with_definitions(&p, &defs, &[root], &[x]).unwrap();
        let mut out = [0.0];
        tape.eval(&[0.5], &mut out);
        assert_eq!(out[0], 1.5f64 * 1.5 * 0.5f64.sin() + 1.5);
        assert!(!tape.ops.iter().any(|op| matches!(op, Op::Func(Func::Exp, _))), "the unused definition is left out");
        let y = p.symbol("y");
        let root = p.add2(b, y);
        assert!(matches!(Tape::compile_with_definitions(&p, &defs, &[root], &[x]), Err(EvalError::Unbound { .. })));
    }

    #[test]
    fn tape_shares_subexpressions_and_matches_direct_values() {
        let mut p = Pool::default();
        let x = p.symbol("x");
        let y = p.symbol("y");
        let s = p.func(Func::Sin, x);
        let a = p.mul(&[s, y]);
        let b = p.div(s, y);
        let two = p.int(2);
        let c = p.sub(a, two);
        let mut tape = Tape::compile(&p, &[a, b, c], &[x, y]).unwrap();
        let mut out = [0.0; 3];
        tape.eval(&[0.5, 2.0], &mut out);
        let sx = 0.5f64.sin();
        assert_eq!(out, [sx * 2.0, sx / 2.0, sx * 2.0 - 2.0]);
        // sin(x) is computed once.
        assert_eq!(tape.ops.iter().filter(|o| matches!(o, Op::Func(..))).count(), 1);
    }

    #[test]
    fn unbound_symbols_are_reported() {
        let mut p = Pool::default();
        let x = p.symbol("x");
        let qd = p.velocity("q");
        let e = p.add2(x, qd);
        let err = p.eval(e, &|n| (n == "x").then_some(1.0)).unwrap_err();
        assert_eq!(err, EvalError::Unbound { name: "q'".into() });
        assert!(Tape::compile(&p, &[e], &[x]).is_err());
    }
}
