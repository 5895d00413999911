//! Ensembles: many trajectories of one model over a grid of initial values or
//! parameters, on all cores, one result row per run.
//!
//! Enter at [`Grid::parse`] (the `--grid` text against a model), then
//! [`Sweep::new`], whose [`Sweep::run`] streams the rows in grid order with
//! memory bounded whatever the grid (`sweep/window.rs`), and may skip the rows
//! a resumed sweep already has; [`sweep`] collects them into a [`SweepTable`].
//! [`SweepHeader`] and [`TableRow`] are the CSV's lines, [`SweepTable::to_csv`] /
//! [`SweepTable::parse`] its whole text, and [`merge`] joins the tables of shards.
//!
//! The parts: `grid.rs` (the axes, the grid's points, the shards), `table.rs`
//! (the CSV and the merge), `runs.rs` (each run's start and its integration,
//! one by one or on Taylor lanes), `lyapunov.rs` (the twin), `window.rs` (the
//! jobs in flight); this file holds the sweep that drives them.
//!
//! # A run
//!
//! Each run overrides some initial coordinates (`a`), velocities (`a'`) or
//! parameters of the model and integrates from t = 0 to `until`. The derivation
//! is compiled once ([`Dynamics`]); every worker thread clones the compiled
//! [`System`] (a grid over parameters recompiles per run, since a compiled system
//! holds its parameter values). A run records its final state, the relative drift
//! of H, |H(T) − H(0)| / |H(0)| (absolute where H(0) = 0), and an estimate of the
//! largest Lyapunov exponent.
//!
//! # The Lyapunov exponent (Benettin's two-trajectory method)
//!
//! A twin starts at `y0 + d0·u`, `d0 =` [`LYAPUNOV_D0`], `u` the unit vector with
//! equal components, in the state the integrator uses (`[q, q']` for DOP853).
//! Both are integrated over segments of [`LYAPUNOV_INTERVAL`] time units; after
//! each, the distance `d_k` between them is measured (Euclidean norm of the state
//! difference), `ln(d_k/d0)` added up, and the twin pulled back along the
//! difference to distance `d0`. Then `λ ≈ Σ ln(d_k/d0) / T`. The twin stays
//! within the linear regime (it is renormalized long before the separation
//! saturates at the size of the phase space), so this estimates the exponent of
//! the tangent dynamics without variational equations. It is a finite-time
//! estimate: positive and of order one on chaotic orbits, tending to zero as 1/T
//! on regular ones (a pendulum's twin drifts apart linearly). `d0 = 1e-8` sits
//! well above the integration error per segment at the default `rtol = 1e-10`
//! and well below any scale of the motion. The main trajectory is integrated in
//! the same segments whether or not the exponent is asked for, so the final
//! state does not depend on that choice.
//!
//! # Shards
//!
//! `Shard { index: i, count: n }` takes the runs whose index is `i` modulo `n`
//! (strided rather than contiguous: neighbouring grid points cost alike — a
//! chaotic region is expensive — so striding balances machines). [`merge`]
//! checks the shards belong to the same sweep (same columns and provenance),
//! sorts the rows by run index and reports duplicated or missing runs.
//!
//! # Default method
//!
//! The Taylor method ([`num::Taylor`]) at `rtol` (default [`DEFAULT_RTOL`]):
//! for an ensemble the cost per trajectory is what counts, and at tight
//! tolerances a high-order Taylor series (order 13 at 1e-10) takes the fewest
//! and cheapest steps — the transcendental functions are evaluated once per
//! step, and its native code is compiled once for the whole sweep. Runs go
//! [`crate::run::ensemble::LANES`] trajectories at a time in lock step (the
//! Lyapunov twins on their own lanes), each lane with its own step, and a lane
//! whose run ends takes the next run of its job (so lanes idle only at a job's
//! end: the 200×200 chaos map on one thread takes 14.5 s instead of the 17.4 s
//! of fixed batches of 8, where a fifth of the lanes idled); a lane
//! computes exactly what a single `simulate --method taylor` run computes. Models with
//! rigid bodies default to DOP853, whose events guard the Euler angles'
//! gimbal singularity. Any other method runs trajectory by trajectory.

use crate::derive::Derivation;
use crate::error::ModelError;
use crate::model::columns::{refuse_duplicates, Column};
use crate::model::Model;
use crate::run::body::GimbalGuard;
use crate::run::dynamics::{Dynamics, Form};
use crate::run::ensemble::LANES;
use crate::run::series::{LagrangeSeries, SeriesCode};
use crate::run::{choose_method, SettingError};
use num::Method;
use std::ops::ControlFlow;
use std::sync::OnceLock;
use std::thread;

mod grid;
mod lyapunov;
mod runs;
mod table;
mod window;

use grid::format_axes;
pub use grid::{Axis, Grid, Shard, Target};
use runs::{complete, initial_values, row, start_of, Begin, Initial, Plan, Start};
pub use table::{merge, SweepHeader, SweepTable, TableRow};

