//! Adaptive cubature of a density's mass moments over a box: nested
//! Gauss–Kronrod (7-point Gauss, 15-point Kronrod) per axis, each axis adaptive
//! by bisection of the interval with the largest error.
//!
//! Enter with [`moments`]: it integrates ρ times the ten monomials
//! 1, u, v, w, u², v², w², uv, uw, vw (u, v, w measured from the box's centre,
//! so a box far from the origin loses no digits) in one pass, with one
//! absolute tolerance per group (mass, first moments, second moments) set
//! from a pilot estimate of ∫|ρ| and the box's size. The error estimate of an
//! interval is |K15 − G7| (conservative for smooth integrands: it bounds the
//! Gauss rule's error while the Kronrod value is returned) plus the inner
//! levels' estimates, carried through the Kronrod weights.

/// The number of integrated moments.
pub const N_MOMENTS: usize = 10;

/// Most intervals per axis and per inner integral. Smooth densities need a
/// handful; the limit bounds the work (at most (15·MAX_INTERVALS)³
/// evaluations) for a density with a singularity, whose error estimate then
/// stays above the tolerance and is reported as such.
const MAX_INTERVALS: usize = 24;

/// Most density evaluations of one cubature (about a second of work); beyond
/// it no interval is split further and the result is marked unconverged.
const MAX_EVALUATIONS: u64 = 20_000_000;

/// The error of an inner integral need not go below a few ulps of its value:
/// beyond that, |K15 − G7| measures round-off, not the rule's error.
const ROUND_OFF: f64 = 1e-14;

/// Kronrod abscissae on [−1, 1] (positive half, descending; QUADPACK's qk15).
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights of [`XGK`].
const WGK: [f64; 8] = [
    0.022_935_322_010_529_225,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_18,
    0.140_653_259_715_525_92,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_83,
];
/// Gauss weights of the odd-indexed Kronrod abscissae XGK[1], XGK[3], XGK[5], XGK[7].
const WG: [f64; 4] =
    [0.129_484_966_168_869_7, 0.279_705_391_489_276_7, 0.381_830_050_505_118_9, 0.417_959_183_673_469_4];

/// An integral of the ten moments with an absolute error estimate for each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The integrals.
    pub value: [f64; N_MOMENTS],
    /// Their estimated absolute errors.
    pub error: [f64; N_MOMENTS],
}

impl Estimate {
    const ZERO: Estimate = Estimate { value: [0.0; N_MOMENTS], error: [0.0; N_MOMENTS] };
}

/// The result of [`moments`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    /// ∫ρ·(1, u, v, w, u², v², w², uv, uw, vw) dV, u = x − centre, with errors.
    pub estimate: Estimate,
    /// The box's centre (where u, v, w are measured from).
    pub center: [f64; 3],
    /// Density evaluations used.
    pub evaluations: u64,
    /// Whether every level met its tolerance within [`MAX_INTERVALS`] and the evaluation budget.
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
    let mut ctx = Ctx { density, center, half, tol: [0.0; N_MOMENTS], evaluations: 0, converged: true, bad: None };
    // Pilot: one Kronrod product rule of |ρ| gives the scale of the mass.
    let pilot = ctx.pilot_abs_mass();
    if let Some(bad) = ctx.bad {
        return Err(bad);
    }
    let diag2 = half.iter().map(|h| h * h).sum::<f64>();
    // Shares of the tolerance: the tensor sums up to twice the six second
    // moments, the centre of mass three first moments.
    let scale = [pilot, pilot * diag2.sqrt() / 3.0, pilot * diag2 / 12.0];
    for (k, t) in ctx.tol.iter_mut().enumerate() {
        *t = rtol * scale[group(k)];
    }
    let mut point = [0.0; 3];
    let estimate = if pilot > 0.0 { ctx.axis(0, &mut point) } else { Estimate::ZERO };
    if let Some(bad) = ctx.bad {
        return Err(bad);
    }
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
    bad: Option<NotFinite>,
}

