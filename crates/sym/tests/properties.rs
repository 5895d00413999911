//! Property tests of the expression kernel over random expressions.
//!
//! Expressions are random trees of constructor calls ([`Gen`], built through the
//! `Pool` constructors, so they are in canonical form). The properties:
//! printing then parsing is the identity on ids; `diff` matches a central finite
//! difference of `eval`; `simplify`, `together` and `together_trig` keep the
//! value; what `is_identically_zero` proves is 0 at every point; a [`Tape`] of several roots
//! agrees with `eval` of each; MathML is well-formed XML; and the parser returns `Ok` or `Err`, never panics,
//! on any text. The runner is seeded, so every run tries the same cases.

use proptest::prelude::*;
use sym::{ExprId, Limits, ParseOptions, Pool, Tape};

use crate::common::*;

fn env(p: &[f64; 5]) -> impl Fn(&str) -> Option<f64> + '_ {
    move |name: &str| SYMBOLS.iter().position(|s| s.2 == name).map(|i| p[i])
}

fn eval(pool: &Pool, e: ExprId, p: &[f64; 5]) -> f64 {
    pool.eval(e, &env(p)).expect("every symbol has a value")
}

/// True when every subexpression of `e` is moderate (finite, below 10^6) at `p`.
/// Rewrites may move an
/// infinity (`(x + y)/0` against `x/0 + y/0`), so values are only compared at
/// such points, and `sin` of a huge argument is noise.
fn finite_inside(pool: &Pool, e: ExprId, p: &[f64; 5]) -> bool {
    pool.reachable(&[e]).into_iter().all(|s| eval(pool, s, p).abs() < 1e6)
}

/// Whether no constant part of `e` is undefined ([`Pool::undefined_value`]):
/// the parser refuses text with one, so round trips are only asked of
/// expressions without them. Overflows (`9223372036854775807^17`) are defined,
/// and stay in the test.
fn defined(pool: &Pool, e: ExprId) -> bool {
    pool.reachable(&[e]).into_iter().all(|s| pool.undefined_value(s).is_none())
}

/// `a` and `b` agree to `rel` relative to `scale` (and both are NaN or both not).
fn close(a: f64, b: f64, rel: f64, scale: f64) -> bool {
    (a.is_nan() && b.is_nan()) || a == b || (a - b).abs() <= rel * scale.max(1.0)
}

