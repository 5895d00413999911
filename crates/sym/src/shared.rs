//! Named intermediates: the subexpressions that a printout of several
//! expressions would write again and again, each written once as a
//! definition `w1 = …` and referred to by its name everywhere else.
//!
//! Enter with [`Pool::share`], given the roots of everything one output
//! prints; print the roots with [`Shared::print`] and the definitions, in
//! order, with [`Shared::definitions`] and [`Shared::print_definition`].
//! [`Pool::sharing_pays`] says whether an output is large enough to be
//! printed this way: small ones print as trees, as they always have. A
//! [`Printout`] lets one rendering code run twice: once to list its roots,
//! once to write them with the names chosen.
//!
//! A node is named when the printout would write it more than once (it has
//! two or more uses, counting each parent's use and each root's), unless its
//! tree is tiny (`sin(q1)` reads better than a name for it); and when a
//! node's text, with the named nodes cut out, would still be very long, its
//! longest children are named too. Names are
//! `w1, w2, …` in children-first order (so each definition uses only names
//! defined before it), skipping any name the pool knows, so that no
//! definition clashes with a symbol of the expressions. Every node not
//! named and not tiny is then written once, and the printout grows with the
//! size of the DAG instead of the size of its trees, which can be
//! exponentially larger.
//!
//! The text parses back: parsing the definitions in order and substituting
//! each into the next, and into the roots, gives the original expressions
//! (checked by a property test at random points).

use crate::expr::{ExprId, Pool};
use crate::print::{Names, PrintOptions, Printed};
use rustc_hash::FxHashMap;
use std::cell::RefCell;

/// The smallest tree (in nodes, [`Pool::tree_size`]) named when it is shared.
///
/// Measured on the benchmark bicycle (`derive` text, 1.5 MB as trees): 135 kB
/// with 3 or 4, 145 kB with 5, 152 kB with 8, 192 kB with 16, 215 kB with 32.
/// Below 5 the saving is small and names stand for short products
/// (`l*sin(q1)`, 4 nodes); at 5 `sin(q1)` (2) and `l*sin(q1)` stay inline,
/// and `a - b` (5) and `a*b + c*d` (7) are named.
pub const MIN_NAMED_TREE: u64 = 5;

/// The longest text (in nodes, with the named nodes counted as one) a node
/// used only once is written out in. A longer one is named too, so that no
/// root or definition nests the whole of a huge expression: its lines stay
/// readable, and the printer's recursion stays shallow.
pub const MAX_CUT_TREE: u64 = 2000;

/// The total tree size of an output's roots past which it is printed with
/// named intermediates. Every example model but the bicycle is well below
/// it (the largest, `chain50`, prints 8 592 nodes in its JSON report; the
/// bicycle 438 574, the 20-link pendulum of rods some 4.4 million).
pub const SHARING_PAYS_ABOVE: u64 = 100_000;

/// The nodes to name in one printout, with their names; see the module documentation.
#[derive(Clone, Debug, Default)]
pub struct Shared {
    /// The named nodes, children first, each with the number of its name (`w12`: 12).
    defs: Vec<(ExprId, usize)>,
    /// The position in `defs` of each named node.
    index: FxHashMap<ExprId, usize>,
}

impl Pool {
    /// Whether printing `roots` (everything one output prints) with named
    /// intermediates pays: whether their trees add up to more than
    /// [`SHARING_PAYS_ABOVE`] nodes.
    pub fn sharing_pays(&self, roots: &[ExprId]) -> bool {
        roots.iter().map(|&r| self.tree_size(r)).fold(0u64, u64::saturating_add) > SHARING_PAYS_ABOVE
    }

