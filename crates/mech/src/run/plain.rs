//! The stepping of a model without constraints: the method the derivation
//! calls for (or the one asked for), the form it integrates (Lagrange `[q, q']`,
//! Hamilton `[q, p]`, separable `[q, p]`), pilot runs that fix the step of a
//! fixed-step method from the tolerance (refusing a step that cannot reach the
//! end time within the run's step budget, before running), and failures told in
//! the user's terms.

use super::dynamics::{Dynamics, Form, System};
use super::{
    choose_method, RowBuffer, RunConfig, RunError, RunFailure, RunWarning, Start, StepBudget, Stepping, TimeScale,
};
use crate::derive::Derivation;
use crate::error::ModelError;
use crate::probe;
use num::{integrate, probe_spacing, Config, Method, Output, RhsError, SolveError, Solver};
use std::ops::ControlFlow;

/// A run of a model without constraints.
pub(crate) struct Plain {
    /// The system rows and failure diagnoses are evaluated with.
    system: System,
    names: Vec<String>,
    form: Form,
    n: usize,
    promise: Option<Promise>,
}

/// What the pilot runs promised of the drift of H, and the run's drift so far.
struct Promise {
    /// The relative drift the pilots found the step to meet.
    bound: f64,
    /// Beyond this the audit warns on its own (the drift the tolerance explains).
    explained: f64,
    /// H at the first row.
    h0: Option<f64>,
    drift: f64,
}

impl Plain {
    /// Chooses the method and form and builds the solver at (q0, q0').
    pub(crate) fn start(
        d: &Derivation,
        dynamics: &Dynamics,
        config: &RunConfig,
        q0: &[f64],
        qd0: &[f64],
    ) -> Result<(Plain, Start), RunError> {
        let (method, form) = choose_method(d, dynamics, config.method, config.dt.is_some()).map_err(RunError::Input)?;
        if config.dt.is_some() && method.is_adaptive() {
            return Err(RunError::StepNotApplicable { method });
        }
        let n = dynamics.n_coords();
        let mut system = dynamics.system(form);
        let y0 = system.initial_state(0.0, q0, qd0).map_err(RunError::Input)?;
        if let Some(e) = singular_start(&mut system, dynamics.coordinate_names(), q0, &y0) {
            // A parameter at 0 that leaves a coordinate without inertia is the cause to name.
            let all: Vec<usize> = (0..n).collect();
            let e = match d.no_inertia_at(&all, q0, &|p| d.model.parameter(p)) {
                Some(idle) if !idle.zero_parameters.is_empty() => {
                    let start = dynamics.coordinate_names().iter().zip(q0).map(|(c, v)| format!("{c} = {v}"));
                    let at = format!("the start ({})", start.collect::<Vec<_>>().join(", "));
                    ModelError::whole(idle.message(&at)).with_help(idle.help())
                }
                _ => e,
            };
            return Err(RunError::Input(e));
        }
        let mut probe_system = system.clone();
        let solver_config = Config { look_ahead: look_ahead(method, config), ..config.solver_config() };
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
        // The drift of H the pilot runs found the step to meet, if they did.
        let mut promise = None;
        if !method.is_adaptive() {
            // A fixed step chosen from the tolerance at the start may be too long
            // later in the run (a pendulum released from rest speeds up): pilot
            // runs check the drift of H along the run (its first tenth of the
            // budget's steps, where the run is longer) and shorten the step until
            // it meets the tolerance. Then the step is made to divide the sample
            // spacing, so that every output row is an integrator state, not an
            // interpolation between two.
            let mut h = solver.step_size();
            pilot_rhs += solver.statistics().rhs_evaluations;
            // The steps are known once the step is: a step that cannot reach the
            // end within the budget is refused before the pilots run it.
            let refuse_beyond_budget = |h: f64| -> Result<(), RunError> {
                if config.until / h <= config.max_steps as f64 {
                    return Ok(());
                }
                let mut probe = build(system.clone(), &Config { dt: Some(h), ..solver_config }).map_err(input_error)?;
                let steps = (0..PROBE_STEPS).take_while(|_| probe.step().is_ok()).count().max(1);
                let rhs_per_step = probe.statistics().rhs_evaluations as f64 / steps as f64;
                let mut scale_system = system.clone();
                let time_scale = || TimeScale::of(&mut scale_system, 0.0, &y0);
                let refused = StepBudget::refused(method, h, config.until, config.max_steps, rhs_per_step, time_scale);
                refused.map_or(Ok(()), |b| Err(RunError::StepBudget(Box::new(b))))
            };
            refuse_beyond_budget(h)?;
            if config.dt.is_none() && d.hamiltonian_conserved() {
                let target = 10.0 * config.rtol.max(1e-14);
                let mut previous: Option<f64> = None;
                for _ in 0..4 {
                    let cfg = Config { dt: Some(h), ..solver_config };
                    let pilot = build(system.clone(), &cfg).map_err(input_error)?;
                    let horizon = config.until.min(h * (config.max_steps / PILOT_SHARE).max(1) as f64);
                    let (drift, evaluations) = pilot_drift(pilot, &mut probe_system, horizon, n);
                    pilot_rhs += evaluations;
                    let Some(drift) = drift else { break };
                    if drift <= target {
                        promise = Some(target);
                        break;
                    }
                    // A drift that did not fall with the step is not the step's (H
                    // small beside the kinetic and potential energies of a motion
                    // that runs away, whose every method loses digits of H): a
                    // shorter step would only cost more.
                    if previous.is_some_and(|p| drift > 0.5 * p) {
                        break;
                    }
                    previous = Some(drift);
                    h *= (0.9 * (target / drift).powf(1.0 / f64::from(method.order()))).clamp(0.05, 0.9);
                    refuse_beyond_budget(h)?;
                }
            }
            if let Output::Samples(k) = config.output {
                let spacing = config.until / (k.max(2) - 1) as f64;
                h = spacing / (spacing / h).ceil();
            }
            refuse_beyond_budget(h)?;
            let cfg = Config { dt: Some(h), ..solver_config };
            solver = build(system.clone(), &cfg).map_err(input_error)?;
            dt = Some(h);
        }
        let explained = (1e3 * config.rtol).max(1e-12);
        let promise = promise.map(|bound| Promise { bound, explained, h0: None, drift: 0.0 });
        let plain = Plain { system: probe_system, names: dynamics.coordinate_names().to_vec(), form, n, promise };
        let initial = (q0.to_vec(), qd0.to_vec());
        // After an impact: the same method and step, started afresh at the new state.
        let restart_config = Config { dt, ..solver_config };
        let restart: super::Restart = Box::new(move |t, q, qd| {
            let mut system = system.clone();
            let y = system.initial_state(t, q, qd).map_err(|e| e.message)?;
            let solver = if form == Form::Separable {
                method.build_separable(system, t, &y, &restart_config)
            } else {
                method.build(system, t, &y, &restart_config)
            };
            solver.map_err(|e| e.to_string())
        });
        let start =
            Start { solver, y0, initial, method, form, dt, pilot_rhs_evaluations: pilot_rhs, restart: Some(restart) };
        Ok((plain, start))
    }
}

