//! One-dimensional quadrature: the composite [`midpoint`] rule, Gauss–Legendre rules ([`gauss_legendre_rule`], applied
//! by [`gauss_legendre`] and [`gauss_legendre_centered`], with doubling order by [`gauss_legendre_doubling`]),
//! tanh-sinh for integrable endpoint singularities ([`tanh_sinh`]), and the 7/15-point
//! Gauss–Kronrod pair ([`gauss_kronrod_15`], one interval; [`adaptive_gauss_kronrod`],
//! bisection of the worst interval) as the 1-D building block of nested cubature.
//!
//! The integrands are closures of one real variable. Vector integrands are arrays
//! `[f64; N]`, so that several integrals that share their evaluations (a time and an
//! angle, ten mass moments) are integrated in one pass.

use crate::error::QuadratureError;
use std::f64::consts::{FRAC_PI_2, PI};

/// Most Newton iterations per node of [`gauss_legendre_rule`]; from Chebyshev's
/// guesses 3 to 6 reach round-off, so the bound is only a guard.
const RULE_MAX_NEWTON: usize = 100;

/// Newton on `P_n(x)` stops when its correction falls below this: nodes lie in
/// `[−1, 1]`, where `1e-16` is below half an ulp of most of them.
const RULE_NODE_TOL: f64 = 1e-16;

/// The largest Gauss–Legendre order [`gauss_legendre_rule`] builds: `O(n²)` work per
/// rule, and beyond it double precision no longer tells neighbouring nodes apart near
/// the ends.
pub const MAX_GAUSS_LEGENDRE_ORDER: usize = 1 << 16;

