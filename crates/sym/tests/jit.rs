//! Differential tests of the JIT: on random expressions and random states,
//! [`Compiled::eval`] agrees with the tape interpreter ([`Tape::eval`], the
//! reference) to 1e-12 relative. Native code and tape perform the same IEEE
//! operations in the same order, so in practice they agree bit for bit; the
//! tolerance leaves room for a platform whose `powi` multiplies in another
//! order. The expression generator is the one of `properties.rs` (copied:
//! integration tests cannot share modules without a helper crate). The
//! runner is seeded, so every run tries the same cases.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed};
use sym::{Compiled, ExprId, Func, Pool, Tape};

/// The symbols of random expressions: name, primes, and their text.
const SYMBOLS: [(&str, u8, &str); 5] = [("x", 0, "x"), ("y", 0, "y"), ("z", 0, "z"), ("x", 1, "x'"), ("q", 2, "q''")];

/// 256 cases from a fixed seed; `PROPTEST_CASES` and `PROPTEST_RNG_SEED` in
/// the environment override them for a longer local hunt.
fn config() -> Config {
    let env = Config::default();
    let set = |var: &str| std::env::var_os(var).is_some();
    Config {
        cases: if set("PROPTEST_CASES") { env.cases } else { 256 },
        rng_seed: if set("PROPTEST_RNG_SEED") { env.rng_seed } else { RngSeed::Fixed(0x6c61_6772_616e_6765) },
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..env
    }
}

/// A recipe for an expression: one constructor call per node.
#[derive(Clone, Debug)]
enum Gen {
    Sym(usize),
    Int(i64),
    Rational(i64, i64),
    Float(f64),
    Pi,
    Add(Box<Gen>, Box<Gen>),
    Sub(Box<Gen>, Box<Gen>),
    Mul(Box<Gen>, Box<Gen>),
    Div(Box<Gen>, Box<Gen>),
    Neg(Box<Gen>),
    Powi(Box<Gen>, i64),
    PowRational(Box<Gen>, i64, i64),
    Pow(Box<Gen>, Box<Gen>),
    Sqrt(Box<Gen>),
    Func(Func, Box<Gen>),
    Atan2(Box<Gen>, Box<Gen>),
}

fn build(pool: &mut Pool, g: &Gen) -> ExprId {
    match g {
        Gen::Sym(i) => {
            let (name, order, _) = SYMBOLS[*i];
            pool.var(name, order)
        }
        Gen::Int(n) => pool.int(*n),
        Gen::Rational(n, d) => pool.rational(*n, *d),
        Gen::Float(x) => pool.float(*x),
        Gen::Pi => pool.pi(),
        Gen::Add(a, b) | Gen::Sub(a, b) | Gen::Mul(a, b) | Gen::Div(a, b) | Gen::Pow(a, b) | Gen::Atan2(a, b) => {
            let (a, b) = (build(pool, a), build(pool, b));
            match g {
                Gen::Add(..) => pool.add2(a, b),
                Gen::Sub(..) => pool.sub(a, b),
                Gen::Mul(..) => pool.mul2(a, b),
                Gen::Div(..) => pool.div(a, b),
                Gen::Pow(..) => pool.pow(a, b),
                _ => pool.atan2(a, b),
            }
        }
        Gen::Neg(a) => {
            let a = build(pool, a);
            pool.neg(a)
        }
        Gen::Powi(a, n) => {
            let a = build(pool, a);
            pool.powi(a, *n)
        }
        Gen::PowRational(a, n, d) => {
            let (a, e) = (build(pool, a), pool.rational(*n, *d));
            pool.pow(a, e)
        }
        Gen::Sqrt(a) => {
            let a = build(pool, a);
            pool.sqrt(a)
        }
        Gen::Func(f, a) => {
            let a = build(pool, a);
            pool.func(*f, a)
        }
    }
}

fn leaf() -> impl Strategy<Value = Gen> {
    prop_oneof![
        4 => (0..SYMBOLS.len()).prop_map(Gen::Sym),
        2 => (-5i64..=5).prop_map(Gen::Int),
        1 => ((-7i64..=7), (1i64..=6)).prop_map(|(n, d)| Gen::Rational(n, d)),
        1 => prop_oneof![Just(0.5), Just(-0.25), Just(1.5), Just(2.0), Just(1e-3), Just(-3.75), -4.0..4.0f64]
            .prop_map(Gen::Float),
        1 => Just(Gen::Pi),
    ]
}

/// Leaves at the edges: huge and tiny floats, large rationals and integers.
fn extreme_leaf() -> impl Strategy<Value = Gen> {
    prop_oneof![
        3 => leaf(),
        1 => prop_oneof![Just(1e300), Just(-1e-300), Just(5e-324), Just(1.7976931348623157e308), Just(123456.789),
            Just(-1e-7), Just(1e16), Just(0.1)].prop_map(Gen::Float),
        1 => prop_oneof![Just(i64::MAX), Just(i64::MIN), Just(1 << 40), Just(-(1 << 62)), Just(0)].prop_map(Gen::Int),
        1 => ((-1i64 << 40)..(1i64 << 40), 1i64..(1i64 << 40)).prop_map(|(n, d)| Gen::Rational(n, d)),
    ]
}

