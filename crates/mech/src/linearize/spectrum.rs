//! The eigenvalues of a linearization and the verdict on stability, each to
//! the accuracy the matrices allow.
//!
//! Three ways, the best conditioned that applies: an undamped system without
//! constraints (∂f/∂q' = 0, M and K = −∂f/∂q symmetric) solves K v = ω² M v
//! (real ω² by construction; s = ±i ω, or ±√(−ω²) when ω² < 0); a second-order
//! A = [[0, I], [G, 0]] (an undamped system after the constraints are
//! eliminated) takes μ = s² from G; any other A is balanced and its
//! eigenvalues computed directly. A value is zero only when it lies within the
//! rounding bound of its computation (a few ε times the norm of the balanced
//! matrix), never by a looser rule, and the verdict is read from the unrounded
//! values against that same bound.

use crate::equilibria::Stability;
use nalgebra::DMatrix;

/// Entries of A at most this fraction of max |A| count as zero when a zero
/// row or column is deflated (structural zeros come out exact; this is ε-level
/// rounding, not a threshold on eigenvalues).
const DEFLATE: f64 = 1e-14;
/// M and −∂f/∂q count as symmetric when they differ from their transposes by
/// at most this fraction of their largest entry (rounding of two derivatives
/// of one function).
const SYMMETRIC: f64 = 1e-12;

/// What the second-order problem needs: M and F_q = ∂f/∂q (with the
/// constraints' terms) when the model has no constraints and no velocity
/// terms.
pub(super) struct SecondOrder<'a> {
    pub m: &'a DMatrix<f64>,
    pub fq: &'a DMatrix<f64>,
}

/// The eigenvalues (sorted: decay rate ascending, then frequency descending,
/// + before −) and the verdict; the error says why they cannot be computed.
pub(super) fn spectrum(a: &DMatrix<f64>, second: Option<SecondOrder>) -> Result<(Vec<(f64, f64)>, Stability), String> {
    if a.is_empty() {
        return Ok((Vec::new(), Stability::Marginal));
    }
    if !a.iter().all(|v| v.is_finite()) {
        return Err("A has entries that are not finite".into());
    }
    let mut ev = match second.and_then(symmetric) {
        Some(ev) => ev,
        None => match second_order(a)? {
            Some(ev) => ev,
            None => general(a)?,
        },
    };
    ev.sort_by(|x, y| (-x.0).total_cmp(&-y.0).then(y.1.abs().total_cmp(&x.1.abs())).then(y.1.total_cmp(&x.1)));
    let stability = if ev.iter().any(|e| e.0 > 0.0) {
        Stability::Unstable
    } else if ev.iter().all(|e| e.0 < 0.0) {
        Stability::Stable
    } else {
        Stability::Marginal
    };
    Ok((ev, stability))
}

/// s = ±√μ for each μ = s² (real within `bound`: a pair on an axis).
fn roots_of_squares(mu: &[(f64, f64)], bound: f64) -> Vec<(f64, f64)> {
    let mut ev = Vec::with_capacity(2 * mu.len());
    for &(re, im) in mu {
        if im.abs() <= bound {
            if re.abs() <= bound {
                ev.extend([(0.0, 0.0), (0.0, 0.0)]);
            } else if re > 0.0 {
                let s = re.sqrt();
                ev.extend([(s, 0.0), (-s, 0.0)]);
            } else {
                let w = (-re).sqrt();
                ev.extend([(0.0, w), (0.0, -w)]);
            }
        } else {
            // The principal square root of a complex μ, and its negative.
            let r = (re * re + im * im).sqrt();
            let x = ((r + re) / 2.0).sqrt();
            let y = ((r - re) / 2.0).sqrt().copysign(im);
            ev.extend([(x, y), (-x, -y)]);
        }
    }
    ev
}

