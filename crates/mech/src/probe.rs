//! Numeric probes of symbolic facts: is an expression identically zero, is a
//! matrix singular, evaluated at random points.
//!
//! Simplification is not complete (no CAS decides zero-equivalence in general),
//! so decisions like "this coordinate is cyclic" or "H is the energy" are made by
//! evaluating at several random points with a tolerance scaled to the size of
//! the terms. The points are deterministic (a fixed-seed generator), so the
//! same model always gets the same verdict.

use rustc_hash::FxHashMap;
use sym::{ExprId, Node, Pool, Tape};

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

/// True when `e` vanishes at random points, relative to the size of its terms.
/// Points where it is not finite are skipped; if every point is, the answer is
/// false (nothing was shown).
pub fn is_zero(pool: &Pool, e: ExprId) -> bool {
    if pool.is_zero(e) {
        return true;
    }
    if pool.as_number(e).is_some() {
        return false;
    }
    let terms = pool.terms(e);
    let mut roots = vec![e];
    roots.extend(&terms);
    let Some(samples) = finite_samples(pool, &roots, 5, 0x5eed_0001) else { return false };
    let mut tested = 0;
    for out in &samples {
        // Relative to the size of the terms, with no absolute floor: a potential
        // 1e-12*k*x^2 is small, not zero.
        let scale: f64 = out[1..].iter().map(|v| v.abs()).sum::<f64>();
        if out[0] != 0.0 && out[0].abs() > 1e-10 * scale {
            return false;
        }
        tested += 1;
    }
    tested > 0
}

/// True when `a` and `b` are equal at random points.
pub fn are_equal(pool: &mut Pool, a: ExprId, b: ExprId) -> bool {
    let d = pool.sub(a, b);
    is_zero(pool, d)
}

/// True when the square matrix of expressions is singular at every one of a few
/// random points (its smallest pivot is negligible against its largest entry).
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

/// Replaces expressions that are numerically zero by the literal zero.
pub fn zero_if_vanishing(pool: &Pool, e: ExprId) -> ExprId {
    if is_zero(pool, e) {
        pool.zero()
    } else {
        e
    }
}

/// A map from symbol nodes to nodes, for substitution.
pub type Subst = FxHashMap<ExprId, ExprId>;
