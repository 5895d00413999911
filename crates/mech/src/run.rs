//! A simulation run: choose the integrator the derivation calls for, integrate
//! from the model's initial state, hand every output row to the caller, and
//! audit the invariants along the way.
//!
//! Entry point: [`simulate`], the one driver of plain and constrained runs: it
//! checks the settings, builds the events (stop conditions, crossings, gimbal
//! guards) and the rows, audits them and writes the report, around a
//! [`Stepping`] that says what differs (`plain.rs`: the method and form the
//! derivation calls for; `constrained.rs`: the projection onto the constraints
//! and their columns). The caller (the CLI) does the IO — CSV, plots,
//! progress — in the `on_row` callback; this module only computes.
//!
//! The default method follows the derivation (issue #4): H conserved and
//! separable → an 8th-order symplectic composition; H conserved, not separable →
//! Gauss–Legendre (order 6) on Hamilton's equations; otherwise DOP853.

mod audit;
pub(crate) mod body;
mod budget;
pub(crate) mod constrained;
pub(crate) mod dynamics;
pub(crate) mod ensemble;
mod plain;
pub(crate) mod series;
pub(crate) mod tree;

use crate::clock::Instant;
use crate::derive::Derivation;
use crate::error::ModelError;
use audit::InvariantAudit;
pub use budget::{approx, BudgetAdvice, BudgetStage, StepBudget, TimeScale, STEPS_PER_TIME_SCALE};
use dynamics::{Dynamics, Form};
use num::{
    integrate, integrate_projected, Direction, Event, Method, ObservationKind, Output, RhsError, SolveError, Solver,
    StopReason,
};
use std::ops::ControlFlow;
use sym::Tape;

/// A condition that ends the run (or records a row) where an expression g(q,
/// q', t) crosses zero: `lhs < rhs` (falling through), `lhs > rhs` (rising),
/// `lhs = rhs` or `lhs` alone (either way).
#[derive(Debug, Clone)]
pub struct StopCondition {
    /// g = lhs − rhs, compiled over the derivation's [`Layout`](crate::Layout).
    tape: Tape,
    /// Which crossings count.
    pub direction: Direction,
    /// The condition as the user wrote it.
    pub text: String,
}

impl StopCondition {
    /// Reads a condition in the expression language. `what` names it in
    /// messages (`the stop condition`); the spans of errors are byte offsets
    /// into `text`.
    pub fn parse(d: &Derivation, text: &str, what: &str) -> Result<StopCondition, ModelError> {
        let (lhs, rhs, direction) = match text.find(['<', '>', '=']) {
            Some(i) => {
                let direction = match text.as_bytes()[i] {
                    b'<' => Direction::Falling,
                    b'>' => Direction::Rising,
                    _ => Direction::Both,
                };
                let rest = text[i + 1..].strip_prefix('=').unwrap_or(&text[i + 1..]).trim_start();
                (&text[..i], Some((text.len() - rest.len(), rest)), direction)
            }
            None => (text, None, Direction::Both),
        };
        let shift = |mut e: ModelError, offset: usize| {
            if let Some(span) = &mut e.span {
                *span = span.start + offset..span.end + offset;
            }
            e
        };
        // The derivation is frozen: the condition is read into a copy of the model.
        let mut model = d.model.clone();
        let g_lhs = model.parse_state_expr(lhs, what)?;
        let g = match rhs {
            Some((offset, rhs)) => {
                let g_rhs = model.parse_state_expr(rhs, what).map_err(|e| shift(e, offset))?;
                model.pool.sub(g_lhs, g_rhs)
            }
            None => g_lhs,
        };
        let tape = Tape::compile(&model.pool, &[g], d.layout.symbols())
            .map_err(|e| ModelError::at(0..text.len(), format!("{what} cannot be evaluated: {e}")))?;
        Ok(StopCondition { tape, direction, text: text.to_string() })
    }

