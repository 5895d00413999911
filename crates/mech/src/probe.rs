//! Deciding symbolic facts: is an expression identically zero, are two equal,
//! is a matrix singular.
//!
//! A claim of zero (a cyclic coordinate, a conserved quantity, H equal to the
//! energy, a central potential) is made only when it is proven: exactly, by the
//! kernel's canonical form or by rewriting ([`Pool::is_identically_zero`]:
//! expansion, trigonometric identities, a common denominator), which also
//! covers the structural case of a derivative with respect to a symbol that
//! does not occur. Numbers can only refute: [`decide_zero`] evaluates the
//! expression at a few seeded random points together with a bound on its
//! rounding error, and a value well above that bound shows it is not zero. A
//! narrow function such as `exp(-1000000*x^2)` that underflows to 0 at every
//! point shows nothing either way: the answer is then [`Decision::Undecided`],
//! and callers claim nothing. The points are deterministic (a fixed-seed
//! generator), so the same model always gets the same verdict.
//!
//! Numeric uses that are not claims of zero stay numeric: [`is_singular`] (a
//! model whose mass matrix is singular at every probe point is refused),
//! [`smallest_pivot`] (a run's mass matrix going singular) and
//! [`finite_samples`] (the rank of a constraint Jacobian at generic points, a
//! lower bound; a rank below full is proven by its minors).

use rustc_hash::FxHashMap;
use sym::{ExprId, Func, Node, Number, Pool, Tape};

/// A tiny deterministic generator (SplitMix64).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator with a fixed seed.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next value, uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A value uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}

/// What is known about whether an expression is identically zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// Proven: exact rewriting reduces it to 0.
    Zero,
    /// Refuted: at some point its value is well above its rounding error.
    NonZero,
    /// Neither proven nor refuted: nothing may be claimed either way.
    Undecided,
}

impl Decision {
    /// True when the expression is proven zero.
    pub fn is_zero(self) -> bool {
        self == Decision::Zero
    }

    /// True when a point shows the expression is not zero.
    pub fn is_nonzero(self) -> bool {
        self == Decision::NonZero
    }

    /// Some(true) when proven zero, Some(false) when refuted, None when undecided.
    pub fn known(self) -> Option<bool> {
        match self {
            Decision::Zero => Some(true),
            Decision::NonZero => Some(false),
            Decision::Undecided => None,
        }
    }
}

/// Why a zero is undecided, for the sentences that say so.
pub const UNDECIDED: &str = "no exact rewriting reduces it to 0, and no probe point shows it nonzero";

/// Random points at which [`decide_zero`] looks for a nonzero value.
const REFUTING_POINTS: usize = 5;

/// A value refutes zero when it exceeds its rounding-error bound this many
/// times over. The bound is a first-order worst case, so an exact zero
/// evaluates to well below it; the margin covers what first order leaves out.
const REFUTING_MARGIN: f64 = 1e3;

/// Relative rounding error charged to each arithmetic operation: one unit in
/// the last place (twice the unit roundoff of round-to-nearest).
const OP_ERROR: f64 = f64::EPSILON;

/// Relative error charged to a library function (`sin`, `exp`, `powf`, ...):
/// a few ulps, more than libm's documented bounds.
const FUNC_ERROR: f64 = 4.0 * f64::EPSILON;

/// Absolute error charged to each operation for underflow: a result below the
/// smallest normal float may have lost all its digits.
const UNDERFLOW_ERROR: f64 = f64::MIN_POSITIVE;

/// Random points for every symbol of some expressions: values in [0.3, 1.7]
/// (positive, so that masses, lengths and square roots stay in their domains).
pub fn random_points(pool: &Pool, roots: &[ExprId], n_points: usize, seed: u64) -> (Vec<ExprId>, Vec<Vec<f64>>) {
    let symbols: Vec<ExprId> =
        pool.reachable(roots).into_iter().filter(|&id| matches!(pool.node(id), Node::Sym(_))).collect();
    let mut rng = Rng::new(seed);
    let points = (0..n_points).map(|_| symbols.iter().map(|_| rng.range(0.3, 1.7)).collect()).collect();
    (symbols, points)
}

