//! `view`: how lagrange's results look. It turns what `mech` computes into the
//! text people read, LaTeX, MathML, JSON values and SVG figures, so that every front
//! end shows a result the same way: the `lagrange` CLI, the Python package and
//! the coming HTML report.
//!
//! What view is not: it reads no files and writes none, parses no flags,
//! handles no signals and never touches the terminal. Each function takes
//! `mech`'s values (and plain data a front end gathered, such as the signal
//! that stopped a run) and returns a `String` or a `serde_json::Value`;
//! where a sentence points at how the user asks for something (a flag of the
//! CLI, an argument in Python), the front end says how it spells it in
//! [`Terms`].
//!
//! ```
//! let text = r#"
//! name = "pendulum"
//! coordinates = ["th"]
//! gravity = "g"
//! [parameters]
//! g = 9.81
//! [[particles]]
//! mass = "1"
//! position = ["sin(th)", "-cos(th)"]
//! "#;
//! let d = mech::Derivation::new(mech::Model::parse(text, &[])?)?;
//! assert!(view::derive::text(&d).contains("p_th = th'"));
//! assert!(view::derive::latex(&d).contains("\\begin{align*}"));
//! assert!(view::derive::mathml(&d).contains("<math display=\"block\">"));
//! assert_eq!(view::human(0.1 + 0.2), "0.3");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod angles;
pub mod derive;
mod error;
pub mod extremal;
pub mod heatmap;
pub mod inertia;
pub mod linearize;
mod markup;
pub mod modes;
mod number;
pub mod orbit;
pub mod plot;
pub mod report;
pub mod simulate;
mod terms;
pub mod top;

pub use error::DrawError;
pub use number::human;
pub use terms::Terms;
