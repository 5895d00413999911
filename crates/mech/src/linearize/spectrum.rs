//! The eigenvalues of a linearization and the verdict on stability, each to
//! the accuracy the matrices allow.
//!
//! Three ways, the best conditioned that applies: an undamped system without
//! constraints (∂f/∂q' = 0, M and K = −∂f/∂q symmetric) solves K v = ω² M v
//! (real ω² by construction; s = ±i ω, or ±√(−ω²) when ω² < 0); a second-order
//! A = [[0, I], [G, 0]] (an undamped system after the constraints are
//! eliminated) takes μ = s² from G; any other A is balanced and its
//! eigenvalues computed directly. A value takes an exact form (zero, real, or
//! a real part of zero) only when a matrix within the rounding of A (a few ε
//! times the norm of the balanced matrix) has it there, by a test of the
//! smallest singular value of A − sI along the way ([`Resolution`]), never
//! merely for being small beside ‖A‖; the verdict is read from those values.

use crate::equilibria::Stability;
use nalgebra::{Complex, DMatrix};

/// Entries of A at most this fraction of max |A| count as zero when a zero
/// row or column is deflated (structural zeros come out exact; this is ε-level
/// rounding, not a threshold on eigenvalues).
const DEFLATE: f64 = 1e-14;
/// M and −∂f/∂q count as symmetric when they differ from their transposes by
/// at most this fraction of their largest entry (rounding of two derivatives
/// of one function).
const SYMMETRIC: f64 = 1e-12;
/// Points of a segment from a computed eigenvalue to its exact form that must
/// all lie in the rounding pseudospectrum (see [`Resolution`]): enough that a
/// gap between two eigenvalues on the way shows.
const SAMPLES: usize = 8;
/// Bound on the SVD's sweeps (it converges in a few per singular value).
const SVD_ITERATIONS: usize = 10_000;

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
    let mu = deflated(n, &g, false)?;
    Ok(Some(roots_of_squares(&mu, 0.0)))
}

/// The eigenvalues of A itself.
fn general(a: &DMatrix<f64>) -> Result<Vec<(f64, f64)>, String> {
    let n = a.nrows();
    let rows: Vec<f64> = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| a[(i, j)]).collect();
    let ev = deflated(n, &rows, true)?;
    let gap = |k: usize| {
        let e = ev[k];
        (0..ev.len()).filter(|&j| j != k).map(|j| (ev[j].0 - e.0).hypot(ev[j].1 - e.1)).fold(f64::INFINITY, f64::min)
    };
    Ok((0..ev.len())
        .map(|k| {
            let (re, im) = ev[k];
            if im == 0.0 && re != 0.0 {
                (refine(a, re, gap(k)), 0.0)
            } else {
                (re, im)
            }
        })
        .collect())
}

/// A real eigenvalue s₀ of A refined by Newton's method on det(A − sI)
/// (s ← s + 1/tr((A − sI)⁻¹)): the QR iteration gets a small eigenvalue
/// beside a large one only to ε‖A‖ (an overdamped oscillator's slow root),
/// Newton to its own relative accuracy. A move from s₀ of a quarter of the
/// distance to the nearest other eigenvalue (`gap`) would be a jump to
/// another and is not taken.
fn refine(a: &DMatrix<f64>, s0: f64, gap: f64) -> f64 {
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
        if !next.is_finite() || (next - s0).abs() > 0.25 * gap || next == s {
            break;
        }
        s = next;
    }
    s
}

/// The eigenvalues of the n×n row-major `a`, each in its exact form where
/// rounding cannot tell it from one (see [`Resolution`]). A zero row or
/// column (a cyclic coordinate, a rate nothing changes) is an exact zero
/// eigenvalue, deflated first. With `axis`, a real part is also read as zero
/// where it cannot be told from zero (the eigenvalues are s; without, they are
/// s², whose real part has no such meaning).
fn deflated(n: usize, a: &[f64], axis: bool) -> Result<Vec<(f64, f64)>, String> {
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
    let ev = num::eigenvalues(k, &rest).map_err(|e| format!("the eigenvalues of A cannot be computed: {e}"))?;
    let resolution = Resolution::new(k, &rest);
    let mut ev: Vec<(f64, f64)> = ev
        .into_iter()
        .map(|(re, im)| {
            // A pair is decided once, from its upper member, so that both
            // members come out alike.
            let (x, y) = resolution.snap((re, im.abs()), axis);
            (x, y.copysign(im))
        })
        .collect();
    ev.extend(std::iter::repeat_n((0.0, 0.0), zeros));
    Ok(ev)
}

