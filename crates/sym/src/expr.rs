//! The expression arena: a hash-consed DAG of nodes addressed by [`ExprId`].
//!
//! Every node is stored once in [`Pool`]; building an equal node again returns the
//! same id, so equality is `==` on ids and common subexpressions are shared for
//! free. Children always have smaller ids than their parents, which lets
//! evaluation walk the arena in order without recursion. Side tables per node
//! hold its tree size and a 64-bit Bloom filter of its symbols, so "does `e`
//! contain `x`" is usually answered without a traversal.
//!
//! Constructors keep a canonical form (SymPy's "automatic simplification", done
//! cheaply): sums and products are flattened, numeric parts folded exactly, like
//! terms and like powers collected, and operands sorted by [`Pool::cmp`]. Entry
//! points: [`Pool::add`], [`Pool::mul`], [`Pool::pow`], [`Pool::func`].
//!
//! Two parts have files of their own: the hash-consing table (`expr/intern.rs`)
//! and the canonical order (`expr/order.rs`).

use crate::number::{Number, Rational};
use rustc_hash::FxHashMap;
use std::hash::Hash;

mod intern;
mod order;

use intern::{hash_seq, Seq, EMPTY};

pub(crate) use order::natural_cmp;

/// The id of a node in a [`Pool`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct ExprId(u32);

impl ExprId {
    /// The index of the node in the arena.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The id of an interned name.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct NameId(u32);

/// A symbol: a name and how many times it is differentiated in time (`q`, `q'`, `q''`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Symbol {
    /// The base name.
    pub name: NameId,
    /// The number of primes: 0 for `q`, 1 for `q'`, 2 for `q''`.
    pub order: u8,
}

/// The functions of the expression language.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Func {
    /// Sine.
    Sin,
    /// Cosine.
    Cos,
    /// Tangent.
    Tan,
    /// Arc sine.
    Asin,
    /// Arc cosine.
    Acos,
    /// Arc tangent.
    Atan,
    /// Hyperbolic sine.
    Sinh,
    /// Hyperbolic cosine.
    Cosh,
    /// Hyperbolic tangent.
    Tanh,
    /// Exponential.
    Exp,
    /// Natural logarithm.
    Log,
    /// Absolute value.
    Abs,
}

impl Func {
    /// Every function, for parsers and tests.
    pub const ALL: [Func; 12] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
        Func::Exp,
        Func::Log,
        Func::Abs,
    ];

    /// The name in the expression language.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
            Func::Tanh => "tanh",
            Func::Exp => "exp",
            Func::Log => "log",
            Func::Abs => "abs",
        }
    }

    /// The function with this name, if any (`sqrt` and `atan2` are not unary functions here).
    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Applies the function to a float.
    pub fn apply(self, x: f64) -> f64 {
        match self {
            // The native code's sine and cosine, so that every evaluation
            // agrees with it bit for bit (within an ulp of libm's).
            Func::Sin => crate::trig::sin_cos_f64(x).0,
            Func::Cos => crate::trig::sin_cos_f64(x).1,
            Func::Tan => x.tan(),
            Func::Asin => x.asin(),
            Func::Acos => x.acos(),
            Func::Atan => x.atan(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
            Func::Tanh => x.tanh(),
            Func::Exp => x.exp(),
            Func::Log => x.ln(),
            Func::Abs => x.abs(),
        }
    }
}

/// One node of the DAG. Children are ids of earlier nodes.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub enum Node {
    /// A numeric constant.
    Num(Number),
    /// The constant π.
    Pi,
    /// A symbol: a name and how many times it is differentiated in time.
    Sym(Symbol),
    /// A sum of at least two terms, sorted, at most one numeric term (last).
    Add(Box<[ExprId]>),
    /// A product of at least two factors, sorted, at most one numeric factor (first).
    Mul(Box<[ExprId]>),
    /// `base ^ exponent`.
    Pow(ExprId, ExprId),
    /// A unary function.
    Func(Func, ExprId),
    /// `atan2(y, x)`.
    Atan2(ExprId, ExprId),
}

