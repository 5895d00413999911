//! Central-force orbits: the relative motion of the two-body problem in plane
//! polar coordinates, as the notes' Sec. 3.1 reduces and solves it.
//!
//! Entry point: [`Orbit::new`]. It reads μ and U(r) from a derivation of
//! `L = μ/2·(r'² + r²θ'²) − U(r)` (and rejects any other form), takes the
//! angular momentum `l = μr²θ'` and the energy E from the initial state, and
//! finds the turning points of the radial motion as the roots of
//! `E − U_eff(r)`, `U_eff = l²/(2μr²) + U(r)`. For `U = −k/r` the orbit is the
//! notes' conic (α = l²/(μk), ε = sqrt(1 + 2El²/(μk²)), Kepler's third law) and
//! the Laplace–Runge–Lenz vector is reported; for any other U the radial period
//! and the apsidal angle come from quadrature.
//!
//! Quadrature: between the turning points r₁ < r₂ the substitution
//! `r = (r₁ + r₂)/2 + (r₂ − r₁)/2·sin φ` turns the inverse-square-root
//! singularities of `dt = dr/sqrt(2(E − U_eff)/μ)` into a smooth integrand in φ
//! (E − U_eff has simple zeros there), integrated by Gauss–Legendre rules of
//! doubling order until two agree to [`QUADRATURE_RTOL`]
//! (`num::gauss_legendre_doubling`). Near a turning point E − U_eff is taken as
//! an integral of U' from the root, which avoids the cancellation of E against
//! U_eff. Turning points are bracketed by geometric steps out from r₀ and found
//! by Brent's method (`num::brent`). The tolerances are the named constants
//! below, each with what it bounds.

use crate::derive::Derivation;
use crate::error::ModelError;
use crate::modes::short;
use crate::probe::{self, Decision, Subst, UNDECIDED};
use num::DoublingConfig;
use serde::Serialize;
use std::f64::consts::PI;
use sym::{ExprId, Tape};

/// First Gauss–Legendre order of the quadratures in φ: the smooth integrand of a
/// mildly eccentric orbit is exact to round-off with 24 points, so most
/// quadratures stop at the first doubling (48).
const FIRST_ORDER: usize = 24;

/// Largest Gauss–Legendre order tried (the doubling stops at the first order at
/// or beyond it, 3072): a highly eccentric orbit, whose integrand is steep near
/// periapsis, converges before it; beyond it the work (about 6000 evaluations of
/// U per quadrature) outweighs what another doubling could add.
const MAX_ORDER: usize = 2048;

/// Two successive orders agree when they differ by this relative amount: a few
/// hundred ulps, what a sum of up to 3072 terms can promise; periods and apsidal
/// angles are reported to about 1e-12.
const QUADRATURE_RTOL: f64 = 1e-13;

/// The doubling quadrature of the period and the angle.
const QUADRATURE: DoublingConfig =
    DoublingConfig { first_order: FIRST_ORDER, max_order: MAX_ORDER, rtol: QUADRATURE_RTOL };

/// Points of the Gauss–Legendre rule for ∫ U' over the short distance from a
/// turning point (at most a quarter of the orbit's width): U' is smooth there,
/// and a 12-point rule (exact to degree 23) reaches round-off.
const SHORT_RULE_ORDER: usize = 12;

/// Points of the Gauss–Legendre rule per piece of an unbounded orbit's path,
/// whose pieces are short (the branch is cut into at least four); the path is
/// drawn, so 16 points (degree 31) are plenty.
const PATH_RULE_ORDER: usize = 16;

/// Closer to a turning point than this fraction of the orbit's half-width
/// (or of the periapsis, on an unbounded orbit), E − U_eff is measured from the
/// root ([`Orbit::radial_from_root`]): there the direct difference E − U_eff
/// would lose digits to cancellation, further out it costs 12 evaluations for nothing.
const NEAR_ROOT_FRACTION: f64 = 0.25;

/// Relative offset from r₀ at which a start at rest (r' = 0, so r₀ is itself a
/// turning point) looks for the other: far enough that E − U_eff is above its
/// round-off (≈ 1e-16·|U|/δ² in r), close enough not to skip a nearby root.
const AT_REST_OFFSET: f64 = 1e-7;

/// The start is at rest (a turning point) when E − U_eff(r₀) is below this
/// fraction of |E| + |U_eff(r₀)|: a hundred ulps of the terms it is the difference of.
const AT_REST_RTOL: f64 = 1e-14;

/// Factor of the geometric steps inward from r₀ that bracket the periapsis: 5%
/// per step brackets any root within about 50 evaluations per decade of r and
/// does not step over two close roots of a well-resolved U_eff.
const INWARD_STEP: f64 = 0.95;

/// Factor of the steps outward that bracket the apoapsis (5%, as inward).
const OUTWARD_STEP: f64 = 1.05;

/// Inward search ends (the particle falls in) below this fraction of r₀: a
/// periapsis 10¹² times closer than the start is the centre, numerically.
const FALL_IN_RATIO: f64 = 1e-12;

/// Outward search ends (the orbit is unbounded) beyond this multiple of r₀,
/// about 420 steps: an apoapsis 10⁹ times farther out is escape, numerically.
const ESCAPE_RATIO: f64 = 1e9;

/// Absolute tolerance of Brent's method for the turning points: none beyond its
/// own 4ε|r|, so they are found to round-off, since the quadrature measures
/// E − U_eff from them and an error δ there leaves U_eff'·δ at the ends.
const TURNING_POINT_TOL: f64 = 0.0;

/// Absolute tolerance of Brent's method for φ in [`Orbit::r_at`] (φ ∈ [−π/2, π/2]):
/// a few ulps of π/2, r to round-off.
const R_AT_PHI_TOL: f64 = 1e-15;