/// Initial separation of the Lyapunov twin, in state units.
pub const LYAPUNOV_D0: f64 = 1e-8;
/// Time between renormalizations of the twin (also the segment length of every run).
pub const LYAPUNOV_INTERVAL: f64 = 1.0;
/// Default relative tolerance: the integration error per segment stays far below
/// `LYAPUNOV_D0` (the twin's initial separation), which the exponent's estimate needs.
pub const DEFAULT_RTOL: f64 = 1e-10;
/// The most runs one sweep may have (a typo like `count = 1e9` is refused, not run).
pub const MAX_RUNS: usize = 100_000_000;
/// The first line of a sweep's CSV starts with this.
pub const CSV_MAGIC: &str = "# lagrange sweep";

/// Why a grid, a shard, a table or a merge is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SweepError {
    /// An empty `--grid`.
    #[error("the grid is empty; expected NAME=START:STOP:COUNT or NAME=V1;V2;..., comma separated")]
    EmptyGrid,
    /// An axis that is not `NAME=START:STOP:COUNT` or `NAME=V1;V2;...`.
    #[error(
        "in the grid: '{item}' is not NAME=START:STOP:COUNT (evenly spaced) or NAME=V1;V2;... (the values listed)"
    )]
    AxisSyntax {
        /// The offending axis text.
        item: String,
    },
    /// A start, stop or listed value that is not a finite number.
    #[error("in the grid: the {what} of '{name}' must be a finite number, not '{text}'")]
    AxisNumber {
        /// The axis name.
        name: String,
        /// `start`, `stop` or `value`.
        what: &'static str,
        /// The text found.
        text: String,
    },
    /// A count that is not a whole number ≥ 1.
    #[error("in the grid: the count of '{name}' must be a whole number of at least 1, not '{text}'")]
    AxisCount {
        /// The axis name.
        name: String,
        /// The text found.
        text: String,
    },
    /// A name that is no coordinate, velocity or parameter.
    #[error("in the grid: '{name}' is not a coordinate, a velocity or a parameter of the model (known: {known})")]
    UnknownName {
        /// The name.
        name: String,
        /// The names the grid may use.
        known: String,
    },
    /// The same name on two axes.
    #[error("in the grid: '{name}' appears on two axes")]
    DuplicateAxis {
        /// The name.
        name: String,
    },
    /// Too many runs.
    #[error("the grid has {runs} runs; a sweep may have at most {max}")]
    TooLarge {
        /// The product of the counts.
        runs: u128,
        /// [`MAX_RUNS`].
        max: usize,
    },
    /// A `--shard` that is not `i/n` with `i < n`.
    #[error("a shard must be I/N with 0 <= I < N (the I-th of N slices), not '{text}'")]
    ShardSyntax {
        /// The text found.
        text: String,
    },
    /// An end time that is not positive.
    #[error("the end time must be positive and finite, not {}", num::Shortest(*.until))]
    Until {
        /// The value found.
        until: f64,
    },
    /// The thread pool could not be made.
    #[error("cannot start {threads} threads: {reason}")]
    Threads {
        /// Requested threads.
        threads: usize,
        /// Why not.
        reason: String,
    },
    /// A model problem (a missing initial value, an impossible method).
    #[error("{0}")]
    Model(Box<ModelError>),
    /// A CSV that is not a sweep's output.
    #[error("{file}, line {line}: {reason}")]
    Table {
        /// The file's name.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// Shards of different sweeps.
    #[error("{file} is not a shard of the same sweep as {first}: {reason}")]
    Mismatch {
        /// The first shard.
        first: String,
        /// The shard that differs.
        file: String,
        /// What differs.
        reason: String,
    },
    /// A run present twice.
    #[error("run {run} appears twice ({first} and {second})")]
    DuplicateRun {
        /// The run index.
        run: usize,
        /// Where it appeared first.
        first: String,
        /// Where again.
        second: String,
    },
    /// Runs absent from every shard.
    #[error("{count} of {total} runs are missing (first: {first:?}); missing shards: {shards}")]
    MissingRuns {
        /// How many.
        count: usize,
        /// Runs in the sweep.
        total: usize,
        /// The first few missing run indices.
        first: Vec<usize>,
        /// The shards (`i/n`) that would hold them.
        shards: String,
    },
    /// Nothing to merge.
    #[error("no shard files to merge")]
    NothingToMerge,
}

impl SweepError {
    /// A model error, boxed (it is the largest of the variants).
    fn model(e: ModelError) -> SweepError {
        SweepError::Model(Box::new(e))
    }
}

