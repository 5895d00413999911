//! Eigenvalues of small dense real matrices: [`eigenvalues`] for a general
//! matrix (balancing, Householder reduction to Hessenberg form, Francis'
//! double-shift QR), and [`symmetric_definite`] for the pencil K v = μ M v with
//! K symmetric and M symmetric positive definite (Cholesky, then Jacobi's
//! method, whose eigenvalues are real by construction and accurate relative to
//! ‖M⁻¹ᐟ² K M⁻ᐟ²‖).
//!
//! Written here rather than taken from a crate: nalgebra's Schur decomposition
//! indexes out of bounds on nilpotent and other exactly structured matrices
//! (a free particle's [[0, 1], [0, 0]]) and has no bound on its sweeps, and a
//! general-purpose solver crate (faer) would add minutes of build on two cores
//! for the few dozen lines below, which follow EISPACK's `balanc`, `orthes` and
//! `hqr` (the textbook algorithms) with every division guarded and every loop
//! bounded, so that a failure is an `Err`, never a panic or a hang.

/// Why the eigenvalues could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EigenError {
    /// An entry of the matrix is NaN or infinite.
    #[error("the matrix has an entry that is not finite")]
    NotFinite,
    /// The QR iteration did not converge within its bound of sweeps.
    #[error("the QR iteration for the eigenvalues did not converge")]
    NoConvergence,
}

/// QR sweeps allowed per deflation, times max(10, n), before giving up.
/// LAPACK's dlahqr allows 30; a strongly non-normal block (two close complex
/// pairs under a large off-diagonal coupling, as a stiff damped mode beside
/// slow ones leaves) converges only linearly at first and took about 300, so
/// the bound is ten times LAPACK's: each sweep costs O(n²), and the bound only
/// keeps a pathological input from hanging.
const MAX_SWEEPS_PER_DEFLATION: usize = 300;
/// Jacobi sweeps of [`symmetric_definite`] (quadratic convergence: a handful
/// suffice; this is a bound, not an expectation).
const MAX_JACOBI_SWEEPS: usize = 100;

/// The eigenvalues (re, im) of the n×n row-major matrix `a`, unsorted; a
/// complex pair comes as two entries, + then −. Errors when an entry is not
/// finite or the QR iteration does not converge.
pub fn eigenvalues(n: usize, a: &[f64]) -> Result<Vec<(f64, f64)>, EigenError> {
    assert_eq!(a.len(), n * n, "eigenvalues: a is n×n");
    if a.iter().any(|v| !v.is_finite()) {
        return Err(EigenError::NotFinite);
    }
    let mut h: Vec<Vec<f64>> = (0..n).map(|i| a[i * n..(i + 1) * n].to_vec()).collect();
    balance(&mut h);
    hessenberg(&mut h);
    hqr(&mut h)
}

/// A rounding bound for the eigenvalues [`eigenvalues`] returns for `a`: a
/// small multiple of ε times the norm of the balanced matrix (the backward
/// error of the QR iteration; a well-conditioned eigenvalue is that accurate).
pub fn eigenvalue_rounding(n: usize, a: &[f64]) -> f64 {
    let mut h: Vec<Vec<f64>> = (0..n).map(|i| a[i * n..(i + 1) * n].to_vec()).collect();
    balance(&mut h);
    let frob = h.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    16.0 * (n.max(1) as f64) * f64::EPSILON * frob
}

/// The n×n row-major `a` after [`eigenvalues`]' balancing (an exact
/// similarity): the scaling in which [`eigenvalue_rounding`] bounds the
/// backward error normwise, so that a test of whether a value is within
/// rounding of an eigenvalue (the smallest singular value of `a − s I` against
/// that bound) reads this matrix.
pub fn balanced(n: usize, a: &[f64]) -> Vec<f64> {
    assert_eq!(a.len(), n * n, "balanced: a is n×n");
    let mut h: Vec<Vec<f64>> = (0..n).map(|i| a[i * n..(i + 1) * n].to_vec()).collect();
    balance(&mut h);
    h.concat()
}

