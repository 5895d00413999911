//! The boundary-value solver: finds every extremal through both end points by
//! shooting on the curve in parametric form.
//!
//! The curve is followed by its arc length s with the tangent angle φ
//! (`y' = tan φ`), so vertical slopes are ordinary points:
//! `x' = cos φ`, `y' = sin φ`, `φ' = κ = y''·cos³φ` with y'' from the Euler
//! equation, and the functional accumulates as `V' = f·cos φ`. Along with it
//! runs the variational equation of (x, y, φ) with respect to the family
//! parameter; its normal component `J = −sin φ·δx + cos φ·δy` is the Jacobi
//! field of the notes' appendix A.2 (J = h·cos φ with h the solution of
//! `d/dx(P h') − Q h = 0`, `h(x0) = 0`), so its zeros are the conjugate points.
//!
//! The extremals leaving the start form a one-parameter family: the initial
//! angle φ0 at a regular start. At a singular start (f or y'' infinite there,
//! like the brachistochrone's y = 0) the family leaves along the direction φ0
//! where the curvature stays finite, with the local (Frobenius) series
//! `φ = φ0 + c·(s/D)^λ`, λ = dg/dφ at φ0 for `g(φ) = s·κ` on the ray; the curve
//! is then followed in `u = (s/D)^λ`, in which it is smooth, and it starts
//! where the series has turned the tangent by 1e-4, the value of [0, s0] integrated along it
//! by tanh-sinh quadrature (the integrand may be singular at s = 0). Either way each member is integrated with
//! DOP853 until it reaches x1 (a curve that turns back, cos φ < 0, is no graph
//! y(x) and is dropped); y(x1) − y1 is the miss. A scan of the parameter
//! brackets every zero of the miss, and Brent's method solves each.
//!
//! Entry point: [`solve`].

use super::euler::Euler;
use num::{Config, Direction, Event, Method, ObservationKind, OdeSystem, Output, RhsError};
use std::f64::consts::{FRAC_PI_2, PI};
use std::ops::ControlFlow;
use sym::{Compiled, ExprId, Pool, Tape};

/// Relative tolerance of the integrations: near the round-off limit, so that
/// the extremal and its value are good to about 1e-11.
const RTOL: f64 = 1e-12;
/// How far the series turns the tangent before the integration takes over (radians).
const PSI_START: f64 = 1e-4;
/// Bounds on where it hands over, u0 = (s0/D)^λ.
const U0_MIN: f64 = 1e-6;
/// See [`U0_MIN`].
const U0_MAX: f64 = 1e-2;
/// Longest curve followed, in units of the chord length D.
const MAX_LENGTH: f64 = 50.0;
/// Largest accepted miss of a solved extremal, in units of D.
const MISS_TOL: f64 = 1e-9;
/// Relative tolerance of J over the series' start piece, by tanh-sinh (its
/// integrand may be singular at s = 0): a little tighter than [`RTOL`], since the
/// integration continues from it.
const SERIES_VALUE_RTOL: f64 = 1e-13;
/// Absolute tolerance of Brent's method for a departure angle φ0 (radians, within
/// [−π, π]): a few ulps, since the curvature equation amplifies an error in φ0.
const ANGLE_ROOT_TOL: f64 = 1e-15;
/// Tolerance of Brent's method for the family parameter, relative to its size
/// (at least 1): a few ulps, so that the miss of the extremal is its round-off.
const PARAMETER_ROOT_RTOL: f64 = 1e-15;
/// |cos φ| below which y'' is too noisy for the tight tolerance (|y'| > 100).
const VERTICAL_COS: f64 = 0.01;
/// How far φ turns (in units of the family parameter c) before the tight integration takes over.
const VERTICAL_TURN: f64 = 0.02;
/// Runge–Kutta steps up to there (geometric: each about 2.5% of σ for σ0 = 1e-6).
const VERTICAL_STEPS: usize = 400;
/// Bisections toward the edge of the members that reach x1.
const EDGE_BISECTIONS: usize = 40;
/// Most steps of one integration: a smooth extremal needs a few hundred, one
/// that oscillates a few hundred times between the ends (y'' = −y over
/// [0, 1000]) some ten thousand.
const MAX_STEPS: usize = 50_000;
/// Most steps of all integrations of one search together, which bounds its
/// time (seconds); members not followed for want of steps make the search
/// undecided rather than empty.
const SEARCH_STEPS: usize = 10_000_000;