/// The nodes and weights `(x_i, w_i)` of the `n`-point Gauss–Legendre rule on
/// `[−1, 1]`, exact for polynomials of degree `2n − 1`. The nodes come from Newton's
/// method on the Legendre polynomial `P_n` (by its three-term recurrence) from
/// Chebyshev's guesses, in descending order.
///
/// ```
/// let rule = num::gauss_legendre_rule(3).unwrap();
/// let integral: f64 = rule.iter().map(|&(x, w)| w * x.powi(4)).sum();
/// assert!((integral - 0.4).abs() < 1e-15);
/// ```
pub fn gauss_legendre_rule(n: usize) -> Result<Vec<(f64, f64)>, QuadratureError> {
    if n == 0 || n > MAX_GAUSS_LEGENDRE_ORDER {
        return Err(QuadratureError::InvalidOrder { order: n, max: MAX_GAUSS_LEGENDRE_ORDER });
    }
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..RULE_MAX_NEWTON {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < RULE_NODE_TOL {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    Ok(out)
}

/// `∫_a^b f(x) dx` by the rule `rule` (from [`gauss_legendre_rule`]) mapped onto
/// `[a, b]`: [`gauss_legendre_centered`] about `(a + b)/2` with half-width `(b − a)/2`.
///
/// ```
/// let rule = num::gauss_legendre_rule(2).unwrap();
/// let [v] = num::gauss_legendre(&rule, |x| [x * x * x], 1.0, 3.0);
/// assert!((v - 20.0).abs() < 1e-13);
/// ```
pub fn gauss_legendre<const N: usize>(rule: &[(f64, f64)], f: impl FnMut(f64) -> [f64; N], a: f64, b: f64) -> [f64; N] {
    gauss_legendre_centered(rule, f, 0.5 * (a + b), 0.5 * (b - a))
}

/// The integral over `[mid − half, mid + half]` by the rule `rule`:
/// `half · Σ w_i f(mid + half · x_i)`, summed in the rule's order, each component of
/// the array separately. Given the centre and half-width, a short interval next to
/// a large `a` keeps its length exactly (`(a + x) − a` would round `x`).
pub fn gauss_legendre_centered<const N: usize>(
    rule: &[(f64, f64)],
    mut f: impl FnMut(f64) -> [f64; N],
    mid: f64,
    half: f64,
) -> [f64; N] {
    let mut sum = [0.0; N];
    for &(x, w) in rule {
        let v = f(mid + half * x);
        for k in 0..N {
            sum[k] += w * v[k];
        }
    }
    sum.map(|s| s * half)
}

/// `∫_a^b f(x) dx` by the composite midpoint rule with `n` equal pieces:
/// `(b − a)/n · Σ f(a + (b − a)(j + ½)/n)`, summed in order. After `x = cos φ` it is
/// the Gauss–Chebyshev rule of the first kind, exact for `∫ p(x)/sqrt(1 − x²)` with `p`
/// of degree below `2n`: the rule for an integrand with inverse-square-root
/// singularities at both ends, such as a period between two turning points.
///
/// ```
/// // ∫_0^π cos²φ dφ = π/2.
/// let [v] = num::midpoint(|phi| [phi.cos().powi(2)], 0.0, std::f64::consts::PI, 8);
/// assert!((v - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
/// ```
pub fn midpoint<const N: usize>(mut f: impl FnMut(f64) -> [f64; N], a: f64, b: f64, n: usize) -> [f64; N] {
    let mut sum = [0.0; N];
    for j in 0..n {
        let v = f(a + (b - a) * (j as f64 + 0.5) / n as f64);
        for k in 0..N {
            sum[k] += v[k];
        }
    }
    let h = (b - a) / n as f64;
    sum.map(|s| s * h)
}

/// A tolerance must be a number and not negative.
fn check_tolerance(value: f64) -> Result<(), QuadratureError> {
    if value.is_nan() || value < 0.0 {
        return Err(QuadratureError::InvalidTolerance { value });
    }
    Ok(())
}

/// Options of [`gauss_legendre_doubling`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DoublingConfig {
    /// The first order tried.
    pub first_order: usize,
    /// The doubling stops at the first order at or beyond this one; its result is
    /// returned, marked not converged, when two orders never agreed.
    pub max_order: usize,
    /// Two successive results agree when they differ by at most `rtol` times the
    /// larger of them, in every component.
    pub rtol: f64,
}

impl Default for DoublingConfig {
    /// 24 points first (a smooth integrand on a period needs about that many for
    /// ten digits), up to 2048 (so at most 3072 points, the eighth doubling, and
    /// about 6000 evaluations per call), agreement to `1e-13` (a few hundred ulps: what the sum of up to 2048
    /// terms can promise).
    fn default() -> Self {
        DoublingConfig { first_order: 24, max_order: 2048, rtol: 1e-13 }
    }
}

/// Absolute floor of the agreement test of [`gauss_legendre_doubling`]: two results
/// that are both zero (or both denormal) agree, where a purely relative test would
/// double the order up to the limit.
const AGREEMENT_FLOOR: f64 = 1e-300;

/// The result of [`gauss_legendre_doubling`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Doubling<const N: usize> {
    /// The integrals by the last rule applied.
    pub value: [f64; N],
    /// The order of that rule.
    pub order: usize,
    /// Whether it agreed with the rule of half its order.
    pub converged: bool,
}

/// `∫_a^b f(x) dx` by Gauss–Legendre rules of order `first_order`, twice that, …,
/// until two successive results agree to `rtol` in every component or `max_order`
/// is reached. For integrands that are smooth on `[a, b]` (after a substitution that
/// removes endpoint singularities) the error falls geometrically with the order.
pub fn gauss_legendre_doubling<const N: usize>(
    mut f: impl FnMut(f64) -> [f64; N],
    a: f64,
    b: f64,
    config: &DoublingConfig,
) -> Result<Doubling<N>, QuadratureError> {
    check_tolerance(config.rtol)?;
    if !(a.is_finite() && b.is_finite()) {
        return Err(QuadratureError::InvalidInterval { a, b });
    }
    let mut prev: Option<[f64; N]> = None;
    let mut order = config.first_order;
    loop {
        let rule = gauss_legendre_rule(order)?;
        let cur = gauss_legendre(&rule, &mut f, a, b);
        if let Some(p) = prev {
            let close = |u: f64, v: f64| (u - v).abs() <= config.rtol * u.abs().max(v.abs()) + AGREEMENT_FLOOR;
            let converged = (0..N).all(|k| close(cur[k], p[k]));
            if converged || order >= config.max_order {
                return Ok(Doubling { value: cur, order, converged });
            }
        } else if order >= config.max_order {
            return Ok(Doubling { value: cur, order, converged: false });
        }
        prev = Some(cur);
        order *= 2;
    }
}

