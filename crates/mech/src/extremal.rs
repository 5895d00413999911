//! Extremals of functionals (notes, Sec. 2.1 and appendix A.2): for
//! `J[y] = ∫_{x0}^{x1} f(y, y', x) dx` with both ends fixed, the Euler
//! equation, Beltrami's first integral, the extremal path solved as a
//! boundary-value problem, its value against the straight line, and the second
//! variation (Legendre's condition and conjugate points from the Jacobi equation).
//!
//! Entry point: [`extremal`], which reads a [`Problem`] and returns an
//! [`ExtremalReport`]. The submodules do one thing each: `problem` reads the
//! file, `euler` derives the equations symbolically, `bvp` finds every
//! extremal through both ends (and the Jacobi field along it); `num::tanh_sinh`
//! integrates f along the straight line.

mod bvp;
mod euler;
mod problem;

pub use bvp::{Candidate, Start};
pub use euler::{Euler, EulerError};
pub use problem::Problem;

use crate::error::ModelError;
use bvp::{Numeric, SolveFailure};
use rustc_hash::FxHashMap;
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;
use sym::ExprId;

/// Relative tolerance of J along the straight line: the value is compared with
/// the extremal's, which is integrated along the shot to about this accuracy, and
/// tanh-sinh reaches it in a few halvings even with an endpoint singularity.
const STRAIGHT_LINE_RTOL: f64 = 1e-14;

/// The `format` of the JSON report.
pub const EXTREMAL_FORMAT: &str = "lagrange.extremal/1";

/// Options of [`extremal`].
#[derive(Debug, Clone, Copy)]
pub struct ExtremalConfig {
    /// Evaluate the second variation (Legendre and Jacobi).
    pub check_minimum: bool,
    /// Points of the reported path (both ends included). Default 201.
    pub points: usize,
}

impl Default for ExtremalConfig {
    fn default() -> Self {
        ExtremalConfig { check_minimum: false, points: 201 }
    }
}

/// One extremal through both end points.
#[derive(Debug, Clone, Serialize)]
pub struct ExtremalSummary {
    /// J on it.
    pub value: f64,
    /// The angle of its tangent at the start, in radians (π/2: vertical).
    pub start_angle: f64,
    /// y' at the start (null when vertical).
    pub start_slope: Option<f64>,
    /// The first point conjugate to the start (its x), if any.
    pub conjugate_point: Option<f64>,
}

/// The second variation along the chosen extremal.
#[derive(Debug, Clone, Serialize)]
pub struct SecondVariation {
    /// Legendre holds (P > 0 along the path) and there is no conjugate point.
    pub minimum: bool,
    /// The x of the first point conjugate to the start in (x0, x1], if any.
    pub conjugate_point: Option<f64>,
    /// P = f_{y'y'} > 0 at every point of the path (where y' is finite).
    pub legendre: bool,
    /// The smallest P on the path.
    pub legendre_min: f64,
    /// The largest P on the path.
    pub legendre_max: f64,
    /// True when the Jacobi field was followed from the end (the start is singular
    /// and the end regular): then `conjugate_point` is conjugate to the end.
    pub from_end: bool,
}

/// Everything `lagrange extremal` reports (the JSON contract `lagrange.extremal/1`).
#[derive(Debug, Clone, Serialize)]
pub struct ExtremalReport {
    /// `lagrange.extremal/1`.
    pub format: &'static str,
    /// The problem's name.
    pub name: String,
    /// The independent variable.
    pub independent: String,
    /// The unknown.
    pub unknown: String,
    /// f(y, y', x).
    pub integrand: String,
    /// Parameter values.
    pub parameters: BTreeMap<String, f64>,
    /// `{"start": [x0, y0], "end": [x1, y1]}`.
    pub boundary: BTreeMap<&'static str, [f64; 2]>,
    /// ∂f/∂y − d/dx ∂f/∂y', simplified (vanishes on extremals).
    pub euler_equation: String,
    /// y'' solved from the Euler equation.
    pub acceleration: String,
    /// y'·∂f/∂y' − f when f has no x, else null.
    pub first_integral: Option<String>,
    /// Its value on the extremal.
    pub first_integral_constant: Option<f64>,
    /// Its largest deviation along the computed path (a check of the solver).
    pub first_integral_drift: Option<f64>,
    /// P = f_{y'y'}.
    pub legendre: String,
    /// Q = f_{yy} − d/dx f_{yy'} (Jacobi equation d/dx(P h') − Q h = 0).
    pub jacobi_q: String,
    /// J on the chosen (lowest) extremal.
    pub value: f64,
    /// J on the straight line between the ends.
    pub straight_line_value: f64,
    /// The chosen extremal, from start to end.
    pub path: Vec<[f64; 2]>,
    /// Every extremal found through both ends, lowest value first.
    pub extremals: Vec<ExtremalSummary>,
    /// `"regular"`, or `"singular_start"` / `"singular_end"` when f or y'' is
    /// infinite at that end (the extremal leaves it by a local series).
    pub endpoints: &'static str,
    /// For a singular end: the tangent angle there and the exponent λ of `φ − φ0 ∝ s^λ`.
    pub departure: Option<[f64; 2]>,
    /// Distance of the computed path's end from the end point.
    pub end_residual: f64,
    /// Family members integrated to find the extremals.
    pub shots: usize,
    /// Members that ran out of steps before reaching the end: when not zero,
    /// extremals other than those listed may exist.
    pub unfinished_shots: usize,
    /// Whether the extremal is a minimum by the second variation (with `--check-minimum`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub minimum: Option<bool>,
    /// The x of the first conjugate point, null if none (with `--check-minimum`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub conjugate_point: Option<Option<f64>>,
    /// Legendre and Jacobi in detail (with `--check-minimum`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub second_variation: Option<SecondVariation>,
}