/// Whether the MathML of `e` is one element of well-formed XML, every
/// `<msup>`, `<msub>`, `<mfrac>` and `<mroot>` with the two children MathML
/// requires (three for `<msubsup>`).
fn well_formed_mathml(pool: &Pool, e: ExprId) -> bool {
    let xml = format!("<math>{}</math>", pool.mathml(e));
    let Ok(doc) = roxmltree::Document::parse(&xml) else {
        return false;
    };
    let elements = |n: roxmltree::Node| n.children().filter(|c| c.is_element()).count();
    let math = doc.root_element();
    elements(math) == 1
        && math.descendants().filter(|n| n.is_element()).all(|n| match n.tag_name().name() {
            "msup" | "msub" | "mfrac" | "mroot" | "mover" => elements(n) == 2,
            "msubsup" => elements(n) == 3,
            _ => true,
        })
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn print_then_parse_is_identity(g in expr()) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        prop_assume!(defined(&pool, e));
        let text = pool.display(e).to_string();
        // Round trips are about the printer, not the parser's limits.
        let unlimited = ParseOptions::default().with_limits(Limits { max_exponent: u64::MAX, ..Limits::default() });
        let back = pool.parse_with(&text, &unlimited);
        prop_assert_eq!(back.as_ref().ok(), Some(&e), "{:?} printed as {} parsed to {:?} ({})",
            g, text, back, back.as_ref().map(|b| pool.display(*b).to_string()).unwrap_or_default());
        // LaTeX never panics and is never empty.
        prop_assert!(!pool.latex(e).to_string().is_empty());
    }

    #[test]
    fn print_then_parse_is_identity_at_the_edges(g in tree(extreme_leaf())) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        // Folding 1e300*1e300 stores an infinite float, which no text denotes;
        // `Number::Float` is documented finite, so such cases are the
        // constructors' to prevent, not the printer's.
        prop_assume!(pool.reachable(&[e]).into_iter().all(|s| pool.as_number(s).map(|n| n.to_f64().is_finite()) != Some(false)));
        prop_assume!(defined(&pool, e));
        let text = pool.display(e).to_string();
        // Round trips are about the printer, not the parser's limits.
        let unlimited = ParseOptions::default().with_limits(Limits { max_exponent: u64::MAX, ..Limits::default() });
        let back = pool.parse_with(&text, &unlimited);
        prop_assert_eq!(back.as_ref().ok(), Some(&e), "{:?} printed as {} parsed to {:?} ({})",
            g, text, back, back.as_ref().map(|b| pool.display(*b).to_string()).unwrap_or_default());
    }

    #[test]
    fn mathml_is_well_formed(g in expr()) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        prop_assert!(well_formed_mathml(&pool, e), "{:?} printed as {}", g, pool.mathml(e));
    }

    #[test]
    fn mathml_is_well_formed_at_the_edges(g in tree(extreme_leaf())) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        prop_assert!(well_formed_mathml(&pool, e), "{:?} printed as {}", g, pool.mathml(e));
    }

    #[test]
    fn diff_matches_central_difference(g in expr(), p in point(), var in 0..SYMBOLS.len()) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        let (name, order, _) = SYMBOLS[var];
        let x = pool.var(name, order);
        let d = pool.diff(e, x);
        let at = |pool: &Pool, e: ExprId, dx: f64| {
            let mut q = p;
            q[var] += dx;
            eval(pool, e, &q)
        };
        let h = 1e-4 * p[var].abs().max(1.0);
        let fd = |h: f64| (at(&pool, e, h) - at(&pool, e, -h)) / (2.0 * h);
        let (f0, d_sym, fd1, fd2) = (at(&pool, e, 0.0), at(&pool, d, 0.0), fd(h), fd(h / 2.0));
        // Skip points near singularities or kinks: the two differences must
        // agree (Richardson: their gap estimates the truncation error) and
        // every value be finite and moderate.
        let values = [f0, d_sym, fd1, fd2];
        let conditioned = values.iter().all(|v| v.is_finite() && v.abs() < 1e6)
            && finite_inside(&pool, e, &p)
            && (fd1 - fd2).abs() <= 1e-5 * (1.0 + fd2.abs());
        if conditioned {
            // Rounding error of the difference is ~eps*|f|/h, truncation ~|fd1 - fd2|.
            let tol = 1e-5 * (1.0 + d_sym.abs()) + 1e-10 * (1.0 + f0.abs()) / h + 4.0 * (fd1 - fd2).abs();
            prop_assert!((d_sym - fd2).abs() <= tol,
                "d/d{} of {} is {}: {} but the central difference gives {}",
                SYMBOLS[var].2, pool.display(e), pool.display(d), d_sym, fd2);
        }
    }

    #[test]
    fn simplify_keeps_the_value(g in expr(), points in prop::collection::vec(point(), 3)) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        let s = pool.simplify(e);
        for p in &points {
            let (a, b) = (eval(&pool, e, p), eval(&pool, s, p));
            if a.abs() < 1e8 && finite_inside(&pool, e, p) {
                prop_assert!(close(a, b, 1e-7, a.abs()),
                    "simplify({}) = {}, but at {:?} they are {} and {}", pool.display(e), pool.display(s), p, a, b);
            }
        }
    }

    #[test]
    fn together_keeps_the_value(g in expr(), points in prop::collection::vec(point(), 3)) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        let t = pool.together(e);
        let r = pool.simplify_rational(e);
        prop_assert!(pool.tree_size(r) <= pool.tree_size(e));
        for p in &points {
            let (a, b) = (eval(&pool, e, p), eval(&pool, t, p));
            if a.is_finite() && b.is_finite() && a.abs() < 1e8 && finite_inside(&pool, e, p) {
                prop_assert!(close(a, b, 1e-9, a.abs()),
                    "together({}) = {}, but at {:?} they are {} and {}", pool.display(e), pool.display(t), p, a, b);
            }
        }
    }

    #[test]
    fn together_trig_keeps_the_value(g in expr(), points in prop::collection::vec(point(), 3)) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        let t = pool.together_trig(e);
        for p in &points {
            let (a, b) = (eval(&pool, e, p), eval(&pool, t, p));
            if a.is_finite() && b.is_finite() && a.abs() < 1e8 && finite_inside(&pool, e, p) {
                prop_assert!(close(a, b, 1e-9, a.abs()),
                    "together_trig({}) = {}, but at {:?} they are {} and {}", pool.display(e), pool.display(t), p, a, b);
            }
        }
    }

    #[test]
    fn what_is_proven_zero_vanishes(g in expr(), points in prop::collection::vec(point(), 3)) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        // The expression itself (rarely zero) and its differences from its
        // rewrites (identities, which the proof should mostly find).
        let rewrites = [pool.expand(e), pool.simplify(e), pool.together(e)];
        let mut candidates = vec![e];
        candidates.extend(rewrites.iter().map(|&r| pool.sub(e, r)));
        for d in candidates {
            if !pool.is_identically_zero(d) {
                continue;
            }
            for p in &points {
                let v = eval(&pool, d, p);
                if finite_inside(&pool, d, p) {
                    prop_assert!(v.abs() <= 1e-7 * eval(&pool, e, p).abs().max(1.0),
                        "{} was proven zero, but at {:?} it is {}", pool.display(d), p, v);
                }
            }
        }
    }

    #[test]
    fn together_never_panics_at_the_edges(g in tree(extreme_leaf())) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        let t = pool.together(e);
        // The result is an expression of the pool that prints.
        prop_assert!(!pool.display(t).to_string().is_empty());
    }

    #[test]
    fn expand_keeps_the_value(g in expr(), p in point()) {
        let mut pool = Pool::default();
        let e = build(&mut pool, &g);
        let s = pool.expand(e);
        let (a, b) = (eval(&pool, e, &p), eval(&pool, s, &p));
        if a.abs() < 1e8 && finite_inside(&pool, e, &p) {
            prop_assert!(close(a, b, 1e-7, a.abs()),
                "expand({}) = {}, but at {:?} they are {} and {}", pool.display(e), pool.display(s), p, a, b);
        }
    }

    #[test]
    fn tape_agrees_with_eval(gs in prop::collection::vec(expr(), 1..5), p in point()) {
        let mut pool = Pool::default();
        let roots: Vec<ExprId> = gs.iter().map(|g| build(&mut pool, g)).collect();
        let inputs: Vec<ExprId> = SYMBOLS.iter().map(|&(name, order, _)| pool.var(name, order)).collect();
        let mut tape = Tape::compile(&pool, &roots, &inputs).expect("every symbol is an input");
        let mut out = vec![0.0; roots.len()];
        tape.eval(&p, &mut out);
        for (&r, &o) in roots.iter().zip(&out) {
            let v = eval(&pool, r, &p);
            prop_assert!(close(o, v, 1e-9, v.abs()) || (!o.is_finite() && !v.is_finite()),
                "tape gives {} and eval {} for {} at {:?}", o, v, pool.display(r), p);
        }
    }

    #[test]
    fn parse_never_panics_on_text(text in "\\PC{0,60}") {
        let mut pool = Pool::default();
        let _ = pool.parse(&text);
    }

    #[test]
    fn parse_never_panics_on_bytes(bytes in prop::collection::vec(any::<u8>(), 0..60)) {
        let mut pool = Pool::default();
        let _ = pool.parse(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn parse_never_panics_on_token_soup(tokens in prop::collection::vec(prop::sample::select(TOKENS.to_vec()), 0..40)) {
        let mut pool = Pool::default();
        let text = tokens.concat();
        if let Err(err) = pool.parse(&text) {
            // Spans lie inside the text and on character boundaries.
            prop_assert!(err.span.start <= err.span.end && err.span.end as usize <= text.len());
            prop_assert!(text.get(err.span.range()).is_some());
        } else {
            // Whatever parses prints to text that parses back.
            let e = pool.parse(&text).unwrap();
            let printed = pool.display(e).to_string();
            prop_assert_eq!(pool.parse(&printed).ok(), Some(e), "{} printed as {}", text, printed);
        }
    }
}

/// Pieces of the language, and some pieces that are not, for random text.
const TOKENS: [&str; 38] = [
    "x",
    "y",
    "q'",
    "q''",
    "q'''",
    "2",
    "0.5",
    "1e-3",
    ".5",
    "1e",
    "+",
    "-",
    "*",
    "/",
    "^",
    "**",
    "(",
    ")",
    ",",
    " ",
    "sin",
    "atan2",
    "sqrt",
    "pi",
    "ln",
    "abs",
    "foo",
    "é",
    "\t",
    "'",
    "1/2",
    "99999999999999999999999999999999999999999",
    "1e999",
    "_a1",
    "exp(",
    "(-1)",
    "p_q",
    "e",
];
