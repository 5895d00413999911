//! A simulation run: choose the integrator the derivation calls for, integrate
//! from the model's initial state, hand every output row to the caller, and
//! audit the invariants along the way.
//!
//! Entry point: [`simulate`]. The caller (the CLI) does the IO — CSV, plots,
//! progress — in the `on_row` callback; this module only computes.
//!
//! The default method follows the derivation (issue #4): H conserved and
//! separable → an 8th-order symplectic composition; H conserved, not separable →
//! Gauss–Legendre (order 6) on Hamilton's equations; otherwise DOP853.

pub(crate) mod body;
pub(crate) mod constrained;
pub(crate) mod dynamics;
pub(crate) mod ensemble;
pub(crate) mod series;

use crate::derive::Derivation;
use crate::error::ModelError;
use crate::probe;
use dynamics::{Dynamics, Form, System};
use num::{integrate, Config, Direction, Event, Method, ObservationKind, Output, SolveError, Solver, StopReason};
use std::ops::ControlFlow;
use std::time::Instant;
use sym::{ExprId, Tape};

/// A condition that ends the run when an expression crosses zero.
#[derive(Debug, Clone)]
pub struct StopCondition {
    /// The expression g(q, q', t); the run stops where it crosses zero.
    pub expr: ExprId,
    /// Which crossings count.
    pub direction: Direction,
    /// The condition as the user wrote it.
    pub text: String,
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
        }
    }
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

/// The audit of the invariants, row by row: the first row is the reference,
/// the drift is the largest departure from it, the final value the last row's.
/// Plain and constrained runs share it.
pub(crate) struct InvariantAudit {
    names: Vec<String>,
    conserved: Vec<bool>,
    initial: Option<Vec<f64>>,
    last: Vec<f64>,
    max_abs: Vec<f64>,
    max_rel: Vec<f64>,
}

impl InvariantAudit {
    /// The audit of the invariants `dynamics` evaluates; H is conserved as the
    /// derivation says, E never on its own, the conserved momenta always.
    pub(crate) fn new(d: &Derivation, dynamics: &Dynamics) -> InvariantAudit {
        let invariants = dynamics.invariants();
        let n = invariants.len();
        InvariantAudit {
            names: invariants.iter().map(|i| i.name.clone()).collect(),
            conserved: invariants
                .iter()
                .map(|inv| if inv.name == "H" { d.hamiltonian_conserved } else { inv.name != "E" })
                .collect(),
            initial: None,
            last: vec![0.0; n],
            max_abs: vec![0.0; n],
            max_rel: vec![0.0; n],
        }
    }

    /// How many invariants there are.
    pub(crate) fn len(&self) -> usize {
        self.names.len()
    }

    /// Records one row's values. Event rows are interpolated between two steps
    /// (cubic Hermite for the compositions): their error is the interpolant's,
    /// not the integrator's, so they do not enter the drift.
    pub(crate) fn observe(&mut self, inv: &[f64], interpolated_event: bool) {
        let init = self.initial.get_or_insert_with(|| inv.to_vec());
        if !interpolated_event {
            for k in 0..inv.len() {
                let a = (inv[k] - init[k]).abs();
                if a.is_finite() {
                    self.max_abs[k] = self.max_abs[k].max(a);
                    let scale = init[k].abs();
                    self.max_rel[k] = self.max_rel[k].max(if scale > 0.0 { a / scale } else { a });
                }
            }
        }
        self.last.copy_from_slice(inv);
    }

    /// One audit per invariant.
    pub(crate) fn audits(&self) -> Vec<Audit> {
        let initial = self.initial.as_ref().unwrap_or(&self.last);
        (0..self.len())
            .map(|k| Audit {
                name: self.names[k].clone(),
                conserved: self.conserved[k],
                initial: initial[k],
                final_value: self.last[k],
                max_abs_drift: self.max_abs[k],
                max_rel_drift: self.max_rel[k],
            })
            .collect()
    }
}

