//! The Lyapunov twin of a run (Benettin's method, see the module
//! documentation of `sweep`): its start, its segments, its pull-back.

use super::{LYAPUNOV_D0, LYAPUNOV_INTERVAL};
use crate::run::dynamics::System;
use num::Solver;

/// The Lyapunov twin's integrator: one solver restarted every segment, or the
/// system to build a fresh one on.
pub(super) enum Twin<'a> {
    Kept(Box<dyn Solver + 'a>),
    Fresh(&'a mut System),
}

/// `y0` moved by [`LYAPUNOV_D0`] along the unit vector with equal components.
pub(super) fn perturbed(y0: &[f64]) -> Vec<f64> {
    let step = LYAPUNOV_D0 / (y0.len() as f64).sqrt();
    y0.iter().map(|v| v + step).collect()
}

/// The end of Lyapunov segment `segment` (counted from 1): a last sliver
/// shorter than a millionth of a segment joins the one before.
pub(super) fn segment_end(segment: u32, until: f64) -> f64 {
    let t = f64::from(segment) * LYAPUNOV_INTERVAL;
    if t > until - 1e-6 * LYAPUNOV_INTERVAL {
        until
    } else {
        t
    }
}

/// Benettin's renormalization at the end of a segment at `t`: pulls `twin`
/// back to [`LYAPUNOV_D0`] from `main` along their difference and returns
/// `ln(d/d0)`, or why it cannot (the distance became zero or not finite).
pub(super) fn pull_back(main: &[f64], twin: &mut [f64], t: f64) -> Result<f64, String> {
    let dist = distance(main, twin);
    if !(dist > 0.0 && dist.is_finite()) {
        return Err(format!("the perturbed twin's distance became {dist} at t = {t}", t = num::Shortest(t)));
    }
    for (tk, yk) in twin.iter_mut().zip(main) {
        *tk = yk + (*tk - yk) * (LYAPUNOV_D0 / dist);
    }
    Ok((dist / LYAPUNOV_D0).ln())
}

/// The Euclidean distance of two states.
pub(super) fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}
