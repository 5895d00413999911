//! The symmetric top (notes 3.2.7): from a model with one rigid body whose
//! inertia has I₁ = I₂ = I, the quantities the notes compute from the initial
//! state, as numbers.
//!
//! - Free top (no gravity torque): ω₃ is constant, ω₁ + iω₂ turns at the body
//!   precession rate Ω = (I₃ − I)/I·ω₃; the symmetry axis keeps the angle
//!   β₀ = atan(I·A/(I₃ω₃)) to L (A = sqrt(ω₁² + ω₂²)) and precesses about L at
//!   α̇ = A/sin β₀ = |L|/I.
//! - Heavy top on a fixed pivot (centre of mass at [0, 0, S] in the body frame,
//!   gravity g): α and γ are cyclic, p_α and p_γ = I₃ω₃ are conserved,
//!   E' = E − p_γ²/(2I₃) = ½Iβ̇² + U_eff(β) with
//!   U_eff(β) = (p_α − p_γ cos β)²/(2I sin²β) + MgS cos β. In u = cos β,
//!   u̇² = f(u) = (2E'/I − 2MgS u/I)(1 − u²) − ((p_α − p_γ u)/I)², a cubic whose
//!   roots u₁ ≤ u₂ in [−1, 1] are the turning angles of the nutation. Steady
//!   precession at β₀ needs I cos β₀ α̇² − p_γ α̇ + MgS = 0 (∂L/∂β = 0 at β̇ = 0);
//!   the sleeping top (β = 0) is stable when p_γ² > 4IMgS.
//!
//! The mean precession rate and the nutation period are quadratures over one
//! swing from u₁ to u₂ with u = ū − h cos φ, which removes the square-root
//! singularities at the turning points: dt = dφ/sqrt(k(u₃ − u)), k = 2MgS/I.

use crate::derive::Derivation;
use crate::error::ModelError;
use crate::euler;
use serde::Serialize;

/// Points of the midpoint rule over one swing of the nutation (φ from 0 to π):
/// Gauss–Chebyshev in u = cos β, exact for the smooth part up to degree 8191, so
/// the period and the mean precession rate are good to round-off unless a turning
/// point nearly meets the third root u₃ (then the integrand steepens, and 4096
/// points still resolve it for u₃ − u₂ down to about 1e-6 of the swing).
const SWING_POINTS: usize = 4096;

/// The start is off a turning point when f(u₀) = u̇² exceeds this fraction of
/// the cubic's coefficients' size: a few thousand ulps of its terms.
const AT_TURNING_RTOL: f64 = 1e-12;

/// The slope f'(u₀) at a turning point start counts as zero (a steady motion)
/// below this fraction of the coefficients' size.
const SLOPE_RTOL: f64 = 1e-9;

/// How far past u₀ the other turning point is looked for when u₀ is one: far
/// enough that the root at u₀ itself, found to round-off, is not taken again.
const ROOT_GAP: f64 = 1e-9;

/// Turning points closer than this in u = cos β make a steady precession.
const STEADY_GAP: f64 = 1e-9;

/// α̇ = (a − b u)/(1 − u²) counts as vanishing at a turning point (cusps) below
/// this fraction of |a| + |b|.
const CUSP_RTOL: f64 = 1e-7;

/// I cos β₀ counts as zero (a horizontal top, one steady precession rate)
/// below this fraction of I.
const HORIZONTAL_RTOL: f64 = 1e-12;

/// Absolute tolerance of Brent's method for the roots of the cubic in
/// u ∈ [−1, 1]: a few ulps of 1.
const CUBIC_ROOT_TOL: f64 = 1e-15;

/// Roots of the cubic closer than this are one (a double root found twice).
const DUPLICATE_ROOT: f64 = 1e-14;

/// Free or heavy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TopKind {
    /// No torque about the reference point.
    Free,
    /// Gravity acting on a centre of mass above (or below) a fixed pivot.
    Heavy,
}

impl TopKind {
    /// `free` or `heavy`.
    pub fn name(self) -> &'static str {
        match self {
            TopKind::Free => "free",
            TopKind::Heavy => "heavy",
        }
    }
}

