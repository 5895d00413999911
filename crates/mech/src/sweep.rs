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
use crate::run::choose_method;
use crate::run::dynamics::{Dynamics, Form, System};
use crate::run::ensemble::{propagate, Batch, LANES};
use crate::run::series::{LagrangeSeries, SeriesCode};
use num::{integrate, integrate_to, Config, Method, Output, SolveError, Solver, StopReason};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::sync::OnceLock;
use std::thread;
use sym::Lanes;

mod window;

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
    #[error("the grid is empty; expected NAME=START:STOP:COUNT, comma separated")]
    EmptyGrid,
    /// An axis that is not `NAME=START:STOP:COUNT`.
    #[error("in the grid: '{item}' is not NAME=START:STOP:COUNT")]
    AxisSyntax {
        /// The offending axis text.
        item: String,
    },
    /// A start or stop that is not a finite number.
    #[error("in the grid: the {what} of '{name}' must be a finite number, not '{text}'")]
    AxisNumber {
        /// The axis name.
        name: String,
        /// `start` or `stop`.
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
    Model(ModelError),
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

/// What an axis of the grid sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// The initial value of coordinate `k`.
    Coordinate(usize),
    /// The initial velocity of coordinate `k`.
    Velocity(usize),
    /// Parameter `k` (in the model's order).
    Parameter(usize),
}

/// One axis: `count` evenly spaced values from `start` to `stop`, both included.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The name as written (`a`, `a'`, `g`).
    pub name: String,
    /// First value.
    pub start: f64,
    /// Last value (equal to `start` when `count` is 1).
    pub stop: f64,
    /// Number of values, at least 1.
    pub count: usize,
}

impl Axis {
    /// The `k`-th value.
    pub fn value(&self, k: usize) -> f64 {
        if self.count <= 1 {
            self.start
        } else if k + 1 == self.count {
            self.stop
        } else {
            self.start + (self.stop - self.start) * (k as f64 / (self.count - 1) as f64)
        }
    }
}

/// Parses `name=start:stop:count,...` without a model: the axes of a grid as text
/// describes them (used again to read a merged CSV's provenance).
pub fn parse_axes(spec: &str) -> Result<Vec<Axis>, SweepError> {
    let mut axes: Vec<Axis> = Vec::new();
    for item in spec.split(',').map(str::trim) {
        if item.is_empty() {
            if spec.trim().is_empty() {
                return Err(SweepError::EmptyGrid);
            }
            return Err(SweepError::AxisSyntax { item: spec.trim().to_string() });
        }
        let syntax = || SweepError::AxisSyntax { item: item.to_string() };
        let (name, range) = item.split_once('=').ok_or_else(syntax)?;
        let name = name.trim();
        let parts: Vec<&str> = range.split(':').map(str::trim).collect();
        if name.is_empty() || parts.len() != 3 {
            return Err(syntax());
        }
        let number = |what: &'static str, text: &str| {
            text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| SweepError::AxisNumber {
                name: name.to_string(),
                what,
                text: text.to_string(),
            })
        };
        let start = number("start", parts[0])?;
        let stop = number("stop", parts[1])?;
        let count = parts[2]
            .parse::<usize>()
            .ok()
            .filter(|&c| c >= 1)
            .ok_or_else(|| SweepError::AxisCount { name: name.to_string(), text: parts[2].to_string() })?;
        if axes.iter().any(|a| a.name == name) {
            return Err(SweepError::DuplicateAxis { name: name.to_string() });
        }
        axes.push(Axis { name: name.to_string(), start, stop: if count == 1 { start } else { stop }, count });
    }
    let runs = axes.iter().fold(1u128, |acc, a| acc.saturating_mul(a.count as u128));
    if runs > MAX_RUNS as u128 {
        return Err(SweepError::TooLarge { runs, max: MAX_RUNS });
    }
    Ok(axes)
}

/// The axes as text that [`parse_axes`] reads back.
pub fn format_axes(axes: &[Axis]) -> String {
    axes.iter().map(|a| format!("{}={:?}:{:?}:{}", a.name, a.start, a.stop, a.count)).collect::<Vec<_>>().join(",")
}

/// A grid of runs: the cartesian product of its axes, the first axis varying
/// slowest (run index `((i0·n1) + i1)·n2 + i2 …`).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// The axes, in the order given.
    pub axes: Vec<Axis>,
    /// What each axis sets.
    pub targets: Vec<Target>,
}

impl Grid {
    /// Parses a `--grid` text and resolves its names against a model.
    pub fn parse(spec: &str, model: &Model) -> Result<Grid, SweepError> {
        let axes = parse_axes(spec)?;
        let mut targets = Vec::with_capacity(axes.len());
        for axis in &axes {
            let name = axis.name.as_str();
            let base = name.strip_suffix('\'').unwrap_or(name);
            let coord = model.coordinates.iter().position(|c| c.name == base);
            let target = match coord {
                Some(k) if base.len() == name.len() => Some(Target::Coordinate(k)),
                Some(k) => Some(Target::Velocity(k)),
                None => model.parameters.iter().position(|p| p.name == name).map(Target::Parameter),
            };
            let known = || {
                let mut names: Vec<String> = Vec::new();
                for c in &model.coordinates {
                    names.push(c.name.clone());
                    names.push(format!("{}'", c.name));
                }
                names.extend(model.parameters.iter().map(|p| p.name.clone()));
                names.join(", ")
            };
            targets.push(target.ok_or_else(|| SweepError::UnknownName { name: name.to_string(), known: known() })?);
        }
        Ok(Grid { axes, targets })
    }

