//! The settings of a run ([`RunConfig`]) and its stop conditions
//! ([`StopCondition`]), with the checks a run makes of them before it starts.

use crate::derive::Derivation;
use crate::error::ModelError;
use num::{Direction, Method, Output};
use sym::Tape;

use super::report::RunError;

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
    /// The integrator's settings for this run: its tolerances, its step (`dt`),
    /// its end as the longest step, and its step budget. The one copy from a
    /// run's settings to `num::Config`; a caller adds what only it knows (the
    /// Taylor look-ahead).
    pub(crate) fn solver_config(&self) -> num::Config {
        num::Config {
            rtol: self.rtol,
            atol: self.atol,
            dt: self.dt,
            h_max: Some(self.until),
            max_steps: self.max_steps,
            ..num::Config::default()
        }
    }

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
