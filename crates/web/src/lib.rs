//! lagrange in the browser: the library's front end for the playground
//! (`web/`), compiled to `wasm32-unknown-unknown` without sym's JIT and mech's
//! threads (the interpreter computes the same numbers).
//!
//! Every entry point takes the model's text and an options object (JSON text:
//! [`Options`]) and returns JSON text: on success the value of the DESIGN.md
//! contract that the CLI's `--format json` prints for the same command
//! (`lagrange.derive/1`, `lagrange.simulate/1`, `lagrange.report/1`,
//! `lagrange.modes/1`, `lagrange.orbit/1`, `lagrange.top/1`,
//! `lagrange.extremal/1`), built by the same functions of `mech` and `view`;
//! on failure a `lagrange.error/1` value ([`located`]) whose line and column
//! the editor underlines. Nothing here panics on bad input.
//!
//! The functions are plain Rust ([`api`]); `#[wasm_bindgen]` exports them as
//! they are, so the native tests (`tests/`) call what the page calls.

pub mod api;
pub mod located;
pub mod options;

pub use api::{derive, extremal, model, modes, orbit, report, simulate, top};
pub use options::Options;