/// The arena of expressions. See the module documentation.
#[derive(Clone, Debug)]
pub struct Pool {
    nodes: Vec<Node>,
    /// The hash of each node, for the intern table.
    hashes: Vec<u64>,
    /// The intern table: node ids by hash, open addressing with linear probing,
    /// at most half full. It is looked up with borrowed operand slices, so
    /// finding an existing sum or product allocates nothing.
    table: Vec<u32>,
    names: Vec<Box<str>>,
    name_index: FxHashMap<Box<str>, NameId>,
    name_rank: Vec<u8>,
    /// Tree size of each node (the node counted with all its repetitions).
    tree_sizes: Vec<u64>,
    /// The symbols of each node as a 64-bit Bloom filter (one hashed bit per
    /// symbol): a clear bit proves a symbol absent without a traversal.
    sym_masks: Vec<u64>,
    /// Memo of `diff`: (expression, variable) → derivative.
    pub(crate) diff_cache: FxHashMap<(ExprId, ExprId), ExprId>,
    /// Memos of the rewrites of `simplify` (each a pure function of the id).
    pub(crate) rewrite_cache: FxHashMap<(u8, ExprId), ExprId>,
    /// Nodes built so far, found or new: the work done on the pool.
    work: u64,
    /// The work after which the rewrites stop (see [`Pool::set_work_limit`]).
    work_limit: Option<u64>,
}

impl Default for Pool {
    fn default() -> Self {
        let mut pool = Pool {
            nodes: Vec::new(),
            hashes: Vec::new(),
            table: vec![EMPTY; 1024],
            names: Vec::new(),
            name_index: FxHashMap::default(),
            name_rank: Vec::new(),
            tree_sizes: Vec::new(),
            sym_masks: Vec::new(),
            diff_cache: FxHashMap::default(),
            rewrite_cache: FxHashMap::default(),
            work: 0,
            work_limit: None,
        };
        // Fixed ids for the constants used everywhere.
        pool.intern(Node::Num(Number::ZERO));
        pool.intern(Node::Num(Number::ONE));
        pool.intern(Node::Num(Number::MINUS_ONE));
        pool
    }
}

/// Below this many operands, sums and products find like terms by a linear scan.
const SMALL: usize = 16;

/// Largest integer power of a sum or of a rational that constructors expand.
pub(crate) const MAX_FOLD_EXPONENT: i64 = 64;

impl Pool {
    /// The number of nodes stored.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// The work done on the pool: how many nodes its constructors have built
    /// (an existing node found again counts too). It grows with the time spent
    /// in building and rewriting, and never depends on the machine.
    pub fn work(&self) -> u64 {
        self.work
    }

    /// Bounds the work: once [`Pool::work`] passes `limit`, the rewrites
    /// (expansion, trigonometric combination, factoring, quotients) leave what
    /// they have not rewritten yet as it is, so a caller that checks
    /// [`Pool::work_exhausted`] between its steps stops soon after. `None`
    /// lifts the bound. Results rewritten past the bound are still identities,
    /// only less simplified, and a proof of zero may fail where it would have
    /// succeeded: a caller that needs the full rewrites must treat an exhausted
    /// pool as an error.
    pub fn set_work_limit(&mut self, limit: Option<u64>) {
        self.work_limit = limit;
    }

    /// True when a work limit is set and the pool has done more work than it.
    pub fn work_exhausted(&self) -> bool {
        self.work_limit.is_some_and(|limit| self.work > limit)
    }

    /// True when no node is stored (never: the constants are preloaded).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The node behind an id.
    pub fn node(&self, id: ExprId) -> &Node {
        &self.nodes[id.index()]
    }