/// The Taylor method's look-ahead spacing ([`num::Config::look_ahead`]): the
/// event probes' grid ([`num::probe_spacing`]). Its steps come from the
/// series' last terms, which see nothing of a feature the series does not
/// reach yet (a narrow barrier ahead whose force is still ~0); the
/// Runge–Kutta methods evaluate the equations inside each step and need none.
fn look_ahead(method: Method, config: &RunConfig) -> Option<f64> {
    (method == Method::Taylor).then(|| probe_spacing(config.until, config.output))
}

impl Stepping for Plain {
    fn velocity_map(&self) -> super::VelocityMap {
        let mut system = self.system.clone();
        Box::new(move |t, y, qd| system.velocities(t, y, qd))
    }

    fn row(&mut self, t: f64, y: &[f64], row: &mut RowBuffer) -> Result<(), RhsError> {
        row.q.copy_from_slice(&y[..self.n]);
        self.system.invariants_at(t, y, &mut row.qd, &mut row.invariants)?;
        if let (Some(p), Some(&h)) = (&mut self.promise, row.invariants.first()) {
            let h0 = *p.h0.get_or_insert(h);
            let d = (h - h0).abs() / h0.abs().max(f64::MIN_POSITIVE);
            if d.is_finite() {
                p.drift = p.drift.max(d);
            }
        }
        Ok(())
    }

    fn warnings(&self, warnings: &mut Vec<RunWarning>) {
        if let Some(p) = &self.promise {
            if p.drift > p.bound && p.drift <= p.explained {
                warnings.push(RunWarning::PilotOutgrown { drift: p.drift, bound: p.bound });
            }
        }
    }

    fn describe(&mut self, e: &SolveError, y0: &[f64], at: (f64, Vec<f64>)) -> (RunFailure, String) {
        describe_failure(e, &self.names, self.form, &mut self.system, y0, at)
    }

    fn time_scale(&mut self, t: f64, y: &[f64]) -> Option<TimeScale> {
        TimeScale::of(&mut self.system, t, y)
    }
}