    /// g at the inputs `values` (laid out as the derivation's [`Layout`](crate::Layout)).
    pub(crate) fn eval(&mut self, values: &[f64]) -> f64 {
        let mut out = [0.0];
        self.tape.eval(values, &mut out);
        out[0]
    }
}

/// Options of a run.
#[derive(Debug, Clone)]
pub struct RunConfig {
    /// End time (the run starts at t = 0).
    pub until: f64,
    /// The method, or None for the derivation's choice.
    pub method: Option<Method>,
    /// Relative tolerance (also sets the step of fixed-step methods without `dt`).
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Fixed step for fixed-step methods.
    pub dt: Option<f64>,
    /// Output rows: evenly spaced samples or every step.
    pub output: Output,
    /// Stop conditions.
    pub stop_when: Vec<StopCondition>,
    /// Crossings to record without stopping (the rows of a Poincaré section).
    pub crossings: Vec<StopCondition>,
    /// The most steps the run may take: its step budget.
    pub max_steps: usize,
    /// Values that replace `[initial]`'s, by name: a coordinate (`a`) or a
    /// velocity (`a'`). Empty: the model's initial state as it is.
    pub initial: Vec<(String, f64)>,
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            until: 10.0,
            method: None,
            // 1e-9: nine digits per unit time; far below plotting resolution and
            // cheap for the 8th-order methods that are the defaults.
            rtol: 1e-9,
            atol: 1e-12,
            dt: None,
            output: Output::Samples(1001),
            stop_when: Vec::new(),
            crossings: Vec::new(),
            // The solvers' default, 10^7: a long symplectic run fits, a stalled
            // adaptive one stops within seconds.
            max_steps: num::Config::default().max_steps,
            initial: Vec::new(),
        }
    }
}

/// Most output rows a run writes: as many as the steps a solver may take by
/// default (`num::Config::max_steps`); beyond that the file, not the motion, is the work.
pub const MAX_SAMPLES: usize = 10_000_000;

impl RunConfig {
    /// Checks what a run cannot start without, before anything is computed: a
    /// positive, finite end time; a fixed step, if given, that reaches it within
    /// the run's step budget and is no longer than the spacing of the
    /// samples; and no more samples than [`MAX_SAMPLES`].
    pub fn check(&self) -> Result<(), RunError> {
        if !is_positive_time(self.until) {
            return Err(RunError::Until { until: self.until });
        }
        if let Output::Samples(samples) = self.output {
            if samples > MAX_SAMPLES {
                return Err(RunError::TooManySamples { samples, max: MAX_SAMPLES });
            }
        }
        if self.max_steps == 0 {
            return Err(RunError::Input(ModelError::whole("a run needs a step budget of at least one step")));
        }
        if let Some(dt) = self.dt {
            let max = self.max_steps;
            let steps = self.until / dt;
            if !(dt.is_finite() && dt > 0.0) || steps > max as f64 {
                return Err(RunError::TooManySteps { dt, steps, max });
            }
            if let Output::Samples(k) = self.output {
                let spacing = self.until / (k.max(2) - 1) as f64;
                if dt > spacing * (1.0 + 1e-12) {
                    return Err(RunError::StepOverSamples { dt, spacing });
                }
            }
        }
        Ok(())
    }
}

/// Whether an end time is positive and finite (runs and sweeps start at t = 0).
pub(crate) fn is_positive_time(t: f64) -> bool {
    t.is_finite() && t > 0.0
}

/// One output row.
#[derive(Debug)]
pub struct Row<'a> {
    /// Time.
    pub t: f64,
    /// Coordinates.
    pub q: &'a [f64],
    /// Velocities.
    pub qd: &'a [f64],
    /// Invariants, in the order of [`RunReport::invariants`].
    pub invariants: &'a [f64],
    /// Whether this row is a stop event or a crossing.
    pub is_event: bool,
    /// The condition of a stop or crossing row, as the user wrote it.
    pub event: Option<&'a str>,
    /// With constraints: λ, |Aᵀλ| and the residuals, in the order of
    /// [`crate::constraint_columns`] (empty otherwise).
    pub constraints: &'a [f64],
}

