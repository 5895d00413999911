//! `sym`: the expression kernel of lagrange.
//!
//! Expressions live in a [`Pool`], a hash-consed DAG: each distinct subexpression
//! is stored once and named by an [`ExprId`]. The pool parses the expression
//! language, prints it back (text that parses to the same expression, LaTeX and MathML),
//! differentiates, substitutes, simplifies, and evaluates many expressions at once
//! over their shared subexpressions with a [`Tape`], which [`Compiled`] turns into
//! native code.
//!
//! ```
//! let mut pool = sym::Pool::default();
//! let lag = pool.parse("m*l^2*q'^2/2 + m*g*l*cos(q)").unwrap();
//! let q_dot = pool.velocity("q");
//! let p_q = pool.diff(lag, q_dot);
//! assert_eq!(pool.display(p_q).to_string(), "l^2*m*q'");
//! ```

mod ad;
#[cfg(feature = "jit")]
mod cc;
mod diff;
pub mod emit;
mod eval;
mod expr;
#[cfg(not(feature = "jit"))]
mod interpreted;
#[cfg(feature = "jit")]
mod jit;
mod native;
mod number;
mod parse;
mod print;
mod rational;
mod shared;
mod simplify;
mod taylor;
mod trig;

#[cfg(not(feature = "jit"))]
use interpreted::{cc, jit};

pub use cc::compiler as c_compiler;
pub use eval::{EvalError, Tape};
pub use expr::{ExprId, Func, NameId, Node, Pool, Symbol};
pub use jit::Compiled;
pub use native::{CBuild, CcError, JitError, QUICK_MIN_OPS};
pub use number::{Number, Rational};
pub use parse::{Limits, ParseError, ParseErrorKind, ParseOptions, Span};
pub use print::{PrintMode, PrintOptions, Printed};
pub use shared::{Printout, Shared, MAX_CUT_TREE, MIN_NAMED_TREE, SHARING_PAYS_ABOVE};
pub use taylor::{ClosedFormInverse, Lanes, LinearSecondOrder, TaylorCode, TaylorTape};