/// The three kinds of nutation curve (notes 3.2.7 c, observation ii), and the
/// steady precession without nutation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NutationKind {
    /// β₁ = β₂: steady precession at a fixed inclination.
    Steady,
    /// α̇ keeps its sign: the axis precesses monotonically.
    Monotonic,
    /// α̇ changes sign inside [β₁, β₂]: the axis draws loops.
    Loops,
    /// α̇ vanishes at a turning angle: the axis draws cusps.
    Cusps,
}

impl NutationKind {
    /// Its name in the report.
    pub fn name(self) -> &'static str {
        match self {
            NutationKind::Steady => "steady",
            NutationKind::Monotonic => "monotonic",
            NutationKind::Loops => "loops",
            NutationKind::Cusps => "cusps",
        }
    }
}

/// A free symmetric top's precession.
#[derive(Debug, Clone, Serialize)]
pub struct FreeTop {
    /// Ω = (I₃ − I)/I·ω₃: how fast ω turns about the symmetry axis in the body.
    pub body_precession_rate: f64,
    /// α̇ = A/sin β₀ = |L|/I: how fast the symmetry axis turns about L.
    pub space_precession_rate: f64,
    /// β₀ = atan(I·A/(I₃ω₃)): the angle between L and the symmetry axis.
    pub inclination: f64,
    /// A = sqrt(ω₁² + ω₂²).
    pub transverse_omega: f64,
    /// The half-angle of the body cone (ω about the symmetry axis).
    pub body_cone_angle: f64,
    /// The half-angle of the space cone (ω about L).
    pub space_cone_angle: f64,
    /// |L|.
    pub angular_momentum: f64,
    /// I₃ < I (prolate) or I₃ > I (oblate); "spherical" when equal.
    pub shape: &'static str,
}

/// A heavy symmetric top's nutation and precession.
#[derive(Debug, Clone)]
pub struct HeavyTop {
    /// M g S.
    pub mgs: f64,
    /// E' = E − p_γ²/(2I₃).
    pub energy_prime: f64,
    /// The turning angles β₁ ≤ β₂ (smallest and largest β).
    pub beta_min: f64,
    /// See `beta_min`.
    pub beta_max: f64,
    /// The kind of nutation curve.
    pub kind: NutationKind,
    /// Where α̇ = 0: β with cos β = p_α/p_γ, when that is an angle.
    pub alpha_dot_zero: Option<f64>,
    /// Steady precession rates at the initial β: [slow, fast]; None when there
    /// is none at this spin (discriminant < 0); fast is None at β = π/2.
    pub steady_precession: Option<[Option<f64>; 2]>,
    /// p_γ² > 4 I M g S: a top spinning upright stays upright.
    pub sleeping_stable: bool,
    /// The smallest |ω₃| for a stable sleeping top, sqrt(4 I M g S)/I₃ (0 if MgS ≤ 0).
    pub sleeping_omega3_min: f64,
    /// One full nutation period (β₁ → β₂ → β₁).
    pub nutation_period: f64,
    /// The mean α̇ over a nutation period.
    pub mean_precession_rate: f64,
}

/// Everything `lagrange top` reports.
#[derive(Debug, Clone)]
pub struct Top {
    /// Free or heavy.
    pub kind: TopKind,
    /// The body's name.
    pub body: String,
    /// The names of α, β, γ.
    pub angle_names: [String; 3],
    /// I = I₁ = I₂ (about the reference point).
    pub i: f64,
    /// I₃.
    pub i3: f64,
    /// The initial angles and rates.
    pub angles: [f64; 3],
    /// See `angles`.
    pub rates: [f64; 3],
    /// Body-frame ω at the start.
    pub omega: [f64; 3],
    /// p_α = I α̇ sin²β + p_γ cos β.
    pub p_alpha: f64,
    /// p_γ = I₃ ω₃.
    pub p_gamma: f64,
    /// E = ½[I(α̇² sin²β + β̇²) + I₃ω₃²] + MgS cos β (rotation and gravity; no translation).
    pub energy: f64,
    /// For a free top.
    pub free: Option<FreeTop>,
    /// For a heavy top.
    pub heavy: Option<HeavyTop>,
}

/// Why a model is not a symmetric top this analysis can treat.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TopError {
    /// The model is not one symmetric body alone.
    #[error("{0}")]
    Model(ModelError),
}