    /// The node `id` with each child `c` replaced by `new(c)`, rebuilt in
    /// canonical form; `id` itself when no child changes.
    pub(crate) fn rebuild(&mut self, id: ExprId, new: impl Fn(ExprId) -> ExprId) -> ExprId {
        match self.node(id) {
            Node::Num(_) | Node::Pi | Node::Sym(_) => id,
            Node::Add(ts) | Node::Mul(ts) => {
                if ts.iter().all(|&c| new(c) == c) {
                    return id;
                }
                let is_add = matches!(self.node(id), Node::Add(_));
                let ts: Vec<ExprId> = ts.iter().map(|&c| new(c)).collect();
                if is_add {
                    self.add(&ts)
                } else {
                    self.mul(&ts)
                }
            }
            &Node::Pow(b, p) => {
                let (nb, np) = (new(b), new(p));
                if (nb, np) == (b, p) {
                    id
                } else {
                    self.pow(nb, np)
                }
            }
            &Node::Func(f, u) => {
                let nu = new(u);
                if nu == u {
                    id
                } else {
                    self.func(f, nu)
                }
            }
            &Node::Atan2(y, x) => {
                let (ny, nx) = (new(y), new(x));
                if (ny, nx) == (y, x) {
                    id
                } else {
                    self.atan2(ny, nx)
                }
            }
        }
    }

    /// The Bloom filter of the symbols of `e` (see [`Pool::may_contain`]).
    pub(crate) fn sym_mask(&self, e: ExprId) -> u64 {
        self.sym_masks[e.index()]
    }

    /// True when `x` (a symbol node) may occur in `e`; false proves it does
    /// not (a Bloom filter: no traversal, but false positives).
    pub(crate) fn may_contain(&self, e: ExprId, x: ExprId) -> bool {
        let bit = self.sym_masks[x.index()];
        self.sym_masks[e.index()] & bit == bit
    }

    /// The size of `e` written out as a tree (how long its printed form is, roughly).
    pub fn tree_size(&self, e: ExprId) -> u64 {
        self.tree_sizes[e.index()]
    }