/// A Kepler orbit is a circle when 1 + 2El²/(μk²) = ε² is below this: ε below
/// 1e-5, where r₀ and the turning points agree to 1e-10 and the quadrature of
/// the nearly-circular motion is not needed.
const CIRCLE_EPS2: f64 = 1e-10;

/// A Kepler orbit is a parabola when |E| is below this fraction of k/r₀: E is
/// the difference of two terms of that size, so below a few hundred ulps of
/// them its sign is round-off.
const PARABOLA_RTOL: f64 = 1e-12;

/// A periapsis angle this close below 2π is reported as 0, not as 2π − ulp.
const ANGLE_WRAP_TOL: f64 = 1e-12;

/// Fewest pieces of a path (per half-period or branch): the quadrature per
/// piece assumes a short piece.
const MIN_PATH_PIECES: usize = 4;

/// An unbounded branch is drawn out to at least this multiple of the periapsis,
/// so that a `r_max` inside it still gives a branch to draw.
const MIN_BRANCH_REACH: f64 = 1.0001;

/// What kind of orbit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OrbitKind {
    /// U = −k/r, ε = 0.
    Circle,
    /// U = −k/r, 0 < ε < 1.
    Ellipse,
    /// U = −k/r, ε = 1 (E = 0).
    Parabola,
    /// U = −k/r, ε > 1.
    Hyperbola,
    /// Another U, r stays between two turning points.
    Bounded,
    /// Another U, r grows without bound.
    Unbounded,
}

impl OrbitKind {
    /// Its name in the JSON contract.
    pub fn name(self) -> &'static str {
        match self {
            OrbitKind::Circle => "circle",
            OrbitKind::Ellipse => "ellipse",
            OrbitKind::Parabola => "parabola",
            OrbitKind::Hyperbola => "hyperbola",
            OrbitKind::Bounded => "bounded",
            OrbitKind::Unbounded => "unbounded",
        }
    }
}

/// The closed form of the Kepler problem U = −k/r.
#[derive(Debug, Clone)]
pub struct Kepler {
    /// k in U = −k/r, as an expression in the parameters.
    pub k_expr: ExprId,
    /// Its value.
    pub k: f64,
    /// α = l²/(μk), the semi-latus rectum.
    pub alpha: f64,
    /// ε = sqrt(1 + 2El²/(μk²)).
    pub eccentricity: f64,
    /// The Laplace–Runge–Lenz vector A = p × l − μk r/r in the plane (|A| = μkε, pointing at periapsis).
    pub runge_lenz: [f64; 2],
}

/// A central-force orbit from a model's initial state.
#[derive(Debug)]
pub struct Orbit {
    /// The pool of the orbit's expressions: the derivation's, extended.
    pub pool: sym::Pool,
    /// The radial and angular coordinate names.
    pub names: [String; 2],
    /// μ as an expression in the parameters.
    pub mu_expr: ExprId,
    /// U(r) as an expression.
    pub potential_expr: ExprId,
    /// The reduced mass μ.
    pub mu: f64,
    /// l = μr²θ'.
    pub angular_momentum: f64,
    /// E = μr'²/2 + U_eff(r).
    pub energy: f64,
    /// The initial state (r, θ, r', θ').
    pub initial: [f64; 4],
    /// The kind of orbit.
    pub kind: OrbitKind,
    /// The inner turning point.
    pub periapsis: f64,
    /// The outer turning point (None: unbounded).
    pub apoapsis: Option<f64>,
    /// The radial period, periapsis to periapsis (for U = −k/r the orbital period).
    pub period: Option<f64>,
    /// The angle swept from periapsis to the next apoapsis.
    pub apsidal_angle: Option<f64>,
    /// θ at a periapsis passage.
    pub periapsis_angle: f64,
    /// The closed form, for U = −k/r with k > 0.
    pub kepler: Option<Kepler>,
    /// U, U', U'', U''' compiled (input 0 is r).
    tape: Tape,
    inputs: Vec<f64>,
    out: [f64; 4],
}

/// Why there is no orbit to report.
#[derive(Debug, Clone, thiserror::Error)]
pub enum OrbitError {
    /// The model itself is wrong.
    #[error("{0}")]
    Model(ModelError),
    /// The model is not L = μ/2·(r'² + r²θ'²) − U(r).
    #[error("not a central-force model: {reason}")]
    NotCentral {
        /// What does not fit.
        reason: String,
    },
    /// A fact the central form rests on could be neither proven nor refuted.
    #[error("cannot tell whether this is a central-force model: could not decide {what} ({})", UNDECIDED)]
    Undecided {
        /// The fact, as a clause ("whether the potential … depends on the angle th").
        what: String,
    },
    /// The initial state has l = 0.
    #[error("the initial state has no angular momentum ({angle}' = 0): the motion is radial, along a line through the centre")]
    Radial {
        /// The angle's name.
        angle: String,
    },
    /// E − U_eff has no inner root: the particle falls into the centre.
    #[error("the particle falls into the centre: E > U_eff(r) all the way down to r = 0")]
    FallsIn,
    /// U is not finite on the way.
    #[error("U(r) is not finite at r = {r}")]
    NotFinite {
        /// Where.
        r: String,
    },
}

impl OrbitError {
    /// A hint on how to fix it.
    pub fn help(&self) -> Option<String> {
        match self {
            OrbitError::Model(e) => e.help.clone(),
            OrbitError::NotCentral { .. } => Some(
                "give coordinates = [\"r\", \"th\"] and L = mu*(r'^2 + r^2*th'^2)/2 - U(r), e.g. lagrangian = \"mu*(r'^2 + r^2*th'^2)/2 + k/r\", or two particles placed at ±r about their centre of mass".into(),
            ),
            OrbitError::Undecided { .. } => Some(
                "an orbit is computed only for a model shown exactly to be central; a term that every probe point rounds to 0 (such as exp(-10000*th^2)) is shown neither absent nor present".into(),
            ),
            OrbitError::Radial { angle } => Some(format!("give \"{angle}'\" a nonzero initial value")),
            OrbitError::FallsIn | OrbitError::NotFinite { .. } => None,
        }
    }
}