impl TopError {
    fn whole(msg: impl Into<String>, help: impl Into<String>) -> TopError {
        TopError::Model(ModelError::whole(msg).with_help(help))
    }
    fn at(span: std::ops::Range<usize>, msg: impl Into<String>, help: impl Into<String>) -> TopError {
        TopError::Model(ModelError::at(span, msg).with_help(help))
    }
}

impl Top {
    /// Reads the top from a derivation and its initial state.
    pub fn new(d: &Derivation) -> Result<Top, TopError> {
        let model = &d.model;
        if model.bodies.len() != 1 {
            return Err(TopError::whole(
                format!(
                    "the top analysis needs a model with exactly one rigid body; this one has {}",
                    model.bodies.len()
                ),
                "describe the top in one [[bodies]] table with inertia = [\"I\", \"I\", \"I3\"]",
            ));
        }
        let body = &model.bodies[0];
        let Some((body_angles, sequence)) = body.orientation.euler() else {
            return Err(TopError::at(
                body.span.clone(),
                "the top analysis reads a top turning in three Euler angles; this body has fewer",
                "give the top angles = [\"al\", \"be\", \"ga\"]; `simulate` takes bodies with one angle or none",
            ));
        };
        if body.parent.is_some() {
            return Err(TopError::at(
                body.span.clone(),
                "the top analysis reads a top turning in space; this body turns relative to a parent",
                "leave out `parent` for the top analysis; `simulate` follows bodies through their tree",
            ));
        }
        if sequence != crate::euler::Sequence::NOTES {
            return Err(TopError::at(
                body.span.clone(),
                format!(
                    "the top analysis reads a top in the notes' z-x-z Euler angles; this body turns in the sequence {}",
                    sequence.name()
                ),
                "leave out `sequence` (or give sequence = \"zxz\") for the top analysis; `simulate` takes any sequence",
            ));
        }
        if !model.particles.is_empty()
            || model.kinetic.is_some()
            || model.potential.is_some()
            || model.dissipation.is_some()
            || model.forces.iter().any(Option::is_some)
        {
            return Err(TopError::whole(
                "the top analysis treats a top alone: the model has other particles, energies, dissipation or forces",
                "keep only the [[bodies]] table (and gravity) in the model; use `simulate` for the rest",
            ));
        }
        let env = |n: &str| model.parameter(n);
        let value = |e| model.pool.eval(e, &env).map_err(|err| TopError::Model(ModelError::whole(err.to_string())));
        let mut inertia = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                inertia[i][j] = value(body.inertia[i][j])?;
            }
        }
        let scale = inertia[0][0].abs().max(inertia[2][2].abs());
        let off = [inertia[0][1], inertia[0][2], inertia[1][2]];
        let symmetric =
            (inertia[0][0] - inertia[1][1]).abs() <= 1e-12 * scale && off.iter().all(|x| x.abs() <= 1e-12 * scale);
        if !symmetric {
            return Err(TopError::at(
                body.inertia_span.clone(),
                format!(
                    "a symmetric top has I1 = I2 and principal axes along the body frame; this inertia is {:?}",
                    inertia
                ),
                "the top analysis treats symmetric tops (notes 3.2.7); use `simulate` for an asymmetric body",
            ));
        }
        let (i, i3) = (inertia[0][0], inertia[2][2]);
        let mass = value(body.mass)?;
        let c = [value(body.center_of_mass[0])?, value(body.center_of_mass[1])?, value(body.center_of_mass[2])?];
        let g = match model.gravity.as_ref().map(|g| (g.span(), g.down_z(&model.pool))) {
            Some((_, Some((g, sign)))) => sign * value(g)?,
            Some((span, None)) => {
                return Err(TopError::at(
                    span,
                    "a top's gravity points along −z of the fixed frame; this gravity vector does not",
                    "give gravity = \"g\" or [\"0\", \"0\", \"-g\"], and the top's axes as the notes draw them",
                ))
            }
            None => 0.0,
        };
        if c[0] != 0.0 || c[1] != 0.0 {
            return Err(TopError::at(
                body.span.clone(),
                "the centre of mass of a symmetric top lies on its symmetry axis: center_of_mass = [\"0\", \"0\", \"S\"]",
                "put the body's 3-axis along the symmetry axis",
            ));
        }
        let mgs = mass * g * c[2];
        let pool = &model.pool;
        let fixed = body.position.iter().all(|&x| d.q.iter().all(|&q| pool.free_of(x, q)) && pool.free_of(x, d.t));
        if c[2] != 0.0 && !fixed {
            return Err(TopError::at(
                body.span.clone(),
                "the reference point moves and is not the centre of mass: rotation and translation are coupled, which is not a top",
                "make `position` the fixed pivot, or the centre of mass with center_of_mass = [\"0\", \"0\", \"0\"]",
            ));
        }
        let kind = if mgs != 0.0 { TopKind::Heavy } else { TopKind::Free };
        let [a, b, gidx] = body_angles;
        let (q0, qd0) = model.initial_state().map_err(TopError::Model)?;
        let angles = [q0[a], q0[b], q0[gidx]];
        let rates = [qd0[a], qd0[b], qd0[gidx]];
        let omega = euler::angular_velocity_f64(angles[1], angles[2], rates);
        let (sb, cb) = angles[1].sin_cos();
        let p_gamma = i3 * omega[2];
        let p_alpha = i * rates[0] * sb * sb + p_gamma * cb;
        let energy =
            0.5 * (i * (rates[0] * rates[0] * sb * sb + rates[1] * rates[1]) + i3 * omega[2] * omega[2]) + mgs * cb;
        let angle_names = [a, b, gidx].map(|k| model.coordinates[k].name.clone());
        let mut top = Top {
            kind,
            body: body.name.clone(),
            angle_names,
            i,
            i3,
            angles,
            rates,
            omega,
            p_alpha,
            p_gamma,
            energy,
            free: None,
            heavy: None,
        };
        match kind {
            TopKind::Free => top.free = Some(top.free_top()),
            TopKind::Heavy => {
                if sb.abs() < crate::run::body::gimbal_threshold(1e-9) {
                    return Err(TopError::whole(
                        format!("the top starts at {} = {} where the Euler angles are singular", top.angle_names[1], angles[1]),
                        "start the top tilted (β away from 0 and π); a top spinning exactly upright is the sleeping top, whose stability is p_γ² > 4 I M g S",
                    ));
                }
                top.heavy = Some(top.heavy_top(mgs));
            }
        }
        Ok(top)
    }

    fn free_top(&self) -> FreeTop {
        let (i, i3, w) = (self.i, self.i3, self.omega);
        let a = w[0].hypot(w[1]);
        let inclination = (i * a).atan2(i3 * w[2]);
        let body_cone = a.atan2(w[2]);
        let l = (i * a).hypot(i3 * w[2]);
        let shape = if (i3 - i).abs() <= 1e-12 * i.abs() {
            "spherical"
        } else if i3 < i {
            "prolate"
        } else {
            "oblate"
        };
        FreeTop {
            body_precession_rate: (i3 - i) / i * w[2],
            space_precession_rate: l / i,
            inclination,
            transverse_omega: a,
            body_cone_angle: body_cone,
            space_cone_angle: (inclination - body_cone).abs(),
            angular_momentum: l,
            shape,
        }
    }

    /// u̇² = f(u) as cubic coefficients [c0, c1, c2, c3] (u = cos β).
    fn cubic(&self, mgs: f64) -> [f64; 4] {
        let i = self.i;
        let ep = self.energy - self.p_gamma * self.p_gamma / (2.0 * self.i3);
        let (e, k, a, b) = (2.0 * ep / i, 2.0 * mgs / i, self.p_alpha / i, self.p_gamma / i);
        [e - a * a, 2.0 * a * b - k, -e - b * b, k]
    }

    fn heavy_top(&self, mgs: f64) -> HeavyTop {
        let c = self.cubic(mgs);
        let f = |u: f64| ((c[3] * u + c[2]) * u + c[1]) * u + c[0];
        let df = |u: f64| (3.0 * c[3] * u + 2.0 * c[2]) * u + c[1];
        let roots = real_roots(&c, -1.0, 1.0);
        let u0 = self.angles[1].cos();
        let scale = c.iter().map(|x| x.abs()).sum::<f64>().max(f64::MIN_POSITIVE);
        let f0 = f(u0);
        let near = ROOT_GAP;
        let below = |limit: f64| roots.iter().copied().filter(|&r| r < limit).fold(-1.0f64, f64::max);
        let above = |limit: f64| roots.iter().copied().filter(|&r| r > limit).fold(1.0f64, f64::min);
        let (u1, u2) = if f0 > AT_TURNING_RTOL * scale {
            (below(u0), above(u0))
        } else {
            let s = df(u0);
            if s > SLOPE_RTOL * scale {
                (u0, above(u0 + near))
            } else if s < -SLOPE_RTOL * scale {
                (below(u0 - near), u0)
            } else {
                (u0, u0)
            }
        };
        let (a, b) = (self.p_alpha / self.i, self.p_gamma / self.i);
        let rate = |u: f64| (a - b * u) / (1.0 - u * u);
        let kind = if (u2 - u1).abs() < STEADY_GAP {
            NutationKind::Steady
        } else {
            let (s1, s2) = (a - b * u1, a - b * u2);
            let tol = CUSP_RTOL * (a.abs() + b.abs());
            if s1.abs() <= tol || s2.abs() <= tol {
                NutationKind::Cusps
            } else if s1 * s2 < 0.0 {
                NutationKind::Loops
            } else {
                NutationKind::Monotonic
            }
        };
        let alpha_dot_zero = (b != 0.0 && (a / b).abs() <= 1.0).then(|| (a / b).acos());
        // Steady precession at β₀: I cos β₀ α̇² − p_γ α̇ + MgS = 0.
        let cb = u0;
        let (i, pg) = (self.i, self.p_gamma);
        let disc = pg * pg - 4.0 * i * cb * mgs;
        let steady_precession = if (i * cb).abs() <= HORIZONTAL_RTOL * i {
            (pg != 0.0).then(|| [Some(mgs / pg), None])
        } else if disc < 0.0 {
            None
        } else {
            let q = pg + if pg >= 0.0 { 1.0 } else { -1.0 } * disc.sqrt();
            let r1 = q / (2.0 * i * cb);
            let r2 = if q != 0.0 { 2.0 * mgs / q } else { r1 };
            let (slow, fast) = if r1.abs() <= r2.abs() { (r1, r2) } else { (r2, r1) };
            Some([Some(slow), Some(fast)])
        };
        // Quadrature over one swing: u = ū − h cos φ, dt = dφ / sqrt(k (u₃ − u)).
        let k = c[3];
        let u3 = -c[2] / k - u1 - u2;
        let (mid, h) = ((u1 + u2) / 2.0, (u2 - u1) / 2.0);
        // The midpoint rule in φ is Gauss–Chebyshev in u, made for the inverse
        // square roots at the turning points.
        let swing = |phi: f64| {
            let u = mid - h * phi.cos();
            let w = 1.0 / (k * (u3 - u)).sqrt();
            [w, w * rate(u)]
        };
        let [half_t, half_alpha] = num::midpoint(swing, 0.0, std::f64::consts::PI, SWING_POINTS);
        HeavyTop {
            mgs,
            energy_prime: self.energy - pg * pg / (2.0 * self.i3),
            beta_min: u2.clamp(-1.0, 1.0).acos(),
            beta_max: u1.clamp(-1.0, 1.0).acos(),
            kind,
            alpha_dot_zero,
            steady_precession,
            sleeping_stable: pg * pg > 4.0 * i * mgs,
            sleeping_omega3_min: if mgs > 0.0 { (4.0 * i * mgs).sqrt() / self.i3 } else { 0.0 },
            nutation_period: 2.0 * half_t,
            mean_precession_rate: half_alpha / half_t,
        }
    }

    /// U_eff(β) = (p_α − p_γ cos β)²/(2I sin²β) + MgS cos β (heavy top; MgS = 0 for a free one).
    pub fn u_eff(&self, beta: f64) -> f64 {
        let mgs = self.heavy.as_ref().map_or(0.0, |h| h.mgs);
        let (s, c) = beta.sin_cos();
        let x = self.p_alpha - self.p_gamma * c;
        x * x / (2.0 * self.i * s * s) + mgs * c
    }

    /// The `lagrange.top/1` report.
    pub fn report(&self) -> TopReport {
        TopReport {
            format: "lagrange.top/1",
            kind: self.kind.name(),
            body: self.body.clone(),
            omega3: self.omega[2],
            p_alpha: self.p_alpha,
            p_gamma: self.p_gamma,
            energy: self.energy,
            inertia: [self.i, self.i3],
            initial_beta: self.angles[1],
            omega: self.omega,
            body_precession_rate: self.free.as_ref().map(|f| f.body_precession_rate),
            space_precession_rate: self.free.as_ref().map(|f| f.space_precession_rate),
            inclination: self.free.as_ref().map(|f| f.inclination),
            free: self.free.clone(),
            nutation: self.heavy.as_ref().map(|h| Nutation {
                beta_min: h.beta_min,
                beta_max: h.beta_max,
                kind: h.kind.name(),
                period: h.nutation_period,
                alpha_dot_zero: h.alpha_dot_zero,
            }),
            steady_precession: self.heavy.as_ref().map(|h| h.steady_precession),
            energy_prime: self.heavy.as_ref().map(|h| h.energy_prime),
            mean_precession_rate: self.heavy.as_ref().map(|h| h.mean_precession_rate),
            sleeping_top_stable: self.heavy.as_ref().map(|h| h.sleeping_stable),
            sleeping_omega3_min: self.heavy.as_ref().map(|h| h.sleeping_omega3_min),
        }
    }
}