/// f and y'' with their derivatives, compiled, at (x, y, y') for given parameters.
pub struct Numeric {
    tape: Tape,
    /// The tape as native code, when cranelift supports the host.
    jit: Option<Compiled>,
    inputs: Vec<f64>,
    out: [f64; 7],
}

/// The compiled quantities at one point.
#[derive(Debug, Clone, Copy)]
pub struct Point {
    /// f.
    pub f: f64,
    /// y''.
    pub acc: f64,
    /// ∂y''/∂x, ∂y''/∂y, ∂y''/∂y'.
    pub acc_x: f64,
    /// ∂y''/∂y.
    pub acc_y: f64,
    /// ∂y''/∂y'.
    pub acc_p: f64,
    /// P = f_{y'y'}.
    pub legendre: f64,
    /// The first integral y'·f_{y'} − f (NaN when f depends on x).
    pub first_integral: f64,
}

impl Numeric {
    /// Compiles `f` and the Euler results; `params` are the parameter symbols with values.
    pub fn new(pool: &mut Pool, f: ExprId, e: &Euler, params: &[(ExprId, f64)]) -> Result<Numeric, sym::EvalError> {
        let v = e.vars;
        let acc_x = pool.diff(e.acceleration, v.x);
        let acc_y = pool.diff(e.acceleration, v.y);
        let acc_p = pool.diff(e.acceleration, v.p);
        let nan = pool.float(f64::NAN);
        let h = e.first_integral.unwrap_or(nan);
        let roots = [f, e.acceleration, acc_x, acc_y, acc_p, e.legendre, h];
        let mut inputs = vec![v.x, v.y, v.p];
        inputs.extend(params.iter().map(|p| p.0));
        let tape = Tape::compile(pool, &roots, &inputs)?;
        let mut values = vec![0.0; 3];
        values.extend(params.iter().map(|p| p.1));
        let jit = Compiled::new(&tape).ok();
        Ok(Numeric { tape, jit, inputs: values, out: [0.0; 7] })
    }

    /// Everything at (x, y, y').
    pub fn at(&mut self, x: f64, y: f64, p: f64) -> Point {
        self.inputs[0] = x;
        self.inputs[1] = y;
        self.inputs[2] = p;
        match &self.jit {
            Some(jit) => jit.eval(&self.inputs, &mut self.out),
            None => self.tape.eval(&self.inputs, &mut self.out),
        }
        let o = self.out;
        Point { f: o[0], acc: o[1], acc_x: o[2], acc_y: o[3], acc_p: o[4], legendre: o[5], first_integral: o[6] }
    }
}

/// How the family of extremals leaves the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// A regular point: the parameter is the initial angle φ0.
    Regular,
    /// A singular point: the curve leaves along `phi0` as `φ = φ0 + c·(s/D)^λ`; the parameter is c.
    Singular {
        /// The direction of departure.
        phi0: f64,
        /// The exponent of the local series.
        lambda: f64,
    },
}

/// One extremal through both ends.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// How its family leaves the start.
    pub start: Start,
    /// The family parameter (φ0 or c).
    pub parameter: f64,
    /// The initial slope angle φ0 (radians; π/2 is straight up).
    pub initial_angle: f64,
    /// J\[y\] on it.
    pub value: f64,
    /// Samples (x, y, φ) from the start to the end.
    pub path: Vec<[f64; 3]>,
    /// The first conjugate point (x, y) after the start, up to and including the end.
    pub conjugate: Option<[f64; 2]>,
    /// The distance of the computed end from the end point.
    pub end_miss: f64,
}

/// The result of a search.
#[derive(Debug, Clone)]
pub struct Solution {
    /// Every extremal found, lowest value first.
    pub candidates: Vec<Candidate>,
    /// Family members integrated (the cost of the search).
    pub shots: usize,
    /// Members that ran out of steps before it was known whether they reach
    /// the end: when not zero, extremals other than the ones found may exist.
    pub unfinished: usize,
}

/// The ODE of one family member in the parametric form, with its variation.
struct Curve<'a> {
    num: &'a mut Numeric,
    /// ds/dσ = scale·σ^exponent (1 for arc length).
    scale: f64,
    exponent: f64,
}