    /// The number of runs.
    pub fn len(&self) -> usize {
        self.axes.iter().map(|a| a.count).product()
    }

    /// True when the grid has no run (never, for a parsed grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The input values of run `run`, one per axis.
    pub fn point(&self, run: usize) -> Vec<f64> {
        let mut rest = run;
        let mut values = vec![0.0; self.axes.len()];
        for (k, axis) in self.axes.iter().enumerate().rev() {
            values[k] = axis.value(rest % axis.count);
            rest /= axis.count;
        }
        values
    }
}

/// The `index`-th of `count` slices of a sweep: the runs `r` with `r % count == index`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which slice, `0..count`.
    pub index: usize,
    /// How many slices.
    pub count: usize,
}

impl Default for Shard {
    fn default() -> Self {
        Shard { index: 0, count: 1 }
    }
}

impl Shard {
    /// Parses `i/n`.
    pub fn parse(text: &str) -> Result<Shard, SweepError> {
        let err = || SweepError::ShardSyntax { text: text.to_string() };
        let (i, n) = text.split_once('/').ok_or_else(err)?;
        let index: usize = i.trim().parse().map_err(|_| err())?;
        let count: usize = n.trim().parse().map_err(|_| err())?;
        if count == 0 || index >= count {
            return Err(err());
        }
        Ok(Shard { index, count })
    }

    /// The run indices of this shard among `total`, ascending.
    pub fn runs(self, total: usize) -> impl Iterator<Item = usize> {
        (self.index..total).step_by(self.count)
    }

    /// The number of this shard's runs among `total`.
    pub fn len(self, total: usize) -> usize {
        total.saturating_sub(self.index).div_ceil(self.count)
    }

    /// The grid index of this shard's `k`-th run.
    pub fn nth(self, k: usize) -> usize {
        self.index + k * self.count
    }

    /// Whether the sweep is split at all.
    pub fn is_whole(self) -> bool {
        self.count == 1
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
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

/// One row of a sweep's table.
#[derive(Debug, Clone, PartialEq)]
pub struct TableRow {
    /// The run index in the whole grid.
    pub run: usize,
    /// Every numeric column between `run` and `failure`.
    pub values: Vec<f64>,
    /// Why the run failed (empty when it did not).
    pub failure: String,
}

impl TableRow {
    /// Appends the row's CSV line, newline included, to `out`. Numbers print in
    /// the shortest form that reads back exactly (`1e-10`, `0.5`, `NaN`).
    pub fn write_csv(&self, out: &mut String) {
        let _ = write!(out, "{}", self.run);
        for v in &self.values {
            let _ = write!(out, ",{v:?}");
        }
        out.push(',');
        out.push_str(&csv_field(&self.failure));
        out.push('\n');
    }

    /// Reads one line that [`TableRow::write_csv`] wrote (without its newline),
    /// under `header`; `file` and `line_no` name it in errors.
    pub fn parse(line: &str, header: &SweepHeader, file: &str, line_no: usize) -> Result<TableRow, SweepError> {
        let err = |reason: String| SweepError::Table { file: file.to_string(), line: line_no, reason };
        let columns = &header.columns;
        let n_values = columns.len() - 2;
        let mut fields = line.splitn(n_values + 2, ',');
        let run = fields
            .next()
            .and_then(|f| f.parse::<usize>().ok())
            .ok_or_else(|| err("the run index is not a whole number".into()))?;
        let mut values = Vec::with_capacity(n_values);
        for c in 0..n_values {
            let field = fields.next().ok_or_else(|| err(format!("{} columns expected", columns.len())))?;
            let v = field
                .parse::<f64>()
                .map_err(|_| err(format!("'{field}' in column '{}' is not a number", columns[c + 1])))?;
            values.push(v);
        }
        let last = fields.next().ok_or_else(|| err(format!("{} columns expected", columns.len())))?;
        let failure = failure_field(last).ok_or_else(|| {
            err(format!(
                "{} columns expected: the last, 'failure', is empty, text without commas or quotes, or quoted; found '{last}'",
                columns.len()
            ))
        })?;
        Ok(TableRow { run, values, failure })
    }
}

/// The first two lines of a sweep's CSV: the provenance comment and the
/// column names. Two sweeps with equal headers compute equal rows.
///
/// Columns: `run`, the grid's names (inputs), `t_final`, `final_<q>` per
/// coordinate, `final_<q>'` per velocity, `energy_drift`, `lyapunov`, `failure`.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepHeader {
    /// Provenance as `key=value` pairs (`model`, `grid`, `runs`, `until`, `method`,
    /// `rtol`, `atol`, `parameters`, `lyapunov`, and `shard` for a part).
    pub meta: Vec<(String, String)>,
    /// Column names, `run` first and `failure` last.
    pub columns: Vec<String>,
}

impl SweepHeader {
    /// A provenance value.
    pub fn meta(&self, key: &str) -> Option<&str> {
        self.meta.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// The number of runs of the whole sweep (from the provenance).
    pub fn total_runs(&self) -> Option<usize> {
        self.meta("runs")?.parse().ok()
    }

    /// The grid's axes (from the provenance).
    pub fn axes(&self) -> Option<Vec<Axis>> {
        parse_axes(self.meta("grid")?).ok()
    }

    /// The index into [`TableRow::values`] of a column (`None` for `run`, `failure` or an unknown name).
    pub fn value_index(&self, column: &str) -> Option<usize> {
        let k = self.columns.iter().position(|c| c == column)?;
        (k >= 1 && k + 1 < self.columns.len()).then(|| k - 1)
    }

    /// The two header lines, each ending in a newline.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(CSV_MAGIC);
        for (k, v) in &self.meta {
            let _ = write!(s, "; {k}={v}");
        }
        s.push('\n');
        s.push_str(&self.columns.join(","));
        s.push('\n');
        s
    }