impl From<ModelError> for OrbitError {
    fn from(e: ModelError) -> Self {
        OrbitError::Model(e)
    }
}

fn not_central(reason: impl Into<String>) -> OrbitError {
    OrbitError::NotCentral { reason: reason.into() }
}

fn undecided(what: impl Into<String>) -> OrbitError {
    OrbitError::Undecided { what: what.into() }
}

/// The Gauss–Legendre rule of a constant order (within `num`'s range, so it
/// is always built).
fn rule(order: usize) -> Vec<(f64, f64)> {
    num::gauss_legendre_rule(order).expect("a constant order within num's range")
}

/// The rule for short integrals of U'.
static SHORT_RULE: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();

impl Orbit {
    /// Reads μ and U(r) from the derivation and computes the orbit of the initial state.
    pub fn new(d: &Derivation) -> Result<Orbit, OrbitError> {
        let names: Vec<String> = d.model.coordinates.iter().map(|c| c.name.clone()).collect();
        if names.len() != 2 {
            return Err(not_central(format!(
                "it has {} coordinates ({}); an orbit needs exactly two, the distance r and the angle",
                names.len(),
                names.join(", ")
            )));
        }
        match d.explicit_time {
            Some(false) => {}
            Some(true) => return Err(not_central("L depends explicitly on the time")),
            None => return Err(undecided("whether L depends explicitly on the time")),
        }
        if d.dissipation.is_some() {
            return Err(not_central("it has dissipation or generalized forces; a central force derives from U(r)"));
        }
        let (r, th, rd, thd) = (d.q[0], d.q[1], d.qd[0], d.qd[1]);
        let m = &d.mass_matrix;
        let (m00, m01, m11) = (m[0][0], m[0][1], m[1][1]);
        // The derivation's pool is frozen: U(r), μ and their derivatives are
        // built in a copy, which the orbit keeps for printing them.
        let mut pool_owned = d.pool().clone();
        let pool = &mut pool_owned;
        let (rn, an) = (&names[0], &names[1]);
        // Each fact of the central form is a claim: a refuted one is "not
        // central", an undecided one is said as such, and neither gives an orbit.
        let check = |decision: Decision, not: String, what: String| match decision {
            Decision::Zero => Ok(()),
            Decision::NonZero => Err(not_central(not)),
            Decision::Undecided => Err(undecided(what)),
        };
        for (k, &f) in d.forces.iter().enumerate() {
            check(
                probe::decide_zero(pool, f),
                "it has dissipation or generalized forces; a central force derives from U(r)".into(),
                format!("whether the generalized force on {} is zero", names[k]),
            )?;
        }
        for q in [r, th] {
            let dm = pool.diff(m00, q);
            check(
                probe::decide_zero(pool, dm),
                format!("∂²L/∂{rn}'² = {} is not a constant reduced mass μ", pool.display(m00)),
                format!("whether ∂²L/∂{rn}'² = {} is a constant reduced mass μ", pool.display(m00)),
            )?;
        }
        check(
            probe::decide_zero(pool, m01),
            format!("L couples {rn}' and {an}' (∂²L/∂{rn}'∂{an}' = {})", pool.display(m01)),
            format!("whether ∂²L/∂{rn}'∂{an}' = {} is zero", pool.display(m01)),
        )?;
        let r2 = pool.powi(r, 2);
        let mu_r2 = pool.mul2(m00, r2);
        check(
            probe::decide_equal(pool, m11, mu_r2),
            format!(
                "∂²L/∂{an}'² = {} is not μ·{rn}^2 = {}: the coordinates are not plane polar ({rn}, {an})",
                pool.display(m11),
                pool.display(mu_r2)
            ),
            format!("whether ∂²L/∂{an}'² = {} equals μ·{rn}^2 = {}", pool.display(m11), pool.display(mu_r2)),
        )?;
        let zero_vel: Subst = [(rd, pool.zero()), (thd, pool.zero())].into_iter().collect();
        let l0 = pool.substitute(d.lagrangian, &zero_vel);
        let u = pool.neg(l0);
        let u = pool.simplify(u);
        let du_th = pool.diff(u, th);
        check(
            probe::decide_zero(pool, du_th),
            format!("the potential U = {} depends on the angle {an}", pool.display(u)),
            format!(
                "whether the potential U = {} depends on the angle {an}, that is whether ∂U/∂{an} = {} is zero",
                pool.display(u),
                pool.display(du_th)
            ),
        )?;
        // L must be exactly μ/2·(r'² + r²θ'²) − U(r): no terms linear in the velocities.
        let rd2 = pool.powi(rd, 2);
        let thd2 = pool.powi(thd, 2);
        let rot = pool.mul2(r2, thd2);
        let sum = pool.add2(rd2, rot);
        let half = pool.rational(1, 2);
        let kin = pool.mul(&[half, m00, sum]);
        let expect = pool.sub(kin, u);
        check(
            probe::decide_equal(pool, d.lagrangian, expect),
            format!("L has terms linear in the velocities (L ≠ μ/2·({rn}'^2 + {rn}^2*{an}'^2) − U({rn}))"),
            format!("whether L = μ/2·({rn}'^2 + {rn}^2*{an}'^2) − U({rn}) exactly"),
        )?;
        let mu_expr = pool.simplify(m00);

        // Kepler: r·U constant.
        let ru = pool.mul2(r, u);
        let dru = pool.diff(ru, r);
        let kepler_k = if probe::is_zero(pool, dru) {
            let k = pool.neg(ru);
            let k = pool.simplify(k);
            Some(k)
        } else {
            None
        };

        // Compile U and three derivatives in r.
        let u1 = pool.diff(u, r);
        let u2 = pool.diff(u1, r);
        let u3 = pool.diff(u2, r);
        let (input_ids, input_values) = (d.layout().symbols(), d.layout().values());
        let tape = Tape::compile(pool, &[u, u1, u2, u3], input_ids)
            .map_err(|e| not_central(format!("U cannot be evaluated: {e}")))?;
        let model = &d.model;
        let env = |name: &str| model.parameter(name);
        let mu = pool.eval(mu_expr, &env).map_err(|e| not_central(format!("μ cannot be evaluated: {e}")))?;
        if !(mu.is_finite() && mu > 0.0) {
            return Err(not_central(format!("the reduced mass μ = {} must be positive", short(mu))));
        }
        let kepler_k = match kepler_k {
            Some(k) => match pool.eval(k, &env) {
                Ok(v) if v.is_finite() && v > 0.0 => Some((k, v)),
                _ => None,
            },
            None => None,
        };
        let (q, qd) = model.initial_state()?;
        let mut orbit = Orbit {
            pool: pool_owned,
            names: [names[0].clone(), names[1].clone()],
            mu_expr,
            potential_expr: u,
            mu,
            angular_momentum: mu * q[0] * q[0] * qd[1],
            energy: 0.0,
            initial: [q[0], q[1], qd[0], qd[1]],
            kind: OrbitKind::Bounded,
            periapsis: q[0],
            apoapsis: None,
            period: None,
            apsidal_angle: None,
            periapsis_angle: q[1],
            kepler: None,
            tape,
            inputs: input_values,
            out: [0.0; 4],
        };
        if !(q[0].is_finite() && q[0] > 0.0) {
            return Err(not_central(format!("the initial distance {} = {} must be positive", rn, short(q[0]))));
        }
        if orbit.angular_momentum == 0.0 {
            return Err(OrbitError::Radial { angle: an.clone() });
        }
        let u_r0 = orbit.derivs(q[0])[0];
        if !u_r0.is_finite() {
            return Err(OrbitError::NotFinite { r: short(q[0]) });
        }
        orbit.energy = 0.5 * mu * qd[0] * qd[0] + orbit.u_eff(q[0]);
        orbit.turning_points()?;
        if let Some((k_expr, k)) = kepler_k {
            orbit.kepler_elements(k_expr, k);
        } else if let Some(r2) = orbit.apoapsis {
            let (t, dth) = orbit.half_orbit(orbit.periapsis, r2);
            orbit.period = Some(2.0 * t);
            orbit.apsidal_angle = Some(dth);
        }
        orbit.periapsis_angle = orbit.find_periapsis_angle();
        if orbit.kepler.is_some() {
            // A closed orbit: any periapsis passage will do; report it in [0, 2π).
            let a = orbit.periapsis_angle.rem_euclid(2.0 * PI);
            orbit.periapsis_angle = if 2.0 * PI - a < ANGLE_WRAP_TOL { 0.0 } else { a };
        }
        Ok(orbit)
    }