fn expr() -> impl Strategy<Value = Gen> {
    tree(leaf())
}

fn tree(leaf: impl Strategy<Value = Gen> + 'static) -> impl Strategy<Value = Gen> {
    leaf.prop_recursive(4, 24, 2, |inner| {
        let b = |g: Gen| Box::new(g);
        prop_oneof![
            3 => (inner.clone(), inner.clone()).prop_map(move |(x, y)| Gen::Add(b(x), b(y))),
            2 => (inner.clone(), inner.clone()).prop_map(move |(x, y)| Gen::Sub(b(x), b(y))),
            3 => (inner.clone(), inner.clone()).prop_map(move |(x, y)| Gen::Mul(b(x), b(y))),
            2 => (inner.clone(), inner.clone()).prop_map(move |(x, y)| Gen::Div(b(x), b(y))),
            1 => inner.clone().prop_map(move |x| Gen::Neg(b(x))),
            2 => (inner.clone(), prop_oneof![4 => -3i64..=4, 1 => -300i64..=300]).prop_map(move |(x, n)| Gen::Powi(b(x), n)),
            1 => (inner.clone(), -5i64..=5, 2i64..=3).prop_map(move |(x, n, d)| Gen::PowRational(b(x), n, d)),
            1 => (inner.clone(), inner.clone()).prop_map(move |(x, y)| Gen::Pow(b(x), b(y))),
            1 => inner.clone().prop_map(move |x| Gen::Sqrt(b(x))),
            3 => (prop::sample::select(Func::ALL.to_vec()), inner.clone()).prop_map(move |(f, x)| Gen::Func(f, b(x))),
            1 => (inner.clone(), inner).prop_map(move |(x, y)| Gen::Atan2(b(x), b(y))),
        ]
    })
}

/// Values for the symbols of [`SYMBOLS`], in order.
fn point() -> impl Strategy<Value = [f64; 5]> {
    prop::array::uniform5(-2.0..2.0f64)
}

/// `a` and `b` agree to `rel` relative, or are the same infinity, or both NaN.
fn agree(a: f64, b: f64, rel: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan()) || (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// Compiles `roots` both ways and compares them at every point.
fn check(pool: &mut Pool, roots: &[ExprId], points: &[[f64; 5]]) -> Result<(), TestCaseError> {
    let inputs: Vec<ExprId> = SYMBOLS.iter().map(|&(name, order, _)| pool.var(name, order)).collect();
    let pool = &*pool;
    let mut tape = Tape::compile(pool, roots, &inputs).expect("every symbol is an input");
    let native = Compiled::new(&tape).expect("cranelift supports the test host");
    prop_assert_eq!((native.n_inputs(), native.n_outputs()), (SYMBOLS.len(), roots.len()));
    let (mut by_tape, mut by_jit) = (vec![0.0; roots.len()], vec![0.0; roots.len()]);
    for p in points {
        tape.eval(p, &mut by_tape);
        native.eval(p, &mut by_jit);
        for k in 0..roots.len() {
            prop_assert!(
                agree(by_tape[k], by_jit[k], 1e-12),
                "root {} = {}: tape gives {} and the JIT {} at {:?}",
                k,
                pool.display(roots[k]),
                by_tape[k],
                by_jit[k],
                p
            );
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn jit_agrees_with_tape(gs in prop::collection::vec(expr(), 1..6), points in prop::collection::vec(point(), 4)) {
        let mut pool = Pool::default();
        let roots: Vec<ExprId> = gs.iter().map(|g| build(&mut pool, g)).collect();
        check(&mut pool, &roots, &points)?;
    }

    #[test]
    fn jit_agrees_with_tape_at_the_edges(gs in prop::collection::vec(tree(extreme_leaf()), 1..4),
                                         points in prop::collection::vec(extreme_point(), 3)) {
        let mut pool = Pool::default();
        let roots: Vec<ExprId> = gs.iter().map(|g| build(&mut pool, g)).collect();
        check(&mut pool, &roots, &points)?;
    }
}

/// States with zeros, huge, tiny and non-finite values among ordinary ones.
fn extreme_point() -> impl Strategy<Value = [f64; 5]> {
    let value = prop_oneof![
        4 => -2.0..2.0f64,
        1 => prop_oneof![Just(0.0), Just(-0.0), Just(1e300), Just(-1e-300), Just(5e-324), Just(f64::INFINITY),
            Just(f64::NEG_INFINITY), Just(f64::NAN), Just(1e8), Just(-123.456)],
    ];
    prop::array::uniform5(value)
}