impl OdeSystem for Curve<'_> {
    fn dim(&self) -> usize {
        7
    }
    fn rhs(&mut self, sigma: f64, z: &[f64], dz: &mut [f64]) -> Result<(), RhsError> {
        let w = if self.exponent == 0.0 { self.scale } else { self.scale * sigma.powf(self.exponent) };
        let (s, c) = z[2].sin_cos();
        let pt = self.num.at(z[0], z[1], s / c);
        let c2 = c * c;
        let kappa = pt.acc * c2 * c;
        let kappa_x = pt.acc_x * c2 * c;
        let kappa_y = pt.acc_y * c2 * c;
        let kappa_phi = pt.acc_p * c - 3.0 * pt.acc * c2 * s;
        dz[0] = w * c;
        dz[1] = w * s;
        dz[2] = w * kappa;
        dz[3] = w * pt.f * c;
        dz[4] = -w * s * z[6];
        dz[5] = w * c * z[6];
        dz[6] = w * (kappa_x * z[4] + kappa_y * z[5] + kappa_phi * z[6]);
        match dz.iter().position(|v| !v.is_finite()) {
            Some(index) => Err(RhsError::NonFinite { index }),
            None => Ok(()),
        }
    }
}

/// The geometry of the search.
struct Family<'a> {
    num: &'a mut Numeric,
    start: [f64; 2],
    end: [f64; 2],
    /// Chord length.
    d: f64,
    kind: Start,
    shots: usize,
    /// Members that ran out of steps (their own or the search's) before
    /// reaching x1 or turning back: whether they reach the end is not known.
    unfinished: usize,
    /// Steps taken by all members so far.
    steps: usize,
    /// Integrate the value over the series start too (the final trace).
    with_value: bool,
}

/// The end of one shot.
struct Shot {
    miss: f64,
    sigma_end: f64,
}

