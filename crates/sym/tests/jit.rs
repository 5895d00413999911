//! Differential tests of the JIT: on random expressions and random states,
//! [`Compiled::eval`] agrees with the tape interpreter ([`Tape::eval`], the
//! reference) bit for bit. Native code and tape perform the same IEEE
//! operations in the same order, the tape's `sin` and `cos` are the native
//! code's (`jit/trig.rs`), and both call the same library for the other
//! functions; the issue asks for 1e-12 relative, which is what a platform
//! whose `powi` multiplies in another order than `__powidf2` gets. The
//! expression generator is shared with `properties.rs` (`tests/common/mod.rs`).
//! The runner is seeded, so every run tries the same cases.

use proptest::prelude::*;
use sym::{Compiled, ExprId, Pool, Tape};

use crate::common::*;

/// Bit for bit where `f64::powi` is compiler-rt's `__powidf2`, whose
/// multiplications the JIT repeats; 1e-12 relative elsewhere.
const TOLERANCE: f64 = if cfg!(any(target_arch = "x86_64", target_arch = "aarch64")) { 0.0 } else { 1e-12 };

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
                agree(by_tape[k], by_jit[k], TOLERANCE),
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
