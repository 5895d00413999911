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
//! assert_eq!(d.pool().display(d.momenta[0]).to_string(), "l^2*m*th'");
//! ```

pub mod body;
mod constrained;
mod constraint;
mod derive;
mod dynamics;
mod ensemble;
mod error;
pub mod euler;
mod extremal;
pub mod inertia;
mod model;
mod modes;
mod orbit;
pub mod probe;
mod quadratic;
mod report;
mod run;
mod series;
mod sweep;
mod top;

pub use body::{Body, BodyMotion, BodyRecorder};
pub use constrained::{constraint_columns, ConstrainedSystem, ConstraintAudit, INITIAL_TOLERANCE};
pub use constraint::{Constraint, ConstraintKind, ConstraintSpec, Constraints};
pub use derive::{Conserved, Derivation, Verdicts};
pub use dynamics::{invariants_of, Dynamics, Form, Invariant, System};
pub use error::ModelError;
pub use extremal::{
    extremal, Candidate, Euler, EulerError, ExtremalConfig, ExtremalError, ExtremalReport, ExtremalSummary, Problem,
    SecondVariation, Start, EXTREMAL_FORMAT,
};
pub use model::{Coordinate, InitialValue, Located, Model, Parameter, Particle, MAX_FILE_BYTES};
pub use modes::{normal_modes, Mode, ModeKind, Modes, ModesConfig, ModesError, ModesReport, SymbolicModes};
pub use orbit::{Kepler, Orbit, OrbitError, OrbitKind, OrbitReport};
pub use report::{BodyReport, ConstraintReport, DeriveReport, HamiltonEquations, NamedExpr, Ordered};
pub use run::{choose_method, simulate, Audit, Row, RunConfig, RunError, RunReport, StopCondition};
pub use sweep::{
    format_axes, merge, parse_axes, sweep, Axis, Grid, Shard, SweepConfig, SweepError, SweepTable, TableRow, Target,
    CSV_MAGIC, DEFAULT_RTOL, LYAPUNOV_D0, LYAPUNOV_INTERVAL, MAX_RUNS,
};
pub use top::{FreeTop, HeavyTop, Nutation, NutationKind, Top, TopError, TopKind, TopReport};