    /// The nodes to name when `roots` are printed together (a root listed
    /// twice is printed twice); see the module documentation.
    pub fn share(&self, roots: &[ExprId]) -> Shared {
        let order = self.reachable(roots);
        let position: FxHashMap<ExprId, usize> = order.iter().enumerate().map(|(i, &id)| (id, i)).collect();
        let mut uses = vec![0u32; order.len()];
        for r in roots {
            uses[position[r]] += 1;
        }
        for &id in &order {
            for c in self.children(self.node(id)) {
                uses[position[&c]] += 1;
            }
        }
        // Children first: a node's printed size counts each named child as one.
        let mut cut = vec![0u64; order.len()];
        let mut named = vec![false; order.len()];
        for (i, &id) in order.iter().enumerate() {
            let children: Vec<usize> = self.children(self.node(id)).iter().map(|c| position[c]).collect();
            let mut size = children.iter().fold(1u64, |s, &k| s.saturating_add(if named[k] { 1 } else { cut[k] }));
            if size > MAX_CUT_TREE {
                // Too long to read as one line: its longest children (used
                // only here, or they would be named) are named until it fits.
                let mut long: Vec<usize> =
                    children.into_iter().filter(|&k| !named[k] && self.tree_size(order[k]) >= MIN_NAMED_TREE).collect();
                long.sort_unstable_by_key(|&k| std::cmp::Reverse(cut[k]));
                for k in long {
                    if size <= MAX_CUT_TREE {
                        break;
                    }
                    named[k] = true;
                    size -= cut[k] - 1;
                }
            }
            cut[i] = size;
            named[i] = uses[i] >= 2 && self.tree_size(id) >= MIN_NAMED_TREE;
        }
        let mut shared = Shared::default();
        let mut k = 0;
        for (i, &id) in order.iter().enumerate().filter(|&(i, _)| named[i]) {
            k += 1;
            while self.find_name(&format!("w{k}")).is_some() {
                k += 1;
            }
            shared.index.insert(id, shared.defs.len());
            shared.defs.push((id, k));
            debug_assert_eq!(i, position[&id]);
        }
        shared
    }
}

impl Shared {
    /// Whether nothing is named.
    pub fn is_empty(&self) -> bool {
        self.defs.is_empty()
    }

    /// The number of named nodes.
    pub fn len(&self) -> usize {
        self.defs.len()
    }

    /// The number of `id`'s name (`w12`: 12), if it is named.
    pub fn number_of(&self, id: ExprId) -> Option<usize> {
        self.index.get(&id).map(|&i| self.defs[i].1)
    }

    /// The named nodes with their names as text (`w12`), in definition
    /// order: children first, each defined after the names it uses.
    pub fn definitions(&self) -> impl Iterator<Item = (String, ExprId)> + '_ {
        self.defs.iter().map(|&(id, k)| (format!("w{k}"), id))
    }

    /// `id` as `options` say, each named node in it written as its name
    /// (`id` too, when it is named).
    pub fn print<'a>(&'a self, pool: &'a Pool, id: ExprId, options: PrintOptions) -> Printed<'a> {
        Printed::with_names(pool, id, options, self, false)
    }

    /// The right side of a definition: `id` written out, the named nodes
    /// inside it written as their names.
    pub fn print_definition<'a>(&'a self, pool: &'a Pool, id: ExprId, options: PrintOptions) -> Printed<'a> {
        Printed::with_names(pool, id, options, self, true)
    }
}

/// How an output writes its expressions.
#[derive(Debug)]
pub enum Printout {
    /// As trees, in full.
    Trees,
    /// Not at all (as empty strings): each expression is listed, so that a
    /// first pass over an output finds the roots it prints.
    Roots(RefCell<Vec<ExprId>>),
    /// With the named nodes as their names.
    Named(Shared),
}

impl Printout {
    /// A printout that lists the roots.
    pub fn roots() -> Printout {
        Printout::Roots(RefCell::default())
    }

    /// `e` as `options` say, or "" while listing roots.
    pub fn write(&self, pool: &Pool, e: ExprId, options: PrintOptions) -> String {
        match self {
            Printout::Trees => pool.print(e, options).to_string(),
            Printout::Roots(roots) => {
                roots.borrow_mut().push(e);
                String::new()
            }
            Printout::Named(shared) => shared.print(pool, e, options).to_string(),
        }
    }

    /// The roots listed (none unless listing).
    pub fn into_roots(self) -> Vec<ExprId> {
        match self {
            Printout::Roots(roots) => roots.into_inner(),
            _ => Vec::new(),
        }
    }

    /// The named nodes, if any.
    pub fn shared(&self) -> Option<&Shared> {
        match self {
            Printout::Named(shared) => Some(shared),
            _ => None,
        }
    }
}

