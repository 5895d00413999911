//! Choosing the step of a fixed-step method from a tolerance ([`select_step`]): step
//! doubling (Richardson extrapolation) at the start of the run.
//!
//! One step of `h` (local error `C·h^(p+1)` for a method of order `p`) and two steps
//! of `h/2` (error `2·C·(h/2)^(p+1)`) differ by `(1 − 2^(−p))·C·h^(p+1)`, so the
//! difference times `2^p/(2^p − 1)` estimates the local error of the step `h`. The step is scaled by
//! `0.9·err^(−1/(p+1))` until the scaled local error (weighted like the adaptive
//! methods, `atol + rtol·|y|`, RMS norm) lies in `[0.2, 1]`: the fixed step then
//! meets the tolerance per step the way an adaptive method would *at the start*.
//! States visited later may need smaller steps; check invariants along the run.

use crate::adaptive::{first_step, StepControl};
use crate::error::SolveError;
use crate::solver::{check_len, Config, Solver, Statistics};
use crate::system::OdeSystem;

/// An initial step guess for a method of order `order` (Hairer's `hinit`).
pub(crate) fn guess_step<S: OdeSystem + ?Sized>(
    system: &mut S,
    order: u32,
    t0: f64,
    y0: &[f64],
    config: &Config,
) -> Result<f64, SolveError> {
    if let Some(h) = config.h_init {
        return Ok(h);
    }
    let n = y0.len();
    let control = StepControl::new(config, order, 0.2, 10.0);
    let (mut f0, mut y1, mut f1) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut stats = Statistics::default();
    first_step(system, &control, order, None, t0, y0, &mut f0, &mut y1, &mut f1, &mut stats)
}

/// Picks a fixed step for a method of order `order` so that the estimated local error
/// per step meets `config.rtol`/`config.atol` (see the module documentation).
///
/// `run(h, steps, out)` must build a fresh solver at the initial state `y0` with step
/// `h`, take `steps` steps and write the state into `out` ([`run_fixed`] does the
/// stepping); `h_guess` is the first trial. The step is capped by `config.h_max`. At
/// most 40 trials (each three steps) are made.
pub fn select_step(
    mut run: impl FnMut(f64, usize, &mut [f64]) -> Result<(), SolveError>,
    order: u32,
    y0: &[f64],
    config: &Config,
    h_guess: f64,
) -> Result<f64, SolveError> {
    config.validate()?;
    if !(h_guess.is_finite() && h_guess > 0.0) {
        return Err(SolveError::InvalidConfig {
            name: "h_guess",
            value: h_guess,
            reason: "must be finite and positive",
        });
    }
    let h_max = config.h_max.unwrap_or(f64::INFINITY);
    let rtol = config.rtol.max(100.0 * f64::EPSILON);
    let p = f64::from(order);
    // Local error of the step h from the difference (see the module documentation).
    let richardson = 1.0 - 2f64.powi(-(order as i32));
    let n = y0.len();
    let mut y_big = vec![0.0; n];
    let mut y_small = vec![0.0; n];
    let mut h = h_guess.min(h_max);
    let mut best: Option<f64> = None;
    let mut last_error = None;
    for _ in 0..40 {
        let err = (|| -> Result<f64, SolveError> {
            run(h, 1, &mut y_big)?;
            run(0.5 * h, 2, &mut y_small)?;
            let mut sum = 0.0;
            for i in 0..n {
                let sk = config.atol + rtol * y0[i].abs().max(y_small[i].abs());
                sum += ((y_big[i] - y_small[i]) / richardson / sk).powi(2);
            }
            Ok((sum / n as f64).sqrt())
        })();
        let err = match err {
            Ok(e) if e.is_finite() => e,
            // A step so large that the solver fails or blows up: shrink hard.
            Ok(_) => {
                h *= 0.1;
                continue;
            }
            Err(e) => {
                last_error = Some(e);
                h *= 0.1;
                continue;
            }
        };
        let factor = if err == 0.0 { 10.0 } else { (0.9 * err.powf(-1.0 / (p + 1.0))).clamp(0.1, 10.0) };
        if err <= 1.0 {
            best = Some(best.map_or(h, |b: f64| b.max(h)));
            if err >= 0.2 || h >= h_max {
                return Ok(h);
            }
            let next = (h * factor).min(h_max);
            if next <= h {
                return Ok(h);
            }
            h = next;
        } else {
            if let Some(b) = best {
                // Between an accepted and a rejected step: take the accepted one.
                if h * factor <= b {
                    return Ok(b);
                }
            }
            h *= factor;
        }
        if h < 1e-300 {
            break;
        }
    }
    match (best, last_error) {
        (Some(b), _) => Ok(b),
        (None, Some(e)) => Err(e),
        (None, None) => Err(SolveError::StepSizeTooSmall { t: 0.0, h }),
    }
}

/// Takes `steps` steps with a freshly built solver and writes its state into `out`:
/// the stepping half of a [`select_step`] trial.
pub fn run_fixed<V: Solver>(solver: Result<V, SolveError>, steps: usize, out: &mut [f64]) -> Result<(), SolveError> {
    let mut solver = solver?;
    check_len(solver.state().len(), out.len())?;
    for _ in 0..steps {
        solver.step()?;
    }
    out.copy_from_slice(solver.state());
    Ok(())
}
