//! `mech`: the physics of lagrange — model files, the derivation of the
//! equations of motion, the Hamiltonian, and the reports built from them.
//!
//! ```
//! let text = r#"
//! coordinates = ["th"]
//! gravity = "g"
//! [parameters]
//! m = 1.0
//! l = 1.0
//! g = 9.81
//! [[particles]]
//! mass = "m"
//! position = ["l*sin(th)", "-l*cos(th)"]
//! "#;
//! let model = mech::Model::parse(text, &[]).unwrap();
//! let d = mech::Derivation::new(model).unwrap();
//! assert_eq!(d.pool().display(d.momenta()[0]).to_string(), "l^2*m*th'");
//! ```

// The stages, in the order data flows through them: a module uses only the
// modules of the groups above its own (`tests/layers.rs` checks it).
// Errors.
mod error;
// Leaves: the numeric probe of symbolic facts, Euler angles, TOML files.
pub mod euler;
mod probe;
mod source;
// Siblings of the pipeline: body files and inertia tensors, variational problems.
mod extremal;
pub mod inertia;
// A model file, read.
mod model;
// The derivation: a pure function of the model.
mod derive;
// The derivation as the `lagrange.derive/1` report.
mod report;
// Runs: the derivation compiled, integrated, audited.
mod run;
// Analyses of a derivation.
mod modes;
mod sweep;
mod top;
// Analyses built on other analyses.
mod orbit;

pub use derive::{BodyMotion, Constraint, Constraints};
pub use derive::{Conserved, Derivation, Verdicts};
pub use error::{ModelError, Setting};
pub use extremal::{
    extremal, tanh_sinh, Candidate, Euler, EulerError, ExtremalConfig, ExtremalError, ExtremalReport, ExtremalSummary,
    Problem, SecondVariation, Start, EXTREMAL_FORMAT,
};
pub use model::{Body, ConstraintKind, ConstraintSpec, Coordinate, InitialValue, Located, Model, Parameter, Particle};
pub use modes::{normal_modes, Mode, ModeKind, Modes, ModesConfig, ModesError, ModesReport, SymbolicModes};
pub use orbit::{Kepler, Orbit, OrbitError, OrbitKind, OrbitReport};
pub use report::{BodyReport, ConstraintReport, DeriveReport, HamiltonEquations, NamedExpr, Ordered};
pub use run::body::BodyRecorder;
pub use run::constrained::{constraint_columns, ConstrainedSystem, ConstraintAudit, INITIAL_TOLERANCE};
pub use run::dynamics::{invariants_of, Dynamics, Form, Invariant, System};
pub use run::{choose_method, simulate, Audit, Row, RunConfig, RunError, RunReport, StopCondition};
pub use source::MAX_FILE_BYTES;
pub use sweep::{
    format_axes, merge, parse_axes, sweep, Axis, Grid, Shard, SweepConfig, SweepError, SweepTable, TableRow, Target,
    CSV_MAGIC, DEFAULT_RTOL, LYAPUNOV_D0, LYAPUNOV_INTERVAL, MAX_RUNS,
};
pub use top::{FreeTop, HeavyTop, Nutation, NutationKind, Top, TopError, TopKind, TopReport};