impl Family<'_> {
    /// σ0, the initial state and the ds/dσ law of the member with parameter `a`.
    fn initial(&mut self, a: f64) -> (f64, [f64; 7], f64, f64) {
        let [x0, y0] = self.start;
        match self.kind {
            Start::Regular => (0.0, [x0, y0, a, 0.0, 0.0, 0.0, 1.0], 1.0, 0.0),
            Start::Singular { phi0, lambda } => {
                // Start where the series has turned the tangent by PSI_START: closer in,
                // y'' would be evaluated at slopes where it has lost its digits.
                let u0 = if a == 0.0 { U0_MAX } else { (PSI_START / a.abs()).clamp(U0_MIN, U0_MAX) };
                let d = self.d;
                let s0 = d * u0.powf(1.0 / lambda);
                let (sn, cs) = phi0.sin_cos();
                // The series to first order in φ − φ0 = a·(s/D)^λ: the position bends off the
                // ray by a·s·(s/D)^λ/(1 + λ) along the normal (−sin φ0, cos φ0).
                let at = move |s: f64| {
                    let bend = a * s * (s / d).powf(lambda) / (1.0 + lambda);
                    [x0 + s * cs - bend * sn, y0 + s * sn + bend * cs, phi0 + a * (s / d).powf(lambda)]
                };
                let num = &mut *self.num;
                let density = |s: f64| {
                    let [x, y, phi] = at(s);
                    let (sp, cp) = phi.sin_cos();
                    num.at(x, y, sp / cp).f * cp
                };
                // ∫ f·cos φ ds over [0, s0] along the series; the integrand may be
                // singular at s = 0 (the brachistochrone's 1/sqrt(y)).
                // Shots only need the miss; the value is integrated on the final trace.
                let v0 = if self.with_value {
                    num::tanh_sinh(density, 0.0, s0, SERIES_VALUE_RTOL).map_or(f64::NAN, |i| i.value)
                } else {
                    0.0
                };
                let [x, y, phi] = at(s0);
                // The variation with a: δφ = u0 and the bend's δ-position.
                let bend_a = s0 * u0 / (1.0 + lambda);
                let state = [x, y, phi, v0, -bend_a * sn, bend_a * cs, u0];
                (u0, state, self.d / lambda, 1.0 / lambda - 1.0)
            }
        }
    }

    /// The state from which member `a` is followed at full accuracy.
    ///
    /// Near a vertical tangent y'' loses digits (its formulas cancel terms of
    /// order y'^2 against each other: a relative error of about 1e-16·y'^2), so
    /// the error control of a tight adaptive integration would stall on the
    /// noise. A curve leaving a singular start vertically is therefore first
    /// followed with classical Runge–Kutta steps growing with σ until |φ − φ0| ≈ 0.02
    /// (|y'| ≈ 50); in u the curve is smooth there (φ ≈ φ0 + c·u), so the
    /// truncation error is negligible and the noise moves it by about
    /// 1e-16·y'^2·Δφ, below 1e-10 in all.
    fn handover(&mut self, a: f64) -> Option<(f64, [f64; 7], f64, f64)> {
        let (sigma0, z0, scale, exponent) = self.initial(a);
        if z0.iter().any(|v| !v.is_finite()) {
            return None;
        }
        if self.kind == Start::Regular || z0[2].cos().abs() >= VERTICAL_COS || a == 0.0 {
            return Some((sigma0, z0, scale, exponent));
        }
        let sigma_end = (VERTICAL_TURN / a.abs()).min(self.sigma_max());
        if sigma_end <= sigma0 {
            return Some((sigma0, z0, scale, exponent));
        }
        let mut curve = Curve { num: &mut *self.num, scale, exponent };
        // Geometric steps: the curve's scale near the start is σ itself.
        let ratio = (sigma_end / sigma0).powf(1.0 / VERTICAL_STEPS as f64);
        let mut z = z0;
        let mut k = [[0.0; 7]; 4];
        let mut tmp = [0.0; 7];
        let mut t = sigma0;
        for step in 0..VERTICAL_STEPS {
            let t_next = if step + 1 == VERTICAL_STEPS { sigma_end } else { t * ratio };
            let h = t_next - t;
            curve.rhs(t, &z, &mut k[0]).ok()?;
            for i in 0..7 {
                tmp[i] = z[i] + 0.5 * h * k[0][i];
            }
            curve.rhs(t + 0.5 * h, &tmp, &mut k[1]).ok()?;
            for i in 0..7 {
                tmp[i] = z[i] + 0.5 * h * k[1][i];
            }
            curve.rhs(t + 0.5 * h, &tmp, &mut k[2]).ok()?;
            for i in 0..7 {
                tmp[i] = z[i] + h * k[2][i];
            }
            curve.rhs(t_next, &tmp, &mut k[3]).ok()?;
            for i in 0..7 {
                z[i] += h / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
            }
            if z[2].cos() < 0.0 {
                return None;
            }
            t = t_next;
        }
        Some((sigma_end, z, scale, exponent))
    }

    fn sigma_max(&self) -> f64 {
        match self.kind {
            Start::Regular => MAX_LENGTH * self.d,
            Start::Singular { lambda, .. } => MAX_LENGTH.powf(lambda),
        }
    }

    fn config(&self) -> Config {
        // Steps of at most 1/32 of the curve's natural scale keep the dense output,
        // which locates x = x1, as accurate as the steps themselves.
        let scale = match self.kind {
            Start::Regular => self.d,
            Start::Singular { .. } => 1.0,
        };
        Config {
            rtol: RTOL,
            atol: RTOL * 1e-2 * self.d.max(1e-300),
            max_steps: MAX_STEPS,
            h_max: Some(scale / 32.0),
            ..Config::default()
        }
    }

    /// Integrates member `a` to the perpendicular through the end; None if it never gets there as a graph.
    fn shoot(&mut self, a: f64) -> Option<Shot> {
        self.shots += 1;
        if self.steps >= SEARCH_STEPS {
            self.unfinished += 1;
            return None;
        }
        let (sigma0, z0, scale, exponent) = self.handover(a)?;
        let config = self.config();
        let sigma_max = self.sigma_max();
        let [x1, y1] = self.end;
        let curve = Curve { num: &mut *self.num, scale, exponent };
        let mut solver = Method::Dop853.build(curve, sigma0, &z0, &config).ok()?;
        let mut events = [
            Event::new(move |_, z: &[f64]| z[0] - x1).with_direction(Direction::Rising).with_terminal(true),
            Event::new(|_, z: &[f64]| z[2].cos()).with_direction(Direction::Falling).with_terminal(true),
        ];
        let mut hit: Option<(f64, [f64; 2])> = None;
        let r = num::integrate(&mut solver, sigma_max, Output::EveryStep, &mut events, |o| {
            if o.kind == (ObservationKind::Event { index: 0 }) {
                hit = Some((o.t, [o.y[0], o.y[1]]));
            }
            ControlFlow::Continue(())
        });
        self.steps += solver.statistics().steps;
        if let Err(num::SolveError::MaxStepsExceeded { .. } | num::SolveError::MaxStepsForeseen { .. }) = r {
            self.unfinished += 1;
        }
        r.ok()?;
        let (sigma_end, [_, y]) = hit?;
        let miss = y - y1;
        Some(Shot { miss, sigma_end })
    }

    /// The full member `a` to `sigma_end`, sampled at `n` points, with its conjugate point.
    fn trace(&mut self, a: f64, sigma_end: f64, n: usize) -> Option<Candidate> {
        self.with_value = true;
        let series_end = self.initial(a).0;
        let (sigma0, z0, scale, exponent) = self.handover(a)?;
        let config = self.config();
        let (start, kind, end) = (self.start, self.kind, self.end);
        let curve = Curve { num: &mut *self.num, scale, exponent };
        let mut solver = Method::Dop853.build(curve, sigma0, &z0, &config).ok()?;
        let jacobi = |_: f64, z: &[f64]| -z[2].sin() * z[4] + z[2].cos() * z[5];
        let mut events = [Event::new(jacobi).with_direction(Direction::Falling)];
        let mut path = Vec::with_capacity(n + 1);
        if let Start::Singular { phi0, .. } = kind {
            path.push([start[0], start[1], phi0]);
            if sigma0 > series_end {
                path.push([z0[0], z0[1], z0[2]]);
            }
        }
        let mut conjugate = None;
        let mut value = f64::NAN;
        let n_samples = n.saturating_sub(path.len()).max(2);
        num::integrate(&mut solver, sigma_end, Output::Samples(n_samples), &mut events, |o| {
            match o.kind {
                ObservationKind::Event { .. } => {
                    if conjugate.is_none() && o.t > sigma0 {
                        conjugate = Some([o.y[0], o.y[1]]);
                    }
                }
                _ => {
                    path.push([o.y[0], o.y[1], o.y[2]]);
                    value = o.y[3];
                }
            }
            ControlFlow::Continue(())
        })
        .ok()?;
        let last = *path.last()?;
        let end_miss = (last[0] - end[0]).hypot(last[1] - end[1]);
        if path.iter().any(|p| p[2].cos() < -1e-12) {
            return None;
        }
        let initial_angle = match kind {
            Start::Regular => a,
            Start::Singular { phi0, .. } => phi0,
        };
        Some(Candidate { start: kind, parameter: a, initial_angle, value, path, conjugate, end_miss })
    }
}