/// K v = ω² M v with K = −F_q, when M and F_q are symmetric.
fn symmetric(s: SecondOrder) -> Option<Vec<(f64, f64)>> {
    let n = s.m.nrows();
    let asym = |x: &DMatrix<f64>| (x - x.transpose()).amax() <= SYMMETRIC * x.amax();
    if !asym(s.m) || !asym(s.fq) {
        return None;
    }
    let row_major = |x: &DMatrix<f64>| -> Vec<f64> {
        (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| x[(i, j)]).collect()
    };
    let fq: Vec<f64> = row_major(s.fq);
    // μ of F_q v = μ M v is s² (M s² v = F_q v).
    let mu = num::symmetric_definite(n, &fq, &row_major(s.m))?;
    let bound = num::symmetric_rounding(n, &mu);
    let mu: Vec<(f64, f64)> = mu.into_iter().map(|v| (v, 0.0)).collect();
    Some(roots_of_squares(&mu, bound))
}

/// A = [[0, I], [G, 0]] exactly (in this state order): s² = μ(G).
fn second_order(a: &DMatrix<f64>) -> Result<Option<Vec<(f64, f64)>>, String> {
    let n2 = a.nrows();
    if !n2.is_multiple_of(2) {
        return Ok(None);
    }
    let n = n2 / 2;
    for i in 0..n {
        for j in 0..n2 {
            let want = if j == n + i { 1.0 } else { 0.0 };
            if a[(i, j)] != want {
                return Ok(None);
            }
        }
        for j in n..n2 {
            if a[(n + i, j)] != 0.0 {
                return Ok(None);
            }
        }
    }
    let g: Vec<f64> = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| a[(n + i, j)]).collect();
    let (mu, bound) = deflated(n, &g)?;
    Ok(Some(roots_of_squares(&mu, bound)))
}

/// The eigenvalues of A itself.
fn general(a: &DMatrix<f64>) -> Result<Vec<(f64, f64)>, String> {
    let n = a.nrows();
    let rows: Vec<f64> = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| a[(i, j)]).collect();
    let (ev, bound) = deflated(n, &rows)?;
    Ok(ev
        .into_iter()
        .map(|(re, im)| (if re.abs() <= bound { 0.0 } else { re }, if im.abs() <= bound { 0.0 } else { im }))
        .map(|(re, im)| if im == 0.0 && re != 0.0 { (refine(a, re), 0.0) } else { (re, im) })
        .collect())
}

/// A real eigenvalue s₀ of A refined by Newton's method on det(A − sI)
/// (s ← s + 1/tr((A − sI)⁻¹)): the QR iteration gets a small eigenvalue
/// beside a large one only to ε‖A‖ (an overdamped oscillator's slow root),
/// Newton to its own relative accuracy. A step larger than a millionth of s₀
/// would be a jump to another eigenvalue and is not taken.
fn refine(a: &DMatrix<f64>, s0: f64) -> f64 {
    let n = a.nrows();
    let mut s = s0;
    for _ in 0..3 {
        let shifted = a - DMatrix::identity(n, n) * s;
        let Some(inv) = shifted.try_inverse() else { break };
        let t = inv.trace();
        if t == 0.0 || !t.is_finite() {
            break;
        }
        let next = s + 1.0 / t;
        if !next.is_finite() || (next - s0).abs() > 1e-6 * s0.abs() || next == s {
            break;
        }
        s = next;
    }
    s
}