/// Options of a sweep.
#[derive(Debug, Clone)]
pub struct SweepConfig {
    /// End time of every run (each starts at t = 0).
    pub until: f64,
    /// The integrator; `None`: Taylor, or DOP853 with rigid bodies (see the module documentation).
    pub method: Option<Method>,
    /// Relative tolerance (fixed-step methods choose their step from it).
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Whether to estimate the largest Lyapunov exponent (doubles the cost).
    pub lyapunov: bool,
    /// Which slice of the runs.
    pub shard: Shard,
    /// Worker threads; `None`: one per core.
    pub threads: Option<usize>,
}

/// A sweep's settings as a front end receives them, before defaults and
/// checks: [`SweepConfig::from_settings`] makes them a configuration.
#[derive(Debug, Clone, Copy)]
pub struct SweepSettings<'a> {
    /// End time of every run.
    pub until: f64,
    /// A method's name; None for the sweep's default.
    pub method: Option<&'a str>,
    /// Relative tolerance; None for [`DEFAULT_RTOL`].
    pub rtol: Option<f64>,
    /// Absolute tolerance; None for `rtol`/100.
    pub atol: Option<f64>,
    /// Whether to estimate the largest Lyapunov exponent.
    pub lyapunov: bool,
    /// The runs of this shard.
    pub shard: Shard,
    /// Worker threads; None for every core.
    pub threads: Option<usize>,
}

impl SweepConfig {
    /// The configuration of `settings`: the one place that checks a front
    /// end's method and tolerances for a sweep and fills in the defaults
    /// (`rtol` [`DEFAULT_RTOL`], `atol` `rtol`/100), refusing with the same
    /// [`SettingError`] as a run's settings.
    pub fn from_settings(settings: &SweepSettings<'_>) -> Result<SweepConfig, SettingError> {
        let method = SettingError::method(settings.method)?;
        SettingError::positive(&[("rtol", settings.rtol), ("atol", settings.atol)])?;
        let rtol = settings.rtol.unwrap_or(DEFAULT_RTOL);
        Ok(SweepConfig {
            until: settings.until,
            method,
            rtol,
            atol: settings.atol.unwrap_or(rtol * 1e-2),
            lyapunov: settings.lyapunov,
            shard: settings.shard,
            threads: settings.threads,
        })
    }

    /// The integrator's settings for each run: the tolerances, and the end as
    /// the longest step (the one copy from a sweep's settings to `num::Config`).
    pub(crate) fn solver_config(&self) -> num::Config {
        num::Config { rtol: self.rtol, atol: self.atol, h_max: Some(self.until), ..num::Config::default() }
    }
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            until: 10.0,
            method: None,
            rtol: DEFAULT_RTOL,
            // Two digits below rtol for states of order one: protects components
            // through zero without binding elsewhere.
            atol: DEFAULT_RTOL * 1e-2,
            lyapunov: true,
            shard: Shard::default(),
            threads: None,
        }
    }
}

/// Jobs a worker thread may run ahead of the row being written, per thread:
/// enough that a slow job at the head of the line (a chaotic region) does not
/// idle the others, few enough that the rows held stay a handful of jobs'.
const WINDOW_PER_THREAD: usize = 4;

/// A sweep ready to run: its inputs checked, its method chosen, its header
/// known. [`Sweep::run`] streams its rows in grid order; [`sweep`] collects
/// them into a table.
pub struct Sweep<'a> {
    d: &'a Derivation,
    grid: &'a Grid,
    config: &'a SweepConfig,
    dynamics: Dynamics,
    method: Method,
    form: Form,
    /// The model's `[initial]` values (None where the grid must give them).
    base: Initial,
    /// Rigid bodies: one gimbal guard per body.
    guards: Vec<GimbalGuard>,
    header: SweepHeader,
    /// The lock-step batches' series ([`Sweep::batched`]).
    batched: OnceLock<Option<LagrangeSeries<LANES>>>,
}