/// A warning for each conserved invariant that drifted by more than
/// `explained` (relative), the drift the method's tolerance accounts for.
pub(crate) fn drift_warnings(audits: &[Audit], explained: f64) -> Vec<String> {
    audits
        .iter()
        .filter(|a| a.conserved && a.max_rel_drift > explained)
        .map(|a| {
            format!(
                "{} is conserved, but drifted by {:.3e} (relative), more than the tolerance explains ({:.1e})",
                a.name, a.max_rel_drift, explained
            )
        })
        .collect()
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// The method used.
    pub method: Method,
    /// The state variables integrated.
    pub form: Form,
    /// The fixed step used, for fixed-step methods.
    pub dt: Option<f64>,
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
    /// Right-hand-side evaluations of the pilot runs that chose a fixed step.
    pub pilot_rhs_evaluations: usize,
    /// Wall-clock seconds of the integration (compilation included).
    pub wall_seconds: f64,
    /// With constraints: the audit of each constraint (empty otherwise).
    pub constraints: Vec<constrained::ConstraintAudit>,
}

/// Why a run did not complete.
#[derive(Debug)]
pub enum RunError {
    /// Bad input: an impossible method, a missing initial value (exit 2).
    Input(ModelError),
    /// The run failed midway (exit 1); the report covers what was done.
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
    row_error: Option<String>,
) -> Result<RunReport, RunError> {
    report.stopped_by = match stop {
        StopReason::Event { index } => Some(conditions[index].0.text.clone()),
        StopReason::Observer => row_error.clone().or(Some("stopped by the caller".into())),
        StopReason::Finished => None,
    };
    match row_error {
        Some(message) => {
            report.failure = Some(message.clone());
            Err(RunError::Failed { message, report: Box::new(report) })
        }
        None => Ok(report),
    }
}

