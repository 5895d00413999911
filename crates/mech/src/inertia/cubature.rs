//! Adaptive cubature of a density's mass moments over a box: nested
//! Gauss–Kronrod (7-point Gauss, 15-point Kronrod) per axis, each axis adaptive
//! by bisection of the interval with the largest error
//! ([`num::adaptive_gauss_kronrod`], whose nodes on one axis are the integrals
//! over the next).
//!
//! Enter with [`moments`]: it integrates ρ times the ten monomials
//! 1, u, v, w, u², v², w², uv, uw, vw (u, v, w measured from the box's centre,
//! so a box far from the origin loses no digits) in one pass, with one
//! absolute tolerance per group (mass, first moments, second moments) set
//! from a pilot estimate of ∫|ρ| and the box's size. The error estimate of an
//! interval is |K15 − G7| (conservative for smooth integrands: it bounds the
//! Gauss rule's error while the Kronrod value is returned) plus the inner
//! levels' estimates, carried through the Kronrod weights.

use num::{adaptive_gauss_kronrod, AdaptiveConfig, Integrand, KRONROD_15_NODES, KRONROD_15_WEIGHTS};

/// The number of integrated moments.
pub const N_MOMENTS: usize = 10;

/// Most density evaluations of one cubature (about a second of work); beyond
/// it no interval is split further and the result is marked unconverged. Each
/// axis splits at most [`num::KRONROD_MAX_INTERVALS`] intervals per inner
/// integral, which alone bounds the work at (15·24)³ evaluations; this budget
/// stops a density with a singularity sooner.
const MAX_EVALUATIONS: u64 = 20_000_000;

/// An integral of the ten moments with an absolute error estimate for each.
pub type Estimate = num::Estimate<N_MOMENTS>;

/// The result of [`moments`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    /// ∫ρ·(1, u, v, w, u², v², w², uv, uw, vw) dV, u = x − centre, with errors.
    pub estimate: Estimate,
    /// The box's centre (where u, v, w are measured from).
    pub center: [f64; 3],
    /// Density evaluations used.
    pub evaluations: u64,
    /// Whether every level met its tolerance within [`num::KRONROD_MAX_INTERVALS`] and the evaluation budget.
    pub converged: bool,
}

/// The density was not finite somewhere in the box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NotFinite {
    /// Where (x, y, z).
    pub at: [f64; 3],
    /// The value found there.
    pub value: f64,
}

/// ∫ρ·(1, u, v, w, u², v², w², uv, uw, vw) over the box `region` (per axis
/// [lower, upper]) to the relative tolerance `rtol`: the summed error of the
/// second moments stays below rtol·∫|ρ|·d²/12 (d the half-diagonal, so the
/// tensor's error is below rtol·∫|ρ|·d²/6), the first moments' below
/// rtol·∫|ρ|·d/3 and the mass's below rtol·∫|ρ|.
pub fn moments(
    density: &mut dyn FnMut([f64; 3]) -> f64,
    region: [[f64; 2]; 3],
    rtol: f64,
) -> Result<Moments, NotFinite> {
    let center = region.map(|[a, b]| 0.5 * (a + b));
    let half = region.map(|[a, b]| 0.5 * (b - a));
    let mut ctx = Ctx { density, center, half, tol: [0.0; N_MOMENTS], evaluations: 0, converged: true };
    // Pilot: one Kronrod product rule of |ρ| gives the scale of the mass.
    let pilot = ctx.pilot_abs_mass()?;
    let diag2 = half.iter().map(|h| h * h).sum::<f64>();
    // Shares of the tolerance: the tensor sums up to twice the six second
    // moments, the centre of mass three first moments.
    let scale = [pilot, pilot * diag2.sqrt() / 3.0, pilot * diag2 / 12.0];
    for (k, t) in ctx.tol.iter_mut().enumerate() {
        *t = rtol * scale[group(k)];
    }
    let mut point = [0.0; 3];
    let estimate = if pilot > 0.0 { ctx.axis(0, &mut point)? } else { Estimate::ZERO };
    Ok(Moments { estimate, center, evaluations: ctx.evaluations, converged: ctx.converged })
}

/// Which tolerance group a moment belongs to: 0 mass, 1 first, 2 second moments.
fn group(k: usize) -> usize {
    match k {
        0 => 0,
        1..=3 => 1,
        _ => 2,
    }
}

struct Ctx<'a> {
    density: &'a mut dyn FnMut([f64; 3]) -> f64,
    center: [f64; 3],
    half: [f64; 3],
    /// Absolute tolerances of the whole integral.
    tol: [f64; N_MOMENTS],
    evaluations: u64,
    converged: bool,
}