impl Ctx<'_> {
    /// ρ at centre + u, times the ten monomials of u.
    fn leaf(&mut self, u: &[f64; 3]) -> [f64; N_MOMENTS] {
        let x = [self.center[0] + u[0], self.center[1] + u[1], self.center[2] + u[2]];
        self.evaluations += 1;
        let r = (self.density)(x);
        if !r.is_finite() {
            self.bad.get_or_insert(NotFinite { at: x, value: r });
            return [0.0; N_MOMENTS];
        }
        let [a, b, c] = *u;
        [r, r * a, r * b, r * c, r * a * a, r * b * b, r * c * c, r * a * b, r * a * c, r * b * c]
    }

    /// ∫|ρ| dV by the 15³-point Kronrod product rule.
    fn pilot_abs_mass(&mut self) -> f64 {
        let nodes: Vec<(f64, f64)> =
            (0..15).map(|i| if i < 8 { (-XGK[i], WGK[i]) } else { (XGK[14 - i], WGK[14 - i]) }).collect();
        let mut sum = 0.0;
        for &(a, wa) in &nodes {
            for &(b, wb) in &nodes {
                for &(c, wc) in &nodes {
                    let u = [a * self.half[0], b * self.half[1], c * self.half[2]];
                    sum += wa * wb * wc * self.leaf(&u)[0].abs();
                }
            }
        }
        sum * self.half[0] * self.half[1] * self.half[2]
    }

    /// The integral over axes `axis..3` at the fixed coordinates `point[..axis]`.
    fn axis(&mut self, axis: usize, point: &mut [f64; 3]) -> Estimate {
        // An inner integral is multiplied by the outer axes' lengths on its
        // way out: divide the tolerance by them, and by 4 per level so that
        // the inner errors take a small share of the total.
        let mut shrink = 1.0;
        for a in 0..axis {
            shrink *= 4.0 * 2.0 * self.half[a];
        }
        let tol: [f64; N_MOMENTS] = self.tol.map(|t| t / shrink);
        let h = self.half[axis];
        let mut intervals = vec![(-h, h, self.kronrod(axis, -h, h, point))];
        loop {
            let mut total = Estimate::ZERO;
            for (_, _, e) in &intervals {
                for k in 0..N_MOMENTS {
                    total.value[k] += e.value[k];
                    total.error[k] += e.error[k];
                }
            }
            let done = (0..N_MOMENTS).all(|k| total.error[k] <= tol[k].max(ROUND_OFF * total.value[k].abs()));
            if done || self.bad.is_some() {
                return total;
            }
            if intervals.len() >= MAX_INTERVALS || self.evaluations >= MAX_EVALUATIONS {
                self.converged = false;
                return total;
            }
            // Bisect the interval whose error is largest against the tolerance.
            let worst = |e: &Estimate| (0..N_MOMENTS).map(|k| e.error[k] / tol[k]).fold(0.0, f64::max);
            let (i, _) = intervals
                .iter()
                .enumerate()
                .map(|(i, (_, _, e))| (i, worst(e)))
                .fold((0, f64::NEG_INFINITY), |best, c| if c.1 > best.1 { c } else { best });
            let (a, b, _) = intervals.swap_remove(i);
            let m = 0.5 * (a + b);
            let left = self.kronrod(axis, a, m, point);
            let right = self.kronrod(axis, m, b, point);
            intervals.push((a, m, left));
            intervals.push((m, b, right));
        }
    }

    /// The Gauss–Kronrod estimate over [a, b] along `axis`.
    fn kronrod(&mut self, axis: usize, a: f64, b: f64, point: &mut [f64; 3]) -> Estimate {
        let c = 0.5 * (a + b);
        let h = 0.5 * (b - a);
        let mut kron = [0.0; N_MOMENTS];
        let mut gauss = [0.0; N_MOMENTS];
        let mut inner = [0.0; N_MOMENTS];
        for i in 0..8 {
            let signs: &[f64] = if i == 7 { &[1.0] } else { &[-1.0, 1.0] };
            for &s in signs {
                point[axis] = c + s * h * XGK[i];
                let f = if axis == 2 {
                    Estimate { value: self.leaf(point), error: [0.0; N_MOMENTS] }
                } else {
                    self.axis(axis + 1, point)
                };
                for k in 0..N_MOMENTS {
                    kron[k] += WGK[i] * f.value[k];
                    inner[k] += WGK[i] * f.error[k];
                    if i % 2 == 1 {
                        gauss[k] += WG[i / 2] * f.value[k];
                    }
                }
            }
        }
        Estimate {
            value: kron.map(|v| h * v),
            error: std::array::from_fn(|k| h * ((kron[k] - gauss[k]).abs() + inner[k])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ x^n over [−1, 1] with the Kronrod (`true`) or the Gauss rule.
    fn rule(n: i32, kronrod: bool) -> f64 {
        let mut s = 0.0;
        for i in 0..8 {
            let (w, on) = if kronrod { (WGK[i], true) } else { (if i % 2 == 1 { WG[i / 2] } else { 0.0 }, i % 2 == 1) };
            if !on {
                continue;
            }
            let x = XGK[i];
            s += w * if i == 7 { x.powi(n) } else { x.powi(n) + (-x).powi(n) };
        }
        s
    }

    #[test]
    fn rules_have_their_degree() {
        for n in 0..=22 {
            let exact = if n % 2 == 1 { 0.0 } else { 2.0 / f64::from(n + 1) };
            assert!((rule(n, true) - exact).abs() < 1e-15, "Kronrod x^{n}");
            if n <= 13 {
                assert!((rule(n, false) - exact).abs() < 1e-15, "Gauss x^{n}");
            }
        }
        // Degree 24 is beyond the Kronrod rule: the check above is not vacuous.
        assert!((rule(24, true) - 2.0 / 25.0).abs() > 1e-9);
    }

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