impl<'a> Sweep<'a> {
    /// Checks a sweep before anything runs: the end time, the method, the
    /// initial values the model and the grid give.
    pub fn new(d: &'a Derivation, grid: &'a Grid, config: &'a SweepConfig) -> Result<Sweep<'a>, SweepError> {
        if !crate::run::is_positive_time(config.until) {
            return Err(SweepError::Until { until: config.until });
        }
        d.model.check_inputs_applied().map_err(SweepError::model)?;
        if let Some(i) = d.model.impacts.first() {
            // The sweep's runs (lock-step batches among them) have no events to jump at.
            return Err(SweepError::model(
                ModelError::at(i.name_span.clone(), "a sweep does not run models with [[impacts]] yet")
                    .with_help("simulate each start on its own; a sweep of Poincaré sections runs whole simulations and takes impacts"),
            ));
        }
        let dynamics = Dynamics::new(d);
        // Rigid bodies need the gimbal guard's events, which the lock-step batches
        // do not check, and equations with a kink (abs) that a Taylor series does
        // not see: DOP853 by default there.
        let default = if d.model.bodies.is_empty() && dynamics.is_analytic() { Method::Taylor } else { Method::Dop853 };
        let (method, form) =
            choose_method(d, &dynamics, Some(config.method.unwrap_or(default)), false).map_err(SweepError::model)?;
        // Initial values from the model; a value neither in [initial] nor on an axis
        // is an error before anything runs.
        let base = initial_values(&d.model).map_err(SweepError::model)?;
        if grid.is_empty() {
            return Err(SweepError::EmptyGrid);
        }
        complete(&base, grid, &grid.point(0), &d.model).map_err(SweepError::model)?;
        // Rigid bodies: a run through the Euler angles' gimbal singularity fails
        // there (as `simulate` does) instead of integrating garbage.
        let guards = crate::run::body::gimbal_guards(d, config.rtol);
        let names = dynamics.coordinate_names();
        refuse_duplicates(&columns(&d.model, grid, names), "the sweep's CSV").map_err(SweepError::model)?;
        let header = header(d, grid, config, method, names);
        Ok(Sweep { d, grid, config, dynamics, method, form, base, guards, header, batched: OnceLock::new() })
    }

    /// The series of the lock-step batches, compiled on first use (None when
    /// the runs go one at a time).
    fn batched(&self) -> Option<&LagrangeSeries<LANES>> {
        self.batched
            .get_or_init(|| {
                // The Taylor method on smooth Lagrange-form models runs batches of
                // trajectories in lock step (`run/ensemble.rs`); its code is compiled once here.
                (self.method == Method::Taylor && self.form == Form::Lagrange && self.guards.is_empty())
                    .then(|| self.dynamics.lagrange_series::<LANES>(num::taylor_order(self.config.rtol)))
            })
            .as_ref()
    }

    /// Compiles the code the runs will use, if they share compiled code (the
    /// Taylor method's lock-step batches), and says which and what it cost;
    /// [`run`](Self::run) compiles it otherwise. The code does not change a
    /// row: C, cranelift and the interpreter give the same numbers, bit for bit.
    pub fn code(&self) -> Option<SeriesCode> {
        self.batched().map(|s| s.made().clone())
    }

    /// The provenance and columns of the sweep's CSV.
    pub fn header(&self) -> &SweepHeader {
        &self.header
    }

    /// The number of runs (of the shard, for a part).
    pub fn len(&self) -> usize {
        self.config.shard.len(self.grid.len())
    }

    /// True when there is no run (a shard beyond a grid smaller than the shard count).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Runs the sweep's runs after the first `skip` (those a resumed sweep
    /// already has) on worker threads, and hands their rows to `on_row` on
    /// the calling thread, one at a time, in grid order, holding a bounded
    /// window of rows (see `sweep/window.rs`) however large the grid.
    /// `progress` is called once per finished run, from any thread. `stop` is
    /// looked at between rows and by the workers between runs (in lock step:
    /// between segments); once it is true, or once `on_row` breaks, the rows
    /// handed over are a prefix in grid order and `run` returns `Ok(false)`.
    /// A run that fails does not stop the sweep: its row holds NaN where values
    /// are missing and the reason in `failure`.
    pub fn run(
        &self,
        skip: usize,
        progress: &(dyn Fn() + Sync),
        stop: &(dyn Fn() -> bool + Sync),
        mut on_row: impl FnMut(TableRow) -> ControlFlow<()>,
    ) -> Result<bool, SweepError> {
        let (config, grid, d, base) = (self.config, self.grid, self.d, &self.base);
        let remaining = self.len().saturating_sub(skip);
        let threads = config.threads.unwrap_or_else(|| thread::available_parallelism().map_or(1, |n| n.get()));
        let shard = config.shard;
        // The k-th run of the rest: its index in the whole grid.
        let run_at = |k: usize| shard.nth(skip + k);
        let has_parameters = grid.targets.iter().any(|t| matches!(t, Target::Parameter(_)));
        let system = self.dynamics.system(self.form);
        let n = self.dynamics.n_coords();
        let plan = Plan { method: self.method, form: self.form, config, guards: &self.guards };
        let mut emit = |rows: Vec<TableRow>| {
            for row in rows {
                if stop() {
                    return ControlFlow::Break(());
                }
                on_row(row)?;
            }
            ControlFlow::Continue(())
        };
        let shape = |per_job: usize| window::Plan {
            jobs: remaining.div_ceil(per_job),
            threads,
            window: WINDOW_PER_THREAD * threads,
        };
        let jobs_of = |job: usize, per_job: usize| job * per_job..((job + 1) * per_job).min(remaining);

        let end = if let Some(series) = self.batched() {
            // Jobs of up to 8 lanes' worth of runs (lanes take the next run as
            // theirs ends), at least 4 jobs per thread while there are runs enough.
            let slots = if config.lyapunov { LANES / 2 } else { LANES };
            let per_job = remaining.div_ceil(4 * threads).clamp(slots, 8 * slots);
            window::ordered(
                shape(per_job),
                || (series.clone(), system.clone(), Vec::new(), has_parameters.then(|| d.model.clone())),
                |(series, sys, scratch, model), job, halted| {
                    let runs = jobs_of(job, per_job);
                    let count = runs.len();
                    let starts: Vec<Start> = runs
                        .map(|k| {
                            let run = run_at(k);
                            let inputs = grid.point(run);
                            let begin = start_of(&inputs, grid, base, d, model.as_mut());
                            Start { run, inputs, begin }
                        })
                        .collect();
                    let rows = plan.run_batch(series, sys, scratch, n, starts, halted)?;
                    (0..count).for_each(|_| progress());
                    Some(rows)
                },
                stop,
                &mut emit,
            )
        } else {
            let per_job = remaining.div_ceil(4 * threads).clamp(1, 16);
            window::ordered(
                shape(per_job),
                || (system.clone(), system.clone(), has_parameters.then(|| d.model.clone())),
                |(sys, twin, model), job, halted| {
                    let mut rows = Vec::with_capacity(per_job);
                    for k in jobs_of(job, per_job) {
                        if halted() {
                            return None;
                        }
                        let run = run_at(k);
                        let inputs = grid.point(run);
                        let outcome = start_of(&inputs, grid, base, d, model.as_mut()).map(
                            |Begin { q, qd, parameters: values }| {
                                if has_parameters {
                                    // The tapes take the parameters as inputs: no recompilation.
                                    sys.set_parameters(&values);
                                    twin.set_parameters(&values);
                                }
                                plan.run(sys, twin, &q, &qd)
                            },
                        );
                        progress();
                        rows.push(row(run, inputs, n, outcome));
                    }
                    Some(rows)
                },
                stop,
                &mut emit,
            )
        };
        match end {
            Ok(end) => Ok(end == window::End::Finished),
            Err(e) => Err(SweepError::Threads { threads, reason: e.to_string() }),
        }
    }
}

/// The header of a sweep: its columns, and its provenance (every setting that
/// changes a row; not the threads, which do not).
fn header(d: &Derivation, grid: &Grid, config: &SweepConfig, method: Method, names: &[String]) -> SweepHeader {
    let columns = columns(&d.model, grid, names).into_iter().map(|c| c.name).collect();
    let model = &d.model;
    let parameters: Vec<String> = model.parameters.iter().map(|p| format!("{}={:?}", p.name, p.value)).collect();
    let mut meta = vec![
        ("model".to_string(), model.name.replace([';', '\n', '\r'], ",")),
        ("grid".into(), format_axes(&grid.axes)),
        ("runs".into(), grid.len().to_string()),
        ("until".into(), format!("{:?}", config.until)),
        ("method".into(), method.name().to_string()),
        ("rtol".into(), format!("{:?}", config.rtol)),
        ("atol".into(), format!("{:?}", config.atol)),
        ("parameters".into(), parameters.join(" ")),
        (
            "lyapunov".into(),
            if config.lyapunov { format!("d0 {LYAPUNOV_D0:?} every {LYAPUNOV_INTERVAL:?}") } else { "off".into() },
        ),
    ];
    if !config.shard.is_whole() {
        meta.push(("shard".into(), config.shard.to_string()));
    }
    SweepHeader { meta, columns }
}

/// The columns of a sweep's CSV, each with the name that makes it: `run`, the
/// grid's axes, `t_final`, `final_q` and `final_q'` per coordinate,
/// `energy_drift`, `lyapunov`, `failure`.
fn columns(model: &Model, grid: &Grid, names: &[String]) -> Vec<Column> {
    let fixed = |name: &str| Column { name: name.into(), origin: "the sweep itself".into(), span: None };
    let coordinate = |k: usize| model.coordinates.get(k).map(|c| c.span.clone());
    let mut cols = vec![fixed("run")];
    for (axis, target) in grid.axes.iter().zip(&grid.targets) {
        let span = match *target {
            Target::Coordinate(k) | Target::Velocity(k) => coordinate(k),
            Target::Parameter(k) => Some(model.parameters[k].span.clone()),
        };
        cols.push(Column { name: axis.name.clone(), origin: format!("the grid's axis '{}'", axis.name), span });
    }
    cols.push(fixed("t_final"));
    for prime in ["", "'"] {
        for (k, c) in names.iter().enumerate() {
            let origin = format!("coordinate '{c}' (its final value)");
            cols.push(Column { name: format!("final_{c}{prime}"), origin, span: coordinate(k) });
        }
    }
    cols.extend(["energy_drift", "lyapunov", "failure"].map(fixed));
    cols
}

/// Runs the sweep of `grid` (the runs of `config.shard`) and returns its table,
/// rows in run order whatever the scheduling: [`Sweep::run`] with every row kept.
/// `progress` is called once per finished run, from any thread.
pub fn sweep(
    d: &Derivation,
    grid: &Grid,
    config: &SweepConfig,
    progress: &(dyn Fn() + Sync),
) -> Result<SweepTable, SweepError> {
    let sweep = Sweep::new(d, grid, config)?;
    let mut rows = Vec::with_capacity(sweep.len());
    sweep.run(0, progress, &|| false, |row| {
        rows.push(row);
        ControlFlow::Continue(())
    })?;
    Ok(SweepTable { header: sweep.header.clone(), rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOUBLE_PENDULUM: &str = include_str!("../../../examples/double_pendulum.toml");
    const OSCILLATOR: &str = include_str!("../../../examples/oscillator.toml");

    use crate::test_models::derive as derivation;

    #[track_caller]
    fn check_grid(spec: &str, expect: &str) {
        let d = derivation(DOUBLE_PENDULUM);
        let got = match Grid::parse(spec, &d.model) {
            Ok(g) => format!("{} runs: {} {:?}", g.len(), format_axes(&g.axes), g.targets),
            Err(e) => format!("error: {e}"),
        };
        assert_eq!(got, expect);
    }

    #[test]
    fn grids() {
        check_grid("a=0:3:4,b=-1:1:3", "12 runs: a=0.0:3.0:4,b=-1.0:1.0:3 [Coordinate(0), Coordinate(1)]");
        check_grid(" a' = 0 : 1 : 2 , g=1:2:2", "4 runs: a'=0.0:1.0:2,g=1.0:2.0:2 [Velocity(0), Parameter(4)]");
        check_grid("a=1:5:1", "1 runs: a=1.0:1.0:1 [Coordinate(0)]");
        check_grid("a=0;1;5,g=9.81", "3 runs: a=0.0;1.0;5.0,g=9.81 [Coordinate(0), Parameter(4)]");
        check_grid(" b = -1 ; 2 ", "2 runs: b=-1.0;2.0 [Coordinate(1)]");
        check_grid("a=0;;1", "error: in the grid: the value of 'a' must be a finite number, not ''");
        check_grid("a=0;nan", "error: in the grid: the value of 'a' must be a finite number, not 'nan'");
        check_grid("a=", "error: in the grid: 'a=' is not NAME=START:STOP:COUNT (evenly spaced) or NAME=V1;V2;... (the values listed)");
        check_grid("", "error: the grid is empty; expected NAME=START:STOP:COUNT or NAME=V1;V2;..., comma separated");
        check_grid("a=0:1", "error: in the grid: 'a=0:1' is not NAME=START:STOP:COUNT (evenly spaced) or NAME=V1;V2;... (the values listed)");
        check_grid("a=0:1:2,", "error: in the grid: 'a=0:1:2,' is not NAME=START:STOP:COUNT (evenly spaced) or NAME=V1;V2;... (the values listed)");
        check_grid("a=x:1:2", "error: in the grid: the start of 'a' must be a finite number, not 'x'");
        check_grid("a=0:inf:2", "error: in the grid: the stop of 'a' must be a finite number, not 'inf'");
        check_grid("a=0:1:0", "error: in the grid: the count of 'a' must be a whole number of at least 1, not '0'");
        check_grid("a=0:1:2.5", "error: in the grid: the count of 'a' must be a whole number of at least 1, not '2.5'");
        check_grid(
            "c=0:1:2",
            "error: in the grid: 'c' is not a coordinate, a velocity or a parameter of the model (known: a, a', b, b', mA, mB, lA, lB, g)",
        );
        check_grid("a''=0:1:2", "error: in the grid: 'a''' is not a coordinate, a velocity or a parameter of the model (known: a, a', b, b', mA, mB, lA, lB, g)");
        check_grid("a=0:1:2,a=0:1:3", "error: in the grid: 'a' appears on two axes");
        check_grid(
            "a=0:1:100000,b=0:1:100000",
            "error: the grid has 10000000000 runs; a sweep may have at most 100000000",
        );
    }

    #[test]
    fn points_vary_the_last_axis_fastest_and_hit_both_ends() {
        let d = derivation(DOUBLE_PENDULUM);
        let g = Grid::parse("a=0:1:3,b=-2:2:2", &d.model).unwrap();
        let points: Vec<Vec<f64>> = (0..g.len()).map(|r| g.point(r)).collect();
        assert_eq!(points, [[0.0, -2.0], [0.0, 2.0], [0.5, -2.0], [0.5, 2.0], [1.0, -2.0], [1.0, 2.0]]);
    }

    #[test]
    fn shards_cover_every_run_exactly_once() {
        for total in [0, 1, 7, 100, 101] {
            for count in 1..=9 {
                let mut hits = vec![0; total];
                for index in 0..count {
                    let shard = Shard::parse(&format!("{index}/{count}")).unwrap();
                    shard.runs(total).for_each(|r| hits[r] += 1);
                }
                assert!(hits.iter().all(|&h| h == 1), "{total} runs in {count} shards: {hits:?}");
                for index in 0..count {
                    let shard = Shard { index, count };
                    let runs: Vec<usize> = shard.runs(total).collect();
                    assert_eq!(shard.len(total), runs.len(), "{shard} of {total}");
                    assert!(runs.iter().enumerate().all(|(k, &r)| shard.nth(k) == r), "{shard} of {total}");
                }
            }
        }
        for bad in ["3/3", "1", "a/2", "0/0", "-1/2", ""] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    fn config(until: f64) -> SweepConfig {
        SweepConfig { until, ..SweepConfig::default() }
    }

    fn column(t: &SweepTable, name: &str) -> Vec<f64> {
        let k = t.header.value_index(name).unwrap();
        t.rows.iter().map(|r| r.values[k]).collect()
    }

    #[test]
    fn lyapunov_exponents_tell_chaos_from_order() {
        // Released from a = 2, b = 2.5 the double pendulum is chaotic; at small amplitude it is nearly linear.
        let d = derivation(DOUBLE_PENDULUM);
        let grid = Grid::parse("a=0.05:2:2,b=0.05:2.5:2", &d.model).unwrap();
        let t = sweep(&d, &grid, &config(30.0), &|| {}).unwrap();
        let lyapunov = column(&t, "lyapunov");
        assert!(lyapunov[3] > 0.5, "chaotic: {lyapunov:?}");
        assert!(lyapunov[0].abs() < 0.2, "near-linear: {lyapunov:?}");
        assert!(column(&t, "energy_drift").iter().all(|&e| e < 1e-7), "{t:?}");

        let d = derivation(OSCILLATOR);
        let grid = Grid::parse("x=0.5:2:3,om=0.5:2:2", &d.model).unwrap();
        let t = sweep(&d, &grid, &config(20.0), &|| {}).unwrap();
        for (row, l) in t.rows.iter().zip(column(&t, "lyapunov")) {
            assert!(l.abs() < 0.05, "harmonic oscillator {:?}: {l}", row.values);
        }
        // Parameters reach the dynamics: om = 2 runs x(20) = x0 cos(40).
        let final_x = column(&t, "final_x");
        assert!((final_x[5] - 2.0 * 40f64.cos()).abs() < 1e-7, "{final_x:?}");
        assert!((final_x[0] - 0.5 * 10f64.cos()).abs() < 1e-7, "{final_x:?}");
    }

    #[test]
    fn rows_are_in_run_order_whatever_the_threads_and_shards_merge_back() {
        let d = derivation(DOUBLE_PENDULUM);
        let grid = Grid::parse("a=-3:3:3,b'=-1:1:3", &d.model).unwrap();
        let whole = sweep(&d, &grid, &SweepConfig { threads: Some(3), ..config(1.5) }, &|| {}).unwrap();
        assert_eq!(whole.rows.iter().map(|r| r.run).collect::<Vec<_>>(), (0..9).collect::<Vec<_>>());
        let text = whole.to_csv();
        assert_eq!(SweepTable::parse(&text, "whole.csv").unwrap(), whole);
        let part = |i: usize| {
            let cfg = SweepConfig { shard: Shard { index: i, count: 2 }, threads: Some(1), ..config(1.5) };
            let t = sweep(&d.clone(), &grid, &cfg, &|| {}).unwrap();
            (format!("part{i}.csv"), SweepTable::parse(&t.to_csv(), "part").unwrap())
        };
        let (p0, p1) = (part(0), part(1));
        assert_eq!(p0.1.rows.len(), 5);
        assert_eq!(merge(&[p1.clone(), p0.clone()]).unwrap().to_csv(), text);

        let err = |shards: &[(String, SweepTable)]| merge(shards).unwrap_err().to_string();
        assert_eq!(
            err(std::slice::from_ref(&p0)),
            "4 of 9 runs are missing (first: [1, 3, 5, 7]); missing shards: 1/2"
        );
        let mut cut = p1.clone();
        cut.1.rows.remove(2);
        assert_eq!(
            err(&[p0.clone(), cut]),
            "1 of 9 runs are missing (first: [5]); missing shards: none (rows are missing from the shard files)"
        );
        assert_eq!(
            err(&[p0.clone(), p0.clone()]),
            "part0.csv is not a shard of the same sweep as part0.csv: both are shard 0/2"
        );
        let mut other = p1.clone();
        other.1.header.meta.iter_mut().find(|(k, _)| k == "until").unwrap().1 = "3".into();
        assert_eq!(
            err(&[p0, other]),
            "part1.csv is not a shard of the same sweep as part0.csv: until is '1.5' there and '3' here"
        );
    }

    /// A sweep that skips the rows it has (a resumed one) gives the rest of
    /// the rows of a whole run, bit for bit, on lanes and run by run; one that
    /// is stopped has given a prefix in grid order.
    #[test]
    fn a_resumed_sweep_gives_the_rest_and_a_stopped_one_a_prefix() {
        let d = derivation(DOUBLE_PENDULUM);
        let grid = Grid::parse("a=-3:3:5,b'=-1:1:5", &d.model).unwrap();
        for method in [None, Some(Method::Dop853)] {
            let cfg = SweepConfig { method, threads: Some(2), ..config(1.5) };
            let whole = sweep(&d, &grid, &cfg, &|| {}).unwrap();
            let s = Sweep::new(&d, &grid, &cfg).unwrap();
            let mut rest = Vec::new();
            let done = s.run(17, &|| {}, &|| false, |row| {
                rest.push(row);
                ControlFlow::Continue(())
            });
            assert_eq!(done, Ok(true));
            assert_eq!(format!("{rest:?}"), format!("{:?}", &whole.rows[17..]), "{method:?}");

            let given = std::sync::atomic::AtomicUsize::new(0);
            let mut prefix = Vec::new();
            let stop = || given.load(std::sync::atomic::Ordering::Relaxed) >= 6;
            let done = s.run(0, &|| {}, &stop, |row| {
                prefix.push(row);
                given.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                ControlFlow::Continue(())
            });
            assert_eq!(done, Ok(false));
            assert_eq!(format!("{prefix:?}"), format!("{:?}", &whole.rows[..6]), "{method:?}");
        }
    }

    #[test]
    fn a_run_that_fails_is_a_row_with_its_reason() {
        // x'' = -x^3 * 1e6 from x = 1e3 overflows: the run fails, the sweep goes on.
        let text = "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"k*x^4/4\"\n[parameters]\nk = 1e6\n[initial]\n\"x'\" = 0\n";
        let d = derivation(text);
        let grid = Grid::parse("x=1:1e200:2", &d.model).unwrap();
        let t = sweep(&d, &grid, &config(1.0), &|| {}).unwrap();
        assert_eq!(t.rows[0].failure, "");
        assert!(!t.rows[1].failure.is_empty(), "{t:?}");
        assert!(column(&t, "lyapunov")[1].is_nan());
        // NaN is not equal to itself: compare through the text.
        let csv = t.to_csv();
        assert_eq!(SweepTable::parse(&csv, "f.csv").unwrap().to_csv(), csv);
    }

    /// Every row has the header's width: a row with extra columns is not read as
    /// a failure message holding them, and a stray quote is an error too.
    #[test]
    fn a_row_of_the_wrong_width_is_refused() {
        let head = format!("{CSV_MAGIC} runs=2\nrun,x,failure\n");
        let read = |rows: &str| SweepTable::parse(&format!("{head}{rows}"), "f.csv");
        let t = read("0,1.5,\n1,2.5,\"diverged, at t = 1\"\n").unwrap();
        assert_eq!(t.rows[1].failure, "diverged, at t = 1");
        for bad in ["0,1.5,,extra,cols\n", "0,1.5,\"unclosed\n", "0,1.5\n", "0,1.5,a\"b\n", "0,x,\n"] {
            let e = read(bad).unwrap_err().to_string();
            assert!(e.starts_with("f.csv, line 3:"), "{bad:?}: {e}");
        }
    }

    #[test]
    fn a_value_missing_from_initial_and_grid_is_an_error() {
        let d = derivation("coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\n[initial]\nx = 1\n");
        let grid = Grid::parse("x=0:1:2", &d.model).unwrap();
        let e = sweep(&d, &grid, &config(1.0), &|| {}).unwrap_err();
        assert_eq!(e.to_string(), "no initial value for x': neither [initial] nor the grid gives one");
    }

    /// A top swinging through β = 0 (no spin, thrown towards the vertical)
    /// fails at the gimbal singularity instead of integrating through it; one
    /// spinning fast stays away from it and finishes. A grid point at β = 0
    /// fails at once.
    #[test]
    fn a_run_through_the_gimbal_singularity_fails_with_its_reason() {
        let d = derivation(include_str!("../../../examples/tops/heavy_top.toml"));
        let grid = Grid::parse("ga'=0:12:2,be'=-6:-6:1", &d.model).unwrap();
        let t = sweep(&d, &grid, &config(3.0), &|| {}).unwrap();
        let t_final = column(&t, "t_final");
        assert!(t.rows[0].failure.contains("gimbal singularity"), "{:?}", t.rows[0]);
        assert!(t_final[0] > 0.0 && t_final[0] < 3.0, "{t_final:?}");
        assert!(t.rows[1].failure.is_empty() && t_final[1] == 3.0, "{:?}", t.rows[1]);
        let grid = Grid::parse("be=0:0:1", &d.model).unwrap();
        let t = sweep(&d, &grid, &config(1.0), &|| {}).unwrap();
        assert!(t.rows[0].failure.contains("gimbal singularity"), "{:?}", t.rows[0]);
    }
}
