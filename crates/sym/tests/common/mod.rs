//! The random-expression generator shared by the property tests
//! (`properties.rs`) and the JIT's differential tests (`jit.rs`): random trees
//! of `Pool` constructor calls, seeded so every run tries the same cases.

// Each test file uses a part of the generator.
#![allow(dead_code)]

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed};
use sym::{ExprId, Func, Pool};

/// The symbols of random expressions: name, primes, and their text.
pub const SYMBOLS: [(&str, u8, &str); 5] =
    [("x", 0, "x"), ("y", 0, "y"), ("z", 0, "z"), ("x", 1, "x'"), ("q", 2, "q''")];

/// 256 cases from a fixed seed; `PROPTEST_CASES` and `PROPTEST_RNG_SEED` in
/// the environment override them for a longer local hunt.
pub fn config() -> Config {
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
pub enum Gen {
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

pub fn build(pool: &mut Pool, g: &Gen) -> ExprId {
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

pub fn leaf() -> impl Strategy<Value = Gen> {
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
pub fn extreme_leaf() -> impl Strategy<Value = Gen> {
    prop_oneof![
        3 => leaf(),
        1 => prop_oneof![Just(1e300), Just(-1e-300), Just(5e-324), Just(1.7976931348623157e308), Just(123456.789),
            Just(-1e-7), Just(1e16), Just(0.1)].prop_map(Gen::Float),
        1 => prop_oneof![Just(i64::MAX), Just(i64::MIN), Just(1 << 40), Just(-(1 << 62)), Just(0)].prop_map(Gen::Int),
        1 => ((-1i64 << 40)..(1i64 << 40), 1i64..(1i64 << 40)).prop_map(|(n, d)| Gen::Rational(n, d)),
    ]
}

pub fn expr() -> impl Strategy<Value = Gen> {
    tree(leaf())
}

pub fn tree(leaf: impl Strategy<Value = Gen> + 'static) -> impl Strategy<Value = Gen> {
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
pub fn point() -> impl Strategy<Value = [f64; 5]> {
    prop::array::uniform5(-2.0..2.0f64)
}