/// What rounding leaves undecided about the eigenvalues of a matrix: the
/// eigenvalues QR computes are exact for a matrix within η = a few ε‖A‖ of A
/// (balanced), so a value s is as good as an eigenvalue when σ_min(A − sI)
/// ≤ η (s lies in the η-pseudospectrum). A computed λ takes an exact form p
/// (0, real, or on the imaginary axis) only when the whole segment from λ to p
/// lies there: then a matrix within rounding of A has p where λ is, and the
/// data cannot tell them apart. A value merely small beside ‖A‖ (a slow
/// gyroscopic pair beside a stiff mode) leaves the pseudospectrum on the way
/// to 0 and is kept; a defective zero, split by rounding into a cluster of
/// radius √η, does not, and is zero.
struct Resolution {
    a: DMatrix<Complex<f64>>,
    eta: f64,
}

impl Resolution {
    fn new(n: usize, rows: &[f64]) -> Resolution {
        let bal = num::balanced(n, rows);
        Resolution {
            a: DMatrix::from_fn(n, n, |i, j| Complex::new(bal[i * n + j], 0.0)),
            eta: num::eigenvalue_rounding(n, rows),
        }
    }

    /// σ_min(A − sI) ≤ η. An SVD that does not converge decides nothing (the
    /// value stays as computed).
    fn within(&self, s: (f64, f64)) -> bool {
        let n = self.a.nrows();
        let shifted = &self.a - DMatrix::identity(n, n) * Complex::new(s.0, s.1);
        match nalgebra::linalg::SVD::try_new(shifted, false, false, f64::EPSILON, SVD_ITERATIONS) {
            Some(svd) => svd.singular_values.iter().fold(f64::INFINITY, |m, &v| m.min(v)) <= self.eta,
            None => false,
        }
    }

    /// Every sample of the segment from λ to p is within (p first: most
    /// values fail there).
    fn reaches(&self, l: (f64, f64), p: (f64, f64)) -> bool {
        (0..=SAMPLES).rev().all(|k| {
            let t = k as f64 / SAMPLES as f64;
            self.within((l.0 + t * (p.0 - l.0), l.1 + t * (p.1 - l.1)))
        })
    }

    /// λ in the first exact form it reaches: 0, then real, then (with `axis`)
    /// on the imaginary axis; else as computed.
    fn snap(&self, l: (f64, f64), axis: bool) -> (f64, f64) {
        if self.a.nrows() == 0 || l == (0.0, 0.0) {
            return l;
        }
        if self.reaches(l, (0.0, 0.0)) {
            return (0.0, 0.0);
        }
        let real = l.1 != 0.0 && self.reaches(l, (l.0, 0.0));
        let imaginary = axis && l.0 != 0.0 && self.reaches(l, (0.0, l.1));
        (if imaginary { 0.0 } else { l.0 }, if real { 0.0 } else { l.1 })
    }
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