/// The values of `roots` at `n_points` random points ([`random_points`]), at the
/// points where every value is finite; None when the expressions cannot be
/// evaluated (a symbol without a value).
pub fn finite_samples(pool: &Pool, roots: &[ExprId], n_points: usize, seed: u64) -> Option<Vec<Vec<f64>>> {
    let (inputs, points) = random_points(pool, roots, n_points, seed);
    let mut tape = Tape::compile(pool, roots, &inputs).ok()?;
    let mut samples = Vec::with_capacity(points.len());
    for p in &points {
        let mut out = vec![0.0; roots.len()];
        tape.eval(p, &mut out);
        if out.iter().all(|v| v.is_finite()) {
            samples.push(out);
        }
    }
    Some(samples)
}

/// Decides whether `e` is identically zero: [`Decision::Zero`] only when exact
/// rewriting shows it, [`Decision::NonZero`] when a random point shows a value
/// well above its rounding error, [`Decision::Undecided`] otherwise (see the
/// module documentation).
pub fn decide_zero(pool: &mut Pool, e: ExprId) -> Decision {
    if pool.is_zero(e) {
        return Decision::Zero;
    }
    if pool.as_number(e).is_some() {
        return Decision::NonZero;
    }
    if refuted_at_points(pool, e) {
        return Decision::NonZero;
    }
    if pool.is_identically_zero(e) {
        Decision::Zero
    } else {
        Decision::Undecided
    }
}

/// [`decide_zero`] without rewriting, for expressions too long to expand:
/// [`Decision::Zero`] only when the canonical form is 0, [`Decision::NonZero`]
/// when a point refutes it, [`Decision::Undecided`] otherwise.
pub fn decide_zero_without_rewriting(pool: &Pool, e: ExprId) -> Decision {
    if pool.is_zero(e) {
        Decision::Zero
    } else if pool.as_number(e).is_some() || refuted_at_points(pool, e) {
        Decision::NonZero
    } else {
        Decision::Undecided
    }
}

/// Decides whether `a − b` is identically zero ([`decide_zero`]).
pub fn decide_equal(pool: &mut Pool, a: ExprId, b: ExprId) -> Decision {
    let d = pool.sub(a, b);
    decide_zero(pool, d)
}

/// True when `e` is proven identically zero; false when it is refuted or
/// undecided, so false is never a claim that `e` is nonzero.
pub fn is_zero(pool: &mut Pool, e: ExprId) -> bool {
    decide_zero(pool, e).is_zero()
}

/// `e` itself, or the literal zero when `e` is proven zero.
pub fn zero_if_proven(pool: &mut Pool, e: ExprId) -> ExprId {
    if is_zero(pool, e) {
        pool.zero()
    } else {
        e
    }
}

/// True when a random point shows `e` nonzero: finite, and above
/// [`REFUTING_MARGIN`] times its rounding-error bound. A point where the value
/// or the bound is not finite is skipped; a value that underflowed to 0 shows
/// nothing.
fn refuted_at_points(pool: &Pool, e: ExprId) -> bool {
    refuted_each(pool, &[e])[0]
}

/// [`refuted_at_points`] for many expressions at once, with one walk and one
/// evaluation of their shared DAG per point (the symbols get their values in
/// the order of the whole DAG, so a root may meet other points than alone):
/// for each root, true when some point shows it nonzero.
pub fn refuted_each(pool: &Pool, roots: &[ExprId]) -> Vec<bool> {
    let order = pool.reachable(roots);
    let (symbols, points) = random_points(pool, roots, REFUTING_POINTS, 0x5eed_0001);
    let slot: FxHashMap<ExprId, usize> = order.iter().enumerate().map(|(k, &id)| (id, k)).collect();
    let mut values = vec![Bounded::EXACT_ZERO; order.len()];
    let mut refuted = vec![false; roots.len()];
    for point in &points {
        for (&s, &x) in symbols.iter().zip(point) {
            values[slot[&s]] = Bounded { value: x, error: 0.0 };
        }
        for (k, &id) in order.iter().enumerate() {
            if !matches!(pool.node(id), Node::Sym(_)) {
                values[k] = bounded_node(pool, id, |c| values[slot[&c]]);
            }
        }
        for (r, &e) in roots.iter().enumerate() {
            let Bounded { value, error } = values[slot[&e]];
            refuted[r] |= value.is_finite() && error.is_finite() && value.abs() > REFUTING_MARGIN * error;
        }
    }
    refuted
}