/// Why no extremal was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveFailure {
    /// No member of the family from the start reaches the end.
    #[error("no extremal joins the end points: none of the {shots} extremals leaving the start reaches the end")]
    NoExtremal {
        /// Members tried.
        shots: usize,
    },
    /// None was found, but some members could not be followed to the end:
    /// whether an extremal exists is not known.
    #[error(
        "could not decide whether an extremal joins the end points: none was found, but {unfinished} of the {shots} extremals tried ran out of steps before reaching the end ({MAX_STEPS} each, {SEARCH_STEPS} in all)"
    )]
    Undecided {
        /// Members tried.
        shots: usize,
        /// Members not followed to the end.
        unfinished: usize,
    },
    /// The start is singular and no extremal can leave it.
    #[error("the Euler equation is singular at the start and no extremal leaves it with a finite curvature")]
    SingularStart,
    /// The functional diverges at the singular start.
    #[error("the integrand is not integrable at the singular start")]
    Divergent,
}

/// Is (x, y) a singular point of the problem (f or y'' not finite along the chord's slope)?
pub fn is_singular(num: &mut Numeric, at: [f64; 2], slope: f64) -> bool {
    let pt = num.at(at[0], at[1], slope);
    !(pt.f.is_finite() && pt.acc.is_finite())
}