/// Diagonal similarity by powers of two (exact) that makes each row and the
/// matching column of similar size, so that the eigenvalues are computed to
/// the accuracy of the matrix's own scales (a stiff spring beside a slow mode).
fn balance(a: &mut [Vec<f64>]) {
    let n = a.len();
    const RADIX: f64 = 2.0;
    for _ in 0..64 * n.max(1) {
        let mut done = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0f64, 0.0f64);
            for j in 0..n {
                if j != i {
                    c += a[j][i].abs();
                    r += a[i][j].abs();
                }
            }
            if c == 0.0 || r == 0.0 || !c.is_finite() || !r.is_finite() {
                continue;
            }
            let s = c + r;
            let mut f = 1.0f64;
            let mut g = r / RADIX;
            // Bounded: at most ~1100 halvings span f64's exponent range.
            for _ in 0..1100 {
                if c >= g {
                    break;
                }
                f *= RADIX;
                c *= RADIX * RADIX;
            }
            g = r * RADIX;
            for _ in 0..1100 {
                if c <= g {
                    break;
                }
                f /= RADIX;
                c /= RADIX * RADIX;
            }
            if (c + r) / f < 0.95 * s && f.is_finite() && f > 0.0 {
                done = false;
                let g = 1.0 / f;
                for j in 0..n {
                    a[i][j] *= g;
                }
                for j in 0..n {
                    a[j][i] *= f;
                }
            }
        }
        if done {
            break;
        }
    }
}

/// Householder reduction to upper Hessenberg form (entries below the
/// subdiagonal set to zero; the eigenvalues are all that is kept).
fn hessenberg(a: &mut [Vec<f64>]) {
    let n = a.len();
    let mut ort = vec![0.0; n];
    for m in 1..n.saturating_sub(1) {
        let scale: f64 = (m..n).map(|i| a[i][m - 1].abs()).sum();
        if scale == 0.0 {
            continue;
        }
        let mut h = 0.0;
        for i in (m..n).rev() {
            ort[i] = a[i][m - 1] / scale;
            h += ort[i] * ort[i];
        }
        let g = if ort[m] > 0.0 { -h.sqrt() } else { h.sqrt() };
        h -= ort[m] * g;
        ort[m] -= g;
        for j in m..n {
            let f = (m..n).map(|i| ort[i] * a[i][j]).sum::<f64>() / h;
            for i in m..n {
                a[i][j] -= f * ort[i];
            }
        }
        for i in 0..n {
            let f = (m..n).map(|j| ort[j] * a[i][j]).sum::<f64>() / h;
            for j in m..n {
                a[i][j] -= f * ort[j];
            }
        }
        a[m][m - 1] = scale * g;
        for i in m + 1..n {
            a[i][m - 1] = 0.0;
        }
    }
}

/// `|a|` with the sign of `b`.
fn sign(a: f64, b: f64) -> f64 {
    if b >= 0.0 {
        a.abs()
    } else {
        -a.abs()
    }
}