    /// Reads the two lines [`SweepHeader::to_csv`] writes (without their
    /// newlines); `file` names them in errors.
    pub fn parse(first: &str, second: &str, file: &str) -> Result<SweepHeader, SweepError> {
        let err = |line: usize, reason: String| SweepError::Table { file: file.to_string(), line, reason };
        let Some(rest) = first.strip_prefix(CSV_MAGIC) else {
            return Err(err(
                1,
                format!("not the output of `lagrange sweep` (the first line should start with '{CSV_MAGIC}')"),
            ));
        };
        let mut meta = Vec::new();
        for pair in rest.split("; ").map(str::trim).filter(|p| !p.is_empty()) {
            let (k, v) = pair.split_once('=').ok_or_else(|| err(1, format!("provenance '{pair}' is not KEY=VALUE")))?;
            meta.push((k.to_string(), v.to_string()));
        }
        let columns: Vec<String> = second.split(',').map(str::to_string).collect();
        if columns.len() < 2 || columns[0] != "run" || columns.last().map(String::as_str) != Some("failure") {
            return Err(err(2, "the header should start with 'run' and end with 'failure'".into()));
        }
        Ok(SweepHeader { meta, columns })
    }
}

/// A sweep's result held whole: its header and rows, in run order. Its file
/// form is CSV with one comment line of provenance first ([`SweepTable::to_csv`]).
/// A sweep streams its rows ([`Sweep::run`]); a table is for what needs them
/// all at once ([`merge`], tests).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepTable {
    /// Provenance and columns.
    pub header: SweepHeader,
    /// The rows, ascending by run.
    pub rows: Vec<TableRow>,
}

impl SweepTable {
    /// The CSV text: the provenance comment, the header and one line per row.
    pub fn to_csv(&self) -> String {
        let mut s = self.header.to_csv();
        s.reserve(64 * self.rows.len());
        for row in &self.rows {
            row.write_csv(&mut s);
        }
        s
    }

    /// Reads the text [`SweepTable::to_csv`] writes; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<SweepTable, SweepError> {
        let mut lines = text.lines();
        let first = lines.next().unwrap_or_default();
        let header = SweepHeader::parse(first, lines.next().unwrap_or_default(), file)?;
        let mut rows = Vec::new();
        for (k, line) in lines.enumerate() {
            if !line.is_empty() {
                rows.push(TableRow::parse(line, &header, file, k + 3)?);
            }
        }
        Ok(SweepTable { header, rows })
    }
}

/// A CSV field: quoted when it holds a comma, a quote or a line break (which
/// becomes a space: one row per line).
fn csv_field(text: &str) -> String {
    let text = text.replace(['\n', '\r'], " ");
    if text.contains([',', '"']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text
    }
}