/// The audit of one invariant.
#[derive(Debug, Clone)]
pub struct Audit {
    /// Its name (`H`, `E`, `p_th`).
    pub name: String,
    /// Whether the derivation says it is conserved.
    pub conserved: bool,
    /// Value at the start.
    pub initial: f64,
    /// Value at the last row.
    pub final_value: f64,
    /// Largest |I(t) − I(0)| over the rows.
    pub max_abs_drift: f64,
    /// Largest |I(t) − I(0)| / |I(0)| (or the absolute drift where I(0) = 0).
    pub max_rel_drift: f64,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// The method used.
    pub method: Method,
    /// The state variables integrated.
    pub form: Form,
    /// How the accelerations were computed: `"articulated-body"` (the model's
    /// tree, O(n), [`dynamics`]) or `"mass-matrix"` (M and f, solved).
    pub right_hand_side: &'static str,
    /// The fixed step used, for fixed-step methods.
    pub dt: Option<f64>,
    /// Whether that step was given (`RunConfig::dt`) rather than chosen from the tolerance.
    pub step_given: bool,
    /// Tolerances.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Right-hand-side evaluations of the Taylor method's look-ahead.
    pub look_ahead_evaluations: usize,
    /// Time reached.
    pub t_final: f64,
    /// Coordinates at the end.
    pub final_q: Vec<f64>,
    /// Velocities at the end.
    pub final_qd: Vec<f64>,
    /// Invariant audits.
    pub invariants: Vec<Audit>,
    /// Why the run ended (`finished`, or the stop condition's text).
    pub stopped_by: Option<String>,
    /// Warnings (an invariant drifting beyond what the tolerance explains).
    pub warnings: Vec<String>,
    /// Why the run failed midway, if it did.
    pub failure: Option<String>,
    /// The same as data: what failed, when and where.
    pub failure_reason: Option<RunFailure>,
    /// Right-hand-side evaluations of the pilot runs that chose a fixed step.
    pub pilot_rhs_evaluations: usize,
    /// Wall-clock seconds of the integration (compilation included).
    pub wall_seconds: f64,
    /// With constraints: the audit of each constraint (empty otherwise).
    pub constraints: Vec<constrained::ConstraintAudit>,
}

/// Why a run failed midway, as data beside the message: what happened, at
/// which time, to which component (`x`, `x'` or `p_x`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum RunFailure {
    /// A rigid body reached the gimbal singularity of its Euler angles.
    Gimbal {
        /// The body.
        body: String,
        /// When.
        t: f64,
    },
    /// A component of the state grew without bound or stopped being finite.
    BlowUp {
        /// When.
        t: f64,
        /// Which component.
        component: String,
    },
    /// The equations gave a non-finite rate of change.
    NonFiniteRate {
        /// When.
        t: f64,
        /// Of which component.
        component: String,
    },
    /// The mass matrix (with constraints: the system with the multipliers)
    /// became singular: the accelerations are undetermined.
    Singular {
        /// When.
        t: f64,
    },
    /// The integrator could not take a step (too small, or implicit stages that
    /// do not converge) for no reason that could be told.
    Step {
        /// The last time reached.
        t: f64,
    },
    /// A row could not be evaluated (an invariant, a constraint column).
    Row {
        /// When.
        t: f64,
    },
    /// The run could not reach its end time within its step budget: it spent
    /// the budget, or its pace was foreseen far beyond it.
    StepBudget(StepBudget),
}