/// Francis' double-shift QR on an upper Hessenberg matrix (EISPACK's `hqr`,
/// eigenvalues only), with LAPACK's exceptional shifts every ten sweeps
/// without a deflation (alternately from the top and the bottom of the active
/// block) and when a shift gives no reflection (exact structure such as a
/// nilpotent block).
fn hqr(a: &mut [Vec<f64>]) -> Result<Vec<(f64, f64)>, EigenError> {
    let n = a.len();
    let mut w_out = vec![(0.0, 0.0); n];
    let mut anorm = 0.0;
    for i in 0..n {
        for j in i.saturating_sub(1)..n {
            anorm += a[i][j].abs();
        }
    }
    if anorm == 0.0 {
        return Ok(w_out);
    }
    let eps = f64::EPSILON;
    let mut nn = n as isize - 1;
    while nn >= 0 {
        let mut its = 0usize;
        loop {
            let nu = nn as usize;
            // Look for a small subdiagonal entry.
            let mut l = 0usize;
            for ll in (1..=nu).rev() {
                let mut s = a[ll - 1][ll - 1].abs() + a[ll][ll].abs();
                if s == 0.0 {
                    s = anorm;
                }
                if a[ll][ll - 1].abs() <= eps * s {
                    a[ll][ll - 1] = 0.0;
                    l = ll;
                    break;
                }
            }
            let mut x = a[nu][nu];
            if l == nu {
                w_out[nu] = (x, 0.0);
                nn -= 1;
                break;
            }
            let mut y = a[nu - 1][nu - 1];
            let mut w = a[nu][nu - 1] * a[nu - 1][nu];
            if l + 1 == nu {
                let p = 0.5 * (y - x);
                let q = p * p + w;
                let z = q.abs().sqrt();
                if q >= 0.0 {
                    let z = p + sign(z, p);
                    w_out[nu - 1] = (x + z, 0.0);
                    w_out[nu] = (if z != 0.0 { x - w / z } else { x + z }, 0.0);
                } else {
                    w_out[nu - 1] = (x + p, z);
                    w_out[nu] = (x + p, -z);
                }
                nn -= 2;
                break;
            }
            if its >= MAX_SWEEPS_PER_DEFLATION * n.max(10) {
                return Err(EigenError::NoConvergence);
            }
            // Exceptional shifts (LAPACK's dlahqr): every 20 sweeps without a
            // deflation from the top of the active block, ten later from the
            // bottom; both ad hoc, to break a cycle of the standard shifts.
            if its > 0 && its.is_multiple_of(10) {
                let s = if (its / 10).is_multiple_of(2) {
                    a[l + 1][l].abs() + a[l + 2][l + 1].abs()
                } else {
                    a[nu][nu - 1].abs() + a[nu - 1][nu - 2].abs()
                };
                let s = if s == 0.0 { anorm } else { s };
                let h = 0.75 * s + if (its / 10).is_multiple_of(2) { a[l][l] } else { a[nu][nu] };
                (x, y, w) = (h, h, -0.4375 * s * s);
            }
            its += 1;
            // Two consecutive small subdiagonal entries: where the sweep starts.
            let (mut p, mut q, mut r);
            let mut m = nu - 2;
            loop {
                let z = a[m][m];
                let rr = x - z;
                let ss = y - z;
                p = (rr * ss - w) / a[m + 1][m] + a[m][m + 1];
                q = a[m + 1][m + 1] - z - rr - ss;
                r = a[m + 2][m + 1];
                let s = p.abs() + q.abs() + r.abs();
                if s == 0.0 || !s.is_finite() {
                    p = f64::NAN;
                    break;
                }
                p /= s;
                q /= s;
                r /= s;
                if m == l {
                    break;
                }
                let u = a[m][m - 1].abs() * (q.abs() + r.abs());
                let v = p.abs() * (a[m - 1][m - 1].abs() + z.abs() + a[m + 1][m + 1].abs());
                if u <= eps * v {
                    break;
                }
                m -= 1;
            }
            if p.is_nan() {
                // The shift annihilates the first column: shift exceptionally next time.
                its = 10 * (its / 10 + 1);
                continue;
            }
            for i in m..nu - 1 {
                a[i + 2][i] = 0.0;
                if i != m {
                    a[i + 2][i - 1] = 0.0;
                }
            }
            for k in m..nu {
                if k != m {
                    p = a[k][k - 1];
                    q = a[k + 1][k - 1];
                    r = if k + 1 != nu { a[k + 2][k - 1] } else { 0.0 };
                    x = p.abs() + q.abs() + r.abs();
                    if x != 0.0 {
                        p /= x;
                        q /= x;
                        r /= x;
                    }
                }
                let s = sign((p * p + q * q + r * r).sqrt(), p);
                if s == 0.0 {
                    continue;
                }
                if k == m {
                    if l != m {
                        a[k][k - 1] = -a[k][k - 1];
                    }
                } else {
                    a[k][k - 1] = -s * x;
                }
                p += s;
                x = p / s;
                y = q / s;
                let z = r / s;
                q /= p;
                r /= p;
                for j in k..=nu {
                    let mut pp = a[k][j] + q * a[k + 1][j];
                    if k + 1 != nu {
                        pp += r * a[k + 2][j];
                        a[k + 2][j] -= pp * z;
                    }
                    a[k + 1][j] -= pp * y;
                    a[k][j] -= pp * x;
                }
                let mmin = if nu < k + 3 { nu } else { k + 3 };
                for i in l..=mmin {
                    let mut pp = x * a[i][k] + y * a[i][k + 1];
                    if k + 1 != nu {
                        pp += z * a[i][k + 2];
                        a[i][k + 2] -= pp * r;
                    }
                    a[i][k + 1] -= pp * q;
                    a[i][k] -= pp;
                }
            }
            if a.iter().flatten().any(|v| !v.is_finite()) {
                return Err(EigenError::NoConvergence);
            }
        }
    }
    if w_out.iter().any(|(re, im)| !re.is_finite() || !im.is_finite()) {
        return Err(EigenError::NoConvergence);
    }
    Ok(w_out)
}