impl Names for Shared {
    fn number_of(&self, id: ExprId) -> Option<usize> {
        Shared::number_of(self, id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Func;
    use proptest::prelude::*;
    use proptest::test_runner::RngSeed;
    use std::cell::{Cell, RefCell};

    /// Parses `roots`, names their shared nodes, and checks the printout:
    /// the definitions and roots in text, as `expect` lists them (`w1 = …`
    /// lines, then the roots), and that they parse back to the originals.
    #[track_caller]
    fn check(roots: &[&str], expect: &str) {
        let mut pool = Pool::default();
        let ids: Vec<ExprId> = roots.iter().map(|r| pool.parse(r).expect("parses")).collect();
        let shared = pool.share(&ids);
        let mut lines: Vec<String> = shared
            .definitions()
            .map(|(n, id)| format!("{n} = {}", shared.print_definition(&pool, id, PrintOptions::text())))
            .collect();
        lines.extend(ids.iter().map(|&id| shared.print(&pool, id, PrintOptions::text()).to_string()));
        assert_eq!(lines.join("\n"), expect.trim());
        check_parses_back(&mut pool, &shared, &ids);
    }

    /// Parses the definitions in order, substitutes each into the next and
    /// into the printed roots, and checks that the roots come back with the
    /// same values at random points.
    #[track_caller]
    fn check_parses_back(pool: &mut Pool, shared: &Shared, roots: &[ExprId]) {
        let defs: Vec<(String, String)> = shared
            .definitions()
            .map(|(n, id)| (n, shared.print_definition(pool, id, PrintOptions::text()).to_string()))
            .collect();
        let texts: Vec<String> =
            roots.iter().map(|&id| shared.print(pool, id, PrintOptions::text()).to_string()).collect();
        let mut map: FxHashMap<ExprId, ExprId> = FxHashMap::default();
        for (name, text) in &defs {
            let e = pool.parse(text).unwrap_or_else(|err| panic!("{name} = {text}: {err}"));
            let value = pool.substitute(e, &map);
            let sym = pool.symbol(name);
            map.insert(sym, value);
        }
        let rng = Cell::new(0x2545_f491_4f6c_dd1du64);
        for (&root, text) in roots.iter().zip(&texts) {
            let e = pool.parse(text).unwrap_or_else(|err| panic!("{text}: {err}"));
            let back = pool.substitute(e, &map);
            for _ in 0..3 {
                // Each symbol a value in [0.5, 1.5), the same in both evaluations.
                let values: RefCell<FxHashMap<String, f64>> = RefCell::default();
                let env = |name: &str| -> Option<f64> {
                    Some(*values.borrow_mut().entry(name.to_string()).or_insert_with(|| {
                        let mut r = rng.get();
                        r ^= r << 13;
                        r ^= r >> 7;
                        r ^= r << 17;
                        rng.set(r);
                        0.5 + (r >> 11) as f64 / (1u64 << 53) as f64
                    }))
                };
                let want = pool.eval(root, &env).expect("evaluates");
                let got = pool.eval(back, &env).expect("evaluates");
                let tol = 1e-9 * (1.0 + want.abs());
                assert!((want - got).abs() <= tol || (want.is_nan() && got.is_nan()), "{text}: {want} != {got}");
            }
        }
    }

    #[test]
    fn shared_nodes_are_named_once() {
        // Nothing shared: printed as trees.
        check(&["a*b + c*d", "sin(q1)"], "a*b + c*d\nsin(q1)");
        let chain = [doubling_chain(3)];
        check(
            &chain.each_ref().map(|s| s.as_str()),
            "w1 = x + 2*sin(x + y)*(x + y)\nw2 = x + 3*cos(w1)*w1\nx + 4*sin(w2)*w2",
        );
        // Tiny shared nodes stay inline; a shared sum of products is named,
        // in every root and inside other expressions.
        check(
            &["sin(q1)*(a*b + c*d)", "cos(a*b + c*d) + sin(q1)", "a*b + c*d"],
            "w1 = a*b + c*d\nsin(q1)*w1\nsin(q1) + cos(w1)\nw1",
        );
        // A root printed twice (a symmetric matrix's entries) is named.
        check(&["x*y + z^2", "x*y + z^2"], "w1 = x*y + z^2\nw1\nw1");
        // Names skip the symbols of the expressions; definitions use earlier ones.
        check(
            &["w1 + exp(x*y + z)*(x*y + z)", "(x*y + z)^3 + exp(x*y + z)*(x*y + z)"],
            "w2 = x*y + z\nw3 = exp(w2)*w2\nw1 + w3\nw3 + w2^3",
        );
        // A named term keeps its sign inside; a named power stays above the bar.
        check(
            &["a - 2*x*(y + z)", "b - 2*x*(y + z)", "c/(x*y+z)^2", "d/(x*y+z)^2"],
            "w1 = -2*x*(y + z)\nw2 = 1/(x*y + z)^2\na + w1\nb + w1\nc*w2\nd*w2",
        );
    }

    #[test]
    fn typeset_names() {
        let mut pool = Pool::default();
        let e = pool.parse("sin(x*y + z)^2*(x*y + z)").expect("parses");
        let w = pool.parse("x*y + z").expect("parses");
        let shared = pool.share(&[e]);
        assert_eq!(shared.number_of(w), Some(1));
        assert_eq!(shared.print(&pool, e, PrintOptions::latex()).to_string(), "\\sin^{2}{\\left(w_{1} \\right)} w_{1}");
        assert_eq!(
            shared.print(&pool, e, PrintOptions::mathml()).to_string(),
            "<mrow><mrow><msup><mi>sin</mi><mn>2</mn></msup><mo>&#x2061;</mo><mrow><mo>(</mo>\
             <msub><mi>w</mi><mn>1</mn></msub><mo>)</mo></mrow></mrow><mo>&#x2062;</mo>\
             <msub><mi>w</mi><mn>1</mn></msub></mrow>"
        );
    }

    /// An expression with much sharing: each step uses the previous one twice.
    fn doubling_chain_in(pool: &mut Pool, n: usize) -> ExprId {
        let (x, y) = (pool.symbol("x"), pool.symbol("y"));
        let mut e = pool.add2(x, y);
        for k in 0..n {
            let s = pool.func(if k % 2 == 0 { Func::Sin } else { Func::Cos }, e);
            let c = pool.int(k as i64 + 2);
            let p = pool.mul(&[c, e, s]);
            e = pool.add(&[p, x]);
        }
        e
    }

    /// [`doubling_chain_in`] as text.
    fn doubling_chain(n: usize) -> String {
        let mut pool = Pool::default();
        let e = doubling_chain_in(&mut pool, n);
        pool.display(e).to_string()
    }

    #[test]
    fn chains_print_in_linear_size() {
        let mut pool = Pool::default();
        let e = doubling_chain_in(&mut pool, 40);
        assert!(pool.tree_size(e) > 1 << 40, "a tree that could not be printed");
        let shared = pool.share(&[e]);
        let total: usize = shared
            .definitions()
            .map(|(_, id)| shared.print_definition(&pool, id, PrintOptions::text()).to_string().len())
            .sum();
        assert!(total < 40 * 30, "{total} characters");
        let e = doubling_chain_in(&mut pool, 12);
        let shared = pool.share(&[e]);
        check_parses_back(&mut pool, &shared, &[e]);
    }

    /// A long expression used once is cut into definitions of bounded length.
    #[test]
    fn long_expressions_are_cut() {
        let mut pool = Pool::default();
        let terms: Vec<ExprId> = (0..3 * MAX_CUT_TREE as i64)
            .map(|k| {
                let (a, b) = (pool.symbol(&format!("a{k}")), pool.symbol(&format!("b{}", k % 7)));
                let s = pool.func(Func::Sin, b);
                pool.mul(&[a, s])
            })
            .collect();
        let chunks: Vec<ExprId> = terms.chunks(50).map(|c| pool.add(c)).collect();
        let inner: Vec<ExprId> = chunks
            .iter()
            .map(|&c| {
                let x = pool.symbol("x");
                pool.mul2(x, c)
            })
            .collect();
        let e = pool.add(&inner);
        let shared = pool.share(&[e]);
        assert!(!shared.is_empty());
        check_parses_back(&mut pool, &shared, &[e]);
    }

    /// Random expressions over a few symbols, with deliberate sharing: each
    /// new node combines earlier ones, so later ones reuse them.
    fn random_dag(pool: &mut Pool, ops: &[(u8, usize, usize)]) -> Vec<ExprId> {
        let mut nodes: Vec<ExprId> = ["x", "y", "z", "q1'"].iter().map(|s| pool.parse(s).expect("parses")).collect();
        nodes.push(pool.int(3));
        for &(op, i, j) in ops {
            let (a, b) = (nodes[i % nodes.len()], nodes[j % nodes.len()]);
            let e = match op % 6 {
                0 => pool.add2(a, b),
                1 => pool.mul2(a, b),
                2 => pool.sub(a, b),
                3 => pool.func(Func::Sin, a),
                4 => {
                    let two = pool.int(2);
                    let sq = pool.pow(a, two);
                    let one = pool.one();
                    let d = pool.add2(sq, one);
                    pool.div(b, d)
                }
                _ => pool.neg(a),
            };
            nodes.push(e);
        }
        nodes
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, rng_seed: RngSeed::Fixed(30), failure_persistence: None, ..ProptestConfig::default() })]
        #[test]
        fn definitions_parse_back(ops in prop::collection::vec((0u8..6, 0usize..64, 0usize..64), 1..40), picks in prop::collection::vec(0usize..64, 1..5)) {
            let mut pool = Pool::default();
            let nodes = random_dag(&mut pool, &ops);
            let roots: Vec<ExprId> = picks.iter().map(|&p| nodes[nodes.len() - 1 - p % nodes.len()]).collect();
            let shared = pool.share(&roots);
            check_parses_back(&mut pool, &shared, &roots);
        }
    }
}