/// The real roots of c0 + c1 u + c2 u² + c3 u³ in [lo, hi], ascending: the
/// interval is cut at the critical points into monotonic pieces, and each piece
/// with a sign change has one root, found by Brent's method.
fn real_roots(c: &[f64; 4], lo: f64, hi: f64) -> Vec<f64> {
    let f = |u: f64| ((c[3] * u + c[2]) * u + c[1]) * u + c[0];
    // f'(u) = 3c3 u² + 2c2 u + c1.
    let (qa, qb, qc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let mut cuts = vec![lo];
    if qa != 0.0 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let q = -0.5 * (qb + qb.signum() * disc.sqrt());
            let mut crit = vec![q / qa];
            if q != 0.0 {
                crit.push(qc / q);
            }
            crit.sort_by(f64::total_cmp);
            cuts.extend(crit.into_iter().filter(|&x| x > lo && x < hi));
        }
    } else if qb != 0.0 {
        let x = -qc / qb;
        if x > lo && x < hi {
            cuts.push(x);
        }
    }
    cuts.push(hi);
    let mut roots = Vec::new();
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (fa, fb) = (f(a), f(b));
        if fa == 0.0 {
            roots.push(a);
            continue;
        }
        if fa * fb < 0.0 {
            if let Ok(r) = num::brent(|u| Ok::<_, ()>(f(u)), a, b, fa, fb, CUBIC_ROOT_TOL) {
                roots.push(r);
            }
        }
    }
    if f(hi) == 0.0 {
        roots.push(hi);
    }
    roots.dedup_by(|x, y| (*x - *y).abs() < DUPLICATE_ROOT);
    roots
}