impl RunFailure {
    /// The failure's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            RunFailure::Gimbal { .. } => "gimbal",
            RunFailure::BlowUp { .. } => "blow_up",
            RunFailure::NonFiniteRate { .. } => "non_finite_rate",
            RunFailure::Singular { .. } => "singular",
            RunFailure::Step { .. } => "step",
            RunFailure::Row { .. } => "row",
            RunFailure::StepBudget(_) => "step_budget",
        }
    }
}

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The end time is not a positive, finite number.
    #[error("the end time must be positive and finite, not {}", num::Shortest(*.until))]
    Until {
        /// The end time asked for.
        until: f64,
    },
    /// More output samples than [`MAX_SAMPLES`].
    #[error("{samples} samples are more than a run writes ({max} at most)")]
    TooManySamples {
        /// The samples asked for.
        samples: usize,
        /// [`MAX_SAMPLES`].
        max: usize,
    },
    /// A fixed step that would take more steps than a solver may to reach the end.
    #[error("the step {dt} would take {steps:.3e} steps; a run takes at most {max}")]
    TooManySteps {
        /// The step.
        dt: f64,
        /// The steps it would take.
        steps: f64,
        /// The solvers' budget.
        max: usize,
    },
    /// A fixed step longer than the spacing of the samples, which would be
    /// shortened to that spacing rather than taken as given.
    #[error("the step {dt} is longer than the spacing of the samples ({spacing})")]
    StepOverSamples {
        /// The step.
        dt: f64,
        /// The spacing of the samples.
        spacing: f64,
    },
    /// A fixed step, chosen from the tolerance, that would take more steps than
    /// the run's budget to reach the end time (refused before the run).
    #[error("{0}")]
    StepBudget(Box<StepBudget>),
    /// A fixed step given for an adaptive method, which chooses its own.
    #[error("a fixed step applies only to fixed-step methods, and {} chooses its own", .method.name())]
    StepNotApplicable {
        /// The method.
        method: Method,
    },
    /// Bad input: an impossible method, a missing initial value (exit 2).
    #[error("{0}")]
    Input(ModelError),
    /// The run failed midway (exit 1); the report covers what was done.
    #[error("{message}")]
    Failed {
        /// What happened, naming the time and the coordinate.
        message: String,
        /// The run up to the failure.
        report: Box<RunReport>,
    },
}

/// The end of a run that integrated to its end or stopped: why it stopped (a
/// stop condition, the caller, or the end), and a failure when a row could
/// not be produced.
pub(crate) fn conclude(
    mut report: RunReport,
    stop: StopReason,
    conditions: &[(&StopCondition, bool)],
    row_error: Option<(RunFailure, String)>,
) -> Result<RunReport, RunError> {
    report.stopped_by = match stop {
        StopReason::Event { index } => Some(conditions[index].0.text.clone()),
        StopReason::Observer => {
            Some(row_error.as_ref().map_or_else(|| "stopped by the caller".into(), |(_, m)| m.clone()))
        }
        StopReason::Finished => None,
    };
    match row_error {
        Some((reason, message)) => Err(failed(report, reason, message)),
        None => Ok(report),
    }
}

/// The error of a run that failed midway, its report saying why in words and as data.
fn failed(mut report: RunReport, reason: RunFailure, message: String) -> RunError {
    report.failure = Some(message.clone());
    report.failure_reason = Some(reason);
    RunError::Failed { message, report: Box::new(report) }
}

