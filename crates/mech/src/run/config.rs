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

/// A run's settings as a front end receives them (the CLI's flags, Python's
/// keyword arguments, the browser's options), before defaults and checks:
/// [`RunConfig::from_settings`] makes them a configuration.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunSettings<'a> {
    /// End time; None for the default.
    pub until: Option<f64>,
    /// A method's name (`--list-methods`); None for the derivation's choice.
    pub method: Option<&'a str>,
    /// Relative tolerance; None for the default.
    pub rtol: Option<f64>,
    /// Absolute tolerance; None for the default (see [`RunConfig::from_settings`]).
    pub atol: Option<f64>,
    /// A fixed step, for fixed-step methods.
    pub dt: Option<f64>,
    /// Output rows, both ends included; None for the default.
    pub samples: Option<usize>,
    /// A row at every step instead of samples.
    pub every_step: bool,
}

/// A setting [`RunConfig::from_settings`] refuses, for the front end to name
/// in its own terms (`--rtol` in the CLI, `rtol=` in Python).
#[derive(Debug, Clone, PartialEq)]
pub enum SettingError {
    /// No method has that name: the message lists the known ones.
    UnknownMethod(String),
    /// `rtol`, `atol` or `dt` (the setting's bare name) is not a positive,
    /// finite number.
    NotPositive {
        /// `rtol`, `atol` or `dt`.
        setting: &'static str,
        /// What was given.
        value: f64,
    },
    /// Fewer than two output rows: a run writes both ends.
    TooFewSamples {
        /// What was given.
        samples: usize,
    },
}

impl SettingError {
    /// The method a setting names, if any ([`SettingError::UnknownMethod`] when none has that name).
    pub(crate) fn method(name: Option<&str>) -> Result<Option<Method>, SettingError> {
        name.map(|n| n.parse::<Method>().map_err(|e| SettingError::UnknownMethod(e.to_string()))).transpose()
    }

    /// Each setting given is a positive, finite number ([`SettingError::NotPositive`] at the first that is not).
    pub(crate) fn positive(settings: &[(&'static str, Option<f64>)]) -> Result<(), SettingError> {
        match settings
            .iter()
            .find_map(|&(setting, value)| value.filter(|v| !(v.is_finite() && *v > 0.0)).map(|v| (setting, v)))
        {
            Some((setting, value)) => Err(SettingError::NotPositive { setting, value }),
            None => Ok(()),
        }
    }
}

impl RunConfig {
    /// The configuration of `settings`, the defaults where they are silent: the
    /// one place that checks a front end's settings and fills them in. `atol`
    /// defaults to `rtol`/1000 when only `rtol` is given (the pair then asks for
    /// three more digits near zero than elsewhere), and to the default
    /// otherwise. What needs the model (stop conditions, initial values) and
    /// what needs the output (`check`) come after.
    pub fn from_settings(settings: &RunSettings<'_>) -> Result<RunConfig, SettingError> {
        let method = SettingError::method(settings.method)?;
        SettingError::positive(&[("rtol", settings.rtol), ("atol", settings.atol), ("dt", settings.dt)])?;
        let defaults = RunConfig::default();
        let output = match (settings.every_step, settings.samples) {
            (true, _) => Output::EveryStep,
            (false, Some(samples)) if samples < 2 => return Err(SettingError::TooFewSamples { samples }),
            (false, Some(n)) => Output::Samples(n),
            (false, None) => defaults.output,
        };
        let rtol = settings.rtol.unwrap_or(defaults.rtol);
        Ok(RunConfig {
            until: settings.until.unwrap_or(defaults.until),
            method,
            rtol,
            atol: settings.atol.unwrap_or(if settings.rtol.is_some() { rtol * 1e-3 } else { defaults.atol }),
            dt: settings.dt,
            output,
            ..defaults
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_get_the_defaults_and_atol_follows_a_given_rtol() {
        let defaults = RunConfig::default();
        let c = RunConfig::from_settings(&RunSettings::default()).unwrap();
        assert_eq!(
            (c.until, c.rtol, c.atol, c.method, c.dt),
            (defaults.until, defaults.rtol, defaults.atol, None, None)
        );
        let c = RunConfig::from_settings(&RunSettings { rtol: Some(1e-6), ..RunSettings::default() }).unwrap();
        assert_eq!((c.rtol, c.atol), (1e-6, 1e-6 * 1e-3));
        let c = RunConfig::from_settings(&RunSettings { rtol: Some(1e-6), atol: Some(1e-7), ..RunSettings::default() })
            .unwrap();
        assert_eq!(c.atol, 1e-7);
        let c = RunConfig::from_settings(&RunSettings {
            until: Some(3.0),
            method: Some("DOP853"),
            every_step: true,
            samples: Some(1),
            ..RunSettings::default()
        })
        .unwrap();
        assert_eq!((c.until, c.method, c.output), (3.0, Some(Method::Dop853), Output::EveryStep));
    }

    #[test]
    fn bad_settings_are_refused_by_name() {
        let refused = |s: RunSettings<'_>| RunConfig::from_settings(&s).unwrap_err();
        assert_eq!(
            refused(RunSettings { atol: Some(0.0), ..RunSettings::default() }),
            SettingError::NotPositive { setting: "atol", value: 0.0 }
        );
        assert!(matches!(
            refused(RunSettings { dt: Some(f64::NAN), ..RunSettings::default() }),
            SettingError::NotPositive { setting: "dt", .. }
        ));
        assert_eq!(
            refused(RunSettings { samples: Some(1), ..RunSettings::default() }),
            SettingError::TooFewSamples { samples: 1 }
        );
        match refused(RunSettings { method: Some("rk4"), ..RunSettings::default() }) {
            SettingError::UnknownMethod(message) => assert!(message.contains("dop853"), "{message}"),
            other => panic!("{other:?}"),
        }
    }
}
