//! What a model must be at numbers: the checks that depend on the parameters'
//! values (a body's mass is positive, its inertia a rigid body's, a hinge axis
//! has a direction) and on the start (a rolling wheel's axle is not vertical,
//! an input is finite at t = 0).
//!
//! Reading a model records each check with its place ([`ValueCheck`]) and runs
//! it at the file's values (with `--set` applied); a run runs the start
//! checks at its start (`simulate`, after `--start`; `linearize` at its
//! start); a sweep runs
//! them all again for each row's parameter values and start
//! ([`crate::Model::check_values`]), so that a value `--set` refuses is that
//! row's failure rather than a run of a model that is not one.

use crate::error::ModelError;
use std::ops::Range;
use sym::{ExprId, Pool};

/// One check, with the place in the file the error points at.
#[derive(Debug, Clone)]
pub struct ValueCheck {
    /// What must hold.
    pub kind: CheckKind,
    /// Where the checked value is written.
    pub span: Range<usize>,
}

/// What must hold, of expressions in the parameters (and, for the start
/// checks, the coordinates and t at the start).
#[derive(Debug, Clone)]
pub enum CheckKind {
    /// A body's mass: positive.
    Mass(ExprId),
    /// The one moment of inertia of a body turning about one axis: ≥ 0.
    Moment(ExprId),
    /// An inertia tensor: a rigid body's (symmetric, principal moments ≥ 0,
    /// each at most the sum of the other two).
    Tensor([[ExprId; 3]; 3]),
    /// A hinge axis as written: a direction (its length is not 0).
    Axis([ExprId; 3]),
    /// At the start: the rolling contact `name`'s wheel axle is not vertical;
    /// `tilt` is 1 − e_z², e the axle in space, an expression of (q, t).
    Axle {
        /// The rolling contact's name.
        name: String,
        /// 1 − e_z².
        tilt: ExprId,
    },
    /// At the start: the input `name` (`[inputs]`) is finite at t = 0, where
    /// every run starts and about which linearize holds it.
    Input {
        /// The input's name.
        name: String,
        /// Its value, an expression of t and the parameters.
        value: ExprId,
    },
    /// The impact `name`'s coefficient of restitution: in [0, 1].
    Restitution {
        /// The impact's name.
        name: String,
        /// e, an expression of the parameters.
        e: ExprId,
    },
    /// At the start: the impact `name`'s surface φ(q, t) is not crossed, φ ≥ 0.
    Surface {
        /// The impact's name.
        name: String,
        /// φ, an expression of (q, t).
        phi: ExprId,
    },
}

impl ValueCheck {
    /// Whether the check needs the start (coordinates and t), not only the parameters.
    pub fn at_start(&self) -> bool {
        matches!(self.kind, CheckKind::Axle { .. } | CheckKind::Input { .. } | CheckKind::Surface { .. })
    }