/// An integral with an estimate of its absolute error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integral {
    /// The integral.
    pub value: f64,
    /// An estimate of its absolute error.
    pub error: f64,
}

/// Largest `|t|` of tanh-sinh: at `t = 6`, `π/2·sinh t ≈ 317`, so the nodes are within
/// `e^{−634}` of the ends, far below round-off of any interval.
const TANH_SINH_T_MAX: f64 = 6.0;

/// First step in `t` of tanh-sinh: 13 nodes over `[−6, 6]`, already exact to a few
/// digits for smooth integrands, so the first halving's change estimates the error.
const TANH_SINH_FIRST_STEP: f64 = 1.0;

/// Most halvings of the tanh-sinh step in `t` (from `h = 1`: `2^12 · 12` nodes at the
/// finest level); a smooth or algebraically singular integrand converges in 4 to 7.
const TANH_SINH_MAX_LEVEL: u32 = 12;

/// Nodes closer to an end than this fraction of `b − a` are skipped: they add nothing
/// an integrable singularity of practical interest would notice, and the integrand
/// may underflow or overflow there.
const TANH_SINH_END_GAP: f64 = 1e-200;

/// `∫_a^b g(x) dx` by tanh-sinh (double-exponential) quadrature, for integrands with
/// integrable endpoint singularities such as `1/sqrt(x − a)`: the substitution
/// `x = (a+b)/2 + (b−a)/2·tanh(π/2·sinh t)` makes the transformed integrand decay
/// double-exponentially, so the trapezoidal rule in `t` converges fast and never
/// evaluates `g` at an end. The step in `t` is halved until the result changes by at
/// most `rtol` of itself; the error estimate is the last change.
///
/// A non-finite value of `g` (away from the ends) is an error. `b < a` integrates in
/// the other direction.
///
/// ```
/// let i = num::tanh_sinh(|x| 1.0 / x.sqrt(), 0.0, 1.0, 1e-14).unwrap();
/// assert!((i.value - 2.0).abs() < 1e-13);
/// ```
pub fn tanh_sinh(mut g: impl FnMut(f64) -> f64, a: f64, b: f64, rtol: f64) -> Result<Integral, QuadratureError> {
    if !(a.is_finite() && b.is_finite()) {
        return Err(QuadratureError::InvalidInterval { a, b });
    }
    check_tolerance(rtol)?;
    if b < a {
        let i = tanh_sinh(g, b, a, rtol)?;
        return Ok(Integral { value: -i.value, error: i.error });
    }
    if a == b {
        return Ok(Integral { value: 0.0, error: 0.0 });
    }
    let half = 0.5 * (b - a);
    let mut term = |t: f64| -> Result<f64, QuadratureError> {
        let u = FRAC_PI_2 * t.sinh();
        // Distances to the ends without cancellation: b − x = (b − a)/(1 + e^{2u}).
        let to_b = (b - a) / (1.0 + (2.0 * u).exp());
        let to_a = (b - a) / (1.0 + (-2.0 * u).exp());
        let x = if t < 0.0 { a + to_a } else { b - to_b };
        if x <= a || x >= b || to_a.min(to_b) < TANH_SINH_END_GAP * (b - a) {
            return Ok(0.0);
        }
        let cu = u.cosh();
        let w = half * FRAC_PI_2 * t.cosh() / (cu * cu);
        if w == 0.0 {
            return Ok(0.0);
        }
        let value = g(x);
        if !value.is_finite() {
            return Err(QuadratureError::NotFinite { x, value });
        }
        Ok(w * value)
    };
    let mut h = TANH_SINH_FIRST_STEP;
    let mut sum = term(0.0)?;
    let mut k = 1;
    while (k as f64) * h <= TANH_SINH_T_MAX {
        let t = k as f64 * h;
        sum += term(t)? + term(-t)?;
        k += 1;
    }
    let mut estimate = h * sum;
    let mut change = f64::NAN;
    for _ in 0..TANH_SINH_MAX_LEVEL {
        h *= 0.5;
        let mut k = 1;
        while (k as f64) * h <= TANH_SINH_T_MAX {
            let t = k as f64 * h;
            sum += term(t)? + term(-t)?;
            k += 2;
        }
        let next = h * sum;
        change = (next - estimate).abs();
        estimate = next;
        if !estimate.is_finite() {
            return Err(QuadratureError::Overflow);
        }
        if change <= rtol * estimate.abs() {
            break;
        }
    }
    Ok(Integral { value: estimate, error: change })
}