    /// U and its first three derivatives at r.
    fn derivs(&mut self, r: f64) -> [f64; 4] {
        self.inputs[0] = r;
        self.tape.eval(&self.inputs, &mut self.out);
        self.out
    }

    /// U(r).
    pub fn potential(&mut self, r: f64) -> f64 {
        self.derivs(r)[0]
    }

    /// The effective potential l²/(2μr²) + U(r).
    pub fn u_eff(&mut self, r: f64) -> f64 {
        let l = self.angular_momentum;
        l * l / (2.0 * self.mu * r * r) + self.derivs(r)[0]
    }

    /// E − U_eff(r) and its first three derivatives.
    fn radial(&mut self, r: f64) -> [f64; 4] {
        let [u, u1, u2, u3] = self.derivs(r);
        let c = self.angular_momentum * self.angular_momentum / (2.0 * self.mu);
        [self.energy - c / (r * r) - u, 2.0 * c / r.powi(3) - u1, -6.0 * c / r.powi(4) - u2, 24.0 * c / r.powi(5) - u3]
    }

    /// E − U_eff(r) near a root `a` of it, without cancellation:
    /// l²/(2μ)·(1/a² − 1/r²) − ∫ₐʳ U'(s) ds, the integral by a
    /// [`SHORT_RULE_ORDER`]-point Gauss–Legendre rule.
    fn radial_from_root(&mut self, a: f64, x: f64) -> f64 {
        let r = a + x;
        let c = self.angular_momentum * self.angular_momentum / (2.0 * self.mu);
        let centrifugal = c * x * (r + a) / (a * a * r * r);
        let short = SHORT_RULE.get_or_init(|| rule(SHORT_RULE_ORDER));
        // About the centre a + x/2 with half-width x/2: x, not (a + x) − a, which rounds.
        let [integral] = num::gauss_legendre_centered(short, |s| [self.derivs(s)[1]], a + 0.5 * x, 0.5 * x);
        centrifugal - integral
    }

    /// The root of E − U_eff between `a` and `b`, where it takes the values `fa`
    /// and `fb` of opposite signs, by Brent's method.
    fn root(&mut self, a: f64, b: f64, fa: f64, fb: f64) -> f64 {
        num::brent(|r| Ok::<_, std::convert::Infallible>(self.radial(r)[0]), a, b, fa, fb, TURNING_POINT_TOL)
            .unwrap_or_else(|never| match never {})
    }