    /// Runs the check; `env` gives the parameters (and, for a start check,
    /// the coordinates and t). A value that does not evaluate is left to the
    /// check that reads it.
    pub fn run(&self, pool: &Pool, env: &dyn Fn(&str) -> Option<f64>) -> Result<(), ModelError> {
        let value = |e: ExprId| pool.eval(e, env).ok();
        let at = || self.span.clone();
        match &self.kind {
            CheckKind::Mass(m) => match value(*m) {
                Some(m) if m.is_nan() || m <= 0.0 => {
                    Err(ModelError::at(at(), format!("the body's mass must be positive, not {}", num::Shortest(m))))
                }
                _ => Ok(()),
            },
            CheckKind::Moment(i) => {
                let m = value(*i).unwrap_or(f64::NAN);
                if m.is_nan() || m < 0.0 {
                    return Err(ModelError::at(at(), format!("the moment of inertia must be ≥ 0, not {}", num::Shortest(m))));
                }
                Ok(())
            }
            CheckKind::Tensor(t) => {
                let num = t.map(|row| row.map(|x| value(x).unwrap_or(f64::NAN)));
                if !num.iter().flatten().all(|v| v.is_finite()) {
                    return Ok(());
                }
                physical(&num).map_err(|why| {
                    ModelError::at(
                        at(),
                        format!("the inertia tensor {num:?} is not a rigid body's at the parameters' values: {why}"),
                    )
                    .with_help("principal moments are ≥ 0 and each is at most the sum of the other two (a thin rod has one zero moment)")
                })
            }
            CheckKind::Axis(v) => {
                let size: Option<f64> = v.iter().map(|&c| value(c).map(|x| x * x)).sum::<Option<f64>>().map(f64::sqrt);
                if size.is_some_and(|n| !(n > MIN_AXIS_LENGTH && n.is_finite())) {
                    return Err(ModelError::at(at(), "the axis has no direction (its length is 0)")
                        .with_help("give a non-zero vector; it is normalized"));
                }
                Ok(())
            }
            CheckKind::Axle { name, tilt } => match value(*tilt) {
                Some(s2) if s2.is_nan() || s2 <= MIN_AXLE_TILT => Err(ModelError::at(
                    at(),
                    format!(
                        "the wheel of rolling contact '{name}' lies flat at the start (its axle is vertical): its rim has no lowest point to roll on"
                    ),
                )
                .with_help("start the wheel upright or leaning (axle not along z); a wheel lying flat does not roll")),
                _ => Ok(()),
            },
            CheckKind::Input { name, value: u } => {
                let v = pool.eval(*u, env).unwrap_or(f64::NAN);
                if v.is_finite() {
                    return Ok(());
                }
                let how = if v.is_nan() { "has no real value" } else { "is infinite" };
                Err(ModelError::at(
                    at(),
                    format!(
                        "the input '{name}' {how} at t = 0: runs start at t = 0 and linearize holds the inputs at their values there (no option starts later)"
                    ),
                )
                .with_help("give the input a value that is finite at t = 0, e.g. shifted in time: 1/(t + 1) rather than 1/t"))
            }
            CheckKind::Restitution { name, e } => match value(*e) {
                Some(e) if !(0.0..=1.0).contains(&e) => Err(ModelError::at(
                    at(),
                    format!("the restitution of impact '{name}' must be between 0 and 1, not {}", num::Shortest(e)),
                )
                .with_help("e = 1 is an elastic bounce (no energy lost), e = 0 a plastic one (the normal velocity lost)")),
                _ => Ok(()),
            },
            CheckKind::Surface { name, phi } => match value(*phi) {
                Some(phi) if phi.is_nan() || phi < 0.0 => Err(ModelError::at(
                    at(),
                    format!(
                        "the start is on the wrong side of the surface of impact '{name}': the surface is {} there, and the motion keeps it ≥ 0",
                        num::Shortest(phi)
                    ),
                )
                .with_help("start where the surface expression is ≥ 0 (change [initial]), or write the surface with the other sign")),
                _ => Ok(()),
            },
        }
    }
}

/// The shortest hinge axis taken for a direction: shorter, normalizing it
/// divides by a length that is round-off.
pub(crate) const MIN_AXIS_LENGTH: f64 = 1e-12;

/// The smallest 1 − e_z² (sin² of the axle's angle to the vertical) at which
/// the contact point R·d, with d dividing by √(1 − e_z²), is taken as defined:
/// at 1e-12 the axle is within 1e-6 rad of vertical and d is round-off.
const MIN_AXLE_TILT: f64 = 1e-12;

/// Whether `m` is a rigid body's inertia tensor: symmetric, its principal
/// moments ≥ 0 and each at most the sum of the other two (to rounding).
pub(crate) fn physical(m: &[[f64; 3]; 3]) -> Result<(), String> {
    let scale = m.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
    let tol = 1e-12 * scale;
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if (m[i][j] - m[j][i]).abs() > tol {
            return Err(format!("I{}{} ≠ I{}{}", i + 1, j + 1, j + 1, i + 1));
        }
    }
    let moments = nalgebra::Matrix3::from_fn(|i, j| m[i][j]).symmetric_eigenvalues();
    let (a, b, c) = (moments[0], moments[1], moments[2]);
    if let Some(&negative) = [a, b, c].iter().find(|&&x| x < -tol) {
        return Err(format!("a principal moment is negative ({})", num::Shortest(negative)));
    }
    if scale == 0.0 {
        return Ok(());
    }
    for (x, y, z) in [(a, b, c), (b, c, a), (c, a, b)] {
        if x > y + z + tol {
            let [x, y, z] = [x, y, z].map(num::Shortest);
            return Err(format!("the principal moment {x} exceeds the sum of the other two ({y} + {z})"));
        }
    }
    Ok(())
}