/// The directions in which extremals can leave a singular start, with their exponents λ.
fn departures(num: &mut Numeric, start: [f64; 2], d: f64) -> Vec<(f64, f64)> {
    let eps = 1e-8 * d;
    let mut g = |phi: f64| {
        let (s, c) = phi.sin_cos();
        let pt = num.at(start[0] + eps * c, start[1] + eps * s, s / c);
        eps * pt.acc * c * c * c
    };
    let n = 720;
    let grid: Vec<f64> = (0..=n).map(|k| -PI + 2.0 * PI * k as f64 / n as f64 + 1e-3).collect();
    let values: Vec<f64> = grid.iter().map(|&p| g(p)).collect();
    let mut out: Vec<(f64, f64)> = Vec::new();
    for k in 0..n {
        let (a, b, ga, gb) = (grid[k], grid[k + 1], values[k], values[k + 1]);
        if !(ga.is_finite() && gb.is_finite()) || ga.signum() == gb.signum() {
            continue;
        }
        let Ok(mut root) = num::brent(|p| Ok::<_, ()>(g(p)), a, b, ga, gb, ANGLE_ROOT_TOL) else { continue };
        // Near a vertical tangent y'' loses its digits (its formulas cancel terms of
        // order y'^2), so the root is good to about 1e-8 there; a departure that
        // close to vertical is vertical. (An error in φ0 is absorbed by the family
        // parameter anyway: the start is an unstable node of the curvature equation.)
        if root.cos().abs() < 1e-6 {
            root = FRAC_PI_2.copysign(root);
        }
        // A pole of g changes sign too; a root has g ≈ 0.
        if g(root).abs() > 1e-6 || root.cos() < -1e-9 {
            continue;
        }
        let h = 1e-5;
        let lambda = (g(root + h) - g(root - h)) / (2.0 * h);
        if lambda.is_finite() && lambda > 1e-6 && !out.iter().any(|o| (o.0 - root).abs() < 1e-9) {
            out.push((root, lambda));
        }
    }
    out
}

/// Finds every extremal from `start` to `end`, each sampled at `n_points` points.
pub fn solve(num: &mut Numeric, start: [f64; 2], end: [f64; 2], n_points: usize) -> Result<Solution, SolveFailure> {
    let (dx, dy) = (end[0] - start[0], end[1] - start[1]);
    let d = dx.hypot(dy);
    let slope = dy / dx;
    let kinds: Vec<Start> = if is_singular(num, start, slope) {
        let deps = departures(num, start, d);
        if deps.is_empty() {
            return Err(SolveFailure::SingularStart);
        }
        deps.into_iter().map(|(phi0, lambda)| Start::Singular { phi0, lambda }).collect()
    } else {
        vec![Start::Regular]
    };
    let mut candidates: Vec<Candidate> = Vec::new();
    let (mut shots, mut unfinished, mut steps) = (0, 0, 0);
    let mut divergent = false;
    for kind in kinds {
        let mut fam = Family { num: &mut *num, start, end, d, kind, shots: 0, unfinished: 0, steps, with_value: false };
        let grid = scan_grid(kind);
        // The members closest to the chord's direction first: steep ones take
        // the most steps, and if the search's steps run out they are the ones
        // left unfollowed.
        let mut order: Vec<usize> = (0..grid.len()).collect();
        order.sort_by(|&i, &j| grid[i].abs().total_cmp(&grid[j].abs()));
        let mut misses: Vec<Option<Shot>> = (0..grid.len()).map(|_| None).collect();
        for i in order {
            misses[i] = fam.shoot(grid[i]);
        }
        let mut roots: Vec<(f64, f64)> = Vec::new();
        for k in 0..grid.len() - 1 {
            let bracket = match (&misses[k], &misses[k + 1]) {
                (Some(sa), Some(sb)) if sa.miss.signum() != sb.miss.signum() || sa.miss == 0.0 => {
                    Some((grid[k], sa.miss, grid[k + 1], sb.miss))
                }
                // The family stops reaching x1 between these members (a cusp, a turn):
                // the solution may sit right at that edge, so close in on it.
                (Some(sa), None) => edge(&mut fam, grid[k], sa.miss, grid[k + 1]),
                (None, Some(sb)) => edge(&mut fam, grid[k + 1], sb.miss, grid[k]),
                _ => None,
            };
            let Some((lo, m_lo, hi, m_hi)) = bracket else { continue };
            let tol = PARAMETER_ROOT_RTOL * lo.abs().max(1.0);
            let root = num::brent(|a| fam.shoot(a).map(|s| s.miss).ok_or(()), lo, hi, m_lo, m_hi, tol);
            let Ok(root) = root else { continue };
            let Some(shot) = fam.shoot(root) else { continue };
            if shot.miss.abs() <= MISS_TOL * d && !roots.iter().any(|r| (r.0 - root).abs() < 1e-9) {
                roots.push((root, shot.sigma_end));
            }
        }
        for (a, sigma_end) in roots {
            if let Some(c) = fam.trace(a, sigma_end, n_points) {
                if c.value.is_finite() {
                    candidates.push(c);
                } else {
                    divergent = true;
                }
            }
        }
        shots += fam.shots;
        unfinished += fam.unfinished;
        steps = fam.steps;
    }
    if candidates.is_empty() {
        return Err(if divergent {
            SolveFailure::Divergent
        } else if unfinished > 0 {
            SolveFailure::Undecided { shots, unfinished }
        } else {
            SolveFailure::NoExtremal { shots }
        });
    }
    candidates.sort_by(|a, b| a.value.total_cmp(&b.value));
    Ok(Solution { candidates, shots, unfinished })
}