/// The nutation of a heavy top.
#[derive(Debug, Clone, Serialize)]
pub struct Nutation {
    /// β₁: the smallest inclination.
    pub beta_min: f64,
    /// β₂: the largest inclination.
    pub beta_max: f64,
    /// `steady`, `monotonic`, `loops` or `cusps`.
    pub kind: &'static str,
    /// One full nutation period.
    pub period: f64,
    /// β where α̇ = 0, if any.
    pub alpha_dot_zero: Option<f64>,
}

/// The `lagrange.top/1` JSON contract (DESIGN.md); fields beyond it are extra.
#[derive(Debug, Clone, Serialize)]
pub struct TopReport {
    /// Always `lagrange.top/1`.
    pub format: &'static str,
    /// `free` or `heavy`.
    pub kind: &'static str,
    /// The body's name (extra).
    pub body: String,
    /// ω₃.
    pub omega3: f64,
    /// p_α.
    pub p_alpha: f64,
    /// p_γ.
    pub p_gamma: f64,
    /// E (rotation + gravity).
    pub energy: f64,
    /// [I, I₃] (extra).
    pub inertia: [f64; 2],
    /// The initial β (extra).
    pub initial_beta: f64,
    /// Body-frame ω at the start (extra).
    pub omega: [f64; 3],
    /// Free top: Ω.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_precession_rate: Option<f64>,
    /// Free top: α̇ = A/sin β₀.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub space_precession_rate: Option<f64>,
    /// Free top: β₀.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inclination: Option<f64>,
    /// Free top: cones and |L| (extra).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub free: Option<FreeTop>,
    /// Heavy top: the turning angles.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nutation: Option<Nutation>,
    /// Heavy top: [slow, fast] steady precession rates at the initial β (null: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steady_precession: Option<Option<[Option<f64>; 2]>>,
    /// Heavy top: E' (extra).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_prime: Option<f64>,
    /// Heavy top: the mean α̇ over a nutation period (extra).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean_precession_rate: Option<f64>,
    /// Heavy top: p_γ² > 4IMgS (extra).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sleeping_top_stable: Option<bool>,
    /// Heavy top: the smallest ω₃ of a stable sleeping top (extra).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sleeping_omega3_min: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;

