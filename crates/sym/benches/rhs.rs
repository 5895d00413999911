//! One right-hand side of a linearly implicit second-order system `A y'' = b`, the
//! planar double pendulum's (mA = mB = lA = lB = 1, g = 9.81): the state `(a, b, a', b')`
//! to `(a', b', a'', b'')`, three ways.
//!
//! - `tape_eval`: [`Tape::eval`] of `A` (2×2) and `b` (2) as `lagrange derive` prints them,
//!   from `(a, b, a', b', t, mA, mB, lA, lB, g)`, then a 2×2 solve;
//! - `jit`: the same tape compiled by [`Compiled::new`];
//! - `hand`: the same equations written by hand in Rust with the parameters inlined, the floor
//!   the JIT is measured against.
//!
//! Run with `cargo bench -p lagrange-sym --bench rhs -- --quick`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use sym::{Compiled, ExprId, Pool, Tape};

/// `A` row by row, then `b`, as `lagrange derive` prints them for the double pendulum
/// (the `derive` snapshot of the CLI's tests).
const EQUATIONS: [&str; 6] = [
    "lA^2*(mA + mB)",
    "lA*lB*mB*cos(a - b)",
    "lA*lB*mB*cos(a - b)",
    "lB^2*mB",
    "-lA*(lB*mB*b'^2*sin(a - b) + g*sin(a)*(mA + mB))",
    "-g*lB*mB*sin(b) + lA*lB*mB*a'^2*sin(a - b)",
];

/// The inputs of the tape, in order.
const INPUTS: [&str; 10] = ["a", "b", "a'", "b'", "t", "mA", "mB", "lA", "lB", "g"];

/// mA, mB, lA, lB, g.
const PARAMS: [f64; 5] = [1.0, 1.0, 1.0, 1.0, 9.81];

/// A state away from every symmetry.
const STATE: [f64; 4] = [2.0, 2.5, 0.3, -0.7];

/// `y''` from `A` (row-major 2×2) and `b` by Cramer's rule.
#[inline]
fn solve(m: &[f64; 6]) -> [f64; 2] {
    let det = m[0] * m[3] - m[1] * m[2];
    [(m[4] * m[3] - m[1] * m[5]) / det, (m[0] * m[5] - m[2] * m[4]) / det]
}

/// The hand-written right-hand side.
#[inline(never)]
fn hand(y: &[f64; 4]) -> [f64; 4] {
    const G: f64 = 9.81;
    let [a, b, va, vb] = *y;
    let (s, c) = ((a - b).sin(), (a - b).cos());
    let m = [2.0, c, c, 1.0, -2.0 * G * a.sin() - vb * vb * s, -G * b.sin() + va * va * s];
    let [aa, ab] = solve(&m);
    [va, vb, aa, ab]
}

/// The tape inputs for state `y` at time 0.
fn inputs(y: &[f64; 4]) -> [f64; 10] {
    let mut x = [0.0; 10];
    x[..4].copy_from_slice(y);
    x[5..].copy_from_slice(&PARAMS);
    x
}

fn tape() -> Tape {
    let mut pool = Pool::default();
    let roots: Vec<ExprId> = EQUATIONS.iter().map(|e| pool.parse(e).expect("the derive output parses")).collect();
    let inputs: Vec<ExprId> = INPUTS.iter().map(|n| pool.parse(n).expect("a symbol")).collect();
    Tape::compile(&pool, &roots, &inputs).expect("every symbol is an input")
}

fn rhs(c: &mut Criterion) {
    let mut tape = tape();
    let native = Compiled::new(&tape).expect("cranelift supports the bench host");
    let x = inputs(&STATE);
    let (mut by_tape, mut by_jit) = ([0.0; 6], [0.0; 6]);
    tape.eval(&x, &mut by_tape);
    native.eval(&x, &mut by_jit);
    let want = hand(&STATE);
    for got in [solve(&by_tape), solve(&by_jit)] {
        assert!((got[0] - want[2]).abs() < 1e-12 && (got[1] - want[3]).abs() < 1e-12, "{got:?} vs {want:?}");
    }

    let mut g = c.benchmark_group("double_pendulum/rhs");
    g.bench_function("tape_eval", |bench| {
        let mut m = [0.0; 6];
        bench.iter(|| {
            let y = black_box(&STATE);
            tape.eval(&inputs(y), &mut m);
            let [aa, ab] = solve(&m);
            [y[2], y[3], aa, ab]
        })
    });
    g.bench_function("jit", |bench| {
        let mut m = [0.0; 6];
        bench.iter(|| {
            let y = black_box(&STATE);
            native.eval(&inputs(y), &mut m);
            let [aa, ab] = solve(&m);
            [y[2], y[3], aa, ab]
        })
    });
    g.bench_function("hand", |bench| bench.iter(|| hand(black_box(&STATE))));
    g.finish();
}

criterion_group!(benches, rhs);
criterion_main!(benches);