/// The default method and the form it integrates, or the form a requested method needs.
///
/// The default (no `requested` method) is the adaptive Taylor method when the
/// equations are analytic: it bounds every step's error like DOP853, takes no
/// rejected steps, and at the tolerances people ask for it is the fastest of
/// our methods and drifts least in H on every bench system (the guide's
/// methods and performance chapters give the measurements). A kink in the
/// equations (`abs`) is invisible to a Taylor series, so there DOP853, whose
/// error estimate sees it. A fixed step (`fixed_step`: `--dt` without a
/// method) asks for a fixed-step method: the 8th-order composition when H is
/// separable and conserved, Gauss–Legendre otherwise. Models with constraints
/// choose in [`constrained`].
pub fn choose_method(
    d: &Derivation,
    dynamics: &Dynamics,
    requested: Option<Method>,
    fixed_step: bool,
) -> Result<(Method, Form), ModelError> {
    let conserved = d.hamiltonian_conserved;
    Ok(match requested {
        None if fixed_step && conserved && dynamics.is_separable() => (Method::KahanLi8, Form::Separable),
        None if fixed_step && dynamics.has_hamilton_form() => (Method::Gauss6, Form::Hamilton),
        None if fixed_step => (Method::Gauss6, Form::Lagrange),
        None if dynamics.is_analytic() && taylor_pays(d, dynamics) => (Method::Taylor, Form::Lagrange),
        None => (Method::Dop853, Form::Lagrange),
        Some(m) if m.needs_separable() => {
            if !dynamics.is_separable() {
                return Err(ModelError::whole(format!(
                    "method '{}' needs a separable Hamiltonian H = T(p) + V(q, t) with a constant mass matrix, and this model's is not",
                    m.name()
                ))
                .with_help("use gauss4 or gauss6 (symplectic for any H), or dop853"));
            }
            (m, Form::Separable)
        }
        Some(m @ (Method::Gauss2 | Method::Gauss4 | Method::Gauss6)) if dynamics.has_hamilton_form() => {
            (m, Form::Hamilton)
        }
        Some(m) => (m, Form::Lagrange),
    })
}

/// Most coordinates for which the Taylor method is the default, unless M is
/// constant. A Taylor step's work grows with the square of its order times
/// the right-hand side's, with every sine and cosine carried as a series: whole
/// `simulate --until 10` runs (release build, one machine, 2026-11-28) took
/// 0.18 s with DOP853 against 0.49 s with Taylor for a chain of 10 rods,
/// 0.35 against 1.48 s for the UR5 arm (6 joints), 0.92 against 9.6 s for the
/// Panda; at 5 coordinates the two were even (0.08 s each for 5 rods at
/// t = 100), and below it Taylor is the faster (the performance chapter).
const TAYLOR_MAX_COORDINATES: usize = 4;

/// Whether the Taylor method is the faster default for this model: few
/// coordinates, or a constant mass matrix (a chain of springs, whose series are
/// short polynomials however many coordinates it has).
fn taylor_pays(d: &Derivation, dynamics: &Dynamics) -> bool {
    d.q.len() <= TAYLOR_MAX_COORDINATES || dynamics.is_separable()
}

/// The solver of a run at its initial state, and how it was chosen.
pub(crate) struct Start {
    pub(crate) solver: Box<dyn Solver>,
    /// The initial state in the solver's variables.
    pub(crate) y0: Vec<f64>,
    /// The initial coordinates and velocities, as the run reports them when it ends before its first row.
    pub(crate) initial: (Vec<f64>, Vec<f64>),
    pub(crate) method: Method,
    pub(crate) form: Form,
    /// The fixed step, for fixed-step methods.
    pub(crate) dt: Option<f64>,
    pub(crate) pilot_rhs_evaluations: usize,
}

/// q' of a solver state (t, y), for the stop conditions.
pub(crate) type VelocityMap = Box<dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>>;

/// A map of the state after every step (the projection onto constraints).
pub(crate) type ProjectionMap = Box<dyn FnMut(f64, &mut [f64]) -> Result<(), RhsError>>;

/// One row in the making: the stepping fills q, q', the invariants and the
/// constraint columns of a solver state.
pub(crate) struct RowBuffer {
    pub(crate) q: Vec<f64>,
    pub(crate) qd: Vec<f64>,
    pub(crate) invariants: Vec<f64>,
    pub(crate) constraints: Vec<f64>,
    /// Whether the row is a stop event or a crossing.
    pub(crate) is_event: bool,
}