/// The text of the last field of a row as [`csv_field`] writes it: plain text
/// without commas or quotes, or one quoted field whose quotes inside are doubled.
/// None for anything else (extra columns, a stray quote).
fn failure_field(field: &str) -> Option<String> {
    match field.strip_prefix('"') {
        None => (!field.contains([',', '"'])).then(|| field.to_string()),
        Some(rest) => {
            let inner = rest.strip_suffix('"')?;
            (!inner.replace("\"\"", "").contains('"')).then(|| inner.replace("\"\"", "\""))
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
        d.model.check_inputs_applied().map_err(SweepError::Model)?;
        let dynamics = Dynamics::new(d);
        // Rigid bodies need the gimbal guard's events, which the lock-step batches
        // do not check, and equations with a kink (abs) that a Taylor series does
        // not see: DOP853 by default there.
        let default = if d.model.bodies.is_empty() && dynamics.is_analytic() { Method::Taylor } else { Method::Dop853 };
        let (method, form) =
            choose_method(d, &dynamics, Some(config.method.unwrap_or(default)), false).map_err(SweepError::Model)?;
        // Initial values from the model; a value neither in [initial] nor on an axis
        // is an error before anything runs.
        let base = initial_values(&d.model).map_err(SweepError::Model)?;
        if grid.is_empty() {
            return Err(SweepError::EmptyGrid);
        }
        complete(&base, grid, &grid.point(0), &d.model).map_err(SweepError::Model)?;
        // Rigid bodies: a run through the Euler angles' gimbal singularity fails
        // there (as `simulate` does) instead of integrating garbage.
        let guards = crate::run::body::gimbal_guards(d, config.rtol);
        let names = dynamics.coordinate_names();
        refuse_duplicates(&columns(&d.model, grid, names), "the sweep's CSV").map_err(SweepError::Model)?;
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
                            let start = start_of(&inputs, grid, base, d, model.as_mut());
                            (run, inputs, start)
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
                        let outcome = start_of(&inputs, grid, base, d, model.as_mut()).map(|(q, qd, values)| {
                            if has_parameters {
                                // The tapes take the parameters as inputs: no recompilation.
                                sys.set_parameters(&values);
                                twin.set_parameters(&values);
                            }
                            plan.run(sys, twin, &q, &qd)
                        });
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

/// What one run produced.
#[derive(Debug)]
struct RunOutcome {
    t_final: f64,
    q: Vec<f64>,
    qd: Vec<f64>,
    energy_drift: f64,
    lyapunov: f64,
    failure: Option<String>,
}

impl RunOutcome {
    /// A run of `n` coordinates that ended at `t_final` with `failure`, before
    /// anything was measured (q, q', drift and exponent NaN).
    fn ended(n: usize, t_final: f64, failure: Option<String>) -> RunOutcome {
        RunOutcome {
            t_final,
            q: vec![f64::NAN; n],
            qd: vec![f64::NAN; n],
            energy_drift: f64::NAN,
            lyapunov: f64::NAN,
            failure,
        }
    }
}

/// The row of a run; a run that could not start has only its inputs.
fn row(run: usize, inputs: Vec<f64>, n: usize, outcome: Result<RunOutcome, String>) -> TableRow {
    let outcome = outcome.unwrap_or_else(|message| RunOutcome::ended(n, 0.0, Some(message)));
    let mut values = inputs;
    values.push(outcome.t_final);
    values.extend(&outcome.q);
    values.extend(&outcome.qd);
    values.push(outcome.energy_drift);
    values.push(outcome.lyapunov);
    TableRow { run, values, failure: outcome.failure.unwrap_or_default() }
}

/// The initial (q, q') of a run at grid point `inputs` and its parameter values:
/// from `base` and `d`'s model, or, for grids over parameters, from `derivation`
/// (a worker's copy) with the grid's parameters set.
fn start_of(
    inputs: &[f64],
    grid: &Grid,
    base: &Initial,
    d: &Derivation,
    model: Option<&mut Model>,
) -> Result<Begin, String> {
    // A parameter grid sets the worker's own copy of the model: the initial
    // values may depend on the parameters.
    let start = match model {
        Some(model) => {
            for (value, target) in inputs.iter().zip(&grid.targets) {
                if let Target::Parameter(k) = *target {
                    model.parameters[k].value = *value;
                }
            }
            let model = &*model;
            initial_values(model).and_then(|base| complete(&base, grid, inputs, model)).and_then(|(q, qd)| {
                // What reading the file with --set checks at these values, and
                // what a run checks of its start: refused here, the row's failure.
                model.check_values(Some((&q, &qd)))?;
                no_inertia(d, model, &q)?;
                let values = model.parameters.iter().map(|p| p.value).collect();
                Ok((q, qd, values))
            })
        }
        None => complete(base, grid, inputs, &d.model).and_then(|(q, qd)| {
            d.model.check_values(Some((&q, &qd)))?;
            no_inertia(d, &d.model, &q)?;
            Ok((q, qd, d.model.parameters.iter().map(|p| p.value).collect()))
        }),
    };
    start.map_err(|e| e.message)
}

/// A row whose start leaves a coordinate without inertia because a parameter
/// is 0 (`m = 0`), refused with that cause as a run refuses it. Looked for only
/// when a parameter is 0 and a diagonal entry of M vanishes at the start, so
/// that other rows pay nothing.
fn no_inertia(d: &Derivation, model: &Model, q: &[f64]) -> Result<(), ModelError> {
    if !d.constraints.is_empty() || !model.parameters.iter().any(|p| p.value == 0.0) {
        return Ok(());
    }
    let names: Vec<&str> = model.coordinates.iter().map(|c| c.name.as_str()).collect();
    let env = |name: &str| match names.iter().position(|&c| c == name) {
        Some(k) => Some(q[k]),
        None if name == "t" => Some(0.0),
        None => model.parameter(name),
    };
    let idle_diagonal = (0..q.len()).any(|i| d.pool().eval(d.mass_matrix[i][i], &env) == Ok(0.0));
    if !idle_diagonal {
        return Ok(());
    }
    let all: Vec<usize> = (0..q.len()).collect();
    match d.no_inertia_at(&all, q, &|p| model.parameter(p)) {
        Some(idle) if !idle.zero_parameters.is_empty() => {
            let start = names.iter().zip(q).map(|(c, v)| format!("{c} = {}", num::Shortest(*v)));
            let at = format!("the start ({})", start.collect::<Vec<_>>().join(", "));
            Err(ModelError::whole(idle.message(&at)).with_help(idle.help()))
        }
        _ => Ok(()),
    }
}

/// The `[initial]` values of a model at its current parameter values (None where not given).
type Initial = (Vec<Option<f64>>, Vec<Option<f64>>);

fn initial_values(model: &Model) -> Result<Initial, ModelError> {
    let n = model.n_coords();
    let (mut q, mut qd) = (vec![None; n], vec![None; n]);
    let env = |name: &str| model.parameter(name);
    for iv in &model.initial {
        let v =
            model.pool.eval(iv.value.expr, &env).map_err(|e| ModelError::at(iv.value.span.clone(), e.to_string()))?;
        let slot = if iv.order == 0 { &mut q } else { &mut qd };
        slot[iv.coord] = Some(v);
    }
    Ok((q, qd))
}

/// The initial (q, q') of a run: the model's values overridden by the grid's.
fn complete(base: &Initial, grid: &Grid, inputs: &[f64], model: &Model) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
    let (mut q, mut qd) = base.clone();
    for (value, target) in inputs.iter().zip(&grid.targets) {
        match *target {
            Target::Coordinate(k) => q[k] = Some(*value),
            Target::Velocity(k) => qd[k] = Some(*value),
            Target::Parameter(_) => {}
        }
    }
    let mut missing = Vec::new();
    for (k, c) in model.coordinates.iter().enumerate() {
        if q[k].is_none() {
            missing.push(c.name.clone());
        }
        if qd[k].is_none() {
            missing.push(format!("{}'", c.name));
        }
    }
    if !missing.is_empty() {
        return Err(ModelError::whole(format!(
            "no initial value for {}: neither [initial] nor the grid gives one",
            missing.join(", ")
        ))
        .with_help("add them under [initial] or as axes of the grid"));
    }
    if let Some(v) = q.iter().chain(&qd).flatten().find(|v| !v.is_finite()) {
        return Err(ModelError::whole(format!("an initial value evaluates to {v}")));
    }
    Ok((q.into_iter().flatten().collect(), qd.into_iter().flatten().collect()))
}

/// The integrator and options shared by every run.
struct Plan<'a> {
    method: Method,
    form: Form,
    config: &'a SweepConfig,
    /// One per rigid body, checked after every step of the main trajectory.
    guards: &'a [GimbalGuard],
}

/// A solver in the form the method needs, borrowing its system.
fn build<'a>(
    method: Method,
    form: Form,
    system: &'a mut System,
    t0: f64,
    y0: &[f64],
    config: &Config,
) -> Result<Box<dyn Solver + 'a>, SolveError> {
    if form == Form::Separable {
        method.build_separable(system, t0, y0, config)
    } else {
        method.build(system, t0, y0, config)
    }
}

