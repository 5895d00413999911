//! The convenience driver [`integrate`]: runs a [`Solver`] to an end time, hands every
//! accepted step or evenly spaced samples (from dense output) to an observer, and
//! locates events (zero crossings of `g(t, y)`) with Brent's method on the dense output,
//! then, for the methods whose dense output is of lower order than their steps, on
//! states the method computes itself ([`Solver::restep`]).
//!
//! It also keeps a run within its step budget ([`crate::Config::max_steps`]) by
//! foresight: a fixed step that cannot reach the end time in the budget fails
//! before its first step, and an adaptive run whose recent pace would need more
//! than [`FORESIGHT_MARGIN`] times the budget fails at the checkpoint that sees it
//! ([`SolveError::MaxStepsForeseen`]), rather than after spending the budget. A run
//! with a terminal event may end long before its end time, so it is held to the
//! budget alone.

use std::ops::ControlFlow;

use crate::error::{RhsError, SolveError};
use crate::root::brent;
use crate::solver::{check_len, Solver, StepOutcome};

/// Which points the observer receives (besides events).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Output {
    /// The initial point and the end of every accepted step.
    #[default]
    EveryStep,
    /// `n ≥ 2` evenly spaced points from the initial time to the end time, both
    /// included (`t_k = t0 + k·(t_end − t0)/(n − 1)`), interpolated from dense output.
    Samples(usize),
}

/// Which zero crossings of an event function count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Direction {
    /// `g` goes from negative to non-negative.
    Rising,
    /// `g` goes from positive to non-positive.
    Falling,
    /// Either.
    #[default]
    Both,
}

/// The boxed event function of an [`Event`].
type EventFn<'a> = Box<dyn FnMut(f64, &[f64]) -> f64 + 'a>;

/// Probes per run for events in long steps, at least (see [`Event`]).
const PROBES_PER_RUN: usize = 1000;

/// The spacing of the grid on which long steps are probed over `span` with
/// `output`: that of the samples, at most a thousandth of the span. Events
/// are looked for on it (see [`Event`]), and it suits the Taylor method's
/// look-ahead ([`crate::Config::look_ahead`]) too.
pub fn probe_spacing(span: f64, output: Output) -> f64 {
    let intervals = match output {
        Output::Samples(n) => n.saturating_sub(1).max(PROBES_PER_RUN),
        Output::EveryStep => PROBES_PER_RUN,
    };
    span / intervals as f64
}

impl Direction {
    /// Whether the change of g from `ga` to `gb` is a crossing this direction counts.
    fn counts(self, ga: f64, gb: f64) -> bool {
        let rising = ga < 0.0 && gb >= 0.0;
        let falling = ga > 0.0 && gb <= 0.0;
        match self {
            Direction::Rising => rising,
            Direction::Falling => falling,
            Direction::Both => rising || falling,
        }
    }
}

/// An event function `g(t, y)` whose zero crossings are located.
///
/// A step longer than the event grid's spacing (the spacing of the samples, and
/// at most a thousandth of the run) is probed on that grid through its dense
/// output, so that a step does not hide two crossings that the rows would show:
/// the Taylor method's steps can span the whole run where the motion is a
/// polynomial. Every crossing that a sign change between neighbouring probes
/// brackets is found; two crossings closer together than the grid's spacing
/// may still hide each other, so bound the step (`Config::h_max`) or ask for
/// more samples when `g` changes faster.
pub struct Event<'a> {
    g: EventFn<'a>,
    direction: Direction,
    terminal: bool,
}

impl<'a> Event<'a> {
    /// A non-terminal event counting crossings in both directions.
    pub fn new(g: impl FnMut(f64, &[f64]) -> f64 + 'a) -> Self {
        Event { g: Box::new(g), direction: Direction::Both, terminal: false }
    }
    /// The same event counting only crossings in `direction`.
    pub fn with_direction(mut self, direction: Direction) -> Self {
        self.direction = direction;
        self
    }
    /// The same event, stopping the integration at its first crossing when `terminal`.
    pub fn with_terminal(mut self, terminal: bool) -> Self {
        self.terminal = terminal;
        self
    }
}

impl std::fmt::Debug for Event<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Event")
            .field("direction", &self.direction)
            .field("terminal", &self.terminal)
            .finish_non_exhaustive()
    }
}