    /// The children of a node, in order.
    pub fn children<'a>(&'a self, node: &'a Node) -> Vec<ExprId> {
        match node {
            Node::Num(_) | Node::Pi | Node::Sym(_) => Vec::new(),
            Node::Add(ts) | Node::Mul(ts) => ts.to_vec(),
            Node::Pow(a, b) | Node::Atan2(a, b) => vec![*a, *b],
            Node::Func(_, a) => vec![*a],
        }
    }

    // ---- names and symbols -------------------------------------------------

    /// Interns a name.
    pub fn name(&mut self, name: &str) -> NameId {
        if let Some(&id) = self.name_index.get(name) {
            return id;
        }
        let id = NameId(self.names.len() as u32);
        self.names.push(name.into());
        self.name_index.insert(name.into(), id);
        self.name_rank.push(1);
        id
    }

    /// The text of a name.
    pub fn name_str(&self, name: NameId) -> &str {
        &self.names[name.0 as usize]
    }

    /// Looks a name up without interning it.
    pub fn find_name(&self, name: &str) -> Option<NameId> {
        self.name_index.get(name).copied()
    }

    /// Sets where symbols of this name sort in products and sums (lower first;
    /// default 1). Call it before building expressions that use the name: it
    /// decides the canonical order, e.g. constants (rank 0) before variables
    /// (rank 2) so that `m*l^2*q''` reads as people write it.
    pub fn set_rank(&mut self, name: &str, rank: u8) {
        let id = self.name(name);
        self.name_rank[id.0 as usize] = rank;
    }

    /// The symbol `name` differentiated `order` times in time.
    pub fn var(&mut self, name: &str, order: u8) -> ExprId {
        let name = self.name(name);
        self.intern(Node::Sym(Symbol { name, order }))
    }

    /// The plain symbol `name`.
    pub fn symbol(&mut self, name: &str) -> ExprId {
        self.var(name, 0)
    }

    /// The first time derivative `name'`.
    pub fn velocity(&mut self, name: &str) -> ExprId {
        self.var(name, 1)
    }

    /// The node of a symbol value.
    pub fn sym(&mut self, s: Symbol) -> ExprId {
        self.intern(Node::Sym(s))
    }

    /// The symbol behind an id, if it is one.
    pub fn as_symbol(&self, id: ExprId) -> Option<Symbol> {
        match self.node(id) {
            Node::Sym(s) => Some(*s),
            _ => None,
        }
    }

    /// The text of a symbol: its name followed by its primes.
    pub fn symbol_text(&self, s: Symbol) -> String {
        let mut text = self.name_str(s.name).to_string();
        for _ in 0..s.order {
            text.push('\'');
        }
        text
    }

    // ---- constants ------------------------------------------------------------

    /// A numeric constant.
    pub fn number(&mut self, n: Number) -> ExprId {
        let n = match n {
            Number::Float(x) => Number::float(x),
            r => r,
        };
        self.intern(Node::Num(n))
    }

    /// The integer `n`.
    pub fn int(&mut self, n: i64) -> ExprId {
        self.number(Number::Rational(Rational::int(n as i128)))
    }

    /// The exact fraction `n/d` (`d` must not be zero; zero gives a float NaN-free error value of 0).
    pub fn rational(&mut self, n: i64, d: i64) -> ExprId {
        match Rational::new(n as i128, d as i128) {
            Some(r) => self.number(Number::Rational(r)),
            None => self.int(0),
        }
    }

    /// A floating constant.
    pub fn float(&mut self, x: f64) -> ExprId {
        self.number(Number::float(x))
    }

    /// Zero.
    pub fn zero(&self) -> ExprId {
        ExprId(0)
    }

    /// One.
    pub fn one(&self) -> ExprId {
        ExprId(1)
    }

    /// Minus one.
    pub fn minus_one(&self) -> ExprId {
        ExprId(2)
    }

    /// π.
    pub fn pi(&mut self) -> ExprId {
        self.intern(Node::Pi)
    }

    /// The number behind an id, if it is one.
    pub fn as_number(&self, id: ExprId) -> Option<Number> {
        match self.node(id) {
            Node::Num(n) => Some(*n),
            _ => None,
        }
    }

    /// True when the id is the exact or floating zero.
    pub fn is_zero(&self, id: ExprId) -> bool {
        self.as_number(id).is_some_and(|n| n.is_zero())
    }

    // ---- arithmetic -------------------------------------------------------------

    /// `a + b`.
    pub fn add2(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.add(&[a, b])
    }

    /// `a - b`.
    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let nb = self.neg(b);
        self.add(&[a, nb])
    }

    /// `-a`.
    pub fn neg(&mut self, a: ExprId) -> ExprId {
        let m1 = self.minus_one();
        self.mul(&[m1, a])
    }

    /// `a * b`.
    pub fn mul2(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.mul(&[a, b])
    }

    /// `a / b`.
    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let m1 = self.minus_one();
        let inv = self.pow(b, m1);
        self.mul(&[a, inv])
    }

    /// `a ^ n` for an integer `n`.
    pub fn powi(&mut self, a: ExprId, n: i64) -> ExprId {
        let n = self.int(n);
        self.pow(a, n)
    }

    /// `sqrt(a)`, stored as `a^(1/2)`.
    pub fn sqrt(&mut self, a: ExprId) -> ExprId {
        let half = self.rational(1, 2);
        self.pow(a, half)
    }

    /// Splits a term into its numeric coefficient and the rest (`3*x*y` → `(3, x*y)`).
    pub fn split_coeff(&mut self, id: ExprId) -> (Number, ExprId) {
        let Node::Mul(fs) = self.node(id) else {
            return match self.as_number(id) {
                Some(n) => (n, self.one()),
                None => (Number::ONE, id),
            };
        };
        let Some(n) = self.as_number(fs[0]) else { return (Number::ONE, id) };
        if fs.len() == 2 {
            return (n, fs[1]);
        }
        // The rest of a canonical product is canonical: look it up as it is.
        let rest = &fs[1..];
        let hash = hash_seq(Seq::Mul, rest);
        match self.lookup(hash, |node| matches!(node, Node::Mul(gs) if **gs == *rest)) {
            Ok(r) => (n, r),
            Err(slot) => {
                let node = Node::Mul(rest.into());
                (n, self.insert(node, hash, slot))
            }
        }
    }

    /// `c * rest` without re-canonicalizing `rest` (it is already canonical).
    fn scale(&mut self, c: Number, rest: ExprId) -> ExprId {
        if c.is_zero() {
            return self.zero();
        }
        if c.is_one() {
            return rest;
        }
        if let Node::Num(r) = self.node(rest) {
            let v = c.times(*r);
            return self.number(v);
        }
        let c = self.number(c);
        let mut fs: Vec<ExprId> = Vec::with_capacity(8);
        fs.push(c);
        match self.node(rest) {
            Node::Mul(inner) => fs.extend_from_slice(inner),
            _ => fs.push(rest),
        }
        self.intern_seq(Seq::Mul, &fs)
    }

    /// The canonical sum of `terms`.
    pub fn add(&mut self, terms: &[ExprId]) -> ExprId {
        let mut acc = SumAcc::default();
        for &t in terms {
            match self.node(t) {
                Node::Add(ts) => {
                    // Canonical sums never nest, so one level of flattening suffices.
                    for k in 0..ts.len() {
                        let Node::Add(ts) = self.node(t) else { unreachable!() };
                        let u = ts[k];
                        self.add_term(&mut acc, u);
                    }
                }
                _ => self.add_term(&mut acc, t),
            }
        }
        let SumAcc { constant, parts, .. } = acc;
        let mut out: Vec<ExprId> = Vec::with_capacity(parts.len() + 1);
        for (rest, c) in parts {
            if !c.is_zero() {
                out.push(self.scale(c, rest));
            }
        }
        out.sort_by(|&a, &b| self.cmp_terms(a, b));
        if !constant.is_zero() || (out.is_empty() && matches!(constant, Number::Float(_))) {
            out.push(self.number(constant));
        }
        match out.len() {
            0 => self.zero(),
            1 => out[0],
            _ => self.intern_seq(Seq::Add, &out),
        }
    }

    /// Adds one term (not a sum) to a sum being built.
    fn add_term(&mut self, acc: &mut SumAcc, t: ExprId) {
        if let Node::Add(_) = self.node(t) {
            // Only a non-canonical caller nests sums; flatten it all the same.
            let ts = self.terms(t);
            for u in ts {
                self.add_term(acc, u);
            }
            return;
        }
        if let Some(n) = self.as_number(t) {
            acc.constant = acc.constant.plus(n);
            return;
        }
        let (c, rest) = self.split_coeff(t);
        // Small sums (the common case) find like parts by a linear scan.
        let found = if acc.parts.len() <= SMALL {
            acc.parts.iter().position(|p| p.0 == rest)
        } else {
            if acc.index.is_empty() {
                acc.index.extend(acc.parts.iter().enumerate().map(|(i, p)| (p.0, i)));
            }
            acc.index.get(&rest).copied()
        };
        match found {
            Some(i) => acc.parts[i].1 = acc.parts[i].1.plus(c),
            None => {
                if !acc.index.is_empty() {
                    acc.index.insert(rest, acc.parts.len());
                }
                acc.parts.push((rest, c));
            }
        }
    }

    /// The canonical product of `factors`.
    pub fn mul(&mut self, factors: &[ExprId]) -> ExprId {
        let mut coeff = Number::ONE;
        // Exponent per base, in first-seen order.
        let mut parts: Vec<(ExprId, ExprId)> = Vec::with_capacity(factors.len() + 4);
        for &f in factors {
            match self.node(f) {
                Node::Mul(fs) => {
                    for k in 0..fs.len() {
                        let Node::Mul(fs) = self.node(f) else { unreachable!() };
                        let g = fs[k];
                        self.mul_factor(&mut coeff, &mut parts, g);
                    }
                }
                _ => self.mul_factor(&mut coeff, &mut parts, f),
            }
        }
        if coeff.is_zero() {
            return self.number(coeff);
        }
        let mut out: Vec<ExprId> = Vec::with_capacity(parts.len() + 1);
        // Set when a power changed its base (e.g. (x^a)^2 = x^(2a)) or split
        // into a product: then two factors may share a base again.
        let mut rebased = false;
        for &(base, exp) in &parts {
            let f = self.pow(base, exp);
            match self.node(f) {
                Node::Num(n) => coeff = coeff.times(*n),
                Node::Mul(fs) => {
                    // A power that folded into a product (e.g. (2*x)^2 = 4*x^2).
                    rebased = true;
                    for k in 0..fs.len() {
                        let Node::Mul(fs) = self.node(f) else { unreachable!() };
                        let g = fs[k];
                        match self.as_number(g) {
                            Some(n) => coeff = coeff.times(n),
                            None => out.push(g),
                        }
                    }
                }
                _ => {
                    rebased |= self.base_exp(f).0 != base;
                    out.push(f);
                }
            }
        }
        if coeff.is_zero() {
            return self.number(coeff);
        }
        // Merge factors that share a base after folding.
        if rebased && out.len() > 1 {
            let dup = (1..out.len()).any(|i| (0..i).any(|j| self.base_exp(out[j]).0 == self.base_exp(out[i]).0));
            if dup {
                let c = self.number(coeff);
                out.insert(0, c);
                return self.mul(&out);
            }
        }
        // A number times one sum distributes: 2*(x + y) = 2*x + 2*y, so that
        // -(a - b) is b - a and negation never nests.
        if out.len() == 1 && !coeff.is_one() {
            if let Node::Add(ts) = self.node(out[0]).clone() {
                let c = self.number(coeff);
                let scaled: Vec<ExprId> = ts.iter().map(|&t| self.mul2(c, t)).collect();
                return self.add(&scaled);
            }
        }
        out.sort_by(|&a, &b| self.cmp(a, b));
        if !coeff.is_one() || out.is_empty() {
            if out.is_empty() {
                return self.number(coeff);
            }
            out.insert(0, self.number(coeff));
        }
        match out.len() {
            1 => out[0],
            _ => self.intern_seq(Seq::Mul, &out),
        }
    }

    /// Multiplies one factor (not a product) into a product being built.
    fn mul_factor(&mut self, coeff: &mut Number, parts: &mut Vec<(ExprId, ExprId)>, f: ExprId) {
        if let Node::Mul(_) = self.node(f) {
            // Only a non-canonical caller nests products; flatten it all the same.
            let fs = self.factors(f);
            for g in fs {
                self.mul_factor(coeff, parts, g);
            }
            return;
        }
        if let Some(n) = self.as_number(f) {
            *coeff = coeff.times(n);
            return;
        }
        let (base, exp) = self.base_exp(f);
        match parts.iter().position(|p| p.0 == base) {
            Some(i) => {
                let prev = parts[i].1;
                parts[i].1 = match (self.as_number(prev), self.as_number(exp)) {
                    (Some(a), Some(b)) => self.number(a.plus(b)),
                    _ => self.add2(prev, exp),
                };
            }
            None => parts.push((base, exp)),
        }
    }

    /// Splits a factor into base and exponent (`x^2` → `(x, 2)`, `x` → `(x, 1)`).
    pub fn base_exp(&self, id: ExprId) -> (ExprId, ExprId) {
        match self.node(id) {
            Node::Pow(b, e) => (*b, *e),
            _ => (id, self.one()),
        }
    }

    /// The canonical power `base ^ exp`.
    pub fn pow(&mut self, base: ExprId, exp: ExprId) -> ExprId {
        let e_num = self.as_number(exp);
        if let Some(e) = e_num {
            if e.is_zero() {
                return self.one();
            }
            if e.is_one() {
                return base;
            }
        }
        match (self.node(base).clone(), e_num) {
            (Node::Num(b), Some(e)) => {
                if let Some(v) = fold_number_pow(b, e) {
                    return self.number(v);
                }
            }
            (Node::Num(b), None) if b.is_one() => return self.one(),
            // (x^a)^n = x^(a*n) for integer n.
            (Node::Pow(b, a), Some(Number::Rational(n))) if n.is_integer() => {
                let ae = self.mul2(a, exp);
                return self.pow(b, ae);
            }
            // (x^a)^r = x^(a*r) when a is an odd integer... keep it simple and
            // exact: only (x^(2k))^(1/2) is |x|^k, which we do not rewrite.
            (Node::Mul(fs), Some(Number::Rational(n))) if n.is_integer() => {
                let parts: Vec<ExprId> = fs.iter().map(|&f| self.pow(f, exp)).collect();
                return self.mul(&parts);
            }
            _ => {}
        }
        if self.is_zero(base) {
            if let Some(e) = e_num {
                if !e.is_negative() {
                    return self.zero();
                }
            }
        }
        self.intern(Node::Pow(base, exp))
    }

    /// `f(arg)`, with exact values folded (`sin(0) = 0`) and parity applied
    /// (`cos(-x) = cos(x)`, `sin(-x) = -sin(x)`).
    pub fn func(&mut self, f: Func, arg: ExprId) -> ExprId {
        if let Some(n) = self.as_number(arg) {
            if n.is_zero() {
                match f {
                    Func::Sin | Func::Tan | Func::Asin | Func::Atan | Func::Sinh | Func::Tanh | Func::Abs => {
                        return self.zero()
                    }
                    Func::Cos | Func::Cosh | Func::Exp => return self.one(),
                    Func::Acos | Func::Log => {}
                }
            }
            if f == Func::Log && n.is_one() {
                return self.zero();
            }
            if f == Func::Abs {
                return self.number(n.abs());
            }
            if let Number::Float(x) = n {
                let v = f.apply(x);
                if v.is_finite() {
                    return self.float(v);
                }
            }
        }
        if self.is_negated(arg) {
            let pos = self.neg(arg);
            debug_assert!(!self.is_negated(pos), "negation must flip the sign");
            match f {
                Func::Cos | Func::Cosh | Func::Abs => return self.func(f, pos),
                Func::Sin | Func::Tan | Func::Asin | Func::Atan | Func::Sinh | Func::Tanh => {
                    let v = self.func(f, pos);
                    return self.neg(v);
                }
                _ => {}
            }
        }
        if f == Func::Log {
            if let Node::Func(Func::Exp, x) = self.node(arg) {
                return *x;
            }
        }
        self.intern(Node::Func(f, arg))
    }

    /// `atan2(y, x)`.
    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        if let (Some(Number::Float(a)), Some(Number::Float(b))) = (self.as_number(y), self.as_number(x)) {
            return self.float(a.atan2(b));
        }
        self.intern(Node::Atan2(y, x))
    }

    /// True when the expression reads with a leading minus (negative coefficient,
    /// or a sum whose first term does), so that `-e` is the nicer form.
    pub fn is_negated(&self, id: ExprId) -> bool {
        match self.node(id) {
            Node::Num(n) => n.is_negative(),
            Node::Mul(fs) => self.as_number(fs[0]).is_some_and(|n| n.is_negative()),
            Node::Add(ts) => self.is_negated(ts[0]),
            _ => false,
        }
    }
}

