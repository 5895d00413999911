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
//! The parts of a run beside the driver: `config.rs` (the settings and stop
//! conditions, checked before the run), `report.rs` (rows, audits, the report
//! and the errors a run hands back).
//!
//! The default method follows the derivation (issue #4): H conserved and
//! separable → an 8th-order symplectic composition; H conserved, not separable →
//! Gauss–Legendre (order 6) on Hamilton's equations; otherwise DOP853.

mod audit;
pub(crate) mod body;
mod budget;
mod config;
pub(crate) mod constrained;
pub(crate) mod dynamics;
pub(crate) mod ensemble;
mod impacts;
pub(crate) mod jacobian;
mod plain;
mod report;
pub(crate) mod series;
pub(crate) mod tree;

use crate::clock::Instant;
use crate::derive::Derivation;
use crate::error::{ModelError, ModelErrorKind};
use audit::InvariantAudit;
pub use budget::{approx, BudgetAdvice, BudgetStage, StepBudget, TimeScale, STEPS_PER_TIME_SCALE};
pub(crate) use config::is_positive_time;
pub use config::{RunConfig, RunSettings, SettingError, StopCondition, MAX_SAMPLES};
use dynamics::{Dynamics, Form};

use num::{
    integrate, integrate_projected, integrate_resumed, Event, Method, ObservationKind, Resume, RhsError, SolveError,
    Solver, StopReason, Summary,
};
pub use report::{Audit, ConstraintAudit, ImpactTally, Row, RunError, RunFailure, RunReport, RunWarning};
use std::cell::{Cell, RefCell};
use std::ops::ControlFlow;

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
    /// A solver of the same method and step started afresh at (t, q, q'),
    /// after an impact; None where impacts are not supported (constraints).
    pub(crate) restart: Option<Restart>,
}

/// Builds a run's solver afresh at (t, q, q'); the error is a sentence.
pub(crate) type Restart = Box<dyn FnMut(f64, &[f64], &[f64]) -> Result<Box<dyn Solver>, String>>;

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
    fn audits(&mut self, _invariants: &mut Vec<Audit>, _constraints: &mut Vec<ConstraintAudit>) {}
    /// Adds the stepping's own warnings at the end of the run.
    fn warnings(&self, _warnings: &mut Vec<RunWarning>) {}
    /// A solver failure in the user's terms, from the initial state and the last good one.
    fn describe(&mut self, e: &SolveError, y0: &[f64], at: (f64, Vec<f64>)) -> (RunFailure, String);
    /// The motion's fastest time scale at the solver state (t, y), if it can be told.
    fn time_scale(&mut self, t: f64, y: &[f64]) -> Option<TimeScale>;
}