/// Kronrod abscissae of the 15-point rule on `[−1, 1]` (positive half, descending;
/// QUADPACK's `qk15`). The odd-indexed ones are the 7-point Gauss nodes.
pub const KRONROD_15_NODES: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];

/// Kronrod weights of [`KRONROD_15_NODES`].
pub const KRONROD_15_WEIGHTS: [f64; 8] = [
    0.022_935_322_010_529_225,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_18,
    0.140_653_259_715_525_92,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_83,
];

/// Gauss weights of the odd-indexed Kronrod abscissae
/// `KRONROD_15_NODES[1], [3], [5], [7]`.
pub const GAUSS_7_WEIGHTS: [f64; 4] =
    [0.129_484_966_168_869_7, 0.279_705_391_489_276_7, 0.381_830_050_505_118_9, 0.417_959_183_673_469_4];

/// Integrals of `N` functions with an absolute error estimate for each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate<const N: usize> {
    /// The integrals.
    pub value: [f64; N],
    /// Their estimated absolute errors.
    pub error: [f64; N],
}

impl<const N: usize> Estimate<N> {
    /// Zero integrals with zero error.
    pub const ZERO: Self = Estimate { value: [0.0; N], error: [0.0; N] };

    /// An exact value (an integrand's value at a point, with no error).
    pub fn exact(value: [f64; N]) -> Self {
        Estimate { value, error: [0.0; N] }
    }
}

/// The 7/15-point Gauss–Kronrod estimate over `[a, b]`. `f` returns, at each node,
/// the integrands' values with their own errors (zero for plain functions; the error
/// of an inner integral in nested cubature), or an error that ends the estimate. The
/// error of the result is `|K15 − G7|` (conservative for smooth integrands: it bounds
/// the Gauss rule's error while the Kronrod value is returned) plus the nodes' errors
/// carried through the Kronrod weights.
pub fn gauss_kronrod_15<const N: usize, E>(
    mut f: impl FnMut(f64) -> Result<Estimate<N>, E>,
    a: f64,
    b: f64,
) -> Result<Estimate<N>, E> {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let mut kron = [0.0; N];
    let mut gauss = [0.0; N];
    let mut inner = [0.0; N];
    for i in 0..8 {
        let signs: &[f64] = if i == 7 { &[1.0] } else { &[-1.0, 1.0] };
        for &s in signs {
            let v = f(c + s * h * KRONROD_15_NODES[i])?;
            for k in 0..N {
                kron[k] += KRONROD_15_WEIGHTS[i] * v.value[k];
                inner[k] += KRONROD_15_WEIGHTS[i] * v.error[k];
                if i % 2 == 1 {
                    gauss[k] += GAUSS_7_WEIGHTS[i / 2] * v.value[k];
                }
            }
        }
    }
    Ok(Estimate {
        value: kron.map(|v| h * v),
        error: std::array::from_fn(|k| h * ((kron[k] - gauss[k]).abs() + inner[k])),
    })
}