/// A sum being built by [`Pool::add`]: the constant, and the coefficient of
/// each non-numeric part in first-seen order (indexed by a map once it is long).
struct SumAcc {
    constant: Number,
    parts: Vec<(ExprId, Number)>,
    index: FxHashMap<ExprId, usize>,
}

impl Default for SumAcc {
    fn default() -> Self {
        SumAcc { constant: Number::ZERO, parts: Vec::new(), index: FxHashMap::default() }
    }
}

/// Folds `b^e` for numbers when the result is exact or both are floats.
fn fold_number_pow(b: Number, e: Number) -> Option<Number> {
    match (b, e) {
        (Number::Rational(b), Number::Rational(e)) => {
            if e.is_integer() {
                let n = i64::try_from(e.numer()).ok()?;
                if n.unsigned_abs() > 4 * MAX_FOLD_EXPONENT as u64 {
                    return None;
                }
                b.pow(n).map(Number::Rational)
            } else {
                // Exact roots only: 4^(1/2) = 2, 8^(2/3) = 4.
                let root = b.exact_root(u32::try_from(e.denom()).ok()?)?;
                root.pow(i64::try_from(e.numer()).ok()?).map(Number::Rational)
            }
        }
        _ => {
            let v = b.to_f64().powf(e.to_f64());
            v.is_finite().then(|| Number::float(v))
        }
    }
}