    fn turning_points(&mut self) -> Result<(), OrbitError> {
        let r0 = self.initial[0];
        let delta = AT_REST_OFFSET;
        let f0 = self.radial(r0)[0];
        let scale = self.energy.abs() + self.u_eff(r0).abs();
        let at_rest = self.initial[2] == 0.0 || f0.abs() <= AT_REST_RTOL * scale;
        let (r_in, r_out) = (r0 * (1.0 - delta), r0 * (1.0 + delta));
        let (f_in, f_out) = if at_rest { (self.radial(r_in)[0], self.radial(r_out)[0]) } else { (f0, f0) };
        let (inner_ok, outer_ok) = if at_rest { (f_in > 0.0, f_out > 0.0) } else { (true, true) };
        // Inner turning point.
        self.periapsis = if at_rest && !inner_ok {
            r0
        } else {
            let (mut r, mut f_r) = if at_rest { (r_in, f_in) } else { (r0, f0) };
            loop {
                let next = r * INWARD_STEP;
                if next < FALL_IN_RATIO * r0 {
                    return Err(OrbitError::FallsIn);
                }
                let f = self.radial(next)[0];
                if !f.is_finite() {
                    return Err(OrbitError::NotFinite { r: short(next) });
                }
                if f < 0.0 {
                    break self.root(next, r, f, f_r);
                }
                (r, f_r) = (next, f);
            }
        };
        // Outer turning point.
        self.apoapsis = if !at_rest || outer_ok {
            let (mut r, mut f_r) = if at_rest { (r_out, f_out) } else { (r0, f0) };
            let mut found = None;
            while r < ESCAPE_RATIO * r0 {
                let next = r * OUTWARD_STEP;
                let f = self.radial(next)[0];
                if !f.is_finite() {
                    return Err(OrbitError::NotFinite { r: short(next) });
                }
                if f < 0.0 {
                    found = Some(self.root(r, next, f_r, f));
                    break;
                }
                (r, f_r) = (next, f);
            }
            found
        } else {
            Some(r0)
        };
        self.kind = if self.apoapsis.is_some() { OrbitKind::Bounded } else { OrbitKind::Unbounded };
        Ok(())
    }

    fn kepler_elements(&mut self, k_expr: ExprId, k: f64) {
        let (mu, l, e) = (self.mu, self.angular_momentum, self.energy);
        let alpha = l * l / (mu * k);
        let arg = 1.0 + 2.0 * e * l * l / (mu * k * k);
        let eps = arg.max(0.0).sqrt();
        let [r, th, rd, thd] = self.initial;
        let (c, s) = (th.cos(), th.sin());
        let (vx, vy) = (rd * c - r * thd * s, rd * s + r * thd * c);
        let runge_lenz = [mu * l * vy - mu * k * c, -mu * l * vx - mu * k * s];
        let u_scale = k / r;
        self.kind = if arg.abs() <= CIRCLE_EPS2 {
            OrbitKind::Circle
        } else if e.abs() <= PARABOLA_RTOL * u_scale {
            OrbitKind::Parabola
        } else if e < 0.0 {
            OrbitKind::Ellipse
        } else {
            OrbitKind::Hyperbola
        };
        let eps = if self.kind == OrbitKind::Circle {
            0.0
        } else if self.kind == OrbitKind::Parabola {
            1.0
        } else {
            eps
        };
        self.periapsis = alpha / (1.0 + eps);
        if eps < 1.0 {
            self.apoapsis = Some(alpha / (1.0 - eps));
            let a = alpha / (1.0 - eps * eps);
            self.period = Some(2.0 * PI * (mu * a.powi(3) / k).sqrt());
            self.apsidal_angle = Some(PI);
        } else {
            self.apoapsis = None;
            self.period = None;
            self.apsidal_angle = None;
        }
        self.kepler = Some(Kepler { k_expr, k, alpha, eccentricity: eps, runge_lenz });
    }

    /// (dt/dφ, dθ/dφ) at r = c + h sin φ; the turning points are r1 and r2.
    fn integrand(&mut self, phi: f64, r1: f64, r2: f64) -> (f64, f64) {
        let h = 0.5 * (r2 - r1);
        let (sin, cos) = phi.sin_cos();
        // The distance from the nearer turning point, from φ without cancellation
        // (1 ± sin φ = cos²φ/(1 ∓ sin φ)), so that r and cos φ stay consistent.
        let (near, x) = if phi < 0.0 { (r1, h * cos * cos / (1.0 - sin)) } else { (r2, -h * cos * cos / (1.0 + sin)) };
        let r = near + x;
        // E − U_eff(r) measured from the nearer root where the direct difference would cancel.
        let f = if x.abs() < NEAR_ROOT_FRACTION * h { self.radial_from_root(near, x) } else { self.radial(r)[0] };
        let rate = (2.0 * f.max(0.0) / self.mu).sqrt();
        // h cos φ / sqrt(2f/μ); both vanish together at the ends.
        let dt = if rate > 0.0 { h * cos / rate } else { 0.0 };
        (dt, self.angular_momentum.abs() / (self.mu * r * r) * dt)
    }

    /// ∫ (dt, dθ) over φ ∈ [a, b] with Gauss–Legendre of increasing order
    /// ([`QUADRATURE`]); NaN where the bounds are not finite.
    fn integrate(&mut self, a: f64, b: f64, r1: f64, r2: f64) -> (f64, f64) {
        let integrand = |phi: f64| {
            let (dt, dth) = self.integrand(phi, r1, r2);
            [dt, dth]
        };
        num::gauss_legendre_doubling(integrand, a, b, &QUADRATURE)
            .map_or((f64::NAN, f64::NAN), |d| (d.value[0], d.value[1]))
    }

    /// The time and the angle from r1 to r2.
    fn half_orbit(&mut self, r1: f64, r2: f64) -> (f64, f64) {
        if r2 <= r1 {
            // A circle: the small-oscillation limits.
            let [_, _, f2, _] = self.radial(r1);
            let omega_r = (-f2 / self.mu).max(0.0).sqrt();
            let t = PI / omega_r;
            return (t, self.angular_momentum.abs() / (self.mu * r1 * r1) * t);
        }
        self.integrate(-PI / 2.0, PI / 2.0, r1, r2)
    }

    /// The radial period and the apsidal angle by quadrature, whatever U is
    /// (for U = −k/r they check the closed form). None for an unbounded orbit.
    pub fn quadrature(&mut self) -> Option<(f64, f64)> {
        let r2 = self.apoapsis?;
        let (t, dth) = self.half_orbit(self.periapsis, r2);
        Some((2.0 * t, dth))
    }