impl Plan<'_> {
    /// One run from (q0, q0'): the main trajectory in segments of
    /// [`LYAPUNOV_INTERVAL`], and the twin beside it (module documentation).
    fn run(&self, sys: &mut System, twin_sys: &mut System, q0: &[f64], qd0: &[f64]) -> RunOutcome {
        let n = q0.len();
        let cfg = self.config;
        let mut out = RunOutcome::ended(n, 0.0, None);
        if let Some(g) = self.guards.iter().find(|g| g.violated(q0)) {
            out.failure = Some(g.message(0.0));
            return out;
        }
        let y0 = match sys.initial_state(0.0, q0, qd0) {
            Ok(y) => y,
            Err(e) => {
                out.failure = Some(e.message);
                return out;
            }
        };
        let mut qd = vec![0.0; n];
        let mut inv = vec![0.0; sys.n_invariants()];
        let h0 = sys.invariants_at(0.0, &y0, &mut qd, &mut inv).ok().map(|()| inv[0]);
        let mut solver_config = Config { rtol: cfg.rtol, atol: cfg.atol, h_max: Some(cfg.until), ..Config::default() };
        let mut y = y0.clone();
        let mut t = 0.0;
        let mut twin_failure: Option<String> = None;
        let mut log_sum = 0.0;
        {
            let mut main = match build(self.method, self.form, sys, 0.0, &y0, &solver_config) {
                Ok(s) => s,
                Err(e) => {
                    out.failure = Some(e.to_string());
                    return out;
                }
            };
            if !self.method.is_adaptive() {
                // The twin takes the step chosen for the main trajectory.
                solver_config.dt = Some(main.step_size());
            }
            let mut twin_y = cfg.lyapunov.then(|| perturbed(&y0));
            // The twin's solver: kept from segment to segment and restarted from
            // the renormalized state by the methods that can (DOP853, DOPRI5, Taylor);
            // built afresh every segment by the others.
            let mut twin = Twin::Fresh(twin_sys);
            if let (Some(ty), Method::Dop853 | Method::Dopri5 | Method::Taylor) = (twin_y.as_ref(), self.method) {
                if let Twin::Fresh(sys) = twin {
                    twin = match build(self.method, self.form, sys, 0.0, ty, &solver_config) {
                        Ok(s) => Twin::Kept(s),
                        Err(e) => {
                            out.failure = Some(format!("the perturbed twin failed: {e}"));
                            return out;
                        }
                    };
                }
            }
            let mut twin_h = None;
            let mut segment = 0u32;
            while t < cfg.until {
                segment += 1;
                let t_next = segment_end(segment, cfg.until);
                let mut gimbal: Option<(f64, &GimbalGuard)> = None;
                let mut events = crate::run::body::guard_events(self.guards);
                let result = integrate(main.as_mut(), t_next, Output::EveryStep, &mut events, |obs| {
                    match self.guards.iter().find(|g| g.violated(&obs.y[..n])) {
                        Some(g) => {
                            gimbal = Some((obs.t, g));
                            ControlFlow::Break(())
                        }
                        None => ControlFlow::Continue(()),
                    }
                });
                if let Ok(num::Summary { t: t_event, stop: StopReason::Event { index }, .. }) = result {
                    gimbal = Some((t_event, &self.guards[index / 2]));
                }
                if let Some((t_fail, g)) = gimbal {
                    out.t_final = t_fail;
                    out.failure = Some(g.message(t_fail));
                    return out;
                }
                if let Err(e) = result {
                    out.t_final = main.t();
                    out.failure = Some(e.to_string());
                    return out;
                }
                y.copy_from_slice(main.state());
                if let (Some(ty), None) = (twin_y.as_mut(), &twin_failure) {
                    let step = match &mut twin {
                        Twin::Kept(s) => integrate_to(s.as_mut(), t_next, ty),
                        Twin::Fresh(sys) => {
                            let twin_config = Config { h_init: twin_h, ..solver_config };
                            build(self.method, self.form, sys, t, ty, &twin_config).and_then(|mut s| {
                                integrate_to(s.as_mut(), t_next, ty)?;
                                twin_h = Some(s.step_size());
                                Ok(())
                            })
                        }
                    };
                    match step {
                        Ok(()) => match pull_back(&y, ty, t_next) {
                            Ok(growth) => {
                                log_sum += growth;
                                if let Twin::Kept(s) = &mut twin {
                                    if let Err(e) = s.set_state(ty) {
                                        twin_failure = Some(format!("the perturbed twin failed: {e}"));
                                    }
                                }
                            }
                            Err(message) => twin_failure = Some(message),
                        },
                        Err(e) => twin_failure = Some(format!("the perturbed twin failed: {e}")),
                    }
                }
                t = t_next;
            }
        }
        out.t_final = t;
        self.conclude(&mut out, sys, t, &y, h0, (log_sum, twin_failure));
        out
    }

    /// Fills `out` from the end state `y` at `t` of a run that did not fail:
    /// q and q', the energy's drift from `h0`, the Lyapunov exponent from the
    /// twin's `log_sum`, or the twin's failure (`twin = (log_sum, failure)`).
    fn conclude(
        &self,
        out: &mut RunOutcome,
        sys: &mut System,
        t: f64,
        y: &[f64],
        h0: Option<f64>,
        (log_sum, twin_failure): (f64, Option<String>),
    ) {
        let n = out.q.len();
        let mut qd = vec![0.0; n];
        let mut inv = vec![0.0; sys.n_invariants()];
        if let Err(e) = sys.invariants_at(t, y, &mut qd, &mut inv) {
            out.failure = Some(format!("at t = {t}: {e}", t = num::Shortest(t)));
            return;
        }
        out.q.copy_from_slice(&y[..n]);
        out.qd.copy_from_slice(&qd);
        if let Some(h0) = h0 {
            let drift = (inv[0] - h0).abs();
            out.energy_drift = if h0 != 0.0 { drift / h0.abs() } else { drift };
        }
        if self.config.lyapunov && twin_failure.is_none() {
            out.lyapunov = log_sum / t;
        }
        out.failure = twin_failure;
    }
}