/// Whether `e` is zero to rounding at one point (symbols valued by `env`, by
/// their text): its value is within [`REFUTING_MARGIN`] times its
/// rounding-error bound, as a value that is not a refutation of zero. None
/// when a symbol has no value or the value or bound is not finite. A test at a
/// point, used to explain a refusal, never to claim a zero.
pub fn zero_to_rounding_at(pool: &Pool, e: ExprId, env: &dyn Fn(&str) -> Option<f64>) -> Option<bool> {
    let order = pool.reachable(&[e]);
    let slot: FxHashMap<ExprId, usize> = order.iter().enumerate().map(|(k, &id)| (id, k)).collect();
    let mut values = vec![Bounded::EXACT_ZERO; order.len()];
    for (k, &id) in order.iter().enumerate() {
        values[k] = match pool.as_symbol(id) {
            Some(s) => Bounded { value: env(&pool.symbol_text(s))?, error: 0.0 },
            None => bounded_node(pool, id, |c| values[slot[&c]]),
        };
    }
    let Bounded { value, error } = values[slot[&e]];
    (value.is_finite() && error.is_finite()).then_some(value.abs() <= REFUTING_MARGIN * error)
}

/// The size of the terms `e` is made of at one point: a sum's is the sum of
/// its terms' sizes, a product's the product of its factors', a positive
/// power's the power of its base's, anything else its absolute value. The
/// scale against which a residual that should be 0 is judged: (x² + y² − l²)²
/// at x² + y² ≈ l² has size (x² + y² + l²)², not its own tiny value. None as
/// for [`zero_to_rounding_at`].
pub fn terms_size_at(pool: &Pool, e: ExprId, env: &dyn Fn(&str) -> Option<f64>) -> Option<f64> {
    let order = pool.reachable(&[e]);
    let slot: FxHashMap<ExprId, usize> = order.iter().enumerate().map(|(k, &id)| (id, k)).collect();
    // (value, size) per node.
    let mut nodes = vec![(0.0f64, 0.0f64); order.len()];
    for (k, &id) in order.iter().enumerate() {
        let at = |c: ExprId| nodes[slot[&c]];
        nodes[k] = match pool.node(id) {
            Node::Sym(s) => {
                let v = env(&pool.symbol_text(*s))?;
                (v, v.abs())
            }
            Node::Add(ts) => ts.iter().fold((0.0, 0.0), |(v, z), &t| (v + at(t).0, z + at(t).1)),
            Node::Mul(fs) => fs.iter().fold((1.0, 1.0), |(v, z), &f| (v * at(f).0, z * at(f).1)),
            &Node::Pow(b, x) => {
                let ((bv, bz), (xv, _)) = (at(b), at(x));
                let v = bv.powf(xv);
                (v, if pool.as_number(x).is_some() && xv > 0.0 { bz.powf(xv) } else { v.abs() })
            }
            _ => {
                let v = bounded_node(pool, id, |c| Bounded { value: at(c).0, error: 0.0 }).value;
                (v, v.abs())
            }
        };
    }
    let size = nodes[slot[&e]].1;
    size.is_finite().then_some(size)
}

/// A computed value and a bound on its absolute error (first order).
#[derive(Debug, Clone, Copy)]
struct Bounded {
    value: f64,
    error: f64,
}

impl Bounded {
    const EXACT_ZERO: Bounded = Bounded { value: 0.0, error: 0.0 };

    /// A result of an operation, charged `relative` of itself and the underflow floor.
    fn rounded(value: f64, propagated: f64, relative: f64) -> Bounded {
        Bounded { value, error: propagated + relative * value.abs() + UNDERFLOW_ERROR }
    }
}