/// The eigenvalues μ of K v = μ M v, ascending, for K symmetric and M
/// symmetric positive definite (both n×n row-major; only their lower
/// triangles are read). `None` when M is not positive definite or an entry is
/// not finite.
pub fn symmetric_definite(n: usize, k: &[f64], m: &[f64]) -> Option<Vec<f64>> {
    if k.iter().chain(m).any(|v| !v.is_finite()) {
        return None;
    }
    // Cholesky: M = L Lᵀ.
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s = m[i * n + j] - (0..j).map(|p| l[i * n + p] * l[j * n + p]).sum::<f64>();
            if i == j {
                if s <= 0.0 || !s.is_finite() {
                    return None;
                }
                l[i * n + i] = s.sqrt();
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    // C = L⁻¹ K L⁻ᵀ: Y = L⁻¹ K (forward substitution per column), C = L⁻¹ Yᵀ.
    let sym = |i: usize, j: usize| if i >= j { k[i * n + j] } else { k[j * n + i] };
    let solve_lower = |b: &mut [f64]| {
        for i in 0..n {
            let s = b[i] - (0..i).map(|p| l[i * n + p] * b[p]).sum::<f64>();
            b[i] = s / l[i * n + i];
        }
    };
    let mut y = vec![0.0; n * n];
    for j in 0..n {
        let mut col: Vec<f64> = (0..n).map(|i| sym(i, j)).collect();
        solve_lower(&mut col);
        for i in 0..n {
            y[i * n + j] = col[i];
        }
    }
    let mut c = vec![vec![0.0; n]; n];
    for j in 0..n {
        let mut col: Vec<f64> = (0..n).map(|i| y[j * n + i]).collect();
        solve_lower(&mut col);
        for i in 0..n {
            c[i][j] = col[i];
        }
    }
    for i in 0..n {
        for j in 0..i {
            let v = 0.5 * (c[i][j] + c[j][i]);
            c[i][j] = v;
            c[j][i] = v;
        }
    }
    // Cyclic Jacobi rotations until the off-diagonal part is rounding.
    let norm = c.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    for _ in 0..MAX_JACOBI_SWEEPS {
        let off = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| c[i][j] * c[i][j])
            .sum::<f64>()
            .sqrt();
        if off <= f64::EPSILON * norm || off == 0.0 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = c[p][q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (c[q][q] - c[p][p]) / (2.0 * apq);
                let t = sign(1.0, theta) / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta.is_finite() { t } else { 0.0 };
                let cs = 1.0 / (t * t + 1.0).sqrt();
                let sn = t * cs;
                for r in 0..n {
                    let (crp, crq) = (c[r][p], c[r][q]);
                    c[r][p] = cs * crp - sn * crq;
                    c[r][q] = sn * crp + cs * crq;
                }
                for r in 0..n {
                    let (cpr, cqr) = (c[p][r], c[q][r]);
                    c[p][r] = cs * cpr - sn * cqr;
                    c[q][r] = sn * cpr + cs * cqr;
                }
            }
        }
    }
    let mut mu: Vec<f64> = (0..n).map(|i| c[i][i]).collect();
    if mu.iter().any(|v| !v.is_finite()) {
        return None;
    }
    mu.sort_by(f64::total_cmp);
    Some(mu)
}

