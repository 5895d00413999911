//! The runs of a sweep: each run's start from the model and the grid point,
//! the plan that integrates them (trajectory by trajectory, or on Taylor lanes
//! in lock step), and what each produced, as a row.

use super::grid::{Grid, Target};
use super::lyapunov::{perturbed, pull_back, segment_end, Twin};
use super::table::TableRow;
use super::SweepConfig;
use crate::derive::Derivation;
use crate::error::ModelError;
use crate::model::Model;
use crate::run::body::GimbalGuard;
use crate::run::dynamics::{Form, System};
use crate::run::ensemble::{propagate, Batch, LANES};
use crate::run::series::LagrangeSeries;
use num::{integrate, integrate_to, Config, Method, Output, SolveError, Solver, StopReason};
use std::ops::ControlFlow;
use sym::Lanes;

/// What one run produced.
#[derive(Debug)]
pub(super) struct RunOutcome {
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
pub(super) fn row(run: usize, inputs: Vec<f64>, n: usize, outcome: Result<RunOutcome, String>) -> TableRow {
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
pub(super) fn start_of(
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
                let parameters = model.parameters.iter().map(|p| p.value).collect();
                Ok(Begin { q, qd, parameters })
            })
        }
        None => complete(base, grid, inputs, &d.model).and_then(|(q, qd)| {
            d.model.check_values(Some((&q, &qd)))?;
            no_inertia(d, &d.model, &q)?;
            Ok(Begin { q, qd, parameters: d.model.parameters.iter().map(|p| p.value).collect() })
        }),
    };
    start.map_err(|e| e.message)
}

/// A row whose start leaves a coordinate without inertia because a parameter
/// is 0 (`m = 0`), refused with that cause as a run refuses it. Looked for only
/// when a parameter is 0 and a diagonal entry of M vanishes at the start, so
/// that other rows pay nothing.
pub(super) fn no_inertia(d: &Derivation, model: &Model, q: &[f64]) -> Result<(), ModelError> {
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
#[derive(Clone, Debug)]
pub(super) struct Initial {
    pub(super) q: Vec<Option<f64>>,
    pub(super) qd: Vec<Option<f64>>,
}

pub(super) fn initial_values(model: &Model) -> Result<Initial, ModelError> {
    let n = model.n_coords();
    let (mut q, mut qd) = (vec![None; n], vec![None; n]);
    let env = |name: &str| model.parameter(name);
    for iv in &model.initial {
        let v =
            model.pool.eval(iv.value.expr, &env).map_err(|e| ModelError::at(iv.value.span.clone(), e.to_string()))?;
        let slot = if iv.order == 0 { &mut q } else { &mut qd };
        slot[iv.coord] = Some(v);
    }
    Ok(Initial { q, qd })
}

/// The initial (q, q') of a run: the model's values overridden by the grid's.
pub(super) fn complete(
    base: &Initial,
    grid: &Grid,
    inputs: &[f64],
    model: &Model,
) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
    let Initial { mut q, mut qd } = base.clone();
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
pub(super) struct Plan<'a> {
    pub(super) method: Method,
    pub(super) form: Form,
    pub(super) config: &'a SweepConfig,
    /// One per rigid body, checked after every step of the main trajectory.
    pub(super) guards: &'a [GimbalGuard],
}

/// A solver in the form the method needs, borrowing its system.
pub(super) fn build<'a>(
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
    pub(super) fn run(&self, sys: &mut System, twin_sys: &mut System, q0: &[f64], qd0: &[f64]) -> RunOutcome {
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
        let mut solver_config = cfg.solver_config();
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

/// How a run begins: its initial q, q' and parameter values.
#[derive(Clone, Debug)]
pub(super) struct Begin {
    pub(super) q: Vec<f64>,
    pub(super) qd: Vec<f64>,
    pub(super) parameters: Vec<f64>,
}

/// A run of a batch: its index, its grid inputs, and how it begins, or why it cannot.
#[derive(Debug)]
pub(super) struct Start {
    pub(super) run: usize,
    pub(super) inputs: Vec<f64>,
    pub(super) begin: Result<Begin, String>,
}

/// A run on the lanes of a batch: its main trajectory on lane `slot`, its
/// Lyapunov twin on lane `slot + LANES / 2`.
pub(super) struct OnLanes {
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
    pub(super) fn run_batch(
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
        let mut pending = (0..starts.len()).filter(|&i| starts[i].begin.is_ok());
        let mut outcomes: Vec<Option<RunOutcome>> = (0..starts.len()).map(|_| None).collect();
        let Some(first) = starts.iter().find_map(|s| s.begin.as_ref().ok()) else {
            return Some(finish(starts, outcomes, n));
        };
        // Lanes left without a run keep the first run's state (finite, never read back).
        let mut batch = Batch::new(&[[first.q.as_slice(), &first.qd].concat()]);
        let mut params: Vec<Lanes<LANES>> = first.parameters.iter().map(|&v| [v; LANES]).collect();
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
            let Begin { q, qd, parameters: values } = starts[at].begin.as_ref().expect("pending runs started");
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
        let solver_config = cfg.solver_config();
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
                let values = &starts[at].begin.as_ref().expect("started").parameters;
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
pub(super) fn finish(starts: Vec<Start>, outcomes: Vec<Option<RunOutcome>>, n: usize) -> Vec<TableRow> {
    starts
        .into_iter()
        .zip(outcomes)
        .map(|(Start { run, inputs, begin: start }, outcome)| {
            let outcome = match (start, outcome) {
                (Err(message), _) => Err(message),
                (Ok(_), Some(o)) => Ok(o),
                (Ok(_), None) => unreachable!("every started run has an outcome"),
            };
            row(run, inputs, n, outcome)
        })
        .collect()
}