/// The value of one node from its children's, with the error bound: errors
/// carried from the operands by the derivative's size, plus the node's own
/// rounding.
fn bounded_node(pool: &Pool, id: ExprId, child: impl Fn(ExprId) -> Bounded) -> Bounded {
    match pool.node(id) {
        Node::Num(Number::Float(x)) => Bounded { value: *x, error: 0.0 },
        Node::Num(n) => {
            let v = n.to_f64();
            Bounded { value: v, error: OP_ERROR * v.abs() }
        }
        Node::Pi => Bounded { value: std::f64::consts::PI, error: OP_ERROR * std::f64::consts::PI },
        Node::Sym(_) => unreachable!("symbols are given their point's value"),
        Node::Add(ts) => {
            let (mut value, mut propagated, mut size) = (0.0, 0.0, 0.0);
            for &t in ts.iter() {
                let b = child(t);
                value += b.value;
                propagated += b.error;
                size += b.value.abs();
            }
            let ops = (ts.len() - 1) as f64;
            Bounded { value, error: propagated + ops * OP_ERROR * size + UNDERFLOW_ERROR }
        }
        Node::Mul(fs) => {
            let parts: Vec<Bounded> = fs.iter().map(|&f| child(f)).collect();
            // Σ_i e_i Π_{j≠i} |v_j| from prefix and suffix products.
            let mut suffix = vec![1.0; parts.len() + 1];
            for i in (0..parts.len()).rev() {
                suffix[i] = suffix[i + 1] * parts[i].value.abs();
            }
            let (mut value, mut prefix, mut propagated) = (1.0, 1.0, 0.0);
            for (i, b) in parts.iter().enumerate() {
                propagated += b.error * prefix * suffix[i + 1];
                prefix *= b.value.abs();
                value *= b.value;
            }
            let ops = (parts.len() - 1) as f64;
            Bounded::rounded(value, propagated, ops * OP_ERROR)
        }
        &Node::Pow(b, x) => {
            let (base, exp) = (child(b), child(x));
            let value = base.value.powf(exp.value);
            // d/db b^x = x b^(x−1), d/dx b^x = b^x ln b.
            let d_base = exp.value * base.value.powf(exp.value - 1.0);
            let d_exp = if exp.error == 0.0 { 0.0 } else { value * base.value.abs().ln() };
            Bounded::rounded(value, d_base.abs() * base.error + d_exp.abs() * exp.error, FUNC_ERROR)
        }
        &Node::Func(f, a) => {
            let arg = child(a);
            let value = f.apply(arg.value);
            Bounded::rounded(value, slope(f, arg.value, value).abs() * arg.error, FUNC_ERROR)
        }
        &Node::Atan2(y, x) => {
            let (y, x) = (child(y), child(x));
            let value = y.value.atan2(x.value);
            let r2 = x.value * x.value + y.value * y.value;
            let propagated = (x.value.abs() * y.error + y.value.abs() * x.error) / r2;
            Bounded::rounded(value, propagated, FUNC_ERROR)
        }
    }
}

/// The derivative of `f` at `x`, where `f(x) = value`.
fn slope(f: Func, x: f64, value: f64) -> f64 {
    match f {
        Func::Sin => x.cos(),
        Func::Cos => x.sin(),
        Func::Tan => 1.0 + value * value,
        Func::Asin | Func::Acos => 1.0 / (1.0 - x * x).sqrt(),
        Func::Atan => 1.0 / (1.0 + x * x),
        Func::Sinh => x.cosh(),
        Func::Cosh => x.sinh(),
        Func::Tanh => 1.0 - value * value,
        Func::Exp => value,
        Func::Log => 1.0 / x,
        Func::Abs => 1.0,
    }
}

/// True when the square matrix of expressions is singular at every one of a few
/// random points (its smallest pivot is negligible against its largest entry).
/// A numeric test, used to refuse a model, never to claim a result.
pub fn is_singular(pool: &Pool, m: &[Vec<ExprId>]) -> bool {
    let n = m.len();
    let roots: Vec<ExprId> = m.iter().flatten().copied().collect();
    let (inputs, points) = random_points(pool, &roots, 3, 0x5eed_0002);
    let Ok(mut tape) = Tape::compile(pool, &roots, &inputs) else { return false };
    let mut out = vec![0.0; roots.len()];
    let mut singular_everywhere = true;
    for p in &points {
        tape.eval(p, &mut out);
        let scale = out.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        if smallest_pivot(&out, n).is_some_and(|p| p.is_finite() && p > 1e-10 * scale) {
            singular_everywhere = false;
        }
    }
    singular_everywhere
}