    /// The angle swept from periapsis out to distance r on a bounded orbit.
    fn angle_from_periapsis(&mut self, r: f64) -> f64 {
        let (r1, r2) = (self.periapsis, self.apoapsis.unwrap_or(self.periapsis));
        if r2 <= r1 {
            return 0.0;
        }
        let s = ((2.0 * r - r1 - r2) / (r2 - r1)).clamp(-1.0, 1.0);
        self.integrate(-PI / 2.0, s.asin(), r1, r2).1
    }

    fn find_periapsis_angle(&mut self) -> f64 {
        let [r0, th0, rd0, _] = self.initial;
        let sign = self.angular_momentum.signum();
        if self.apoapsis.is_none() {
            // Unbounded: the angle from periapsis by quadrature in 1/r is not
            // needed for the report; the plot integrates its own path.
            return th0;
        }
        let swept = self.angle_from_periapsis(r0);
        let apsidal = self.apsidal_angle.unwrap_or(PI);
        if rd0 >= 0.0 {
            th0 - sign * swept
        } else {
            th0 + sign * (2.0 * apsidal - swept)
        }
    }

    /// r at the angle θ on a bounded orbit (by inverting θ(φ) with Brent's method).
    pub fn r_at(&mut self, theta: f64) -> Option<f64> {
        let r2 = self.apoapsis?;
        let r1 = self.periapsis;
        if r2 <= r1 {
            return Some(r1);
        }
        let apsidal = self.half_orbit(r1, r2).1;
        let sign = self.angular_momentum.signum();
        let mut psi = (sign * (theta - self.periapsis_angle)).rem_euclid(2.0 * apsidal);
        if psi > apsidal {
            psi = 2.0 * apsidal - psi;
        }
        // The angle swept grows with φ from 0 at −π/2 to the apsidal angle at π/2.
        let phi = num::brent(
            |phi| Ok::<_, std::convert::Infallible>(self.integrate(-PI / 2.0, phi, r1, r2).1 - psi),
            -PI / 2.0,
            PI / 2.0,
            -psi,
            apsidal - psi,
            R_AT_PHI_TOL,
        )
        .unwrap_or_else(|never| match never {});
        Some(0.5 * (r1 + r2) + 0.5 * (r2 - r1) * phi.sin())
    }

    /// Points (θ, r) along one radial period of a bounded orbit, from a
    /// periapsis, or along the outgoing branch of an unbounded one up to
    /// `r_max`.
    pub fn path(&mut self, n: usize, r_max: f64) -> Vec<(f64, f64)> {
        let n = n.max(MIN_PATH_PIECES);
        let sign = self.angular_momentum.signum();
        let r1 = self.periapsis;
        let mut pts = Vec::with_capacity(2 * n + 1);
        match self.apoapsis {
            Some(r2) if r2 > r1 => {
                let mut theta = 0.0;
                let mut prev = -PI / 2.0;
                let mut half = vec![(0.0, r1)];
                for i in 1..=n {
                    let phi = -PI / 2.0 + PI * i as f64 / n as f64;
                    theta += self.integrate(prev, phi, r1, r2).1;
                    prev = phi;
                    half.push((theta, 0.5 * (r1 + r2) + 0.5 * (r2 - r1) * phi.sin()));
                }
                let total = theta;
                pts.extend(half.iter().map(|&(a, r)| (self.periapsis_angle + sign * a, r)));
                pts.extend(
                    half.iter().rev().skip(1).map(|&(a, r)| (self.periapsis_angle + sign * (2.0 * total - a), r)),
                );
            }
            Some(_) => {
                for i in 0..=2 * n {
                    pts.push((self.periapsis_angle + sign * 2.0 * PI * i as f64 / (2 * n) as f64, r1));
                }
            }
            None => {
                // dθ/dr = l/(μr²)/sqrt(2f/μ) with r = r1/(1 − w²): smooth at w = 0.
                let w_max = (1.0 - r1 / r_max.max(r1 * MIN_BRANCH_REACH)).sqrt();
                let rule = rule(PATH_RULE_ORDER);
                let mut theta = 0.0;
                let mut prev = 0.0;
                pts.push((0.0, r1));
                for i in 1..=n {
                    let w = w_max * i as f64 / n as f64;
                    let dtheta_dw = |ww: f64| {
                        let r = r1 / (1.0 - ww * ww);
                        let drdw = 2.0 * r1 * ww / (1.0 - ww * ww).powi(2);
                        let near = r - r1 < NEAR_ROOT_FRACTION * r1;
                        let f = if near { self.radial_from_root(r1, r - r1) } else { self.radial(r)[0] };
                        let rate = (2.0 * f.max(0.0) / self.mu).sqrt();
                        [if rate > 0.0 { self.angular_momentum.abs() / (self.mu * r * r) * drdw / rate } else { 0.0 }]
                    };
                    theta += num::gauss_legendre(&rule, dtheta_dw, prev, w)[0];
                    prev = w;
                    pts.push((theta, r1 / (1.0 - w * w)));
                }
                let [r0, th0, rd0, _] = self.initial;
                // Place the periapsis so that the branch passes the initial point.
                let at_r0 = interpolate_angle(&pts, r0);
                let peri = if rd0 >= 0.0 { th0 - sign * at_r0 } else { th0 + sign * at_r0 };
                self.periapsis_angle = peri;
                let out: Vec<(f64, f64)> = pts.iter().map(|&(a, r)| (peri + sign * a, r)).collect();
                let mut both: Vec<(f64, f64)> = pts.iter().rev().map(|&(a, r)| (peri - sign * a, r)).collect();
                both.extend(out.into_iter().skip(1));
                return both;
            }
        }
        pts
    }