/// What differs between runs of a plain model and of one with constraints;
/// [`simulate`] does the rest (validation, events, rows, audit, report) once.
pub(crate) trait Stepping {
    /// A map from solver states to velocities, one per stop condition.
    fn velocity_map(&self) -> VelocityMap;
    /// The map applied after every step, if any.
    fn projection(&self) -> Option<ProjectionMap> {
        None
    }
    /// Fills `row` (all but `is_event`) from the solver state (t, y).
    fn row(&mut self, t: f64, y: &[f64], row: &mut RowBuffer) -> Result<(), RhsError>;
    /// Adds the stepping's own audits at the end of the run.
    fn audits(&mut self, _invariants: &mut Vec<Audit>, _constraints: &mut Vec<constrained::ConstraintAudit>) {}
    /// Adds the stepping's own warnings at the end of the run.
    fn warnings(&self, _warnings: &mut Vec<String>) {}
    /// A solver failure in the user's terms, from the initial state and the last good one.
    fn describe(&mut self, e: &SolveError, y0: &[f64], at: (f64, Vec<f64>)) -> (RunFailure, String);
    /// The motion's fastest time scale at the solver state (t, y), if it can be told.
    fn time_scale(&mut self, t: f64, y: &[f64]) -> Option<TimeScale>;
}

