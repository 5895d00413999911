//! Taylor-mode evaluation of a tape: the Taylor coefficients of every output,
//! order by order, from the Taylor coefficients of the inputs.
//!
//! This is the engine of the Taylor integrator (Jorba & Zou 2005; heyoka):
//! along a solution `y(t)` of an ODE each tape slot is a function of `t`, and
//! its normalized coefficients `x[k] = x⁽ᵏ⁾(t₀)/k!` follow from the operands'
//! by the classical recurrences (products are Cauchy convolutions, quotients
//! and functions are solved from `w' = g(u) u'`). Order `k` of every slot needs
//! only orders `0..=k` of its operands, so an ODE integrator sets the state's
//! order `k`, calls [`TaylorTape::compute`] for order `k`, and reads the right-
//! hand side's order `k`, which is the state's order `k + 1` times `k + 1`.
//!
//! Slots that depend only on constants and constant inputs (the parameters)
//! are evaluated once by [`TaylorTape::refresh_constants`] and enter the
//! recurrences as scalars: `c·u` costs `O(1)` per order instead of the `O(k)`
//! of a convolution. Integer powers become chains of products (no division by
//! a base that may vanish), and `u^v` becomes `exp(v·ln u)`.
//!
//! A linearly implicit second-order system `A(y, y', t) y'' = b(y, y', t)`
//! whose `A` and `b` are the tape's outputs ([`LinearSecondOrder`]) expands
//! whole: [`TaylorTape::set_second_order`], then
//! [`TaylorTape::expand_second_order`] per expansion point, interpreted until
//! native code is compiled ([`TaylorTape::compile_second_order`], or
//! [`TaylorTape::compile_second_order_in_background`] for one lane, which
//! steps on meanwhile: for one lane both give the same numbers to the last
//! bit, so it does not matter which computed a step).
//!
//! Every coefficient is an array of `L` lanes: `L` independent trajectories
//! run in lock step, and the loops over lanes vectorize.
//!
//! The parts: `program.rs` (the instructions the backends read), `interpret.rs`
//! (the interpreter's recurrences), `cranelift.rs` and `c.rs` (native code),
//! `native.rs` (which alone picks cranelift or C, and holds the code), and
//! `tape.rs` (the public [`TaylorTape`]).

#[cfg(feature = "jit")]
mod c;
#[cfg(feature = "jit")]
mod cranelift;
mod interpret;
mod native;
mod program;
mod tape;

pub use program::{ClosedFormInverse, Lanes, LinearSecondOrder};
pub use tape::{TaylorCode, TaylorTape};