    /// The orbit as the JSON contract `lagrange.orbit/1`.
    pub fn report(&self, d: &Derivation) -> OrbitReport {
        let pool = &self.pool;
        OrbitReport {
            format: "lagrange.orbit/1",
            name: d.model.name.clone(),
            energy: self.energy,
            angular_momentum: self.angular_momentum,
            reduced_mass: self.mu,
            kind: self.kind.name(),
            eccentricity: self.kepler.as_ref().map(|k| k.eccentricity),
            semi_latus_rectum: self.kepler.as_ref().map(|k| k.alpha),
            periapsis: self.periapsis,
            apoapsis: self.apoapsis,
            period: self.period,
            apsidal_angle: self.apsidal_angle,
            precession_per_period: self.apsidal_angle.map(|a| 2.0 * a - 2.0 * PI),
            periapsis_angle: self.periapsis_angle,
            potential: pool.display(self.potential_expr).to_string(),
            reduced_mass_expr: pool.display(self.mu_expr).to_string(),
            runge_lenz: self.kepler.as_ref().map(|k| k.runge_lenz),
        }
    }
}

/// θ where the tabulated branch reaches r (linear interpolation).
fn interpolate_angle(pts: &[(f64, f64)], r: f64) -> f64 {
    for w in pts.windows(2) {
        let ((a0, r0), (a1, r1)) = (w[0], w[1]);
        if (r0..=r1).contains(&r) && r1 > r0 {
            return a0 + (a1 - a0) * (r - r0) / (r1 - r0);
        }
    }
    pts.last().map_or(0.0, |p| p.0)
}

/// The orbit as the JSON contract `lagrange.orbit/1`.
#[derive(Debug, Clone, Serialize)]
pub struct OrbitReport {
    /// Always `lagrange.orbit/1`.
    pub format: &'static str,
    /// The model's name.
    pub name: String,
    /// E.
    pub energy: f64,
    /// l = μr²θ'.
    pub angular_momentum: f64,
    /// μ.
    pub reduced_mass: f64,
    /// circle, ellipse, parabola, hyperbola (U = −k/r), bounded, unbounded.
    pub kind: &'static str,
    /// ε (U = −k/r only).
    pub eccentricity: Option<f64>,
    /// α = l²/(μk) (U = −k/r only).
    pub semi_latus_rectum: Option<f64>,
    /// The inner turning point.
    pub periapsis: f64,
    /// The outer turning point, null when unbounded.
    pub apoapsis: Option<f64>,
    /// The radial period (periapsis to periapsis), null when unbounded.
    pub period: Option<f64>,
    /// The angle from periapsis to the next apoapsis, null when unbounded.
    pub apsidal_angle: Option<f64>,
    /// 2·apsidal angle − 2π: how far the periapsis advances per radial period.
    pub precession_per_period: Option<f64>,
    /// θ at a periapsis.
    pub periapsis_angle: f64,
    /// U(r) as read from the derivation.
    pub potential: String,
    /// μ as read from the derivation.
    pub reduced_mass_expr: String,
    /// The Laplace–Runge–Lenz vector [A_x, A_y] (U = −k/r only).
    pub runge_lenz: Option<[f64; 2]>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;

    fn orbit_of(lagrangian: &str, params: &str, initial: [f64; 4]) -> Result<(Orbit, Derivation), OrbitError> {
        let text = format!(
            "coordinates = [\"r\", \"th\"]\nlagrangian = \"{lagrangian}\"\n[parameters]\n{params}\n[initial]\nr = {}\n\"r'\" = {}\nth = {}\n\"th'\" = {}\n",
            initial[0], initial[2], initial[1], initial[3]
        );
        let model = Model::parse(&text, &[]).expect("model");
        let d = Derivation::new(model).expect("derivation");
        let o = Orbit::new(&d)?;
        Ok((o, d))
    }

    #[track_caller]
    fn close(got: f64, want: f64, rel: f64) {
        assert!((got - want).abs() <= rel * want.abs().max(1e-300), "got {got:.16e}, want {want:.16e}");
    }

    #[test]
    fn kepler_elements_match_the_closed_forms() {
        let (mu, k) = (0.7, 1.3);
        let (r0, thd0, rd0) = (1.0, 1.1, 0.2);
        let (mut o, _) = orbit_of("mu*(r'^2 + r^2*th'^2)/2 + k/r", "mu = 0.7\nk = 1.3", [r0, 0.3, rd0, thd0]).unwrap();
        let l = mu * r0 * r0 * thd0;
        let e = 0.5 * mu * (rd0 * rd0 + r0 * r0 * thd0 * thd0) - k / r0;
        let alpha = l * l / (mu * k);
        let eps = (1.0 + 2.0 * e * l * l / (mu * k * k)).sqrt();
        close(o.angular_momentum, l, 1e-15);
        close(o.energy, e, 1e-14);
        assert_eq!(o.kind, OrbitKind::Ellipse);
        let kep = o.kepler.clone().unwrap();
        close(kep.eccentricity, eps, 1e-14);
        close(o.periapsis, alpha / (1.0 + eps), 1e-14);
        close(o.apoapsis.unwrap(), alpha / (1.0 - eps), 1e-14);
        let a = alpha / (1.0 - eps * eps);
        close(o.period.unwrap(), 2.0 * PI * (mu * a.powi(3) / k).sqrt(), 1e-14);
        // |A| = μkε.
        close(kep.runge_lenz[0].hypot(kep.runge_lenz[1]), mu * k * eps, 1e-13);
        // The quadrature agrees with the closed forms: apsidal angle π, Kepler's third law.
        let (t, dth) = o.quadrature().unwrap();
        close(dth, PI, 1e-10);
        close(t, o.period.unwrap(), 1e-10);
        // The root finder agrees with α/(1 ± ε).
        let (p, ap) = (o.periapsis, o.apoapsis.unwrap());
        o.turning_points().unwrap();
        close(o.periapsis, p, 1e-12);
        close(o.apoapsis.unwrap(), ap, 1e-12);
        // The Runge-Lenz vector points at periapsis.
        // Angles agree modulo a full turn.
        let gap = kep.runge_lenz[1].atan2(kep.runge_lenz[0]) - o.periapsis_angle;
        let gap = gap - (gap / (2.0 * PI)).round() * 2.0 * PI;
        assert!(gap.abs() < 1e-9, "Runge-Lenz direction is off the periapsis by {gap}");
    }