/// The smallest |pivot| of an LU with partial pivoting of the row-major n×n
/// matrix `m` (zero for a singular one), or None when an entry is not finite.
pub fn smallest_pivot(m: &[f64], n: usize) -> Option<f64> {
    if m.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let lu = nalgebra::DMatrix::from_row_slice(n, n, m).lu();
    let u = lu.u();
    Some((0..n).map(|i| u[(i, i)].abs()).fold(f64::INFINITY, f64::min))
}

/// A map from symbol nodes to nodes, for substitution.
pub type Subst = FxHashMap<ExprId, ExprId>;

#[cfg(test)]
mod tests {
    use super::*;

    /// Many roots at once: each refuted exactly when it is refuted alone.
    #[test]
    fn refuted_each_agrees_with_one_at_a_time() {
        let mut pool = Pool::default();
        let texts = ["sin(x)^2 + cos(x)^2 - 1", "x*y", "exp(-1000000*x^2)", "(x + y)^2 - x^2 - 2*x*y - y^2", "y - 1/3"];
        let roots: Vec<ExprId> = texts.iter().map(|t| pool.parse(t).unwrap()).collect();
        let alone: Vec<bool> = roots.iter().map(|&e| refuted_at_points(&pool, e)).collect();
        assert_eq!(refuted_each(&pool, &roots), alone);
        assert_eq!(alone, [false, true, false, false, true]);
    }

    #[track_caller]
    fn check(text: &str, expect: Decision) {
        let mut pool = Pool::default();
        let e = pool.parse(text).unwrap();
        assert_eq!(decide_zero(&mut pool, e), expect, "{text}");
    }

    #[test]
    fn zeros_are_proven_exactly() {
        check("x - x", Decision::Zero);
        check("sin(q)^2 + cos(q)^2 - 1", Decision::Zero);
        check("l^2*m*(sin(a)*cos(b) - cos(a)*sin(b)) - l^2*m*sin(a - b)", Decision::Zero);
        check("(r^2 - 1)/(r - 1) - r - 1", Decision::Zero);
    }

    #[test]
    fn a_point_refutes_what_is_not_zero() {
        check("sin(q)^2 - cos(q)^2", Decision::NonZero);
        check("1e-12*k*x^2", Decision::NonZero);
        check("2*sin(u)*cos(u) - sin(u)", Decision::NonZero);
    }

    #[test]
    fn narrow_functions_are_undecided() {
        // ∂/∂x of the issue's Lagrangian: exp(-1000000*x^2) underflows to 0 at
        // every point, so the points show nothing, and no rewrite removes x.
        check("2000000*x*exp(-1000000*x^2)", Decision::Undecided);
        check("20000*th*exp(-10000*th^2)/r", Decision::Undecided);
        // Every term underflows: the sum is 0 at each point, and that proves nothing.
        check("exp(-1000000*x^2) - exp(-2000000*x^2)", Decision::Undecided);
    }

    #[test]
    fn rounding_noise_does_not_refute_an_identity_the_rewrites_miss() {
        // sqrt(x^2) = x for the positive points, but no rewrite here shows it:
        // neither proven nor refuted.
        check("sqrt(x^2) - x", Decision::Undecided);
        check("exp(log(x)) - x", Decision::Undecided);
    }

    #[test]
    fn the_error_bound_covers_cancellation() {
        let mut pool = Pool::default();
        let e = pool.parse("(1 + x)^2 - 1 - 2*x - x^2").unwrap();
        // Not canonical-zero as written: only its expansion is.
        assert!(!pool.is_zero(e));
        assert!(!refuted_at_points(&pool, e));
        assert_eq!(decide_zero(&mut pool, e), Decision::Zero);
    }
}