/// The default method and the form it integrates, or the form a requested method needs.
pub fn choose_method(
    d: &Derivation,
    dynamics: &Dynamics,
    requested: Option<Method>,
) -> Result<(Method, Form), ModelError> {
    let conserved = d.hamiltonian_conserved;
    Ok(match requested {
        None if conserved && dynamics.is_separable() => (Method::KahanLi8, Form::Separable),
        None if conserved && dynamics.has_hamilton_form() => (Method::Gauss6, Form::Hamilton),
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

/// Runs a simulation. `on_row` receives every output row in time order and may
/// stop the run with `ControlFlow::Break`.
pub fn simulate(
    d: &mut Derivation,
    config: &RunConfig,
    mut on_row: impl FnMut(&Row<'_>) -> ControlFlow<()>,
) -> Result<RunReport, RunError> {
    if !d.constraints.is_empty() {
        return constrained::simulate(d, config, on_row);
    }
    let start = Instant::now();
    if !(config.until.is_finite() && config.until > 0.0) {
        return Err(RunError::Input(ModelError::whole(format!(
            "--until must be a positive time, not {}",
            config.until
        ))));
    }
    let (q0, qd0) = d.model.initial_state().map_err(RunError::Input)?;
    // The events' indices: stop conditions, crossings, then one guard per body.
    let guards = body::gimbal_guards(d, config.rtol);
    if let Some(g) = guards.iter().find(|g| g.violated(&q0)) {
        let span =
            d.model.initial.iter().find(|iv| iv.coord == g.beta && iv.order == 0).map(|iv| iv.value.span.clone());
        let e = crate::ModelError {
            message: format!(
                "the initial state is at the gimbal singularity of body '{}': |sin {}| < {:.1e}",
                g.body, g.beta_name, g.threshold
            ),
            span,
            help: Some(g.advice()),
        };
        return Err(RunError::Input(e));
    }
    let dynamics = Dynamics::new(d);
    let (method, form) = choose_method(d, &dynamics, config.method).map_err(RunError::Input)?;
    let n = dynamics.n_coords();
    let names: Vec<String> = dynamics.coordinate_names().to_vec();
    let mut invariant_audit = InvariantAudit::new(d, &dynamics);

    let mut system = dynamics.system(form);
    let y0 = system.initial_state(0.0, &q0, &qd0).map_err(RunError::Input)?;
    let mut probe_system = system.clone();
    let solver_config =
        Config { rtol: config.rtol, atol: config.atol, dt: config.dt, h_max: Some(config.until), ..Config::default() };
    let build = |system: System, config: &Config| -> Result<Box<dyn Solver>, SolveError> {
        if form == Form::Separable {
            method.build_separable(system, 0.0, &y0, config)
        } else {
            method.build(system, 0.0, &y0, config)
        }
    };
    let input_error = |e: SolveError| RunError::Input(ModelError::whole(e.to_string()));
    let mut solver = build(system.clone(), &solver_config).map_err(input_error)?;
    let mut dt = None;
    let mut pilot_rhs = 0;
    if !method.is_adaptive() {
        // A fixed step chosen from the tolerance at the start may be too long
        // later in the run (a pendulum released from rest speeds up): pilot
        // runs check the drift of H along the whole run and shorten the step
        // until it meets the tolerance. Then the step is made to divide the
        // sample spacing, so that every output row is an integrator state,
        // not an interpolation between two.
        let mut h = solver.step_size();
        pilot_rhs += solver.statistics().rhs_evaluations;
        if config.dt.is_none() && d.hamiltonian_conserved {
            let target = 10.0 * config.rtol.max(1e-14);
            for _ in 0..4 {
                let cfg = Config { dt: Some(h), ..solver_config };
                let pilot = build(system.clone(), &cfg).map_err(input_error)?;
                let (drift, evaluations) = pilot_drift(pilot, &mut probe_system, config.until, n);
                pilot_rhs += evaluations;
                let Some(drift) = drift else { break };
                if drift <= target {
                    break;
                }
                h *= (0.9 * (target / drift).powf(1.0 / f64::from(method.order()))).clamp(0.05, 0.9);
            }
        }
        if let Output::Samples(k) = config.output {
            let spacing = config.until / (k.max(2) - 1) as f64;
            h = spacing / (spacing / h).ceil();
        }
        let cfg = Config { dt: Some(h), ..solver_config };
        solver = build(system.clone(), &cfg).map_err(input_error)?;
        dt = Some(h);
    }

    // Rigid bodies: a terminal event before the Euler angles' gimbal singularity.
    let first_guard = config.stop_when.len() + config.crossings.len();
    // Stop conditions, each compiled over [q, q', t, params].
    let param_syms: Vec<ExprId> = d.model.parameters.iter().map(|p| d.model.pool.symbol(&p.name)).collect();
    let mut inputs: Vec<ExprId> = d.q.clone();
    inputs.extend(&d.qd);
    inputs.push(d.t);
    inputs.extend(&param_syms);
    let mut values = vec![0.0; 2 * n + 1];
    values.extend(d.model.parameters.iter().map(|p| p.value));
    // Stop conditions first (terminal), then crossings (recorded, not stopping).
    let conditions: Vec<(&StopCondition, bool)> =
        config.stop_when.iter().map(|c| (c, true)).chain(config.crossings.iter().map(|c| (c, false))).collect();
    let mut stop_tapes = Vec::new();
    for &(cond, terminal) in &conditions {
        let tape = Tape::compile(&d.model.pool, &[cond.expr], &inputs)
            .map_err(|e| RunError::Input(ModelError::whole(format!("in the condition '{}': {e}", cond.text))))?;
        stop_tapes.push((tape, values.clone(), cond.direction, terminal));
    }
    let mut events: Vec<Event<'_>> = Vec::new();
    for (tape, values, direction, terminal) in stop_tapes {
        let mut sys = probe_system.clone();
        let mut tape = tape;
        let mut values = values;
        let mut qd = vec![0.0; n];
        let mut out = [0.0];
        events.push(
            Event::new(move |t, y| {
                if sys.velocities(t, y, &mut qd).is_err() {
                    return f64::NAN;
                }
                values[..n].copy_from_slice(&y[..n]);
                values[n..2 * n].copy_from_slice(&qd);
                values[2 * n] = t;
                tape.eval(&values, &mut out);
                out[0]
            })
            .with_direction(direction)
            .with_terminal(terminal),
        );
    }

    for g in &guards {
        let (beta, s2) = (g.beta, g.threshold * g.threshold);
        events.push(
            Event::new(move |_t, y| y[beta].sin().powi(2) - s2).with_direction(Direction::Falling).with_terminal(true),
        );
    }

    // The audit, row by row.
    let mut qd = vec![0.0; n];
    let mut inv = vec![0.0; invariant_audit.len()];
    let mut last_q = q0.clone();
    let mut last_qd = qd0.clone();
    let mut last_t = 0.0;
    let mut row_error: Option<String> = None;
    let result = integrate(&mut solver, config.until, config.output, &mut events, |obs| {
        if let Err(e) = probe_system.invariants_at(obs.t, obs.y, &mut qd, &mut inv) {
            row_error = Some(format!("at t = {}: {e}", obs.t));
            return ControlFlow::Break(());
        }
        invariant_audit.observe(&inv, matches!(obs.kind, ObservationKind::Event { .. }));
        last_t = obs.t;
        last_q.copy_from_slice(&obs.y[..n]);
        last_qd.copy_from_slice(&qd);
        let flow = on_row(&Row {
            t: obs.t,
            q: &obs.y[..n],
            qd: &qd,
            invariants: &inv,
            is_event: matches!(obs.kind, ObservationKind::Event { .. }),
            event: match obs.kind {
                ObservationKind::Event { index } if index < first_guard => Some(conditions[index].0.text.as_str()),
                _ => None,
            },
            constraints: &[],
        });
        // The row is kept; past a gimbal guard the run ends as a failure.
        if let Some(g) = guards.iter().find(|g| g.violated(&obs.y[..n])) {
            row_error = Some(g.message(obs.t));
            return ControlFlow::Break(());
        }
        flow
    });

    let stats = solver.statistics();
    let audits = invariant_audit.audits();
    // What the method's tolerance explains: a few hundred local errors of size
    // rtol (fixed-step methods had their step chosen from rtol as well).
    let explained = if config.dt.is_some() { 1e-2 } else { (1e3 * config.rtol).max(1e-12) };
    let warnings = drift_warnings(&audits, explained);
    let mut report = RunReport {
        method,
        form,
        dt,
        rtol: config.rtol,
        atol: config.atol,
        steps: stats.steps,
        rejected: stats.rejected,
        rhs_evaluations: stats.rhs_evaluations,
        t_final: last_t,
        final_q: last_q,
        final_qd: last_qd,
        invariants: audits,
        stopped_by: None,
        warnings,
        failure: None,
        pilot_rhs_evaluations: pilot_rhs,
        wall_seconds: 0.0,
        constraints: Vec::new(),
    };
    report.wall_seconds = start.elapsed().as_secs_f64();
    match result {
        Ok(summary) => {
            report.t_final = summary.t;
            if let StopReason::Event { index } = summary.stop {
                if index >= first_guard {
                    let message = guards[index - first_guard].message(summary.t);
                    report.failure = Some(message.clone());
                    return Err(RunError::Failed { message, report: Box::new(report) });
                }
            }
            conclude(report, summary.stop, &conditions, row_error)
        }
        Err(e) => {
            let at = (solver.t(), solver.state().to_vec());
            // A body near its gimbal singularity: say so rather than only "singular".
            let near = guards.iter().min_by(|a, b| at.1[a.beta].sin().abs().total_cmp(&at.1[b.beta].sin().abs()));
            let gimbal = near.filter(|g| at.1[g.beta].sin().abs() < 0.1).map(|g| g.message(at.0));
            let message = match gimbal {
                Some(m) => format!("{m} ({e})"),
                None => describe_failure(&e, &names, form, &mut probe_system, &y0, at),
            };
            report.failure = Some(message.clone());
            Err(RunError::Failed { message, report: Box::new(report) })
        }
    }
}

/// Why the integrator could not go on, judged from the last good state: a mass
/// matrix that has become singular (measured against its size at the start, so
/// that a 1×1 M → 0 counts), or the component that grows without bound.
fn diagnose(system: &mut System, names: &[String], form: Form, y0: &[f64], t: f64, y: &[f64]) -> Option<String> {
    let n = names.len();
    let m0 = system.mass_matrix_at(0.0, y0);
    let m = system.mass_matrix_at(t, y);
    // A step that cannot be taken near a state where M has lost most of its
    // smallest pivot (x^2 x'^2/2 with x → 0) is M becoming singular; the step
    // that fails may still be a little before the singular point.
    if let (Some(p0), Some(p)) = (probe::smallest_pivot(&m0, n), probe::smallest_pivot(&m, n)) {
        if p < 0.05 * p0 {
            return Some(format!(
                "the mass matrix becomes singular at t ≈ {t} (its smallest pivot fell from {p0:.3e} at the start to {p:.3e}): the accelerations are undetermined there"
            ));
        }
    }
    // The fastest-growing component relative to where it started.
    let (k, size) = y
        .iter()
        .zip(y0)
        .map(|(v, v0)| v.abs() / v0.abs().max(1.0))
        .enumerate()
        .fold((0, 0.0f64), |best, (k, r)| if r > best.1 { (k, r) } else { best });
    (size > 1e3)
        .then(|| format!("the motion blew up at t = {t}: {} has grown to {:.3e}", component_name(k, names, form), y[k]))
}

fn component_name(index: usize, names: &[String], form: Form) -> String {
    let n = names.len();
    if index < n {
        format!("the coordinate '{}'", names[index])
    } else if index < 2 * n {
        match form {
            Form::Lagrange => format!("the velocity '{}''", names[index - n]),
            _ => format!("the momentum 'p_{}'", names[index - n]),
        }
    } else {
        format!("component {index}")
    }
}

/// The largest relative drift of H (the first invariant) over every step of a
/// run without output; None when the pilot fails (the real run reports why).
fn pilot_drift(mut solver: Box<dyn Solver>, system: &mut System, until: f64, n: usize) -> (Option<f64>, usize) {
    let mut qd = vec![0.0; n];
    let mut inv = vec![0.0; system.n_invariants()];
    let mut h0: Option<f64> = None;
    let mut drift = 0.0f64;
    let mut failed = false;
    let result = integrate(&mut solver, until, Output::EveryStep, &mut [], |obs| {
        if system.invariants_at(obs.t, obs.y, &mut qd, &mut inv).is_err() {
            failed = true;
            return ControlFlow::Break(());
        }
        let h = *h0.get_or_insert(inv[0]);
        let d = (inv[0] - h).abs() / h.abs().max(f64::MIN_POSITIVE);
        if !d.is_finite() {
            failed = true;
            return ControlFlow::Break(());
        }
        drift = drift.max(d);
        ControlFlow::Continue(())
    });
    ((result.is_ok() && !failed).then_some(drift), solver.statistics().rhs_evaluations)
}

/// A failure in the user's terms: the time and the coordinate concerned.
fn describe_failure(
    e: &SolveError,
    names: &[String],
    form: Form,
    system: &mut System,
    y0: &[f64],
    (t_last, y_last): (f64, Vec<f64>),
) -> String {
    let component = |index: usize| component_name(index, names, form);
    match e {
        SolveError::NonFiniteState { t, index } => {
            format!("the motion blew up at t = {t}: {} is no longer finite", component(*index))
        }
        SolveError::Rhs { t, source: num::RhsError::NonFinite { index } } => {
            format!("the equations of motion gave a non-finite rate of change of {} at t = {t}", component(*index))
        }
        SolveError::Rhs { t, source: num::RhsError::Singular { detail } } => {
            format!("the mass matrix became singular at t = {t} ({detail}): the accelerations are undetermined there")
        }
        // A step that cannot be taken (too small, or implicit stages that do not
        // converge): say why from the last good state when it can be told.
        other => match diagnose(system, names, form, y0, t_last, &y_last) {
            Some(why) => format!("{why} ({other})"),
            None => other.to_string(),
        },
    }
}