/// An integrand of [`adaptive_gauss_kronrod`]: `N` functions evaluated together, each
/// value possibly with an error of its own (an inner integral).
pub trait Integrand<const N: usize> {
    /// What an evaluation may fail with; it ends the integration.
    type Error;
    /// The values at `x`, with their errors.
    fn eval(&mut self, x: f64) -> Result<Estimate<N>, Self::Error>;
    /// Whether a work budget shared with other integrals is spent; then no interval
    /// is split further and the result is marked not converged.
    fn exhausted(&self) -> bool {
        false
    }
}

/// Options of [`adaptive_gauss_kronrod`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveConfig<const N: usize> {
    /// Absolute tolerance of each integral's summed error.
    pub atol: [f64; N],
    /// The error need not fall below this fraction of an integral's magnitude:
    /// beyond a few ulps, `|K15 − G7|` measures round-off, not the rule's error.
    pub round_off: f64,
    /// Most intervals: the bound on the work for an integrand whose error estimate
    /// never meets the tolerance (a singularity).
    pub max_intervals: usize,
}

impl<const N: usize> AdaptiveConfig<N> {
    /// The given tolerances with the default `round_off` ([`KRONROD_ROUND_OFF`]) and
    /// `max_intervals` ([`KRONROD_MAX_INTERVALS`]).
    pub fn new(atol: [f64; N]) -> Self {
        AdaptiveConfig { atol, round_off: KRONROD_ROUND_OFF, max_intervals: KRONROD_MAX_INTERVALS }
    }
}

/// Default [`AdaptiveConfig::round_off`]: `1e-14`, about fifty ulps, which the sum of
/// fifteen weighted values can miss by round-off alone.
pub const KRONROD_ROUND_OFF: f64 = 1e-14;

/// Default [`AdaptiveConfig::max_intervals`]: smooth integrands need a handful of
/// intervals; a nested cubature does `15·max_intervals` evaluations per level, so this
/// bounds a three-dimensional one at `(15·24)³ ≈ 5·10⁷`.
pub const KRONROD_MAX_INTERVALS: usize = 24;

/// The result of [`adaptive_gauss_kronrod`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive<const N: usize> {
    /// The integrals and their summed error estimates.
    pub estimate: Estimate<N>,
    /// Whether every error met its tolerance.
    pub converged: bool,
}

/// `∫_a^b f` by adaptive 7/15-point Gauss–Kronrod: starting from `[a, b]`, the
/// interval whose error is largest against the tolerance is bisected until the
/// summed errors meet `config.atol` (or `round_off` of the integral) in every
/// component, `max_intervals` is reached or the integrand reports its budget spent.
/// The sums run over the intervals in the order they are kept (a bisected interval's
/// place is taken by the last one, its halves go to the end).
pub fn adaptive_gauss_kronrod<const N: usize, F: Integrand<N>>(
    f: &mut F,
    a: f64,
    b: f64,
    config: &AdaptiveConfig<N>,
) -> Result<Adaptive<N>, F::Error> {
    let tol = config.atol;
    let first = gauss_kronrod_15(|x| f.eval(x), a, b)?;
    let mut intervals = vec![(a, b, first)];
    loop {
        let mut total = Estimate::ZERO;
        for (_, _, e) in &intervals {
            for k in 0..N {
                total.value[k] += e.value[k];
                total.error[k] += e.error[k];
            }
        }
        let done = (0..N).all(|k| total.error[k] <= tol[k].max(config.round_off * total.value[k].abs()));
        if done {
            return Ok(Adaptive { estimate: total, converged: true });
        }
        if intervals.len() >= config.max_intervals || f.exhausted() {
            return Ok(Adaptive { estimate: total, converged: false });
        }
        // Bisect the interval whose error is largest against the tolerance.
        let worst = |e: &Estimate<N>| (0..N).map(|k| e.error[k] / tol[k]).fold(0.0, f64::max);
        let (i, _) = intervals
            .iter()
            .enumerate()
            .map(|(i, (_, _, e))| (i, worst(e)))
            .fold((0, f64::NEG_INFINITY), |best, c| if c.1 > best.1 { c } else { best });
        let (lo, hi, _) = intervals.swap_remove(i);
        let m = 0.5 * (lo + hi);
        let left = gauss_kronrod_15(|x| f.eval(x), lo, m)?;
        let right = gauss_kronrod_15(|x| f.eval(x), m, hi)?;
        intervals.push((lo, m, left));
        intervals.push((m, hi, right));
    }
}