    fn top(text: &str) -> Top {
        let d = Derivation::new(Model::parse(text, &[]).unwrap()).unwrap();
        Top::new(&d).unwrap()
    }

    const HEAVY: &str = r#"
coordinates = ["al", "be", "ga"]
gravity = "g"
[parameters]
M = 1.0
I = 1.0
I3 = 0.5
S = 0.5
g = 9.81
[[bodies]]
mass = "M"
inertia = ["I", "I", "I3"]
angles = ["al", "be", "ga"]
center_of_mass = ["0", "0", "S"]
[initial]
al = 0.0
"al'" = 0.0
be = 0.6
"be'" = 0.0
ga = 0.0
"ga'" = 12.0
"#;

    #[test]
    fn cusps_when_released_without_precession() {
        let t = top(HEAVY);
        let h = t.heavy.as_ref().unwrap();
        assert_eq!(h.kind, NutationKind::Cusps);
        // Released at rest in β: the top starts at its highest point, β₁ = β₀.
        assert!((h.beta_min - 0.6).abs() < 1e-9, "{}", h.beta_min);
        assert!(h.beta_max > 0.6);
        // U_eff(β₁) = U_eff(β₂) = E'.
        for b in [h.beta_min, h.beta_max] {
            assert!((t.u_eff(b) - h.energy_prime).abs() < 1e-9 * h.energy_prime.abs().max(1.0));
        }
    }