/// Runs a simulation, with or without constraints. `on_row` receives every
/// output row in time order and may stop the run with `ControlFlow::Break`,
/// which declines that row: the report's final state (`t_final`, `final_q`,
/// `final_qd`) and its audit end at the last row `on_row` took.
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
        let e = ModelError::located(
            span,
            format!(
                "the initial state is at the gimbal singularity of body '{}': |sin {}| < {:.1e}",
                g.body, g.beta_name, g.threshold
            ),
        )
        .with_help(g.advice())
        .with_kind(ModelErrorKind::Start);
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
    let Start { mut solver, y0, initial, method, form, dt, pilot_rhs_evaluations, restart } = begin;
    let n = d.q.len();
    let layout = &d.layout;
    let mut invariant_audit = InvariantAudit::new(d, dynamics);

    // Stop conditions first (terminal), then crossings (recorded, not stopping),
    // then the impact surfaces (terminal), then one guard per body.
    let conditions: Vec<(&StopCondition, bool)> =
        config.stop_when.iter().map(|c| (c, true)).chain(config.crossings.iter().map(|c| (c, false))).collect();
    let first_impact = conditions.len();
    let mut impacts = impacts::Impacts::new(d, dynamics).map_err(RunError::Input)?;
    let first_guard = first_impact + impacts.as_ref().map_or(0, |i| i.len());
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
    if let Some(i) = &impacts {
        events.extend(i.events(d));
    }
    events.extend(body::guard_events(guards));
    let impact_labels: Vec<[String; 2]> = impacts.as_ref().map_or_else(Vec::new, |i| i.labels.clone());
    let impact_names: Vec<String> = impacts.as_ref().map_or_else(Vec::new, |i| i.names.clone());
    // The surfaces the start rests on, to tell a resting contact from a missed bounce.
    let resting_at_start: Vec<bool> = match impacts.as_mut() {
        Some(i) => i.resting(0.0, &initial.0, &initial.1, layout),
        None => Vec::new(),
    };
    let impacts = impacts.map(RefCell::new);
    // Set while the row after an impact is handed over: that impact's index.
    let after_impact: Cell<Option<usize>> = Cell::new(None);
    // The state at the impact an event stopped at.
    let struck_at: RefCell<Option<impacts::StateAt>> = RefCell::new(None);

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
    let mut observer = |obs: &num::Observation<'_>| {
        row.is_event = matches!(obs.kind, ObservationKind::Event { .. });
        if let Err(e) = stepping.row(obs.t, obs.y, &mut row) {
            row_error = Some((RunFailure::Row { t: obs.t }, format!("at t = {}: {e}", obs.t)));
            return ControlFlow::Break(());
        }
        let event = match obs.kind {
            ObservationKind::Event { index } if index < first_impact => Some(conditions[index].0.text.as_str()),
            ObservationKind::Event { index } if index < first_guard => {
                let k = index - first_impact;
                let after = after_impact.get() == Some(k);
                if after {
                    // The audit follows the invariants across the jump.
                    if let Some(before) = struck_at.borrow().as_ref() {
                        invariant_audit.jump(&before.invariants, &row.invariants);
                    }
                } else {
                    *struck_at.borrow_mut() = Some(impacts::StateAt {
                        t: obs.t,
                        q: row.q.clone(),
                        qd: row.qd.clone(),
                        invariants: row.invariants.clone(),
                    });
                }
                Some(impact_labels[k][usize::from(after)].as_str())
            }
            _ => None,
        };
        if let Some(i) = &impacts {
            let crossed = i.borrow_mut().crossed(obs.t, &row.q, &row.qd, layout);
            if let Some((k, phi)) = crossed {
                let name = &impact_names[k];
                let never_struck = i.borrow().tallies[k].count == 0;
                let message = if resting_at_start[k] && never_struck {
                    format!(
                        "the motion starts resting on the surface of impact '{name}' (in contact, not moving off it) and is pressed through it (it is {} at t = {}): resting contact is not modelled, only impacts; start above the surface or moving off it",
                        num::Shortest(phi),
                        num::Shortest(obs.t)
                    )
                } else {
                    format!(
                        "the surface of impact '{name}' is crossed at t = {} (it is {} there) without an impact found: two crossings within one probe of the events; more output samples or a tighter tolerance find them",
                        num::Shortest(obs.t),
                        num::Shortest(phi)
                    )
                };
                row_error = Some((RunFailure::SurfaceCrossed { t: obs.t, impact: name.to_string() }, message));
                return ControlFlow::Break(());
            }
        }
        let flow = on_row(&Row {
            t: obs.t,
            q: &row.q,
            qd: &row.qd,
            invariants: &row.invariants,
            is_event: row.is_event,
            event,
            constraints: &row.constraints,
            jumps: if first_guard > first_impact { invariant_audit.jumps() } else { &[] },
        });
        if flow.is_break() {
            // Not taken: the run ends at the row before, which the summary reports.
            return flow;
        }
        invariant_audit.observe(&row.invariants);
        last.0 = obs.t;
        last.1.copy_from_slice(&row.q);
        last.2.copy_from_slice(&row.qd);
        // The row is kept; past a gimbal guard the run ends as a failure.
        if let Some(g) = guards.iter().find(|g| g.violated(&row.q)) {
            row_error = Some((g.failure(obs.t), g.message(obs.t)));
            return ControlFlow::Break(());
        }
        flow
    };
    // The run, in parts between impacts: each impact stops a part; its jump
    // starts the next from a fresh solver at the state after it.
    let mut projection = projection;
    let mut resume: Option<Resume> = None;
    let mut spent = num::Statistics::default();
    let mut impact_error: Option<(RunFailure, String)> = None;
    let mut restart = restart;
    let result = loop {
        let part = match (projection.as_mut(), resume) {
            (Some(project), _) => {
                integrate_projected(&mut solver, config.until, config.output, &mut events, project, &mut observer)
            }
            (None, Some(resume)) => {
                integrate_resumed(&mut solver, config.until, config.output, resume, &mut events, &mut observer)
            }
            (None, None) => integrate(&mut solver, config.until, config.output, &mut events, &mut observer),
        };
        let (summary, k) = match part {
            Ok(summary @ Summary { stop: StopReason::Event { index }, .. })
                if (first_impact..first_guard).contains(&index) =>
            {
                (summary, index - first_impact)
            }
            other => break other,
        };
        // (The stepping of constrained models cannot restart; the model refuses impacts with constraints.)
        let (Some(impacts), Some(restart), Some(at)) = (&impacts, restart.as_mut(), struck_at.borrow().clone()) else {
            let t = summary.t;
            impact_error = Some((RunFailure::Step { t }, format!("the run cannot go on after the impact at t = {t}")));
            break Ok(Summary { stop: StopReason::Observer, ..summary });
        };
        let impacts::StateAt { t, mut q, mut qd, .. } = at;
        let struck = impacts.borrow_mut().strike(k, t, &mut q, &mut qd, layout);
        let struck = match struck {
            Ok(struck) => struck,
            Err(failure) => {
                impact_error = Some(failure);
                break Ok(Summary { stop: StopReason::Observer, ..summary });
            }
        };
        add_statistics(&mut spent, &solver.statistics());
        solver = match restart(t, &q, &qd) {
            Ok(fresh) => fresh,
            Err(why) => {
                impact_error =
                    Some((RunFailure::Step { t }, format!("the run cannot go on after the impact at t = {t}: {why}")));
                break Ok(Summary { stop: StopReason::Observer, ..summary });
            }
        };
        // The row after: labelled with the last surface struck.
        let last_struck = struck.surfaces.last().copied().unwrap_or(k);
        after_impact.set(Some(last_struck));
        let y_after = solver.state().to_vec();
        let flow = observer(&num::Observation {
            t,
            y: &y_after,
            kind: ObservationKind::Event { index: first_impact + last_struck },
        });
        after_impact.set(None);
        if flow.is_break() {
            break Ok(Summary { stop: StopReason::Observer, ..summary });
        }
        if let Some(ends) = struck.ends {
            impact_error = Some(ends);
            break Ok(Summary { stop: StopReason::Observer, ..summary });
        }
        resume = Some(Resume { t0: 0.0, next_sample: summary.next_sample });
    };
    drop(events);
    let row_error = row_error.or(impact_error);
    let tallies = impacts.map(|i| i.into_inner().tallies).unwrap_or_default();
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

    let mut stats = solver.statistics();
    add_statistics(&mut stats, &spent);
    let mut audits = invariant_audit.audits();
    let mut constraint_audits = Vec::new();
    stepping.audits(&mut audits, &mut constraint_audits);
    // What the method's tolerance explains: a few hundred local errors of size
    // rtol (fixed-step methods had their step chosen from rtol as well).
    let explained = if config.dt.is_some() { 1e-2 } else { (1e3 * config.rtol).max(1e-12) };
    let mut warnings = audit::drift_warnings(&audits, explained);
    stepping.warnings(&mut warnings);
    if method == Method::Taylor && !dynamics.is_analytic() {
        warnings.push(RunWarning::TaylorAcrossKink);
    }
    warnings.extend(solver.subdivisions().map(RunWarning::Subdivided));
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
        impacts: tallies,
    };
    match result {
        Ok(summary) => {
            if summary.stop != StopReason::Observer {
                report.t_final = summary.t;
            }
            if let StopReason::Event { index } = summary.stop {
                if index >= first_guard {
                    let g = &guards[(index - first_guard) / 2];
                    return Err(failed(report, g.failure(summary.t), g.message(summary.t)));
                }
            }
            conclude(report, summary.stop, &conditions, row_error)
        }
        Err(SolveError::EventNonFinite { event, t }) => {
            // Name the condition and the state, not "event function k".
            let (condition, what) = if event < first_impact {
                let text = conditions[event].0.text.clone();
                (text.clone(), format!("the condition `{text}`"))
            } else if event < first_guard {
                let name = impact_names[event - first_impact].clone();
                (name.clone(), format!("the surface of impact '{name}'"))
            } else {
                ("the gimbal guard".to_string(), "a body's gimbal guard".to_string())
            };
            // The state at t: the event was evaluated there, within the last step
            // (dense output), or at the step's end.
            let mut y = solver.state().to_vec();
            if solver.interpolate(t, &mut y).is_err() {
                y = solver.state().to_vec();
            }
            let message = format!(
                "{what} has no value at t = {} {}: it must be defined wherever the motion goes",
                num::Shortest(t),
                d.point_text(&y)
            );
            Err(failed(report, RunFailure::UndefinedCondition { t, condition }, message))
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

/// Adds the work of one solver to a run's total (a run with impacts uses one per part).
fn add_statistics(total: &mut num::Statistics, part: &num::Statistics) {
    total.steps += part.steps;
    total.rejected += part.rejected;
    total.rhs_evaluations += part.rhs_evaluations;
    total.jacobian_evaluations += part.jacobian_evaluations;
    total.lu_decompositions += part.lu_decompositions;
    total.newton_iterations += part.newton_iterations;
    total.look_ahead_evaluations += part.look_ahead_evaluations;
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