    #[test]
    fn conic_kinds() {
        let kind = |thd: f64| {
            orbit_of("mu*(r'^2 + r^2*th'^2)/2 + k/r", "mu = 1.0\nk = 1.0", [1.0, 0.0, 0.0, thd]).unwrap().0.kind
        };
        assert_eq!(kind(1.0), OrbitKind::Circle);
        assert_eq!(kind(1.2), OrbitKind::Ellipse);
        assert_eq!(kind(2f64.sqrt()), OrbitKind::Parabola);
        assert_eq!(kind(1.6), OrbitKind::Hyperbola);
    }

    #[test]
    fn harmonic_apsidal_angle_is_a_quarter_turn() {
        // U = k r²: ellipses centred on the origin, apsidal angle π/2, radial period π/ω.
        for (rd, thd) in [(0.0, 0.5), (0.3, 1.7), (1.0, 0.2)] {
            let (o, _) = orbit_of("mu*(r'^2 + r^2*th'^2)/2 - k*r^2", "mu = 2.0\nk = 0.5", [1.2, 0.0, rd, thd]).unwrap();
            assert_eq!(o.kind, OrbitKind::Bounded);
            close(o.apsidal_angle.unwrap(), PI / 2.0, 1e-10);
            let omega = (2.0f64 * 0.5 / 2.0).sqrt();
            close(o.period.unwrap(), PI / omega, 1e-10);
        }
    }

    #[test]
    fn highly_eccentric_kepler_quadrature() {
        let (mut o, _) = orbit_of("mu*(r'^2 + r^2*th'^2)/2 + k/r", "mu = 1.0\nk = 1.0", [1.0, 0.0, 0.0, 0.3]).unwrap();
        let (t, dth) = o.quadrature().unwrap();
        close(dth, PI, 1e-10);
        close(t, o.period.unwrap(), 1e-10);
    }

    #[test]
    fn precession_of_a_screened_potential() {
        // Yukawa attraction: bounded orbits precess forward (Δθ > π).
        let (o, _) =
            orbit_of("m*(r'^2 + r^2*th'^2)/2 + k*exp(-r/a)/r", "m = 1.0\nk = 1.0\na = 5.0", [1.0, 0.0, 0.0, 1.1])
                .unwrap();
        assert_eq!(o.kind, OrbitKind::Bounded);
        assert!(o.apsidal_angle.unwrap() > PI);
    }

    #[test]
    fn other_forms_are_rejected() {
        let bad = [
            ("mu*(r'^2 + th'^2)/2 + k/r", "not μ"),
            ("mu*(r'^2 + r^2*th'^2)/2 + k/r + k*th", "angle"),
            ("mu*(r'^2 + r^2*th'^2)/2 + k/r + k*th'", "linear"),
            ("r^2*(r'^2 + r^2*th'^2)/2 + k/r", "constant"),
        ];
        for (l, what) in bad {
            let e = orbit_of(l, "mu = 1.0\nk = 1.0", [1.0, 0.0, 0.0, 1.0]).unwrap_err();
            assert!(matches!(e, OrbitError::NotCentral { .. }), "{l}: {e} ({what})");
        }
        let e = orbit_of("mu*(r'^2 + r^2*th'^2)/2 + k/r", "mu = 1.0\nk = 1.0", [1.0, 0.0, 0.5, 0.0]).unwrap_err();
        assert!(matches!(e, OrbitError::Radial { .. }));
    }

    /// r(θ) from quadrature agrees with a simulation of the same model, and the
    /// Laplace–Runge–Lenz vector of a Kepler orbit stays put along the run.
    #[test]
    fn quadrature_orbit_agrees_with_simulation() {
        for (l, params, kepler) in [
            ("m*(r'^2 + r^2*th'^2)/2 + k*exp(-r/a)/r", "m = 1.0\nk = 1.0\na = 5.0", false),
            ("m*(r'^2 + r^2*th'^2)/2 + k/r", "m = 0.8\nk = 1.0\na = 1.0", true),
        ] {
            let (mut o, d) = orbit_of(l, params, [1.0, 0.4, 0.1, 1.1]).unwrap();
            let config = crate::RunConfig { until: 30.0, rtol: 1e-12, atol: 1e-14, ..Default::default() };
            let mut rows = Vec::new();
            crate::simulate(&d, &config, |row| {
                rows.push([row.q[0], row.q[1], row.qd[0], row.qd[1]]);
                std::ops::ControlFlow::Continue(())
            })
            .unwrap();
            let (mu, lz) = (o.mu, o.angular_momentum);
            let k = o.kepler.as_ref().map_or(0.0, |k| k.k);
            let a0 = o.kepler.as_ref().map(|k| k.runge_lenz);
            for row in rows.iter().step_by(25) {
                let want = o.r_at(row[1]).unwrap();
                close(row[0], want, 1e-8);
                if let Some(a0) = a0 {
                    let [r, th, rd, thd] = *row;
                    let (c, s) = (th.cos(), th.sin());
                    let (vx, vy) = (rd * c - r * thd * s, rd * s + r * thd * c);
                    let a = [mu * lz * vy - mu * k * c, -mu * lz * vx - mu * k * s];
                    assert!(kepler);
                    assert!((a[0] - a0[0]).abs() + (a[1] - a0[1]).abs() < 1e-8, "A = {a:?}, A0 = {a0:?}");
                }
            }
        }
    }
}
