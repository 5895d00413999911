//! `fuzz`: fuzzing of lagrange on stable Rust, without instrumentation.
//!
//! Six targets, each a [`Target`] that makes an input and checks what the
//! library does with it:
//!
//! - [`ExprTarget`]: the expression parser on text mutated from the corpus's
//!   expressions (never a panic; errors carry a span on character boundaries
//!   inside the text; whatever parses prints as text that parses back to the
//!   same expression; simplifying keeps the value);
//! - [`LoaderTarget`]: the model, body-file and problem loaders on TOML text
//!   mutated from `examples/` and the broken models of the CLI tests (never a
//!   panic; every span inside the text it points into); a mutant that loads is
//!   derived too;
//! - [`DeriveTarget`]: derive on *valid* models from a small grammar
//!   ([`generate`]): never a panic, bounded time, and the derivation checked
//!   against an independent one ([`oracle`]) at random points: M symmetric, the
//!   Euler–Lagrange residual, momenta, H, Hamilton's equations, cyclic
//!   coordinates and the verdicts on H;
//! - [`BodiesTarget`]: the body-tree loader on random `[[bodies]]` trees with
//!   loads, inputs and rolling contacts, edited hostilely (spans, derive or a
//!   refusal, the oracle, T ≥ 0 on intact trees);
//! - [`LinearizeTarget`]: `linearize` on quadratic systems built from known
//!   modes (the eigenvalues to a tolerance from their conditioning, the verdict);
//! - [`ReportTarget`]: the report page on models with hostile names, read by
//!   a model of the HTML tokenizer's script states ([`scripts`]).
//!
//! [`run`] drives a target for a budget of iterations or seconds, catches
//! panics, times each case and keeps the mutants whose outcome is new (a crude
//! coverage signal: the kind of error or of expression). The smoke run of
//! `tests/smoke.rs` runs in `cargo test`; the `lagrange-fuzz` binary runs long.
//!
//! ```
//! let corpus = fuzz::Corpus::from_files(vec![("m.toml".into(), "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^2/2\"\n".into())]);
//! let mut target = fuzz::ExprTarget::new(&corpus);
//! let stats = fuzz::run(&mut target, &fuzz::Config { iterations: Some(200), ..fuzz::Config::default() }, &mut |_| {});
//! assert!(stats.findings.is_empty(), "{:?}", stats.findings);
//! ```

mod bodies;
mod corpus;
mod derive;
mod expr;
pub mod generate;
mod linearize;
mod loader;
mod mutate;
pub mod oracle;
mod report;
mod rng;
mod run;
mod script_data;
mod spans;

pub use bodies::{check_bodies, BodiesTarget};
pub use corpus::{Corpus, FileKind, Inputs, Seed, EXPRESSIONS, SEED_DIRS};
pub use derive::{check_derivation, DeriveTarget};
pub use expr::{check_expression, ExprTarget};
pub use linearize::{check_linearization, LinearizeTarget};
pub use loader::{check_file, LoaderTarget};
pub use mutate::{mutate, DICTIONARY, MAX_LEN};
pub use report::{check_page, check_report, report_page, ReportTarget};
pub use rng::Rng;
pub use run::{run, Config, Event, Finding, FindingKind, Outcome, Stats, Target};
pub use script_data::{scripts, Script};