/// Why there is no report.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ExtremalError {
    /// The problem file is wrong.
    #[error("{0}")]
    Model(ModelError),
    /// The problem is well formed but has no extremal through its ends (exit 1).
    #[error("{message}")]
    NoExtremal {
        /// What happened.
        message: String,
        /// A hint.
        help: Option<String>,
    },
}

impl From<ModelError> for ExtremalError {
    fn from(e: ModelError) -> Self {
        ExtremalError::Model(e)
    }
}

/// Solves an extremal problem.
pub fn extremal(problem: &Problem, config: &ExtremalConfig) -> Result<ExtremalReport, ExtremalError> {
    let mut pool = problem.pool.clone();
    let (xn, yn) = (problem.independent.as_str(), problem.unknown.as_str());
    let f = problem.integrand;
    let located = |message: String| ModelError::at(problem.integrand_span.clone(), message);
    let euler = Euler::new(&mut pool, f, xn, yn).map_err(|e| {
        located(format!("in the integrand: {e}"))
            .with_help(format!("f must be nonlinear in {yn}', e.g. sqrt(1 + {yn}'^2)"))
    })?;
    let params: Vec<(ExprId, f64)> = problem.parameters.iter().map(|(n, v)| (pool.symbol(n), *v)).collect();
    let mut num = Numeric::new(&mut pool, f, &euler, &params)
        .map_err(|e| located(format!("cannot compile the integrand: {e}")))?;
    let [x0, y0] = problem.start;
    let [x1, y1] = problem.end;
    let slope = (y1 - y0) / (x1 - x0);

    // A path must start and end where f is real for some slope; an infinite f
    // (the brachistochrone's start) is a singular end, a NaN one is outside the
    // integrand's domain, which no search should be asked to explore.
    for (k, (which, point)) in [("start", problem.start), ("end", problem.end)].into_iter().enumerate() {
        if !real_somewhere(&mut num, point) {
            let [x, y] = point;
            return Err(ModelError::at(
                problem.boundary_spans[k].clone(),
                format!("the integrand is not real at the {which} ({xn}, {yn}) = ({x}, {y}), whatever the slope {yn}' there"),
            )
            .with_help(format!(
                "f must be real along the path: check the signs under square roots and logarithms (the brachistochrone's {yn} is measured downward from its start, so an end above the start is outside its domain)"
            ))
            .into());
        }
    }

    // A singular end and a regular start: solve the mirrored problem x → x0 + x1 − x from the end.
    let singular_start = bvp::is_singular(&mut num, problem.start, slope);
    let singular_end = bvp::is_singular(&mut num, problem.end, slope);
    if singular_start && singular_end {
        return Err(ExtremalError::NoExtremal {
            message: "f or the Euler equation is singular at both end points; that is not supported".into(),
            help: Some("move one end point off the singular set".into()),
        });
    }
    let reversed = singular_end;
    let points = config.points.max(2);
    let solution = if reversed {
        let v = euler.vars;
        let sum = pool.float(x0 + x1);
        let mirrored_x = pool.sub(sum, v.x);
        let minus_p = pool.neg(v.p);
        let mut map = FxHashMap::default();
        map.insert(v.x, mirrored_x);
        map.insert(v.p, minus_p);
        let f_rev = pool.substitute(f, &map);
        let e_rev = Euler::new(&mut pool, f_rev, xn, yn).map_err(|e| located(format!("in the integrand: {e}")))?;
        let mut num_rev = Numeric::new(&mut pool, f_rev, &e_rev, &params)
            .map_err(|e| located(format!("cannot compile the integrand: {e}")))?;
        let mut s = bvp::solve(&mut num_rev, [x0, y1], [x1, y0], points).map_err(no_extremal)?;
        for c in &mut s.candidates {
            c.path.reverse();
            for p in &mut c.path {
                p[0] = x0 + x1 - p[0];
                p[2] = -p[2];
            }
            if let Some(cp) = &mut c.conjugate {
                cp[0] = x0 + x1 - cp[0];
            }
            c.initial_angle = c.path[0][2];
        }
        s
    } else {
        bvp::solve(&mut num, problem.start, problem.end, points).map_err(no_extremal)?
    };
    let best = &solution.candidates[0];

    // The straight line, by tanh-sinh (its integrand may be singular at an end).
    // A non-finite integrand makes the value NaN, which the report shows as such.
    let straight = num::tanh_sinh(|x| num.at(x, y0 + slope * (x - x0), slope).f, x0, x1, STRAIGHT_LINE_RTOL)
        .map_or(f64::NAN, |i| i.value);

    // Beltrami's constant and Legendre's P along the path.
    let mut h_values = Vec::new();
    let (mut p_min, mut p_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &best.path {
        let (s, c) = p[2].sin_cos();
        let y_prime = s / c;
        let pt = num.at(p[0], p[1], y_prime);
        if pt.first_integral.is_finite() {
            h_values.push(pt.first_integral);
        }
        if y_prime.abs() < 1e8 && pt.legendre.is_finite() {
            p_min = p_min.min(pt.legendre);
            p_max = p_max.max(pt.legendre);
        }
    }
    let (h_const, h_drift) = if euler.first_integral.is_some() && !h_values.is_empty() {
        let mid = h_values[h_values.len() / 2];
        (Some(mid), Some(h_values.iter().map(|h| (h - mid).abs()).fold(0.0, f64::max)))
    } else {
        (None, None)
    };

    let second = config.check_minimum.then(|| {
        let legendre = p_min > 0.0;
        let conjugate_point = best.conjugate.map(|c| c[0]);
        SecondVariation {
            minimum: legendre && conjugate_point.is_none(),
            conjugate_point,
            legendre,
            legendre_min: p_min,
            legendre_max: p_max,
            from_end: reversed,
        }
    });
    let extremals = solution
        .candidates
        .iter()
        .map(|c| {
            let a = c.initial_angle;
            ExtremalSummary {
                value: c.value,
                start_angle: a,
                start_slope: (a.cos().abs() > 1e-12).then(|| a.tan()),
                conjugate_point: c.conjugate.map(|p| p[0]),
            }
        })
        .collect();
    let departure = match best.start {
        Start::Singular { phi0, lambda } => Some([if reversed { -phi0 } else { phi0 }, lambda]),
        Start::Regular => None,
    };
    let mut parameters = BTreeMap::new();
    for (n, v) in &problem.parameters {
        parameters.insert(n.clone(), *v);
    }
    let mut boundary = BTreeMap::new();
    boundary.insert("start", problem.start);
    boundary.insert("end", problem.end);
    Ok(ExtremalReport {
        format: EXTREMAL_FORMAT,
        name: problem.name.clone(),
        independent: xn.to_string(),
        unknown: yn.to_string(),
        integrand: pool.display(f).to_string(),
        parameters,
        boundary,
        euler_equation: pool.display(euler.equation).to_string(),
        acceleration: pool.display(euler.acceleration).to_string(),
        first_integral: euler.first_integral.map(|h| pool.display(h).to_string()),
        first_integral_constant: h_const,
        first_integral_drift: h_drift,
        legendre: pool.display(euler.legendre).to_string(),
        jacobi_q: pool.display(euler.jacobi_q).to_string(),
        value: best.value,
        straight_line_value: straight,
        path: best.path.iter().map(|p| [p[0], p[1]]).collect(),
        extremals,
        endpoints: if reversed {
            "singular_end"
        } else if singular_start {
            "singular_start"
        } else {
            "regular"
        },
        departure,
        end_residual: best.end_miss,
        shots: solution.shots,
        unfinished_shots: solution.unfinished,
        minimum: second.as_ref().map(|s| s.minimum),
        conjugate_point: second.as_ref().map(|s| s.conjugate_point),
        second_variation: second,
    })
}

/// Whether f is real (finite, or infinite as at a singular end, but not NaN)
/// at `point` for some slope in a fan of directions.
fn real_somewhere(num: &mut Numeric, point: [f64; 2]) -> bool {
    let n = 64;
    (0..=n).any(|k| {
        let angle = -FRAC_PI_2 + std::f64::consts::PI * (k as f64 + 0.5) / (n + 1) as f64;
        !num.at(point[0], point[1], angle.tan()).f.is_nan()
    })
}

fn no_extremal(e: SolveFailure) -> ExtremalError {
    let help = match e {
        SolveFailure::NoExtremal { .. } => Some(
            "no smooth curve makes J stationary between these ends; for a minimal surface of revolution \
             (f = y*sqrt(1 + y'^2)) this is Goldschmidt's case: the rings are too far apart and the minimum \
             is two flat discs joined along the axis"
                .into(),
        ),
        SolveFailure::Undecided { .. } => Some(
            "the extremals oscillate too often between the ends to be followed; a shorter interval, or other end points, can be decided"
                .into(),
        ),
        SolveFailure::SingularStart => Some("move the start off the singular set".into()),
        SolveFailure::Divergent => None,
    };
    ExtremalError::NoExtremal { message: e.to_string(), help }
}