/// Bisects between member `good` (which reaches x1 with miss `m_good`) and `bad`
/// (which does not) for a member whose miss has the other sign: a bracket.
fn edge(fam: &mut Family<'_>, mut good: f64, mut m_good: f64, mut bad: f64) -> Option<(f64, f64, f64, f64)> {
    for _ in 0..EDGE_BISECTIONS {
        let mid = 0.5 * (good + bad);
        match fam.shoot(mid) {
            Some(s) if s.miss.signum() != m_good.signum() => return Some((good, m_good, mid, s.miss)),
            Some(s) => (good, m_good) = (mid, s.miss),
            None => bad = mid,
        }
    }
    None
}

/// The parameters scanned for sign changes of the miss.
fn scan_grid(kind: Start) -> Vec<f64> {
    let mut grid: Vec<f64> = match kind {
        Start::Regular => {
            let n = 180;
            let mut g: Vec<f64> = (0..n).map(|k| -FRAC_PI_2 + PI * (k as f64 + 0.5) / n as f64).collect();
            for j in 3..=8 {
                let near = FRAC_PI_2 - 10f64.powi(-j);
                g.push(near);
                g.push(-near);
            }
            g
        }
        Start::Singular { .. } => {
            let mut g = vec![0.0];
            for j in -48..=36 {
                let c = 10f64.powf(j as f64 / 12.0);
                g.push(c);
                g.push(-c);
            }
            g
        }
    };
    grid.sort_by(f64::total_cmp);
    grid
}

#[cfg(test)]
mod tests {
    use super::*;

    fn numeric(pool: &mut Pool, f: &str, params: &[(&str, f64)]) -> Numeric {
        let f = pool.parse(f).unwrap();
        let e = Euler::new(pool, f, "x", "y").unwrap();
        let params: Vec<(ExprId, f64)> = params.iter().map(|(n, v)| (pool.symbol(n), *v)).collect();
        Numeric::new(pool, f, &e, &params).unwrap()
    }

    #[track_caller]
    fn check_departures(f: &str, start: [f64; 2], expect: &[(f64, f64)]) {
        let mut pool = Pool::default();
        let mut num = numeric(&mut pool, f, &[("g", 9.81)]);
        assert!(is_singular(&mut num, start, 1.0));
        let got = departures(&mut num, start, 1.0);
        assert_eq!(got.len(), expect.len(), "{got:?}");
        for ((phi, lambda), (want_phi, want_lambda)) in got.iter().zip(expect) {
            assert!((phi - want_phi).abs() < 1e-12, "{got:?}");
            assert!((lambda - want_lambda).abs() < 1e-5, "{got:?}");
        }
    }

    #[test]
    fn singular_starts_leave_where_the_curvature_is_finite() {
        // Brachistochrone: φ − π/2 ∝ sqrt(s) up and down from y = 0 (the upward one has y < 0,
        // where f is not real; its shots fail).
        check_departures("sqrt((1 + y'^2)/(2*g*y))", [0.0, 0.0], &[(-FRAC_PI_2, 0.5), (FRAC_PI_2, 0.5)]);
        // A catenary cannot touch the axis: κ = cos φ/y repels every direction.
        check_departures("y*sqrt(1 + y'^2)", [0.0, 0.0], &[]);
    }

    #[test]
    fn straight_line_is_the_only_shortest_path() {
        let mut pool = Pool::default();
        let mut num = numeric(&mut pool, "sqrt(1 + y'^2)", &[]);
        let s = solve(&mut num, [0.0, 1.0], [2.0, -1.0], 11).unwrap();
        assert_eq!(s.candidates.len(), 1);
        let c = &s.candidates[0];
        assert!((c.value - 8f64.sqrt()).abs() < 1e-13);
        assert!((c.initial_angle + PI / 4.0).abs() < 1e-13);
        assert!(c.conjugate.is_none());
        assert_eq!(c.path.len(), 11);
    }
}