/// A run's initial q, q' and parameter values.
type Begin = (Vec<f64>, Vec<f64>, Vec<f64>);

/// A run of a batch: its index, its grid inputs, and how it begins, or why it cannot.
type Start = (usize, Vec<f64>, Result<Begin, String>);

/// A run on the lanes of a batch: its main trajectory on lane `slot`, its
/// Lyapunov twin on lane `slot + LANES / 2`.
struct OnLanes {
    /// Its index in the job's `starts`.
    at: usize,
    /// Its initial state `[q, q']`.
    y0: Vec<f64>,
    /// The segment being integrated (from 1; see [`segment_end`]).
    segment: u32,
    log_sum: f64,
    twin_failure: Option<String>,
}

impl Plan<'_> {
    /// The runs of one job with the Taylor method in lock step
    /// ([`crate::run::ensemble`]), each in the same segments as [`Plan::run`]. A
    /// lane (with its twin's) takes the job's next run as soon as its run
    /// ends, so that no lane idles while runs remain. Gives up (None) when
    /// `halted()` turns true, which it looks at between rounds of the lanes.
    fn run_batch(
        &self,
        series: &mut LagrangeSeries<LANES>,
        sys: &mut System,
        scratch: &mut Vec<Lanes<LANES>>,
        n: usize,
        starts: Vec<Start>,
        halted: &dyn Fn() -> bool,
    ) -> Option<Vec<TableRow>> {
        let cfg = self.config;
        let slots = if cfg.lyapunov { LANES / 2 } else { LANES };
        let twin_of = |slot: usize| slot + LANES / 2;
        let mut pending = (0..starts.len()).filter(|&i| starts[i].2.is_ok());
        let mut outcomes: Vec<Option<RunOutcome>> = (0..starts.len()).map(|_| None).collect();
        let Some(first) = starts.iter().find_map(|s| s.2.as_ref().ok()) else {
            return Some(finish(starts, outcomes, n));
        };
        // Lanes left without a run keep the first run's state (finite, never read back).
        let mut batch = Batch::new(&[[first.0.as_slice(), &first.1].concat()]);
        let mut params: Vec<Lanes<LANES>> = first.2.iter().map(|&v| [v; LANES]).collect();
        let mut target = [cfg.until; LANES];
        let mut on: Vec<Option<OnLanes>> = (0..slots).map(|_| None).collect();
        // Puts the next pending run (if any) on the lanes of `slot`.
        let mut take = |slot: usize, batch: &mut Batch, params: &mut Vec<Lanes<LANES>>, target: &mut [f64; LANES]| {
            let lanes: Vec<usize> = if cfg.lyapunov { vec![slot, twin_of(slot)] } else { vec![slot] };
            let Some(at) = pending.next() else {
                for &l in &lanes {
                    batch.failure[l] = Some("unused lane".into());
                }
                return None;
            };
            let (q, qd, values) = starts[at].2.as_ref().expect("pending runs started");
            let y0 = [q.as_slice(), qd].concat();
            for (k, &v) in values.iter().enumerate() {
                for &l in &lanes {
                    params[k][l] = v;
                }
            }
            batch.set_state(slot, &y0);
            if cfg.lyapunov {
                batch.set_state(twin_of(slot), &perturbed(&y0));
            }
            for &l in &lanes {
                (batch.t[l], batch.steps[l], batch.failure[l], target[l]) = (0.0, 0, None, segment_end(1, cfg.until));
            }
            Some(OnLanes { at, y0, segment: 1, log_sum: 0.0, twin_failure: None })
        };
        for (slot, run) in on.iter_mut().enumerate() {
            *run = take(slot, &mut batch, &mut params, &mut target);
        }
        series.set_parameters(&params);
        let solver_config = Config { rtol: cfg.rtol, atol: cfg.atol, h_max: Some(cfg.until), ..Config::default() };
        while on.iter().any(Option::is_some) {
            if halted() {
                return None;
            }
            propagate(series, &mut batch, &target, &solver_config, scratch);
            let mut refilled = false;
            for slot in 0..slots {
                let Some(run) = on[slot].as_mut() else { continue };
                let twin = twin_of(slot);
                let at_end = |l: usize| batch.failure[l].is_some() || batch.t[l] >= target[l];
                // A main trajectory that failed ends its run at once; one that
                // reached its segment's end waits for its twin.
                if !at_end(slot) || (cfg.lyapunov && batch.failure[slot].is_none() && !at_end(twin)) {
                    continue;
                }
                let t_next = target[slot];
                if cfg.lyapunov && batch.failure[slot].is_none() && run.twin_failure.is_none() {
                    if let Some(e) = &batch.failure[twin] {
                        run.twin_failure = Some(format!("the perturbed twin failed: {e}"));
                    } else {
                        let (main, mut other) = (batch.state(slot), batch.state(twin));
                        match pull_back(&main, &mut other, t_next) {
                            Ok(growth) => {
                                run.log_sum += growth;
                                batch.set_state(twin, &other);
                            }
                            Err(message) => {
                                run.twin_failure = Some(message.clone());
                                batch.failure[twin] = Some(message);
                            }
                        }
                    }
                }
                if batch.failure[slot].is_none() && t_next < cfg.until {
                    run.segment += 1;
                    target[slot] = segment_end(run.segment, cfg.until);
                    if cfg.lyapunov {
                        target[twin] = target[slot];
                    }
                    continue;
                }
                let run = on[slot].take().expect("checked above");
                let at = run.at;
                let values = &starts[at].2.as_ref().expect("started").2;
                outcomes[at] = Some(self.outcome(sys, values, &batch, slot, run, n));
                on[slot] = take(slot, &mut batch, &mut params, &mut target);
                refilled |= on[slot].is_some();
            }
            if refilled {
                series.set_parameters(&params);
            }
        }
        Some(finish(starts, outcomes, n))
    }

    /// The outcome of the run that ended on lane `slot`.
    fn outcome(
        &self,
        sys: &mut System,
        values: &[f64],
        batch: &Batch,
        slot: usize,
        run: OnLanes,
        n: usize,
    ) -> RunOutcome {
        sys.set_parameters(values);
        let mut out = RunOutcome::ended(n, batch.t[slot], batch.failure[slot].clone());
        if out.failure.is_some() {
            return out;
        }
        let mut qd = vec![0.0; n];
        let mut inv = vec![0.0; sys.n_invariants()];
        let h0 = sys.invariants_at(0.0, &run.y0, &mut qd, &mut inv).ok().map(|()| inv[0]);
        self.conclude(&mut out, sys, self.config.until, &batch.state(slot), h0, (run.log_sum, run.twin_failure));
        out
    }
}

