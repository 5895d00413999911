//! Many trajectories in lock step: the Taylor method on [`LANES`] lanes at
//! once, for sweeps.
//!
//! Each lane is an independent trajectory with its own time, step (the step
//! rule of [`num::Taylor`], per lane) and end time; one expansion of the
//! [`LagrangeSeries`] serves all lanes, and its native code handles as many
//! lanes per instruction as the processor's vectors hold (two with cranelift). [`propagate`] returns as soon as a lane reaches its end
//! time, so that the caller can give the lane its next segment or its next
//! trajectory; a lane at its end time idles (step 0) until then, and a lane
//! whose expansion stops being finite is frozen with its failure while the
//! others go on.

use crate::run::series::LagrangeSeries;
use num::lanes;
use num::{taylor_advance, taylor_step, Config};
use sym::Lanes;

/// Trajectories per batch.
pub(crate) const LANES: usize = 8;

/// The state of a batch of trajectories: `y[i]` is component `i` on every lane.
#[derive(Debug, Clone)]
pub(crate) struct Batch {
    pub(crate) t: Lanes<LANES>,
    pub(crate) y: Vec<Lanes<LANES>>,
    /// Why a lane stopped early (None: still going).
    pub(crate) failure: [Option<String>; LANES],
    pub(crate) steps: [usize; LANES],
}

impl Batch {
    /// A batch at t = 0 from each lane's state (`states[lane]`; missing lanes
    /// repeat the first state, and are never read back).
    pub(crate) fn new(states: &[Vec<f64>]) -> Batch {
        let dim = states[0].len();
        let y = (0..dim).map(|i| std::array::from_fn(|l| states.get(l).unwrap_or(&states[0])[i])).collect();
        Batch { t: [0.0; LANES], y, failure: Default::default(), steps: [0; LANES] }
    }

    /// The state of one lane.
    pub(crate) fn state(&self, lane: usize) -> Vec<f64> {
        self.y.iter().map(|c| c[lane]).collect()
    }

    /// Sets the state of one lane.
    pub(crate) fn set_state(&mut self, lane: usize, state: &[f64]) {
        for (c, &v) in self.y.iter_mut().zip(state) {
            c[lane] = v;
        }
    }
}

/// Advances the live lanes of `batch` (not failed, before their end time
/// `t_end[lane]`) with the Taylor method (`series` on [`LANES`] lanes, its
/// order chosen from `config.rtol`) until one of them reaches its end time or
/// fails, or none is live.
pub(crate) fn propagate(
    series: &mut LagrangeSeries<LANES>,
    batch: &mut Batch,
    t_end: &[f64; LANES],
    config: &Config,
    scratch: &mut Vec<Lanes<LANES>>,
) {
    let p = series.order();
    let dim = batch.y.len();
    let len = dim * (p + 1);
    // The series, then the state before the step (to go back to).
    scratch.resize(len + dim, [0.0; LANES]);
    let live_lanes = |batch: &Batch| -> [bool; LANES] {
        std::array::from_fn(|l| batch.failure[l].is_none() && batch.t[l] < t_end[l])
    };
    let not_finite =
        |t: f64| format!("right-hand side failed at t = {t}: the Taylor series is not finite", t = num::Shortest(t));
    let mut live = live_lanes(batch);
    while live.contains(&true) {
        let (coefficients, before) = scratch.split_at_mut(len);
        if let Err(e) = series.expand(batch.t, &batch.y, coefficients) {
            for l in (0..LANES).filter(|&l| live[l]) {
                batch.failure[l] = Some(format!("right-hand side failed at t = {}: {e}", batch.t[l]));
            }
            return;
        }
        // Per lane: the ratios of the last two orders to the state (component by
        // component, see `num::taylor_ratio`).
        let (before_last, last) = lanes::ratios(coefficients, dim, p, config.atol / config.rtol);
        let mut h = [0.0; LANES];
        let mut lands_on_end = [false; LANES];
        for l in 0..LANES {
            if !live[l] {
                continue;
            }
            // Whether every coefficient is finite is read only where the
            // ratios are not, or before the last step allowed; a non-finite
            // coefficient elsewhere shows in the state after the step, which
            // is then undone below.
            let suspect = !(before_last[l].is_finite() && last[l].is_finite()) || batch.steps[l] >= config.max_steps;
            if suspect && !lanes::finite(coefficients, dim, p, l) {
                batch.failure[l] = Some(not_finite(batch.t[l]));
                continue;
            }
            if batch.steps[l] >= config.max_steps {
                batch.failure[l] = Some(format!(
                    "maximal number of steps ({}) reached at t = {}",
                    config.max_steps,
                    num::Shortest(batch.t[l])
                ));
                continue;
            }
            // The step rule of `num::Taylor`, so that a lane takes a single run's steps.
            let step = taylor_step(p, before_last[l], last[l]);
            match taylor_advance(step, batch.t[l], config.h_max.unwrap_or(f64::INFINITY), Some(t_end[l])) {
                Ok((step, lands)) => (h[l], lands_on_end[l]) = (step, lands),
                Err(step) => {
                    batch.failure[l] =
                        Some(format!("step size {step:e} too small at t = {}", num::Shortest(batch.t[l])))
                }
            }
        }
        // Horner's rule on every lane; a lane that does not step (h = 0) keeps
        // its state, as does one whose series turns out not to be finite.
        before.copy_from_slice(&batch.y);
        lanes::horner(coefficients, dim, p, &h, &mut batch.y);
        for l in 0..LANES {
            let keep = h[l] == 0.0
                || (batch.y.iter().any(|c| !c[l].is_finite()) && {
                    let finite = lanes::finite(coefficients, dim, p, l);
                    batch.failure[l] = Some(if finite {
                        let t = if lands_on_end[l] { t_end[l] } else { batch.t[l] + h[l] };
                        format!("the state became non-finite at t = {t}", t = num::Shortest(t))
                    } else {
                        not_finite(batch.t[l])
                    });
                    !finite
                });
            if keep {
                for (y, old) in batch.y.iter_mut().zip(before.iter()) {
                    y[l] = old[l];
                }
            } else {
                batch.steps[l] += 1;
                batch.t[l] = if lands_on_end[l] { t_end[l] } else { batch.t[l] + h[l] };
            }
        }
        let after = live_lanes(batch);
        if (0..LANES).any(|l| live[l] && !after[l]) {
            return;
        }
        live = after;
    }
}