/// What kind of point an [`Observation`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObservationKind {
    /// The end of an accepted step (or the initial point), with [`Output::EveryStep`].
    Step,
    /// An output sample, with [`Output::Samples`].
    Sample,
    /// A located crossing of event `index`.
    Event {
        /// Index of the event in the slice given to [`integrate`].
        index: usize,
    },
}

/// A point handed to the observer.
#[derive(Clone, Copy, Debug)]
pub struct Observation<'s> {
    /// Time.
    pub t: f64,
    /// State at `t`.
    pub y: &'s [f64],
    /// Why the observer sees it.
    pub kind: ObservationKind,
}

/// Why [`integrate`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The end time was reached.
    Finished,
    /// A terminal event occurred.
    Event {
        /// Index of the event.
        index: usize,
    },
    /// The observer returned `ControlFlow::Break`.
    Observer,
}

/// The result of [`integrate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// The last time observed: `t_end`, the time of a terminal event, or of the point
    /// at which the observer stopped.
    pub t: f64,
    /// Why the run stopped.
    pub stop: StopReason,
    /// Number of event crossings located.
    pub events: usize,
    /// The index of the first sample of [`Output::Samples`] not yet observed
    /// (the count of samples for [`Output::EveryStep`]: 0): where a run
    /// resumed after a terminal event picks up its grid ([`integrate_resumed`]).
    pub next_sample: usize,
}

/// Where a run resumed after a terminal event stands on its output grid: the
/// grid's start and the next sample to observe (the previous part's
/// [`Summary::next_sample`]). The samples and the event probes stay on the
/// grid of the whole run from `t0`, as if it had not stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resume {
    /// The start of the whole run.
    pub t0: f64,
    /// The next sample to observe.
    pub next_sample: usize,
}

/// How many times its step budget an adaptive run's foreseen steps must exceed
/// for the run to stop early. The pace is measured over the steps since the last
/// checkpoint; a run whose steps grow later (a transient that dies out) takes
/// fewer than its pace says, so only a run foreseen far beyond the budget is
/// stopped, and one that might just make it runs until the budget is spent.
pub const FORESIGHT_MARGIN: f64 = 4.0;

/// The first budget checkpoint of an adaptive run, as a fraction of its budget
/// (then at every doubling of the steps): late enough that an initial transient
/// is behind it, early enough to stop a hopeless run at a hundredth of its cost.
const FIRST_CHECKPOINT: usize = 128;