    /// A of M q'' + C q' + K q = 0 (M = I) with K = R diag(k) Rᵀ and C = R c Rᵀ
    /// for a rotation R by float angles (so that nothing is structurally zero).
    fn quadratic(k: &[f64], c: &[f64]) -> DMatrix<f64> {
        let n = k.len();
        let mut r = DMatrix::<f64>::identity(n, n);
        for (i, angle) in (0..n - 1).zip([0.7f64, -1.3, 2.1, 0.4]) {
            let mut g = DMatrix::<f64>::identity(n, n);
            let (s, co) = angle.sin_cos();
            g[(i, i)] = co;
            g[(i + 1, i + 1)] = co;
            g[(i, i + 1)] = -s;
            g[(i + 1, i)] = s;
            r = g * r;
        }
        let kk = &r * DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(k)) * r.transpose();
        let cc = &r * DMatrix::from_row_slice(n, n, c) * r.transpose();
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
        }
        a.view_mut((n, 0), (n, n)).copy_from(&(-kk));
        a.view_mut((n, n), (n, n)).copy_from(&(-cc));
        a
    }

    #[track_caller]
    fn has(ev: &[(f64, f64)], want: (f64, f64), tol: f64) {
        assert!(ev.iter().any(|e| (e.0 - want.0).hypot(e.1 - want.1) <= tol), "{want:?} not in {ev:?}");
    }

    #[test]
    fn a_slow_gyroscopic_pair_beside_a_stiff_mode_is_kept() {
        // Stiffness 2.28e-5 on a pair coupled by 0.18, beside ω² = 5426:
        // s = ±i(√(g² + 4k) ∓ g)/2, the slow one ≈ ±1.26e-4 i (was 0 ×2).
        let (k, g) = (2.28e-5, 0.18);
        let c = [0.0, g, 0.0, -g, 0.0, 0.0, 0.0, 0.0, 0.0];
        let (ev, st) = spectrum(&quadratic(&[k, k, 5426.0], &c), None).unwrap();
        let r = (g * g + 4.0 * k).sqrt();
        let slow = 2.0 * k / (r + g);
        has(&ev, (0.0, slow), 1e-8 * slow);
        has(&ev, (0.0, -slow), 1e-8 * slow);
        has(&ev, (0.0, (r + g) / 2.0), 1e-12);
        assert_eq!(st, Stability::Marginal, "{ev:?}");
    }

    #[test]
    fn zero_stiffness_gives_exact_zeros_and_a_marginal_verdict() {
        // A damped free mode (s = 0, −0.003) beside stiff ones: the zero is
        // exactly 0, not a small positive real (was "unstable").
        let mut c = vec![0.0; 9];
        c[0] = 0.003;
        let (ev, st) = spectrum(&quadratic(&[0.0, 14017.1, 14205.6], &c), None).unwrap();
        assert!(ev.contains(&(0.0, 0.0)), "{ev:?}");
        has(&ev, (-0.003, 0.0), 1e-8);
        assert_eq!(st, Stability::Marginal, "{ev:?}");
        // A gyroscopic pair without stiffness (s = 0, 0, ±i g) beside a stiff
        // mode: no real part may be left over (was 1.9e-11 ± 0.0103i, "unstable").
        let g = 0.0103;
        let c = [0.0, g, 0.0, -g, 0.0, 0.0, 0.0, 0.0, 0.0];
        let (ev, st) = spectrum(&quadratic(&[0.0, 0.0, 23759.4], &c), None).unwrap();
        assert!(ev.iter().all(|e| e.0 == 0.0), "{ev:?}");
        has(&ev, (0.0, g), 1e-10);
        assert_eq!(st, Stability::Marginal, "{ev:?}");
    }

    #[test]
    fn a_critically_damped_mode_is_a_double_real_root() {
        // s² + 2√k s + k: s = −√k twice, split by rounding into a pair ±1e-8 i.
        let k = 12.463930185738803f64;
        let mut c = vec![0.0; 4];
        c[0] = 2.0 * k.sqrt();
        c[3] = 1.0;
        let (ev, st) = spectrum(&quadratic(&[k, 9.0], &c), None).unwrap();
        assert_eq!(ev.iter().filter(|e| e.1 == 0.0 && (e.0 + k.sqrt()).abs() < 1e-6).count(), 2, "{ev:?}");
        assert_eq!(st, Stability::Stable);
    }

    #[test]
    fn a_very_slow_overdamped_root_is_refined_to_its_own_accuracy() {
        // k = 4.74e-6, b = 861.6 (a fuzz case, seed 7): s ≈ −5.5e-9 came out
        // of QR with a relative error of 1.6e-5, more than Newton was let move.
        let (k, b) = (4.740183e-6f64, 861.6331083652605);
        let (ev, st) = spectrum(&a(&[&[0.0, 1.0], &[-k, -b]]), None).unwrap();
        let fast = (-b - (b * b - 4.0 * k).sqrt()) / 2.0;
        let slow = k / fast;
        assert!((ev[0].0 - slow).abs() <= 1e-12 * slow.abs(), "{ev:?} vs {slow}");
        assert_eq!(st, Stability::Stable);
    }
}