/// A rounding bound for the μ of [`symmetric_definite`]: a small multiple of ε
/// times the largest |μ| (Jacobi's method is accurate to that, and so is the
/// reduction for a well-conditioned M).
pub fn symmetric_rounding(n: usize, mu: &[f64]) -> f64 {
    16.0 * (n.max(1) as f64) * f64::EPSILON * mu.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sorted(mut v: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
        v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        v
    }

    #[test]
    fn nilpotent_and_zero_matrices_give_zeros() {
        assert_eq!(eigenvalues(2, &[0.0, 1.0, 0.0, 0.0]).unwrap(), vec![(0.0, 0.0); 2]);
        assert_eq!(eigenvalues(3, &[0.0; 9]).unwrap(), vec![(0.0, 0.0); 3]);
        // A 4×4 Jordan block and a shifted-cycle nilpotent matrix.
        let mut j = vec![0.0; 16];
        for i in 0..3 {
            j[i * 4 + i + 1] = 1.0;
        }
        for (re, im) in eigenvalues(4, &j).unwrap() {
            assert!(re.abs() < 1e-3 && im.abs() < 1e-3, "{re} {im}");
        }
        let sub = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        for (re, im) in eigenvalues(3, &sub).unwrap() {
            assert!(re.abs() < 1e-4 && im.abs() < 1e-4, "{re} {im}");
        }
    }

    #[test]
    fn a_rotation_and_a_permutation_are_on_the_unit_circle() {
        let ev = sorted(eigenvalues(2, &[0.0, -1.0, 1.0, 0.0]).unwrap());
        assert_eq!(ev, vec![(0.0, -1.0), (0.0, 1.0)]);
        // The cyclic permutation of 3: the cube roots of 1 (a case plain QR cycles on).
        let ev = sorted(eigenvalues(3, &[0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap());
        let h = 3f64.sqrt() / 2.0;
        let want = [(-0.5, -h), (-0.5, h), (1.0, 0.0)];
        for (g, w) in ev.iter().zip(want) {
            assert!((g.0 - w.0).abs() < 1e-12 && (g.1 - w.1).abs() < 1e-12, "{ev:?}");
        }
    }

    #[test]
    fn non_finite_entries_are_an_error() {
        assert!(eigenvalues(1, &[f64::NAN]).is_err());
    }

    #[test]
    fn the_symmetric_pencil_gives_real_eigenvalues() {
        // K = [[2, -1], [-1, 2]], M = I: μ = 1, 3.
        let mu = symmetric_definite(2, &[2.0, -1.0, -1.0, 2.0], &[1.0, 0.0, 0.0, 1.0]).unwrap();
        assert!((mu[0] - 1.0).abs() < 1e-15 && (mu[1] - 3.0).abs() < 1e-15, "{mu:?}");
        // M not positive definite: refused.
        assert!(symmetric_definite(1, &[1.0], &[0.0]).is_none());
    }

    /// A block with the eigenvalues `s` (real) or `re ± i im`, written
    /// unsymmetrically so that balancing has work to do.
    fn block(re: f64, im: f64, skew: f64) -> Vec<f64> {
        if im == 0.0 {
            vec![re]
        } else {
            // [[re, im·skew], [−im/skew, re]]: eigenvalues re ± i im.
            vec![re, im * skew, -im / skew, re]
        }
    }

    #[test]
    fn two_close_pairs_under_a_large_coupling_converge() {
        // A of a fuzz case (issue 29): ω² = 0.00305 twice (damped 0.0012 and
        // 0.0048) beside a gyroscopic pair at ω² = 67498 and a nearly
        // critically damped 856035. The standard shifts stall for hundreds of
        // sweeps on the two slow pairs; they must converge, to the known values.
        #[rustfmt::skip]
        let a: Vec<f64> = vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -699000.6521496164, -926448.192441881, 0.0, 221.15378101386935, -947607.2597687844, -1510.9895138978325, -2002.6457713795628, 0.001043647628126206, -1.5567782968329245e-5, -2048.4082250254237, -57903.012027617566, -76744.20475742247, 0.0, 43.607643200296096, -78495.45460671255, -125.16536071122268, -165.89390157665645, 0.00020578899074444828, -3.0696935046295845e-6, -169.68305043963602, 0.0, 0.0, -67498.03105065563, 0.0, 0.0, -0.001043647628126206, -0.0032926238519111724, 0.0, 0.3184772766255975, 0.015536419681416334, 221.15378101386935, 697.7222912047375, 0.0, -67486.81756270121, -3292.2395101232546, -1.5567782968329245e-5, -4.911509607407335e-5, -0.3184772766255975, -7.893563745192751e-7, 0.00023175217687163656, -59225.453735549025, -78495.45460671255, 0.0, -205.7649693827034, -80301.53443517273, -128.02551406408898, -169.68305043963602, -0.0009710262300885209, 1.4484511054477285e-5, -173.5658992047067];
        let got = eigenvalues(10, &a).unwrap();
        let mode = |w2: f64, c: f64| (-c / 2.0, (4.0 * w2 - c * c).sqrt() / 2.0);
        for (re, im) in
            [mode(0.0030530881745625634, 0.0011882613125736964), mode(0.0030530881745625634, 0.004751420689436199)]
        {
            for w in [(re, im), (re, -im)] {
                let d = got.iter().map(|g| (g.0 - w.0).hypot(g.1 - w.1)).fold(f64::INFINITY, f64::min);
                assert!(d < 1e-9, "{w:?} not in {got:?}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Random block-diagonal matrices, permuted, with eigenvalues spread
        /// over 1e-6 … 1e6 in size: each is found to 1e-10 relative to itself.
        #[test]
        fn block_diagonal_spectra_are_found_to_their_own_accuracy(
            blocks in proptest::collection::vec(
                (-6.0f64..6.0, -6.0f64..6.0, any::<bool>(), any::<bool>(), any::<bool>(), -3.0f64..3.0),
                1..6,
            ),
            perm_seed in any::<u64>(),
        ) {
            let mut want: Vec<(f64, f64)> = Vec::new();
            let mut parts: Vec<Vec<f64>> = Vec::new();
            for (e_re, e_im, neg, complex, zero_re, e_skew) in blocks {
                let sgn = if neg { -1.0 } else { 1.0 };
                let re = if complex && zero_re { 0.0 } else { sgn * 10f64.powf(e_re) };
                let im = if complex { 10f64.powf(e_im) } else { 0.0 };
                parts.push(block(re, im, 10f64.powf(e_skew)));
                want.push((re, im));
                if complex {
                    want.push((re, -im));
                }
            }
            let n = want.len();
            let mut a = vec![0.0; n * n];
            let mut at = 0;
            for p in &parts {
                let k = if p.len() == 1 { 1 } else { 2 };
                for i in 0..k {
                    for j in 0..k {
                        a[(at + i) * n + at + j] = p[i * k + j];
                    }
                }
                at += k;
            }
            // A permutation similarity P A Pᵀ (exact) hides the block structure.
            let mut perm: Vec<usize> = (0..n).collect();
            let mut s = perm_seed;
            for i in (1..n).rev() {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                perm.swap(i, (s >> 33) as usize % (i + 1));
            }
            let mut b = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    b[perm[i] * n + perm[j]] = a[i * n + j];
                }
            }
            let got = eigenvalues(n, &b).unwrap();
            // Match each wanted eigenvalue to the nearest computed one.
            let mut free: Vec<bool> = vec![true; n];
            for w in &want {
                let size = (w.0 * w.0 + w.1 * w.1).sqrt();
                let (k, d) = got
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| free[*k])
                    .map(|(k, g)| (k, ((g.0 - w.0).powi(2) + (g.1 - w.1).powi(2)).sqrt()))
                    .min_by(|x, y| x.1.total_cmp(&y.1))
                    .unwrap();
                free[k] = false;
                prop_assert!(d <= 1e-10 * size, "want {:?}, got {:?} (all {:?})", w, got[k], got);
                // Re = 0 exactly stays exactly zero in these blocks.
                if w.0 == 0.0 {
                    prop_assert!(got[k].0.abs() <= 1e-10 * size);
                }
            }
        }

        /// Arbitrary small matrices, dense or with exact zeros: never a panic,
        /// and the sum of the eigenvalues is the trace.
        #[test]
        fn any_matrix_gives_eigenvalues_whose_sum_is_the_trace(
            n in 1usize..7,
            entries in proptest::collection::vec(prop_oneof![Just(0.0), Just(1.0), Just(-1.0), -1e3f64..1e3], 36),
        ) {
            let a: Vec<f64> = entries[..n * n].to_vec();
            let got = eigenvalues(n, &a).unwrap();
            let trace: f64 = (0..n).map(|i| a[i * n + i]).sum();
            let sum: f64 = got.iter().map(|g| g.0).sum();
            let im: f64 = got.iter().map(|g| g.1).sum();
            let scale = a.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            prop_assert!((sum - trace).abs() <= 1e-8 * scale * n as f64, "{sum} vs {trace}");
            prop_assert!(im.abs() <= 1e-8 * scale * n as f64);
        }
    }
}