/// The rows of a job's runs, in order: those that could not start with their reason.
fn finish(starts: Vec<Start>, outcomes: Vec<Option<RunOutcome>>, n: usize) -> Vec<TableRow> {
    starts
        .into_iter()
        .zip(outcomes)
        .map(|((run, inputs, start), outcome)| {
            let outcome = match (start, outcome) {
                (Err(message), _) => Err(message),
                (Ok(_), Some(o)) => Ok(o),
                (Ok(_), None) => unreachable!("every started run has an outcome"),
            };
            row(run, inputs, n, outcome)
        })
        .collect()
}

/// The Lyapunov twin's integrator: one solver restarted every segment, or the
/// system to build a fresh one on.
enum Twin<'a> {
    Kept(Box<dyn Solver + 'a>),
    Fresh(&'a mut System),
}

/// `y0` moved by [`LYAPUNOV_D0`] along the unit vector with equal components.
fn perturbed(y0: &[f64]) -> Vec<f64> {
    let step = LYAPUNOV_D0 / (y0.len() as f64).sqrt();
    y0.iter().map(|v| v + step).collect()
}

/// The end of Lyapunov segment `segment` (counted from 1): a last sliver
/// shorter than a millionth of a segment joins the one before.
fn segment_end(segment: u32, until: f64) -> f64 {
    let t = f64::from(segment) * LYAPUNOV_INTERVAL;
    if t > until - 1e-6 * LYAPUNOV_INTERVAL {
        until
    } else {
        t
    }
}

/// Benettin's renormalization at the end of a segment at `t`: pulls `twin`
/// back to [`LYAPUNOV_D0`] from `main` along their difference and returns
/// `ln(d/d0)`, or why it cannot (the distance became zero or not finite).
fn pull_back(main: &[f64], twin: &mut [f64], t: f64) -> Result<f64, String> {
    let dist = distance(main, twin);
    if !(dist > 0.0 && dist.is_finite()) {
        return Err(format!("the perturbed twin's distance became {dist} at t = {t}", t = num::Shortest(t)));
    }
    for (tk, yk) in twin.iter_mut().zip(main) {
        *tk = yk + (*tk - yk) * (LYAPUNOV_D0 / dist);
    }
    Ok((dist / LYAPUNOV_D0).ln())
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// Joins the tables of a sweep's shards (`name`, table) into the table of the
/// whole sweep, rows sorted by run. Fails when the shards come from different
/// sweeps (columns or provenance differ), when a shard or a run appears twice,
/// or when runs are missing.
pub fn merge(shards: &[(String, SweepTable)]) -> Result<SweepTable, SweepError> {
    let Some((first_name, first)) = shards.first() else {
        return Err(SweepError::NothingToMerge);
    };
    let whole = |t: &SweepTable| -> Vec<(String, String)> {
        t.header.meta.iter().filter(|(k, _)| k != "shard").cloned().collect()
    };
    let meta = whole(first);
    let total = first.header.total_runs().ok_or_else(|| SweepError::Table {
        file: first_name.clone(),
        line: 1,
        reason: "the provenance line has no 'runs='".into(),
    })?;
    let shard_of = |name: &str, t: &SweepTable| -> Result<Shard, SweepError> {
        match t.header.meta("shard") {
            None => Ok(Shard::default()),
            Some(text) => Shard::parse(text).map_err(|_| SweepError::Table {
                file: name.to_string(),
                line: 1,
                reason: format!("'shard={text}' is not I/N"),
            }),
        }
    };
    let count = shard_of(first_name, first)?.count;
    let mut seen: BTreeMap<usize, &str> = BTreeMap::new();
    let mut rows: Vec<(usize, &str, &TableRow)> = Vec::new();
    for (name, table) in shards {
        let mismatch = |reason: String| SweepError::Mismatch { first: first_name.clone(), file: name.clone(), reason };
        if table.header.columns != first.header.columns {
            return Err(mismatch(format!(
                "its columns are {} instead of {}",
                table.header.columns.join(","),
                first.header.columns.join(",")
            )));
        }
        let other = whole(table);
        if other != meta {
            let keys: Vec<&String> = meta.iter().chain(&other).map(|(k, _)| k).collect();
            let value = |m: &[(String, String)], k: &str| m.iter().find(|(kk, _)| kk == k).map(|(_, v)| v.clone());
            let key = keys.into_iter().find(|k| value(&meta, k) != value(&other, k)).cloned().unwrap_or_default();
            return Err(mismatch(format!(
                "{key} is '{}' there and '{}' here",
                value(&meta, &key).unwrap_or_default(),
                value(&other, &key).unwrap_or_default()
            )));
        }
        let shard = shard_of(name, table)?;
        if shard.count != count {
            return Err(mismatch(format!("it is one of {} shards, not of {count}", shard.count)));
        }
        if let Some(previous) = seen.insert(shard.index, name) {
            return Err(SweepError::Mismatch {
                first: previous.to_string(),
                file: name.clone(),
                reason: format!("both are shard {shard}"),
            });
        }
        for (k, row) in table.rows.iter().enumerate() {
            if row.run >= total || row.run % shard.count != shard.index {
                return Err(SweepError::Table {
                    file: name.clone(),
                    line: k + 3,
                    reason: format!("run {} does not belong to shard {shard} of {total} runs", row.run),
                });
            }
            rows.push((row.run, name, row));
        }
    }
    rows.sort_by_key(|r| r.0);
    for pair in rows.windows(2) {
        if pair[0].0 == pair[1].0 {
            return Err(SweepError::DuplicateRun {
                run: pair[0].0,
                first: pair[0].1.to_string(),
                second: pair[1].1.to_string(),
            });
        }
    }
    if rows.len() != total {
        let present: Vec<usize> = rows.iter().map(|r| r.0).collect();
        let missing: Vec<usize> = (0..total).filter(|r| present.binary_search(r).is_err()).collect();
        let mut absent: Vec<String> =
            (0..count).filter(|i| !seen.contains_key(i)).map(|i| Shard { index: i, count }.to_string()).collect();
        if absent.is_empty() {
            absent.push("none (rows are missing from the shard files)".into());
        }
        return Err(SweepError::MissingRuns {
            count: missing.len(),
            total,
            first: missing.iter().take(5).copied().collect(),
            shards: absent.join(", "),
        });
    }
    let header = SweepHeader { meta, columns: first.header.columns.clone() };
    Ok(SweepTable { header, rows: rows.into_iter().map(|r| r.2.clone()).collect() })
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
        check_grid("", "error: the grid is empty; expected NAME=START:STOP:COUNT, comma separated");
        check_grid("a=0:1", "error: in the grid: 'a=0:1' is not NAME=START:STOP:COUNT");
        check_grid("a=0:1:2,", "error: in the grid: 'a=0:1:2,' is not NAME=START:STOP:COUNT");
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