    #[test]
    fn steady_precession_rates_solve_the_beta_equation() {
        let t = top(HEAVY);
        let h = t.heavy.as_ref().unwrap();
        let [slow, fast] = h.steady_precession.unwrap();
        for r in [slow.unwrap(), fast.unwrap()] {
            // I cos β α̇² − p_γ α̇ + MgS = 0.
            let res = t.i * 0.6f64.cos() * r * r - t.p_gamma * r + h.mgs;
            assert!(res.abs() < 1e-9, "{r}: {res}");
        }
        assert!(slow.unwrap().abs() < fast.unwrap().abs());
        // The notes' quadratic formula, written out.
        let (cb, pg) = (0.6f64.cos(), t.p_gamma);
        let d = (pg * pg - 4.0 * t.i * cb * h.mgs).sqrt();
        assert!((slow.unwrap() - (pg - d) / (2.0 * t.i * cb)).abs() < 1e-12);
        assert!((fast.unwrap() - (pg + d) / (2.0 * t.i * cb)).abs() < 1e-12);
    }

    #[test]
    fn roots_of_a_known_cubic() {
        // (u + 0.5)(u − 0.25)(u − 3) = u³ − 2.75u² + 0.125u + 0.375 … expand exactly:
        let (r1, r2, r3) = (-0.5f64, 0.25f64, 3.0f64);
        let c = [-r1 * r2 * r3, r1 * r2 + r1 * r3 + r2 * r3, -(r1 + r2 + r3), 1.0];
        let roots = real_roots(&c, -1.0, 1.0);
        assert_eq!(roots.len(), 2);
        assert!((roots[0] - r1).abs() < 1e-14 && (roots[1] - r2).abs() < 1e-14, "{roots:?}");
    }
}