/// Runs a simulation, with or without constraints. `on_row` receives every
/// output row in time order and may stop the run with `ControlFlow::Break`.
pub fn simulate(
    d: &Derivation,
    config: &RunConfig,
    on_row: impl FnMut(&Row<'_>) -> ControlFlow<()>,
) -> Result<RunReport, RunError> {
    let start = Instant::now();
    config.check()?;
    d.model.check_inputs_applied().map_err(RunError::Input)?;
    let (mut q0, mut qd0) = d.model.initial_state().map_err(RunError::Input)?;
    override_initial(d, &config.initial, &mut q0, &mut qd0)?;
    d.model.check_values(Some((&q0, &qd0))).map_err(RunError::Input)?;
    d.check_constraints_at(&q0, &qd0).map_err(RunError::Input)?;
    // Rigid bodies: a terminal event before the Euler angles' gimbal singularity.
    let guards = body::gimbal_guards(d, config.rtol);
    if let Some(g) = guards.iter().find(|g| g.violated(&q0)) {
        let span =
            d.model.initial.iter().find(|iv| iv.coord == g.beta && iv.order == 0).map(|iv| iv.value.span.clone());
        let e = ModelError {
            message: format!(
                "the initial state is at the gimbal singularity of body '{}': |sin {}| < {:.1e}",
                g.body, g.beta_name, g.threshold
            ),
            span,
            help: Some(g.advice()),
            setting: None,
            within: None,
        };
        return Err(RunError::Input(e));
    }
    let dynamics = Dynamics::new(d);
    if d.constraints.is_empty() {
        let (stepping, begin) = plain::Plain::start(d, &dynamics, config, &q0, &qd0)?;
        drive(d, config, &dynamics, stepping, begin, &guards, start, on_row)
    } else {
        let (stepping, begin) = constrained::Constrained::start(d, &dynamics, config, &q0, &qd0)?;
        drive(d, config, &dynamics, stepping, begin, &guards, start, on_row)
    }
}

/// The names of a run's values, in the order of its CSV file: `t`, the
/// coordinates, the velocities (`q'`), the invariants audited along the run,
/// the rigid bodies' ω and L ([`body::BodyRecorder`]), and the constraints'
/// columns ([`crate::constraint_columns`]).
pub fn row_columns(d: &Derivation) -> Vec<String> {
    let names = d.coordinate_names();
    let mut cols = vec!["t".to_string()];
    cols.extend(names.iter().map(|c| c.to_string()));
    cols.extend(names.iter().map(|c| format!("{c}'")));
    cols.extend(dynamics::invariants_of(d).into_iter().map(|i| i.name));
    cols.extend(body::column_names(&d.bodies));
    cols.extend(constrained::constraint_columns(d));
    cols
}

/// Replaces values of the initial state by the caller's (`RunConfig::initial`).
fn override_initial(d: &Derivation, given: &[(String, f64)], q: &mut [f64], qd: &mut [f64]) -> Result<(), RunError> {
    for (name, value) in given {
        let base = name.strip_suffix('\'').unwrap_or(name);
        let Some(k) = d.model.coordinates.iter().position(|c| c.name == base) else {
            let setting = crate::Setting::Start { name: name.clone() };
            let known = d.coordinate_names().join(", ");
            let message = format!("'{base}' is not a coordinate of the model (coordinates: {known})");
            return Err(RunError::Input(ModelError::setting(setting, message)));
        };
        if !value.is_finite() {
            let setting = crate::Setting::Start { name: name.clone() };
            return Err(RunError::Input(ModelError::setting(
                setting,
                format!("the initial value must be finite, not {value}"),
            )));
        }
        if base.len() == name.len() {
            q[k] = *value;
        } else {
            qd[k] = *value;
        }
    }
    Ok(())
}

/// The one run driver: events, rows, audit and report around a [`Stepping`].
#[allow(clippy::too_many_arguments)]
fn drive(
    d: &Derivation,
    config: &RunConfig,
    dynamics: &Dynamics,
    mut stepping: impl Stepping,
    begin: Start,
    guards: &[body::GimbalGuard],
    started: Instant,
    mut on_row: impl FnMut(&Row<'_>) -> ControlFlow<()>,
) -> Result<RunReport, RunError> {
    let Start { mut solver, y0, initial, method, form, dt, pilot_rhs_evaluations } = begin;
    let n = d.q.len();
    let layout = &d.layout;
    let mut invariant_audit = InvariantAudit::new(d, dynamics);

    // Stop conditions first (terminal), then crossings (recorded, not stopping),
    // then one guard per body.
    let conditions: Vec<(&StopCondition, bool)> =
        config.stop_when.iter().map(|c| (c, true)).chain(config.crossings.iter().map(|c| (c, false))).collect();
    let first_guard = conditions.len();
    let mut events: Vec<Event<'_>> = Vec::new();
    for &(cond, terminal) in &conditions {
        let mut velocities = stepping.velocity_map();
        let direction = cond.direction;
        let mut cond = cond.clone();
        let mut values = layout.values();
        let mut qd = vec![0.0; n];
        events.push(
            Event::new(move |t, y| {
                if velocities(t, y, &mut qd).is_err() {
                    return f64::NAN;
                }
                layout.set_state(&mut values, t, &y[..n], &qd);
                cond.eval(&values)
            })
            .with_direction(direction)
            .with_terminal(terminal),
        );
    }
    events.extend(body::guard_events(guards));

    // The rows and their audit.
    let mut row = RowBuffer {
        q: vec![0.0; n],
        qd: vec![0.0; n],
        invariants: vec![0.0; invariant_audit.len()],
        constraints: vec![0.0; constrained::constraint_columns(d).len()],
        is_event: false,
    };
    let projection = stepping.projection();
    let mut last = (0.0, initial.0, initial.1);
    let mut row_error: Option<(RunFailure, String)> = None;
    let observer = |obs: &num::Observation<'_>| {
        row.is_event = matches!(obs.kind, ObservationKind::Event { .. });
        if let Err(e) = stepping.row(obs.t, obs.y, &mut row) {
            row_error = Some((RunFailure::Row { t: obs.t }, format!("at t = {}: {e}", obs.t)));
            return ControlFlow::Break(());
        }
        invariant_audit.observe(&row.invariants);
        last.0 = obs.t;
        last.1.copy_from_slice(&row.q);
        last.2.copy_from_slice(&row.qd);
        let flow = on_row(&Row {
            t: obs.t,
            q: &row.q,
            qd: &row.qd,
            invariants: &row.invariants,
            is_event: row.is_event,
            event: match obs.kind {
                ObservationKind::Event { index } if index < first_guard => Some(conditions[index].0.text.as_str()),
                _ => None,
            },
            constraints: &row.constraints,
        });
        // The row is kept; past a gimbal guard the run ends as a failure.
        if let Some(g) = guards.iter().find(|g| g.violated(&row.q)) {
            row_error = Some((g.failure(obs.t), g.message(obs.t)));
            return ControlFlow::Break(());
        }
        flow
    };
    let result = match projection {
        Some(mut project) => {
            integrate_projected(&mut solver, config.until, config.output, &mut events, &mut project, observer)
        }
        None => integrate(&mut solver, config.until, config.output, &mut events, observer),
    };
    drop(events);
    // A run that failed ends where its solver stands: the summary's final state
    // is the last one reached, audited like a row, not the last row written.
    if result.is_err() && solver.t() > last.0 {
        let y = solver.state();
        row.is_event = false;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if stepping.row(solver.t(), y, &mut row).is_ok() && finite(&row.q) && finite(&row.qd) {
            invariant_audit.observe(&row.invariants);
            last.0 = solver.t();
            last.1.copy_from_slice(&row.q);
            last.2.copy_from_slice(&row.qd);
        }
    }

    let stats = solver.statistics();
    let mut audits = invariant_audit.audits();
    let mut constraint_audits = Vec::new();
    stepping.audits(&mut audits, &mut constraint_audits);
    // What the method's tolerance explains: a few hundred local errors of size
    // rtol (fixed-step methods had their step chosen from rtol as well).
    let explained = if config.dt.is_some() { 1e-2 } else { (1e3 * config.rtol).max(1e-12) };
    let mut warnings = audit::drift_warnings(&audits, explained);
    stepping.warnings(&mut warnings);
    if method == Method::Taylor && !dynamics.is_analytic() {
        warnings.push(
            "the equations contain abs(), whose kink a Taylor series does not see: a step across it is not error-controlled (dop853 is the default for such models)"
                .into(),
        );
    }
    warnings.extend(solver.subdivisions().map(|s| s.to_string()));
    let (t_last, final_q, final_qd) = last;
    let articulated = form == Form::Lagrange && method != Method::Taylor && dynamics.uses_articulated_body();
    let mut report = RunReport {
        method,
        form,
        right_hand_side: if articulated { "articulated-body" } else { "mass-matrix" },
        dt,
        step_given: config.dt.is_some(),
        rtol: config.rtol,
        atol: config.atol,
        steps: stats.steps,
        rejected: stats.rejected,
        rhs_evaluations: stats.rhs_evaluations,
        look_ahead_evaluations: stats.look_ahead_evaluations,
        t_final: t_last,
        final_q,
        final_qd,
        invariants: audits,
        stopped_by: None,
        warnings,
        failure: None,
        failure_reason: None,
        pilot_rhs_evaluations,
        wall_seconds: started.elapsed().as_secs_f64(),
        constraints: constraint_audits,
    };
    match result {
        Ok(summary) => {
            report.t_final = summary.t;
            if let StopReason::Event { index } = summary.stop {
                if index >= first_guard {
                    let g = &guards[(index - first_guard) / 2];
                    return Err(failed(report, g.failure(summary.t), g.message(summary.t)));
                }
            }
            conclude(report, summary.stop, &conditions, row_error)
        }
        Err(e) => {
            let at = (solver.t(), solver.state().to_vec());
            let time_scale = || stepping.time_scale(at.0, &at.1);
            if let Some(budget) = StepBudget::ran_out(&e, &*solver, config.until, time_scale) {
                let message = budget.to_string();
                return Err(failed(report, RunFailure::StepBudget(budget), message));
            }
            // A body near its gimbal singularity: say so rather than only "singular".
            let near = guards.iter().min_by(|a, b| at.1[a.beta].sin().abs().total_cmp(&at.1[b.beta].sin().abs()));
            let (reason, message) = match near.filter(|g| at.1[g.beta].sin().abs() < 0.1) {
                Some(g) => (g.failure(at.0), format!("{} ({e})", g.message(at.0))),
                None => stepping.describe(&e, &y0, at),
            };
            Err(failed(report, reason, message))
        }
    }
}