/// The error for a mass matrix that is singular at the initial state, naming
/// the coordinates whose velocities have no inertia there (the null vector of
/// M(q₀)): the spherical pendulum at θ = 0, where φ' costs no kinetic energy.
fn singular_start(system: &mut System, names: &[String], q0: &[f64], y0: &[f64]) -> Option<ModelError> {
    let n = names.len();
    let m = system.mass_matrix_at(0.0, y0);
    let largest = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let pivot = probe::smallest_pivot(&m, n)?;
    if pivot > 1e-12 * largest && largest > 0.0 {
        return None;
    }
    let svd = nalgebra::DMatrix::from_row_slice(n, n, &m).svd(false, true);
    let v_t = svd.v_t?;
    let k = svd.singular_values.imin();
    let null: Vec<f64> = v_t.row(k).iter().copied().collect();
    let top = null.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let idle: Vec<&str> =
        names.iter().zip(&null).filter(|(_, v)| v.abs() > 0.1 * top).map(|(name, _)| name.as_str()).collect();
    let start: Vec<String> = names.iter().zip(q0).map(|(name, v)| format!("{name} = {v}")).collect();
    let what = match idle.as_slice() {
        [one] => format!("the velocity of {one} has no inertia there, so its acceleration is undetermined"),
        many => format!(
            "a combination of the velocities of {} has no inertia there, so the accelerations are undetermined",
            many.join(", ")
        ),
    };
    Some(
        ModelError::whole(format!("the mass matrix M is singular at the start ({}): {what}", start.join(", ")))
            .with_help(
                "the coordinates are singular at this configuration (like polar angles at the pole): start away from it (change [initial]), or choose other coordinates",
            ),
    )
}

/// A pilot run takes at most this share of the run's step budget (1/10): four
/// pilots cost less than half a run however long the run, and a tenth of the
/// budget spans many periods of any motion the step can follow.
const PILOT_SHARE: usize = 10;

/// Steps a fixed-step method takes to measure its evaluations per step (the
/// implicit methods' Newton iterations vary), for the estimate of a refused run.
const PROBE_STEPS: usize = 8;

/// Why the integrator could not go on, judged from the last good state: a mass
/// matrix that has become singular (measured against its size at the start, so
/// that a 1×1 M → 0 counts), or the component that grows without bound.
fn diagnose(
    system: &mut System,
    names: &[String],
    form: Form,
    y0: &[f64],
    t: f64,
    y: &[f64],
) -> Option<(RunFailure, String)> {
    let n = names.len();
    let m0 = system.mass_matrix_at(0.0, y0);
    let m = system.mass_matrix_at(t, y);
    // A step that cannot be taken near a state where M has lost most of its
    // smallest pivot (x^2 x'^2/2 with x → 0) is M becoming singular; the step
    // that fails may still be a little before the singular point.
    if let (Some(p0), Some(p)) = (probe::smallest_pivot(&m0, n), probe::smallest_pivot(&m, n)) {
        if p < 0.05 * p0 {
            return Some((RunFailure::Singular { t }, format!(
                "the mass matrix becomes singular at t ≈ {t} (its smallest pivot fell from {p0:.3e} at the start to {p:.3e}): the accelerations are undetermined there"
            )));
        }
    }
    // The fastest-growing component relative to where it started.
    let (k, size) = y
        .iter()
        .zip(y0)
        .map(|(v, v0)| v.abs() / v0.abs().max(1.0))
        .enumerate()
        .fold((0, 0.0f64), |best, (k, r)| if r > best.1 { (k, r) } else { best });
    (size > 1e3).then(|| {
        let failure = RunFailure::BlowUp { t, component: component_symbol(k, names, form) };
        (
            failure,
            format!(
                "the motion blew up at t = {t}: {} has grown to {:.3e}",
                component_name(k, names, form),
                y[k],
                t = num::Shortest(t)
            ),
        )
    })
}

/// A component of the state as the expression language names it: `x`, `x'` or `p_x`.
fn component_symbol(index: usize, names: &[String], form: Form) -> String {
    let n = names.len();
    match (index.checked_sub(n), form) {
        (None, _) => names[index].clone(),
        (Some(k), Form::Lagrange) if k < n => format!("{}'", names[k]),
        (Some(k), _) if k < n => format!("p_{}", names[k]),
        _ => format!("y{index}"),
    }
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
) -> (RunFailure, String) {
    let component = |index: usize| component_name(index, names, form);
    let symbol = |index: usize| component_symbol(index, names, form);
    match e {
        SolveError::NonFiniteState { t, index } => (
            RunFailure::BlowUp { t: *t, component: symbol(*index) },
            format!("the motion blew up at t = {t}: {} is no longer finite", component(*index), t = num::Shortest(*t)),
        ),
        SolveError::Rhs { t, source: num::RhsError::NonFinite { index } } => (
            RunFailure::NonFiniteRate { t: *t, component: symbol(*index) },
            format!(
                "the equations of motion gave a non-finite rate of change of {} at t = {t}",
                component(*index),
                t = num::Shortest(*t)
            ),
        ),
        SolveError::Rhs { t, source: num::RhsError::Singular { detail } } => (
            RunFailure::Singular { t: *t },
            format!(
                "the mass matrix became singular at t = {t} ({detail}): the accelerations are undetermined there",
                t = num::Shortest(*t)
            ),
        ),
        // A step that cannot be taken (too small, or implicit stages that do not
        // converge): say why from the last good state when it can be told.
        other => match diagnose(system, names, form, y0, t_last, &y_last) {
            Some((failure, why)) => (failure, format!("{why} ({other})")),
            None => (RunFailure::Step { t: t_last }, other.to_string()),
        },
    }
}