/// A scalar function as an [`Integrand`] that fails on a non-finite value.
struct Scalar<F>(F);

impl<F: FnMut(f64) -> f64> Integrand<1> for Scalar<F> {
    type Error = QuadratureError;
    fn eval(&mut self, x: f64) -> Result<Estimate<1>, QuadratureError> {
        let value = (self.0)(x);
        if !value.is_finite() {
            return Err(QuadratureError::NotFinite { x, value });
        }
        Ok(Estimate::exact([value]))
    }
}

/// `∫_a^b f(x) dx` of a scalar function by [`adaptive_gauss_kronrod`] to the absolute
/// tolerance `atol`, with the default round-off floor and interval limit. A
/// non-finite value of `f` is an error.
///
/// ```
/// let r = num::gauss_kronrod(|x| x.exp(), 0.0, 1.0, 1e-12).unwrap();
/// assert!(r.converged && (r.estimate.value[0] - (1f64.exp() - 1.0)).abs() < 1e-14);
/// ```
pub fn gauss_kronrod(f: impl FnMut(f64) -> f64, a: f64, b: f64, atol: f64) -> Result<Adaptive<1>, QuadratureError> {
    if !(a.is_finite() && b.is_finite()) {
        return Err(QuadratureError::InvalidInterval { a, b });
    }
    check_tolerance(atol)?;
    adaptive_gauss_kronrod(&mut Scalar(f), a, b, &AdaptiveConfig::new([atol]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫_{−1}^{1} x^k dx`.
    fn monomial(k: i32) -> f64 {
        if k % 2 == 1 {
            0.0
        } else {
            2.0 / f64::from(k + 1)
        }
    }

    #[track_caller]
    fn check(got: f64, want: f64, rel: f64) {
        assert!((got - want).abs() <= rel * want.abs().max(1.0), "got {got:e}, want {want:e}");
    }

    #[test]
    fn gauss_legendre_is_exact_to_its_degree() {
        for n in [1, 2, 3, 5, 12, 24] {
            let rule = gauss_legendre_rule(n).unwrap();
            for k in 0..(2 * n as i32) {
                check(gauss_legendre(&rule, |x| [x.powi(k)], -1.0, 1.0)[0], monomial(k), 1e-14);
            }
            // Degree 2n is beyond the rule: the check above is not vacuous.
            let k = 2 * n as i32;
            if n <= 5 {
                assert!((gauss_legendre(&rule, |x| [x.powi(k)], -1.0, 1.0)[0] - monomial(k)).abs() > 1e-4);
            }
        }
        assert_eq!(
            gauss_legendre_rule(0),
            Err(QuadratureError::InvalidOrder { order: 0, max: MAX_GAUSS_LEGENDRE_ORDER })
        );
    }

    #[test]
    fn midpoint_is_gauss_chebyshev() {
        // ∫_{−1}^{1} x^k/sqrt(1 − x²) dx = ∫_0^π cos^k φ dφ, exact for k < 2n.
        let n = 5;
        for k in 0..2 * n as i32 {
            // π·(k − 1)!!/k!! for even k, 0 for odd.
            let want = if k % 2 == 1 {
                0.0
            } else {
                (1..=k / 2).fold(PI, |acc, j| acc * f64::from(2 * j - 1) / f64::from(2 * j))
            };
            check(midpoint(|phi| [phi.cos().powi(k)], 0.0, PI, n)[0], want, 1e-14);
        }
        assert_eq!(midpoint(|x| [x, 1.0], 0.0, 2.0, 4), [2.0, 2.0]);
    }

    #[test]
    fn gauss_legendre_doubling_converges() {
        let r = gauss_legendre_doubling(|x| [x.exp(), x.cos()], 0.0, 2.0, &DoublingConfig::default()).unwrap();
        assert!(r.converged && r.order == 48, "{r:?}");
        check(r.value[0], 2f64.exp() - 1.0, 1e-15);
        check(r.value[1], 2f64.sin(), 1e-15);
        // An endpoint singularity never settles to 1e-13: the last order is returned.
        let r = gauss_legendre_doubling(|x| [x.sqrt()], 0.0, 1.0, &DoublingConfig::default()).unwrap();
        assert!(!r.converged && r.order == 3072, "{r:?}");
        check(r.value[0], 2.0 / 3.0, 1e-8);
        let bad = DoublingConfig { rtol: f64::NAN, ..DoublingConfig::default() };
        assert!(gauss_legendre_doubling(|x| [x], 0.0, 1.0, &bad).is_err());
    }

    #[test]
    fn tanh_sinh_smooth_and_singular() {
        let ts = |g: fn(f64) -> f64, a, b| tanh_sinh(g, a, b, 1e-14).unwrap().value;
        check(ts(|x| x * x, 0.0, 1.0), 1.0 / 3.0, 1e-13);
        check(ts(|x| 1.0 / x.sqrt(), 0.0, 2.0), 2.0 * 2f64.sqrt(), 1e-13);
        check(ts(|x| x.powf(-0.75), 0.0, 1.0), 4.0, 1e-13);
        check(ts(|x| x.ln(), 0.0, 1.0), -1.0, 1e-13);
        check(ts(|x| x * x, 1.0, 0.0), -1.0 / 3.0, 1e-13);
        assert_eq!(ts(|x| x, 2.0, 2.0), 0.0);
        assert!(matches!(tanh_sinh(|x| 1.0 / (x - 0.5), 0.0, 1.0, 1e-14), Err(QuadratureError::NotFinite { .. })));
        assert!(tanh_sinh(|x| x, 0.0, f64::INFINITY, 1e-14).is_err());
    }

    #[test]
    fn kronrod_rules_have_their_degree() {
        for k in 0..=24 {
            let e = gauss_kronrod_15(|x| Ok::<_, ()>(Estimate::exact([x.powi(k)])), -1.0, 1.0).unwrap();
            if k <= 22 {
                check(e.value[0], monomial(k), 1e-15);
            } else if k == 24 {
                // Degree 24 is beyond the Kronrod rule: the check above is not vacuous.
                assert!((e.value[0] - monomial(k)).abs() > 1e-9);
            }
            if k <= 13 {
                // The Gauss rule is exact too, so K15 − G7 vanishes.
                assert!(e.error[0] < 1e-15, "x^{k}: {e:?}");
            }
        }
    }

    #[test]
    fn adaptive_kronrod_converges_and_reports_failures() {
        let r = gauss_kronrod(|x| (-x * x).exp(), 0.0, 3.0, 1e-13).unwrap();
        assert!(r.converged, "{r:?}");
        // ∫_0^3 exp(−x²) = √π/2·erf(3).
        check(r.estimate.value[0], 0.886_207_348_259_521_6, 1e-15);
        // A peak needs bisection.
        let r = gauss_kronrod(|x| 1.0 / (1e-2 + x * x), -1.0, 1.0, 1e-10).unwrap();
        assert!(r.converged, "{r:?}");
        check(r.estimate.value[0], 2.0 * 10.0 * 10f64.atan(), 1e-12);
        // A singularity at a node is an error, one between them fails to converge.
        assert!(matches!(gauss_kronrod(|x| 1.0 / x, -1.0, 1.0, 1e-10), Err(QuadratureError::NotFinite { .. })));
        let r = gauss_kronrod(|x| 1.0 / x.abs().sqrt().max(1e-300), -0.3, 1.0, 1e-14).unwrap();
        assert!(!r.converged);
        assert!(gauss_kronrod(|x| x, f64::NAN, 1.0, 1e-10).is_err());
    }
}
