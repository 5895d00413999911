//! `mech`: the physics of lagrange. A model file goes in; its equations of
//! motion, Hamiltonian, motion and analyses come out, as the lecture notes
//! (PHYS 3010, T. Kirchner, York University) derive them by hand.
//!
//! Data flows one way: a [`Model`] (plain data read from TOML) → a
//! [`Derivation`] (a pure function of the model: L, momenta, `M q'' = f`,
//! cyclic coordinates, H, Hamilton's equations, and the verdicts on H as
//! [`Verdicts`]) → a run ([`simulate`], [`sweep`]) or an analysis
//! ([`normal_modes`], [`Orbit`], [`Top`]), each taking `&Derivation`.
//! [`inertia`] and [`extremal`] stand beside the pipeline. Errors are values
//! with byte spans into the model text ([`ModelError`]) or enums with fields;
//! the library never prints, and never names a command-line flag.
//!
//! ```
//! use std::ops::ControlFlow;
//!
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
//! [initial]
//! th = 0.01
//! "th'" = 0.0
//! "#;
//! let model = mech::Model::parse(text, &[])?;
//! let d = mech::Derivation::new(model)?;
//! assert_eq!(d.pool().display(d.momenta()[0]).to_string(), "l^2*m*th'");
//! assert_eq!(d.hamiltonian_is_energy(), Some(true));
//!
//! // The trajectory, row by row: a small swing has the period 2π√(l/g).
//! let period = 2.0 * std::f64::consts::PI / 9.81f64.sqrt();
//! let config = mech::RunConfig { until: period, ..mech::RunConfig::default() };
//! let mut rows = Vec::new();
//! let report = mech::simulate(&d, &config, |row| {
//!     rows.push((row.t, row.q[0], row.qd[0]));
//!     ControlFlow::Continue(())
//! })?;
//! let (t, th, _) = rows[rows.len() - 1];
//! assert_eq!(t, period);
//! assert!((th - 0.01).abs() < 1e-6, "back where it started after one period: {th}");
//! assert!(report.invariants.iter().all(|a| a.max_rel_drift < 1e-8));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// The stages, in the order data flows through them: a module uses only the
// modules of the groups above its own (`tests/layers.rs` checks it).
// Errors.
mod error;
// Leaves: the clock, deciding symbolic facts (proofs, numeric refutation), Euler angles, TOML files.
mod clock;
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
// A run seen where it crosses a surface: Poincaré sections.
mod section;
// Equilibria found from a start, and trusted (shared by the analyses).
mod equilibria;
// Analyses of a derivation, and its equations as code for other programs.
pub mod export;
mod linearize;
mod modes;
mod sweep;
mod top;
// Analyses built on other analyses.
mod orbit;
// The mechanism as a picture (for drawing it move).
pub mod mechanism;
// Test models shared by the unit tests and `tests/` (which includes the file).
#[cfg(test)]
mod test_models;

// The test models name the crate `mech`, as the integration tests do.
#[cfg(test)]
extern crate self as mech;

pub use derive::{BodyMotion, Constraint, Constraints, ImpactLaw, NoInertia};
pub use derive::{
    ConservationReason, Conserved, ConservedReason, CyclicReason, Derivation, EnergyReason, Generator, GeneratorKind,
    HamiltonianReason, Layout, RateTerm, Verdicts,
};
pub use equilibria::{Equilibrium, EquilibriumReport, Stability};
pub use error::{ModelError, ModelErrorKind, Setting, Within};
pub use extremal::{
    extremal, Candidate, Euler, EulerError, ExtremalConfig, ExtremalError, ExtremalReport, ExtremalSummary, Problem,
    SecondVariation, Start, EXTREMAL_FORMAT,
};
pub use linearize::{linearize, About, Eigenvalue, Linearization, LinearizeConfig, LinearizeError, LinearizeReport};
pub use mechanism::{Mechanism, Point, PointKind};
pub use model::urdf_to_model;
pub use model::{
    Body, CheckKind, ConstraintKind, ConstraintSpec, Coordinate, Gravity, InitialValue, Input, Load, LoadKind, Located,
    Model, Orientation, Parameter, Particle, UrdfConfig, ValueCheck,
};
pub use modes::{
    normal_modes, DampedRoot, Damping, Mode, ModeKind, Modes, ModesConfig, ModesError, ModesReport, SymbolicModes,
};
pub use num::{Method, Output};
pub use orbit::{Kepler, Orbit, OrbitError, OrbitKind, OrbitReport};
pub use report::{
    prints_shared, BodyReport, ConstraintReport, Definition, DeriveReport, HamiltonEquations, ImpactReport, NamedExpr,
    Ordered, IMPACT_LAW,
};
pub use run::body::BodyRecorder;
pub use run::constrained::constraint_columns;
pub use run::dynamics::{invariants_of, Dynamics, Form, Invariant, System};
pub use run::jacobian::StateJacobian;
pub use run::series::SeriesCode;
pub use run::{
    approx, row_columns, simulate, Audit, BudgetAdvice, BudgetStage, ConstraintAudit, ImpactTally, Row, RunConfig,
    RunError, RunFailure, RunReport, RunSettings, RunWarning, SettingError, StepBudget, StopCondition, TimeScale,
    MAX_SAMPLES, STEPS_PER_TIME_SCALE,
};
pub use section::Section;
pub use source::MAX_FILE_BYTES;
pub use sweep::{
    merge, sweep, Axis, Grid, Shard, Sweep, SweepConfig, SweepError, SweepHeader, SweepSettings, SweepTable, TableRow,
    Target, DEFAULT_RTOL, MAX_RUNS,
};
pub use top::{FreeTop, HeavyTop, Nutation, NutationKind, Top, TopError, TopKind, TopReport};