impl Ctx<'_> {
    /// ρ at centre + u, times the ten monomials of u.
    fn leaf(&mut self, u: &[f64; 3]) -> Result<[f64; N_MOMENTS], NotFinite> {
        let x = [self.center[0] + u[0], self.center[1] + u[1], self.center[2] + u[2]];
        self.evaluations += 1;
        let r = (self.density)(x);
        if !r.is_finite() {
            return Err(NotFinite { at: x, value: r });
        }
        let [a, b, c] = *u;
        Ok([r, r * a, r * b, r * c, r * a * a, r * b * b, r * c * c, r * a * b, r * a * c, r * b * c])
    }

    /// ∫|ρ| dV by the 15³-point Kronrod product rule.
    fn pilot_abs_mass(&mut self) -> Result<f64, NotFinite> {
        let nodes: Vec<(f64, f64)> = (0..15)
            .map(|i| {
                if i < 8 {
                    (-KRONROD_15_NODES[i], KRONROD_15_WEIGHTS[i])
                } else {
                    (KRONROD_15_NODES[14 - i], KRONROD_15_WEIGHTS[14 - i])
                }
            })
            .collect();
        let mut sum = 0.0;
        for &(a, wa) in &nodes {
            for &(b, wb) in &nodes {
                for &(c, wc) in &nodes {
                    let u = [a * self.half[0], b * self.half[1], c * self.half[2]];
                    sum += wa * wb * wc * self.leaf(&u)?[0].abs();
                }
            }
        }
        Ok(sum * self.half[0] * self.half[1] * self.half[2])
    }

    /// The integral over axes `axis..3` at the fixed coordinates `point[..axis]`,
    /// adaptive along `axis` with the inner axes nested in each node.
    fn axis(&mut self, axis: usize, point: &mut [f64; 3]) -> Result<Estimate, NotFinite> {
        // An inner integral is multiplied by the outer axes' lengths on its
        // way out: divide the tolerance by them, and by 4 per level so that
        // the inner errors take a small share of the total.
        let mut shrink = 1.0;
        for a in 0..axis {
            shrink *= 4.0 * 2.0 * self.half[a];
        }
        let config = AdaptiveConfig::new(self.tol.map(|t| t / shrink));
        let h = self.half[axis];
        let result = adaptive_gauss_kronrod(&mut Axis { ctx: self, axis, point }, -h, h, &config)?;
        if !result.converged {
            self.converged = false;
        }
        Ok(result.estimate)
    }
}

/// The integrand along one axis: the leaf on the last axis, the inner axes'
/// integral (with its error) on the others.
struct Axis<'c, 'a> {
    ctx: &'c mut Ctx<'a>,
    axis: usize,
    point: &'c mut [f64; 3],
}

impl Integrand<N_MOMENTS> for Axis<'_, '_> {
    type Error = NotFinite;

    fn eval(&mut self, x: f64) -> Result<Estimate, NotFinite> {
        self.point[self.axis] = x;
        if self.axis == 2 {
            Ok(Estimate::exact(self.ctx.leaf(self.point)?))
        } else {
            self.ctx.axis(self.axis + 1, self.point)
        }
    }

    fn exhausted(&self) -> bool {
        self.ctx.evaluations >= MAX_EVALUATIONS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_density_on_a_box() {
        // ρ = exp(−(x² + y² + z²)) over [0, 1] × [−1, 2] × [0.5, 1.5].
        let mut f = |x: [f64; 3]| (-(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])).exp();
        let m = moments(&mut f, [[0.0, 1.0], [-1.0, 2.0], [0.5, 1.5]], 1e-10).unwrap();
        assert!(m.converged);
        let sqrt_pi = std::f64::consts::PI.sqrt();
        let erf_int = |a: f64, b: f64| 0.5 * sqrt_pi * (erf(b) - erf(a));
        let mass = erf_int(0.0, 1.0) * erf_int(-1.0, 2.0) * erf_int(0.5, 1.5);
        let got = m.estimate.value[0];
        assert!((got - mass).abs() < 1e-10 * mass, "{got} vs {mass}");
        assert!(m.estimate.error[0] < 1e-9 * mass);
    }

    /// erf by its Taylor series (plenty for |x| ≤ 2 in a test).
    fn erf(x: f64) -> f64 {
        let mut term = x;
        let mut sum = x;
        for n in 1..200 {
            term *= -x * x / f64::from(n);
            sum += term / f64::from(2 * n + 1);
        }
        sum * 2.0 / std::f64::consts::PI.sqrt()
    }

    #[test]
    fn not_finite_density_is_reported() {
        let mut f = |x: [f64; 3]| 1.0 / (x[0] - 0.5);
        let r = moments(&mut f, [[0.0, 1.0]; 3], 1e-10);
        // The centre of each axis is a Kronrod node, so x = 0.5 is sampled.
        assert!(r.is_err());
    }
}
