//! Target (a): the expression parser on arbitrary text. Enter with
//! [`check_expression`] (one text) or [`ExprTarget`] (the fuzz loop).
//!
//! For every text: no panic; an error's span lies inside the text on character
//! boundaries, also when names are checked; what parses prints as text that
//! parses back to the same expression (the same id in the same pool), prints
//! as LaTeX, differentiates, and simplifies to an expression of the same value
//! wherever every subexpression is finite and moderate.

use crate::corpus::{Corpus, Inputs};
use crate::mutate::{mutate, DICTIONARY};
use crate::rng::Rng;
use crate::run::{FindingKind, Outcome, Target};
use crate::spans::{check_span, signature_of};
use sym::{ExprId, Node, ParseOptions, Pool};

/// Checks what the parser does with `text`.
pub fn check_expression(text: &str) -> Outcome {
    let mut pool = Pool::default();
    let parsed = pool.parse(text);
    // The same text with names checked: only one-letter names, with at most one prime.
    let known = |name: &str, primes: u8| name.len() == 1 && primes <= 1;
    if let Err(err) = pool.parse_with(text, &ParseOptions::default().with_known(&known)) {
        if let Err(why) = check_span(text, &err.span.range()) {
            return Outcome::problem(FindingKind::Span, format!("with names checked, '{err}': {why}"));
        }
    }
    let e = match parsed {
        Err(err) => {
            if let Err(why) = check_span(text, &err.span.range()) {
                return Outcome::problem(FindingKind::Span, format!("'{err}': {why}"));
            }
            return Outcome::fine(format!("error: {}", signature_of(&err.to_string())));
        }
        Ok(e) => e,
    };
    let printed = pool.display(e).to_string();
    match pool.parse(&printed) {
        Ok(back) if back == e => {}
        Ok(back) => {
            let again = pool.display(back).to_string();
            return Outcome::problem(
                FindingKind::RoundTrip,
                format!("printed as {printed:?}, which parses to a different expression, printed {again:?}"),
            );
        }
        Err(err) => {
            return Outcome::problem(FindingKind::RoundTrip, format!("printed as {printed:?}, which fails: {err}"))
        }
    }
    if pool.latex(e).to_string().is_empty() {
        return Outcome::problem(FindingKind::RoundTrip, "LaTeX is empty");
    }
    let symbols = pool.symbols(e);
    for s in symbols.iter().take(3) {
        let x = pool.sym(*s);
        let d = pool.diff(e, x);
        let _ = pool.display(d).to_string();
    }
    let simplified = pool.simplify(e);
    if let Some(problem) = value_kept(&pool, e, simplified, &symbols) {
        return problem;
    }
    Outcome::fine(format!("ok: {}", shape(&pool, e)))
}

/// A problem when `a` and `b` differ in value at a point where every
/// subexpression of `a` is finite and below 10^6 (elsewhere rewrites may
/// legitimately move an infinity or lose digits).
fn value_kept(pool: &Pool, a: ExprId, b: ExprId, symbols: &[sym::Symbol]) -> Option<Outcome> {
    let names: Vec<String> = symbols.iter().map(|s| pool.symbol_text(*s)).collect();
    for point in [0.37, -0.61, 1.13] {
        let env = |name: &str| names.iter().position(|n| n == name).map(|i| point + 0.29 * i as f64);
        let moderate = pool.reachable(&[a]).into_iter().all(|s| pool.eval(s, &env).is_ok_and(|v| v.abs() < 1e6));
        if !moderate {
            continue;
        }
        let (va, vb) = (pool.eval(a, &env).ok()?, pool.eval(b, &env).ok()?);
        if (va - vb).abs() > 1e-7 * (1.0 + va.abs()) {
            return Some(Outcome::problem(
                FindingKind::Invariant,
                format!(
                    "simplify changes the value: {} is {va} but {} is {vb} at {point}",
                    pool.display(a),
                    pool.display(b)
                ),
            ));
        }
    }
    None
}

/// The kinds of nodes in `e`, for the novelty signal.
fn shape(pool: &Pool, e: ExprId) -> String {
    let mut kinds: Vec<&str> = pool
        .reachable(&[e])
        .into_iter()
        .map(|id| match pool.node(id) {
            Node::Num(n) if n.to_f64().fract() != 0.0 => "fraction",
            Node::Num(_) => "int",
            Node::Pi => "pi",
            Node::Sym(s) if s.order > 0 => "derivative",
            Node::Sym(_) => "symbol",
            Node::Add(_) => "add",
            Node::Mul(_) => "mul",
            Node::Pow(_, x) if pool.as_number(*x).is_none() => "symbolic power",
            Node::Pow(..) => "power",
            Node::Func(f, _) => f.name(),
            Node::Atan2(..) => "atan2",
        })
        .collect();
    kinds.sort();
    kinds.dedup();
    kinds.join(",")
}

/// The expression parser under the fuzz loop: mutants of the corpus's
/// expressions, and now and then a soup of tokens.
pub struct ExprTarget {
    inputs: Inputs,
}

impl ExprTarget {
    /// A target seeded with the corpus's expressions.
    pub fn new(corpus: &Corpus) -> ExprTarget {
        ExprTarget { inputs: Inputs::new(corpus.expressions.clone(), MAX_KEPT) }
    }
}

/// Most mutants kept for a new outcome.
const MAX_KEPT: usize = 4096;

impl Target for ExprTarget {
    fn name(&self) -> &'static str {
        "expr"
    }

    fn input(&mut self, rng: &mut Rng) -> String {
        if rng.chance(0.1) {
            let n = rng.below(40);
            return (0..n).map(|_| *rng.pick(DICTIONARY)).collect();
        }
        let seed = self.inputs.pick(rng).to_string();
        let others: Vec<String> = (0..4).map(|_| self.inputs.pick(rng).to_string()).collect();
        let others: Vec<&str> = others.iter().map(String::as_str).collect();
        let mut text = mutate(rng, &seed, &others);
        // Expressions are short; the length limit has its own unit test.
        text.truncate(text.floor_char_boundary_at(4096));
        text
    }

    fn check(&mut self, input: &str) -> Outcome {
        check_expression(input)
    }

    fn keep(&mut self, input: String) {
        self.inputs.keep(input);
    }

    fn corpus_len(&self) -> usize {
        self.inputs.len()
    }
}

/// The largest character boundary at or below a byte index.
trait FloorBoundary {
    fn floor_char_boundary_at(&self, i: usize) -> usize;
}

impl FloorBoundary for String {
    fn floor_char_boundary_at(&self, i: usize) -> usize {
        (0..=i.min(self.len())).rev().find(|&j| self.is_char_boundary(j)).unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check_fine(text: &str) {
        let outcome = check_expression(text);
        assert!(outcome.problem.is_none(), "{text:?}: {:?}", outcome.problem);
    }

    #[test]
    fn valid_and_broken_texts_pass_the_checks() {
        for text in ["m*l^2*q'^2/2 + m*g*l*cos(q)", "x +", "(x", "é + x", "sin(x, y)", "x^1001", "sqrt(x^2)"] {
            check_fine(text);
        }
    }
}