/// Integrates with `solver` from its current time to `t_end`, calling `observer` on the
/// points `output` asks for and on every event crossing, in time order.
///
/// After a terminal event the solver stands at the end of the step that contained it;
/// the event's state is the one handed to the observer: interpolated, or from
/// [`Solver::restep`] for the methods that offer it. Returns
/// [`SolveError::EndBeforeStart`] when `t_end` lies before the solver's time, and
/// [`SolveError::MaxStepsForeseen`] when the run cannot reach it within the
/// solver's step budget (see the module documentation).
pub fn integrate<V: Solver + ?Sized>(
    solver: &mut V,
    t_end: f64,
    output: Output,
    events: &mut [Event<'_>],
    observer: impl FnMut(&Observation<'_>) -> ControlFlow<()>,
) -> Result<Summary, SolveError> {
    drive(solver, t_end, output, events, None, None, observer)
}

/// [`integrate`] continued after a terminal event from a solver started
/// afresh at a new state (the state after an impact): the observer does not
/// see the solver's initial point again, and the samples are those of the
/// whole run's grid ([`Resume`]) after the point where the last part stopped.
pub fn integrate_resumed<V: Solver + ?Sized>(
    solver: &mut V,
    t_end: f64,
    output: Output,
    resume: Resume,
    events: &mut [Event<'_>],
    observer: impl FnMut(&Observation<'_>) -> ControlFlow<()>,
) -> Result<Summary, SolveError> {
    drive(solver, t_end, output, events, None, Some(resume), observer)
}

/// A post-step map of the state: `project(t, y)` replaces `y` in place (e.g. by
/// its projection onto a constraint manifold).
pub type Projection<'a> = &'a mut dyn FnMut(f64, &mut [f64]) -> Result<(), RhsError>;

/// [`integrate`] with a projection after every accepted step: the solver continues
/// from `project(t, y)` ([`Solver::set_state`]), events are located on the projected
/// step ends, and samples come from the step's dense output as it was computed (the
/// observer may project them too). This keeps an invariant manifold, such as the
/// constraints of a mechanical system, satisfied to round-off over long runs.
pub fn integrate_projected<V: Solver + ?Sized>(
    solver: &mut V,
    t_end: f64,
    output: Output,
    events: &mut [Event<'_>],
    project: Projection<'_>,
    observer: impl FnMut(&Observation<'_>) -> ControlFlow<()>,
) -> Result<Summary, SolveError> {
    drive(solver, t_end, output, events, Some(project), None, observer)
}

/// Runs [`drive_lazily`] with the solver's dense output computed only for the
/// steps that are interpolated in (a sample or an event inside them), and for
/// the last one, so that the caller finds the solver as after eager steps.
fn drive<V: Solver + ?Sized>(
    solver: &mut V,
    t_end: f64,
    output: Output,
    events: &mut [Event<'_>],
    project: Option<Projection<'_>>,
    resume: Option<Resume>,
    observer: impl FnMut(&Observation<'_>) -> ControlFlow<()>,
) -> Result<Summary, SolveError> {
    solver.set_lazy_dense(true);
    let result = drive_lazily(solver, t_end, output, events, project, resume, observer);
    let prepared = solver.prepare_dense();
    solver.set_lazy_dense(false);
    let summary = result?;
    prepared?;
    Ok(summary)
}

fn drive_lazily<V: Solver + ?Sized>(
    solver: &mut V,
    t_end: f64,
    output: Output,
    events: &mut [Event<'_>],
    mut project: Option<Projection<'_>>,
    resume: Option<Resume>,
    mut observer: impl FnMut(&Observation<'_>) -> ControlFlow<()>,
) -> Result<Summary, SolveError> {
    let t_start = solver.t();
    if t_end.is_nan() || t_end < t_start {
        return Err(SolveError::EndBeforeStart { t: t_start, t_end });
    }
    // The grid's start: this call's, or the whole run's when resumed.
    let t0 = resume.map_or(t_start, |r| r.t0);
    if let Output::Samples(n) = output {
        if n < 2 {
            return Err(SolveError::InvalidConfig {
                name: "samples",
                value: n as f64,
                reason: "needs at least 2 samples (both ends)",
            });
        }
    }
    let dim = solver.state().len();
    let mut y = vec![0.0; dim];
    let mut g_prev = vec![0.0; events.len()];
    let mut g_new = vec![0.0; events.len()];
    // Located crossings of the current step: (time, event index).
    let mut found: Vec<(f64, usize)> = Vec::with_capacity(events.len());
    let mut n_events = 0;
    for (k, ev) in events.iter_mut().enumerate() {
        g_prev[k] = eval_event(ev, k, t_start, solver.state())?;
    }
    let kind = match output {
        Output::EveryStep => ObservationKind::Step,
        Output::Samples(_) => ObservationKind::Sample,
    };
    let mut next_sample = resume.map_or(1, |r| r.next_sample);
    let sample_time = |k: usize, n: usize| {
        if k + 1 == n {
            t_end
        } else {
            t0 + (t_end - t0) * (k as f64 / (n - 1) as f64)
        }
    };
    // The grid on which long steps are probed for events (see [`Event`]).
    let probe_spacing = probe_spacing(t_end - t0, output);
    let mut probes: Vec<f64> = Vec::new();
    let mut brackets: Vec<(f64, f64, f64, f64)> = Vec::new();
    let stopped = |flow: ControlFlow<()>| flow.is_break();
    let summary =
        |t: f64, stop: StopReason, events: usize, next_sample: usize| Summary { t, stop, events, next_sample };
    if resume.is_none() && stopped(observer(&Observation { t: t0, y: solver.state(), kind })) {
        return Ok(summary(t0, StopReason::Observer, 0, next_sample));
    }
    if t_end == t_start && resume.is_some() {
        // Resumed at the end: the samples left are all at the end.
        if let Output::Samples(n) = output {
            for k in next_sample..n {
                y.copy_from_slice(solver.state());
                if stopped(observer(&Observation { t: t_end, y: &y, kind })) {
                    return Ok(summary(t_end, StopReason::Observer, 0, k + 1));
                }
            }
            next_sample = n;
        }
        return Ok(summary(t_end, StopReason::Finished, 0, next_sample));
    }
    if t_end == t0 {
        if let Output::Samples(n) = output {
            // Degenerate span: every sample is the initial point.
            for _ in 1..n {
                y.copy_from_slice(solver.state());
                if stopped(observer(&Observation { t: t0, y: &y, kind })) {
                    return Ok(summary(t0, StopReason::Observer, 0, n));
                }
            }
        }
        return Ok(summary(t0, StopReason::Finished, 0, next_sample));
    }
    solver.set_stop_time(t_end)?;
    // A terminal event may end the run long before t_end (a shot stopped where
    // it reaches its target): then the pace to t_end foresees nothing.
    let may_end_early = events.iter().any(|e| e.terminal);
    let mut budget = Budget::new(solver, t_end, may_end_early)?;
    loop {
        let outcome = solver.step()?;
        budget.check(solver, t_end)?;
        let t_a = solver.step_start();
        let t_b = solver.t();
        if let Some(project) = project.as_mut() {
            y.copy_from_slice(solver.state());
            project(t_b, &mut y).map_err(|source| SolveError::Rhs { t: t_b, source })?;
            solver.set_state(&y)?;
        }
        // Events in this step.
        found.clear();
        probes.clear();
        if !events.is_empty() && probe_spacing > 0.0 {
            let first = ((t_a - t0) / probe_spacing).floor().max(0.0) as usize + 1;
            probes.extend((first..).map(|j| t0 + j as f64 * probe_spacing).take_while(|&t| t < t_b));
        }
        for (k, ev) in events.iter_mut().enumerate() {
            g_new[k] = eval_event(ev, k, t_b, solver.state())?;
            // Every bracket [t_a, t_b] of neighbouring probes whose sign change counts.
            brackets.clear();
            let (mut t_a, mut ga) = (t_a, g_prev[k]);
            for j in 0..=probes.len() {
                let (t_p, g_p) = match probes.get(j) {
                    Some(&t_p) => {
                        solver.prepare_dense()?;
                        solver.interpolate(t_p, &mut y)?;
                        (t_p, eval_event(ev, k, t_p, &y)?)
                    }
                    None => (t_b, g_new[k]),
                };
                if ev.direction.counts(ga, g_p) {
                    brackets.push((t_a, ga, t_p, g_p));
                }
                (t_a, ga) = (t_p, g_p);
            }
            for &(t_a, ga, t_b, gb) in &brackets {
                solver.prepare_dense()?;
                let tol = 4.0 * f64::EPSILON * t_a.abs().max(t_b.abs());
                let mut root = brent(
                    |t| {
                        solver.interpolate(t, &mut y)?;
                        eval_event(ev, k, t, &y)
                    },
                    t_a,
                    t_b,
                    ga,
                    gb,
                    tol,
                )?;
                // The interpolant's root is within its error of the method's:
                // refine it on the method's own states, in the half of the step
                // the sign there points to.
                if let Some(restepped) = solver.restep(root, &mut y) {
                    restepped?;
                    let g_root = eval_event(ev, k, root, &y)?;
                    if g_root != 0.0 {
                        let (a, b, fa, fb) = if (g_root > 0.0) == (ga > 0.0) {
                            (root, t_b, g_root, gb)
                        } else {
                            (t_a, root, ga, g_root)
                        };
                        root = brent(
                            |t| {
                                state_at(solver, t, &mut y)?;
                                eval_event(ev, k, t, &y)
                            },
                            a,
                            b,
                            fa,
                            fb,
                            tol,
                        )?;
                    }
                }
                found.push((root, k));
            }
        }
        std::mem::swap(&mut g_prev, &mut g_new);
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        // The first terminal crossing cuts the step.
        let cut = found.iter().position(|&(_, k)| events[k].terminal).map(|i| (i, found[i].0));
        let t_limit = cut.map_or(t_b, |(_, t)| t);
        let found_count = cut.map_or(found.len(), |(i, _)| i + 1);
        let mut next_event = 0;
        // Emit samples and events in time order up to t_limit.
        loop {
            let sample_t = match output {
                Output::Samples(n) if next_sample < n => {
                    let ts = sample_time(next_sample, n);
                    (ts <= t_limit).then_some(ts)
                }
                _ => None,
            };
            let event = (next_event < found_count).then(|| found[next_event]);
            let (t, obs_kind) = match (sample_t, event) {
                (Some(ts), Some((te, k))) if te < ts => (te, ObservationKind::Event { index: k }),
                (Some(ts), _) => (ts, ObservationKind::Sample),
                (None, Some((te, k))) => (te, ObservationKind::Event { index: k }),
                (None, None) => break,
            };
            match obs_kind {
                ObservationKind::Sample => next_sample += 1,
                _ => {
                    next_event += 1;
                    n_events += 1;
                }
            }
            if t == t_b {
                y.copy_from_slice(solver.state());
            } else if obs_kind == ObservationKind::Sample {
                solver.prepare_dense()?;
                solver.interpolate(t, &mut y)?;
            } else {
                state_at(solver, t, &mut y)?;
            }
            if stopped(observer(&Observation { t, y: &y, kind: obs_kind })) {
                return Ok(summary(t, StopReason::Observer, n_events, next_sample));
            }
            if let (ObservationKind::Event { index }, Some(_)) = (obs_kind, cut) {
                if events[index].terminal {
                    return Ok(summary(t, StopReason::Event { index }, n_events, next_sample));
                }
            }
        }
        if output == Output::EveryStep
            && stopped(observer(&Observation { t: t_b, y: solver.state(), kind: ObservationKind::Step }))
        {
            return Ok(summary(t_b, StopReason::Observer, n_events, next_sample));
        }
        if outcome == StepOutcome::ReachedStop {
            return Ok(summary(t_b, StopReason::Finished, n_events, next_sample));
        }
    }
}

/// The state at `t` within the last step: the method's own
/// ([`Solver::restep`]) where its dense output is of lower order, else interpolated.
fn state_at<V: Solver + ?Sized>(solver: &mut V, t: f64, y: &mut [f64]) -> Result<(), SolveError> {
    match solver.restep(t, y) {
        Some(result) => result,
        None => {
            solver.prepare_dense()?;
            solver.interpolate(t, y)
        }
    }
}

/// The step budget of one [`integrate`] call, checked by foresight (see the
/// module documentation).
struct Budget {
    /// Steps at the start of the call.
    start: usize,
    /// The most steps the solver takes.
    max_steps: usize,
    /// Steps and time at the last checkpoint, and the steps of the next one.
    last: (usize, f64),
    next: usize,
}

impl Budget {
    /// The budget of a run from the solver's state to `t_end`. A fixed step is
    /// checked at once: its steps are known. A run that `may_end_early` (at a
    /// terminal event) is held to the budget itself, not to a foresight.
    fn new<V: Solver + ?Sized>(solver: &V, t_end: f64, may_end_early: bool) -> Result<Budget, SolveError> {
        let (steps, t, max_steps) = (solver.statistics().steps, solver.t(), solver.solver_state().max_steps());
        if may_end_early {
            return Ok(Budget { start: steps, max_steps, last: (steps, t), next: usize::MAX });
        }
        if !solver.method().is_adaptive() {
            let projected = steps as f64 + (t_end - t) / solver.step_size();
            if projected > max_steps as f64 {
                return Err(SolveError::MaxStepsForeseen { t, steps, t_end, projected, max_steps });
            }
        }
        let next =
            if solver.method().is_adaptive() { steps + (max_steps / FIRST_CHECKPOINT).max(1) } else { usize::MAX };
        Ok(Budget { start: steps, max_steps, last: (steps, t), next })
    }

    /// After a step: at a checkpoint, the steps the run needs at the pace since
    /// the last one; an error when they exceed the budget by [`FORESIGHT_MARGIN`].
    fn check<V: Solver + ?Sized>(&mut self, solver: &V, t_end: f64) -> Result<(), SolveError> {
        let steps = solver.statistics().steps;
        if steps < self.next || steps >= self.max_steps {
            return Ok(());
        }
        let t = solver.t();
        let (last_steps, last_t) = self.last;
        let pace = (steps - last_steps) as f64 / (t - last_t);
        let projected = steps as f64 + (t_end - t) * pace;
        if projected > FORESIGHT_MARGIN * self.max_steps as f64 {
            return Err(SolveError::MaxStepsForeseen { t, steps, t_end, projected, max_steps: self.max_steps });
        }
        self.last = (steps, t);
        self.next = self.start + 2 * (steps - self.start);
        Ok(())
    }
}

fn eval_event(ev: &mut Event<'_>, index: usize, t: f64, y: &[f64]) -> Result<f64, SolveError> {
    let g = (ev.g)(t, y);
    if g.is_finite() {
        Ok(g)
    } else {
        Err(SolveError::EventNonFinite { event: index, t })
    }
}

/// Runs `solver` to `t_end` and writes the final state into `y_end` (no observer,
/// no events).
pub fn integrate_to<V: Solver + ?Sized>(solver: &mut V, t_end: f64, y_end: &mut [f64]) -> Result<(), SolveError> {
    check_len(solver.state().len(), y_end.len())?;
    integrate(solver, t_end, Output::EveryStep, &mut [], |_| ControlFlow::Continue(()))?;
    y_end.copy_from_slice(solver.state());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_models::Oscillator;
    use crate::{Config, Method, StepOutcome};

    /// The driver builds DOP853's interpolant only on the steps it samples in:
    /// the samples are bit for bit those of eager dense output, with fewer
    /// evaluations, and after the run the last step interpolates as usual.
    #[test]
    fn lazy_dense_output_gives_the_eager_samples_with_fewer_evaluations() {
        let config = Config { rtol: 1e-10, atol: 1e-12, ..Config::default() };
        let t_end = 20.0;
        let n = 11;
        let mut lazy = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
        let mut samples = Vec::new();
        integrate(&mut lazy, t_end, Output::Samples(n), &mut [], |o| {
            samples.push((o.t, o.y.to_vec()));
            ControlFlow::Continue(())
        })
        .unwrap();
        let mut eager = Method::Dop853.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
        eager.set_stop_time(t_end).unwrap();
        let mut y = vec![0.0; 2];
        let mut k = 1;
        loop {
            let outcome = eager.step().unwrap();
            while k < n && samples[k].0 <= eager.t() {
                if samples[k].0 == eager.t() {
                    y.copy_from_slice(eager.state());
                } else {
                    eager.interpolate(samples[k].0, &mut y).unwrap();
                }
                assert_eq!(y, samples[k].1, "sample {k} at t = {}", samples[k].0);
                k += 1;
            }
            if outcome == StepOutcome::ReachedStop {
                break;
            }
        }
        assert_eq!(k, n);
        assert_eq!(lazy.statistics().steps, eager.statistics().steps);
        assert!(
            lazy.statistics().rhs_evaluations + 2 * eager.statistics().steps < eager.statistics().rhs_evaluations,
            "{:?} vs {:?}",
            lazy.statistics(),
            eager.statistics()
        );
        // The last step's interpolant is there after the run.
        let mut mid = [0.0; 2];
        lazy.interpolate(0.5 * (lazy.step_start() + lazy.t()), &mut mid).unwrap();
        eager.interpolate(0.5 * (eager.step_start() + eager.t()), &mut y).unwrap();
        assert_eq!(mid.to_vec(), y);
        // Asked for while pending, the interpolant is an error, not stale numbers.
        lazy.set_lazy_dense(true);
        lazy.set_stop_time(t_end + 1.0).unwrap();
        lazy.step().unwrap();
        let t = 0.5 * (lazy.step_start() + lazy.t());
        assert!(matches!(lazy.interpolate(t, &mut mid), Err(SolveError::DenseOutputNotPrepared { .. })));
        lazy.prepare_dense().unwrap();
        lazy.interpolate(t, &mut mid).unwrap();
    }

    /// A run stopped at a terminal event and resumed from a fresh solver at the
    /// event's state, with its velocity reversed (a bounce off x = 0), keeps
    /// the whole run's sample grid: every sample of the uninterrupted grid is
    /// observed once, in order, and the samples after the bounce are the
    /// reflected oscillator's, |x| = |sin t|.
    #[test]
    fn a_resumed_run_keeps_the_grid_of_the_whole_run() {
        let config = Config { rtol: 1e-12, atol: 1e-12, ..Config::default() };
        let (t_end, n) = (5.0, 51);
        let mut solver = Method::Dop853.build(Oscillator, 0.0, &[0.0, -1.0], &config).unwrap();
        let mut times = Vec::new();
        let mut xs = Vec::new();
        let mut event_state = vec![0.0; 2];
        let mut events = [Event::new(|_, y: &[f64]| y[0] + 0.5).with_direction(Direction::Falling).with_terminal(true)];
        let first = integrate(&mut solver, t_end, Output::Samples(n), &mut events, |o| {
            match o.kind {
                ObservationKind::Event { .. } => event_state.copy_from_slice(o.y),
                _ => {
                    times.push(o.t);
                    xs.push(o.y[0]);
                }
            }
            ControlFlow::Continue(())
        })
        .unwrap();
        // x = −sin t reaches −1/2 at t = π/6.
        assert!((first.t - std::f64::consts::FRAC_PI_6).abs() < 1e-10, "{first:?}");
        assert_eq!(first.stop, StopReason::Event { index: 0 });
        assert_eq!(first.next_sample, times.len());
        event_state[1] = -event_state[1];
        let mut fresh = Method::Dop853.build(Oscillator, first.t, &event_state, &config).unwrap();
        let resume = Resume { t0: 0.0, next_sample: first.next_sample };
        // (It would cross x = −1/2 falling again at t = 3π/2: no events now.)
        let second = integrate_resumed(&mut fresh, t_end, Output::Samples(n), resume, &mut [], |o| {
            times.push(o.t);
            xs.push(o.y[0]);
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(second.stop, StopReason::Finished);
        assert_eq!(second.next_sample, n);
        let grid: Vec<f64> =
            (0..n).map(|k| if k + 1 == n { t_end } else { t_end * (k as f64 / (n - 1) as f64) }).collect();
        assert_eq!(times, grid);
        // After the bounce: x = −sin(π/3 − t) (the reflected motion), i.e. x(π/6) = −1/2 rising.
        for (&t, &x) in times.iter().zip(&xs).filter(|(&t, _)| t > first.t) {
            let expected = -(std::f64::consts::FRAC_PI_3 - t).sin();
            assert!((x - expected).abs() < 1e-9, "t = {t}: {x} vs {expected}");
        }
    }

    /// Over 100 periods the projection keeps x² + v² = 1 at round-off, where the
    /// plain run drifts by the accumulated local errors; both stay on the solution.
    #[test]
    fn a_projection_after_each_step_keeps_the_invariant_at_round_off() {
        let config = Config { rtol: 1e-6, atol: 1e-9, ..Config::default() };
        let t_end = 200.0 * std::f64::consts::PI;
        let radius_error = |projected: bool, method: Method| {
            let mut solver = method.build(Oscillator, 0.0, &[1.0, 0.0], &config).unwrap();
            let mut worst = 0.0f64;
            let mut observe = |o: &Observation<'_>| {
                worst = worst.max((o.y[0].hypot(o.y[1]) - 1.0).abs());
                ControlFlow::Continue(())
            };
            let mut project = |_t: f64, y: &mut [f64]| {
                let r = y[0].hypot(y[1]);
                y[0] /= r;
                y[1] /= r;
                Ok(())
            };
            let summary = if projected {
                integrate_projected(&mut solver, t_end, Output::EveryStep, &mut [], &mut project, &mut observe)
            } else {
                integrate(&mut solver, t_end, Output::EveryStep, &mut [], &mut observe)
            }
            .unwrap();
            assert_eq!(summary.stop, StopReason::Finished);
            assert!((solver.state()[0] - 1.0).abs() < 1e-3, "{method}: back at x = 1 after 100 periods");
            worst
        };
        for method in [Method::Dop853, Method::Dopri5] {
            let plain = radius_error(false, method);
            let projected = radius_error(true, method);
            assert!(plain > 1e-8, "{method}: the plain run drifts ({plain:e})");
            assert!(projected < 4.0 * f64::EPSILON, "{method}: projected runs stay on the circle ({projected:e})");
        }
        // Methods that carry more than the state from step to step refuse.
        let mut gauss =
            Method::Gauss4.build(Oscillator, 0.0, &[1.0, 0.0], &Config { dt: Some(0.1), ..config }).unwrap();
        let mut project = |_t: f64, _y: &mut [f64]| Ok(());
        let err = integrate_projected(&mut gauss, 1.0, Output::EveryStep, &mut [], &mut project, |_| {
            ControlFlow::Continue(())
        });
        assert!(matches!(err, Err(SolveError::RestartUnsupported { method: "gauss4" })), "{err:?}");
    }
}