/// The eigenvalues of the n×n row-major `a` and their rounding bound. A zero
/// row or column (a cyclic coordinate, a rate nothing changes) is an exact
/// zero eigenvalue, deflated first: the iteration would split a defective zero
/// by a root of the rounding error. Values within the bound of zero (alone,
/// or a cluster whose sum is) are the zeros they round.
fn deflated(n: usize, a: &[f64]) -> Result<(Vec<(f64, f64)>, f64), String> {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let tiny = DEFLATE * scale;
    let mut keep: Vec<usize> = (0..n).collect();
    let mut zeros = 0;
    while let Some(pos) = (0..keep.len()).find(|&p| {
        let i = keep[p];
        keep.iter().all(|&j| a[i * n + j].abs() <= tiny) || keep.iter().all(|&j| a[j * n + i].abs() <= tiny)
    }) {
        keep.remove(pos);
        zeros += 1;
    }
    let k = keep.len();
    let rest: Vec<f64> = keep.iter().flat_map(|&i| keep.iter().map(move |&j| a[i * n + j])).collect();
    let mut ev = num::eigenvalues(k, &rest).map_err(|e| format!("the eigenvalues of A cannot be computed: {e}"))?;
    let bound = num::eigenvalue_rounding(k, &rest);
    // A defective zero splits into a cluster of radius about the k-th root of
    // the rounding; the cluster's mean is accurate to the rounding.
    let radius = bound.sqrt() * rest.iter().fold(0.0f64, |m, v| m.max(v.abs())).sqrt();
    let near: Vec<usize> = (0..ev.len()).filter(|&i| ev[i].0.hypot(ev[i].1) <= radius.max(bound)).collect();
    let sum = near.iter().fold((0.0, 0.0), |s, &i| (s.0 + ev[i].0, s.1 + ev[i].1));
    if !near.is_empty() && sum.0.hypot(sum.1) <= bound * near.len() as f64 {
        for &i in &near {
            ev[i] = (0.0, 0.0);
        }
    } else {
        for e in ev.iter_mut().filter(|e| e.0.hypot(e.1) <= bound) {
            *e = (0.0, 0.0);
        }
    }
    ev.extend(std::iter::repeat_n((0.0, 0.0), zeros));
    Ok((ev, bound))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a(rows: &[&[f64]]) -> DMatrix<f64> {
        DMatrix::from_row_slice(rows.len(), rows.len(), &rows.concat())
    }

    #[test]
    fn a_free_particle_is_a_double_zero_and_marginal() {
        let (ev, st) = spectrum(&a(&[&[0.0, 1.0], &[0.0, 0.0]]), None).unwrap();
        assert_eq!(ev, vec![(0.0, 0.0), (0.0, 0.0)]);
        assert_eq!(st, Stability::Marginal);
    }

    #[test]
    fn an_overdamped_oscillator_keeps_its_slow_root() {
        // m = k = 1, b = 1e4: s = (−b ± √(b² − 4))/2.
        let b = 1e4f64;
        let (ev, st) = spectrum(&a(&[&[0.0, 1.0], &[-1.0, -b]]), None).unwrap();
        let fast = (-b - (b * b - 4.0).sqrt()) / 2.0;
        let slow = 1.0 / fast; // s₁ s₂ = k/m = 1
        assert!((ev[0].0 - slow).abs() <= 1e-14 * slow.abs(), "{ev:?} vs {slow}");
        assert!((ev[1].0 - fast).abs() <= 1e-12 * fast.abs(), "{ev:?}");
        assert_eq!(st, Stability::Stable);
    }

    #[test]
    fn a_fast_and_a_slow_mode_are_both_found_and_an_unstable_one_is_unstable() {
        // Uncoupled ω = 3162 and 1, and the same with the slow one inverted (s = ±1).
        let w2 = 3162.0f64 * 3162.0;
        let m = a(&[&[0.0, 0.0, 1.0, 0.0], &[0.0, 0.0, 0.0, 1.0], &[-w2, 0.0, 0.0, 0.0], &[0.0, -1.0, 0.0, 0.0]]);
        let (ev, st) = spectrum(&m, None).unwrap();
        assert_eq!(st, Stability::Marginal);
        assert!(ev.contains(&(0.0, 1.0)) && ev.contains(&(0.0, -1.0)), "{ev:?}");
        let mut m = m;
        m[(3, 1)] = 1.0;
        let (ev, st) = spectrum(&m, None).unwrap();
        assert_eq!(st, Stability::Unstable);
        assert!(ev.contains(&(1.0, 0.0)) && ev.contains(&(-1.0, 0.0)), "{ev:?}");
    }
}
