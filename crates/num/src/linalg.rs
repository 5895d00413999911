//! Small dense linear algebra for the mechanics side and the implicit integrators:
//! [`LinearSolver`] factors an `n × n` matrix once (LU with partial pivoting) and
//! solves `M x = f` for many right-hand sides, with a banded fast path that makes a
//! chain of `n` masses cost `O(n·b²)` instead of `O(n³)`.
//!
//! The factorization is written here rather than taken from `nalgebra::linalg::LU`
//! because nalgebra's allocates its permutation on every factorization; this one
//! reuses its storage, so refactoring inside an integration allocates nothing. The
//! tests check it against nalgebra.

use crate::error::LinalgError;

/// Default pivot-ratio threshold of [`LinearSolver`]: with `min|u_kk| / max|u_kk|`
/// below `1e-13` the matrix's condition number is at least about `1e13`, and a solve
/// would keep at most three correct digits.
pub const DEFAULT_PIVOT_RATIO: f64 = 1e-13;

/// Dense LU with partial pivoting, row-major, storage reused across factorizations.
#[derive(Clone, Debug, Default)]
pub(crate) struct DenseLu {
    n: usize,
    lu: Vec<f64>,
    piv: Vec<usize>,
    factored: bool,
}

impl DenseLu {
    pub(crate) fn new(n: usize) -> Self {
        DenseLu { n, lu: vec![0.0; n * n], piv: vec![0; n], factored: false }
    }

    /// The matrix to factor, row-major; fill it, then call [`factor`](Self::factor).
    pub(crate) fn matrix_mut(&mut self) -> &mut [f64] {
        self.factored = false;
        &mut self.lu
    }

    /// Factors the matrix in [`matrix_mut`](Self::matrix_mut) in place; returns the
    /// pivot ratio `min|u_kk| / max|u_kk|`.
    pub(crate) fn factor(&mut self) -> Result<f64, LinalgError> {
        // The same algorithm with the size known at compile time: the loops
        // unroll and the bounds checks go (the right-hand side of a double
        // pendulum factors a 2 × 2 M at every call). Same operations, same
        // order, so the results are bit for bit those of the general loop.
        match self.n {
            1 => self.factor_fixed::<1>(),
            2 => self.factor_fixed::<2>(),
            3 => self.factor_fixed::<3>(),
            4 => self.factor_fixed::<4>(),
            _ => self.factor_general(),
        }
    }

    fn factor_fixed<const N: usize>(&mut self) -> Result<f64, LinalgError> {
        let a = &mut self.lu[..N * N];
        if let Some(pos) = a.iter().position(|x| !x.is_finite()) {
            return Err(LinalgError::NonFinite { row: pos / N, col: pos % N });
        }
        let mut u_min = f64::INFINITY;
        let mut u_max = 0.0_f64;
        for k in 0..N {
            let mut p = k;
            let mut best = a[k * N + k].abs();
            for i in k + 1..N {
                let v = a[i * N + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.piv[k] = p;
            if best == 0.0 {
                return Err(LinalgError::Singular { col: k });
            }
            if p != k {
                for j in 0..N {
                    a.swap(k * N + j, p * N + j);
                }
            }
            let pivot = a[k * N + k];
            u_min = u_min.min(best);
            u_max = u_max.max(best);
            for i in k + 1..N {
                let l = a[i * N + k] / pivot;
                a[i * N + k] = l;
                if l != 0.0 {
                    for j in k + 1..N {
                        a[i * N + j] -= l * a[k * N + j];
                    }
                }
            }
        }
        self.factored = true;
        Ok(u_min / u_max)
    }

    fn factor_general(&mut self) -> Result<f64, LinalgError> {
        let n = self.n;
        let a = &mut self.lu;
        if let Some(pos) = a.iter().position(|x| !x.is_finite()) {
            return Err(LinalgError::NonFinite { row: pos / n.max(1), col: pos % n.max(1) });
        }
        let mut u_min = f64::INFINITY;
        let mut u_max = 0.0_f64;
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].abs();
            for i in k + 1..n {
                let v = a[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.piv[k] = p;
            if best == 0.0 {
                return Err(LinalgError::Singular { col: k });
            }
            if p != k {
                for j in 0..n {
                    a.swap(k * n + j, p * n + j);
                }
            }
            let pivot = a[k * n + k];
            u_min = u_min.min(best);
            u_max = u_max.max(best);
            // Row k and the rows below as slices: the updates compile to
            // straight loops (the same operations as indexing, in the same order).
            let (upper, lower) = a.split_at_mut((k + 1) * n);
            let row_k = &upper[k * n + k + 1..];
            for row_i in lower.chunks_exact_mut(n) {
                let l = row_i[k] / pivot;
                row_i[k] = l;
                if l != 0.0 {
                    for (x, &u) in row_i[k + 1..].iter_mut().zip(row_k) {
                        *x -= l * u;
                    }
                }
            }
        }
        self.factored = true;
        Ok(if n == 0 { 1.0 } else { u_min / u_max })
    }

    /// Solves in place with the last factorization.
    pub(crate) fn solve_in_place(&self, b: &mut [f64]) {
        debug_assert!(self.factored && b.len() == self.n);
        match self.n {
            1 => self.solve_fixed::<1>(b),
            2 => self.solve_fixed::<2>(b),
            3 => self.solve_fixed::<3>(b),
            4 => self.solve_fixed::<4>(b),
            _ => self.solve_general(b),
        }
    }

    fn solve_fixed<const N: usize>(&self, b: &mut [f64]) {
        let a = &self.lu[..N * N];
        let piv = &self.piv[..N];
        let b: &mut [f64; N] = b.try_into().expect("N values");
        for k in 0..N {
            b.swap(k, piv[k]);
        }
        for k in 0..N {
            let bk = b[k];
            for i in k + 1..N {
                b[i] -= a[i * N + k] * bk;
            }
        }
        for k in (0..N).rev() {
            let mut s = b[k];
            for j in k + 1..N {
                s -= a[k * N + j] * b[j];
            }
            b[k] = s / a[k * N + k];
        }
    }

    fn solve_general(&self, b: &mut [f64]) {
        let n = self.n;
        let a = &self.lu;
        // Rows were swapped whole (multipliers included), so permute first.
        for k in 0..n {
            b.swap(k, self.piv[k]);
        }
        // Forward: b_i −= Σ_{k<i} l_ik b_k, subtracted in ascending k as the
        // column-oriented loop does, over row slices (no bounds checks).
        for i in 1..n {
            let (done, rest) = b.split_at_mut(i);
            let mut s = rest[0];
            for (&l, &bk) in a[i * n..i * n + i].iter().zip(done.iter()) {
                s -= l * bk;
            }
            rest[0] = s;
        }
        for k in (0..n).rev() {
            let (head, tail) = b.split_at_mut(k + 1);
            let mut s = head[k];
            for (&u, &bj) in a[k * n + k + 1..(k + 1) * n].iter().zip(tail.iter()) {
                s -= u * bj;
            }
            head[k] = s / a[k * n + k];
        }
    }
}

/// Banded LU with partial pivoting (the scheme of LAPACK's `dgbtrf`): row `i` stores
/// columns `i − kl ..= i + kl + ku`, the extra `kl` super-diagonals receiving the
/// fill-in of row swaps.
#[derive(Clone, Debug, Default)]
struct BandLu {
    n: usize,
    kl: usize,
    ku: usize,
    band: Vec<f64>,
    piv: Vec<usize>,
}

impl BandLu {
    fn width(&self) -> usize {
        2 * self.kl + self.ku + 1
    }
    #[inline]
    fn idx(&self, i: usize, j: usize) -> usize {
        i * self.width() + (j + self.kl - i)
    }

    /// Loads the band of the dense row-major `a` and factors it; returns the pivot ratio.
    fn factor(&mut self, n: usize, kl: usize, ku: usize, a: &[f64]) -> Result<f64, LinalgError> {
        self.n = n;
        self.kl = kl;
        self.ku = ku;
        let w = self.width();
        self.band.clear();
        self.band.resize(n * w, 0.0);
        self.piv.resize(n, 0);
        for i in 0..n {
            for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                let at = self.idx(i, j);
                self.band[at] = a[i * n + j];
            }
        }
        let mut u_min = f64::INFINITY;
        let mut u_max = 0.0_f64;
        for k in 0..n {
            let last_row = (k + kl).min(n - 1);
            let last_col = (k + kl + ku).min(n - 1);
            let mut p = k;
            let mut best = self.band[self.idx(k, k)].abs();
            for i in k + 1..=last_row {
                let v = self.band[self.idx(i, k)].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            self.piv[k] = p;
            if best == 0.0 {
                return Err(LinalgError::Singular { col: k });
            }
            if p != k {
                for j in k..=last_col {
                    let (x, y) = (self.idx(k, j), self.idx(p, j));
                    self.band.swap(x, y);
                }
            }
            u_min = u_min.min(best);
            u_max = u_max.max(best);
            let pivot = self.band[self.idx(k, k)];
            for i in k + 1..=last_row {
                let at = self.idx(i, k);
                let l = self.band[at] / pivot;
                self.band[at] = l;
                if l != 0.0 {
                    for j in k + 1..=last_col {
                        let (x, y) = (self.idx(i, j), self.idx(k, j));
                        self.band[x] -= l * self.band[y];
                    }
                }
            }
        }
        Ok(if n == 0 { 1.0 } else { u_min / u_max })
    }

    fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        for k in 0..n {
            b.swap(k, self.piv[k]);
            let bk = b[k];
            for i in k + 1..=(k + self.kl).min(n - 1) {
                b[i] -= self.band[self.idx(i, k)] * bk;
            }
        }
        for k in (0..n).rev() {
            let mut s = b[k];
            for j in k + 1..=(k + self.kl + self.ku).min(n - 1) {
                s -= self.band[self.idx(k, j)] * b[j];
            }
            b[k] = s / self.band[self.idx(k, k)];
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Path {
    None,
    Dense,
    Banded,
    Diagonal,
}

/// Factors an `n × n` matrix and solves `M x = f`, reusing its storage.
///
/// [`factor`](LinearSolver::factor) scans the matrix for its lower and upper
/// bandwidth `(kl, ku)`; a diagonal matrix is divided by (`O(n)`), and when the
/// band is narrow (`4·(2kl + ku + 1) < n`) it uses
/// banded LU, `O(n·kl·(kl + ku))`, otherwise dense LU, `O(n³)`. Singular matrices and
/// matrices whose pivot ratio falls below the threshold ([`DEFAULT_PIVOT_RATIO`]) are
/// reported as errors instead of producing garbage.
///
/// ```
/// let mut solver = num::LinearSolver::new(2);
/// solver.factor(&[4.0, 1.0, 1.0, 3.0]).unwrap();
/// let mut x = [0.0; 2];
/// solver.solve(&[1.0, 2.0], &mut x).unwrap();
/// assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-15);
/// ```
#[derive(Clone, Debug)]
pub struct LinearSolver {
    n: usize,
    threshold: f64,
    path: Path,
    dense: DenseLu,
    band: BandLu,
    /// The diagonal of the last diagonal factorization.
    diag: Vec<f64>,
    pivot_ratio: f64,
}

impl LinearSolver {
    /// A solver for `n × n` matrices with the default pivot-ratio threshold.
    pub fn new(n: usize) -> Self {
        LinearSolver {
            n,
            threshold: DEFAULT_PIVOT_RATIO,
            path: Path::None,
            dense: DenseLu::default(),
            band: BandLu::default(),
            diag: Vec::new(),
            pivot_ratio: f64::NAN,
        }
    }

    /// The same solver with pivot-ratio threshold `threshold` (0 accepts every
    /// non-singular matrix).
    pub fn with_pivot_threshold(mut self, threshold: f64) -> Self {
        self.threshold = if threshold.is_finite() { threshold.max(0.0) } else { DEFAULT_PIVOT_RATIO };
        self
    }

    /// The dimension `n`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// `min|u_kk| / max|u_kk|` of the last factorization (NaN before the first).
    pub fn pivot_ratio(&self) -> f64 {
        self.pivot_ratio
    }

    /// `Some((kl, ku))` when the last factorization took the banded path.
    pub fn bandwidth(&self) -> Option<(usize, usize)> {
        match self.path {
            Path::Banded => Some((self.band.kl, self.band.ku)),
            Path::Diagonal => Some((0, 0)),
            _ => None,
        }
    }

    /// Factors the row-major `n × n` matrix `a` (`a[i * n + j]` is row `i`, column `j`).
    pub fn factor(&mut self, a: &[f64]) -> Result<(), LinalgError> {
        let n = self.n;
        self.path = Path::None;
        if a.len() != n * n {
            return Err(LinalgError::DimensionMismatch { expected: n * n, found: a.len() });
        }
        if n <= 4 {
            // Too small for a band to pay: dense LU (which checks finiteness).
            return self.factor_dense(a);
        }
        let mut kl = 0;
        let mut ku = 0;
        for i in 0..n {
            for j in 0..n {
                let v = a[i * n + j];
                if !v.is_finite() {
                    return Err(LinalgError::NonFinite { row: i, col: j });
                }
                if v != 0.0 {
                    if i > j {
                        kl = kl.max(i - j);
                    } else {
                        ku = ku.max(j - i);
                    }
                }
            }
        }
        if kl == 0 && ku == 0 {
            let diagonal: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
            return self.factor_diagonal(&diagonal);
        }
        if 4 * (2 * kl + ku + 1) < n {
            let r = self.band.factor(n, kl, ku, a)?;
            self.path = Path::Banded;
            self.accept(r)
        } else {
            self.factor_dense(a)
        }
    }

    fn factor_dense(&mut self, a: &[f64]) -> Result<(), LinalgError> {
        let n = self.n;
        if self.dense.n != n {
            self.dense = DenseLu::new(n);
        }
        self.dense.matrix_mut().copy_from_slice(a);
        let r = self.dense.factor()?;
        self.path = Path::Dense;
        self.accept(r)
    }

    /// Records the pivot ratio of a factorization and refuses it below the threshold.
    fn accept(&mut self, ratio: f64) -> Result<(), LinalgError> {
        self.pivot_ratio = ratio;
        if ratio < self.threshold {
            self.path = Path::None;
            return Err(LinalgError::IllConditioned { pivot_ratio: ratio, threshold: self.threshold });
        }
        Ok(())
    }

    /// Factors the diagonal matrix with diagonal `d` (`O(n)`, for callers that
    /// know their matrix is diagonal, such as a chain's mass matrix): the same
    /// checks as [`factor`](Self::factor) — non-finite entries, zero pivots and
    /// the pivot ratio `min|d_i| / max|d_i|` against the threshold.
    pub fn factor_diagonal(&mut self, d: &[f64]) -> Result<(), LinalgError> {
        let n = self.n;
        self.path = Path::None;
        if d.len() != n {
            return Err(LinalgError::DimensionMismatch { expected: n, found: d.len() });
        }
        let mut u_min = f64::INFINITY;
        let mut u_max = 0.0_f64;
        for (i, &v) in d.iter().enumerate() {
            if !v.is_finite() {
                return Err(LinalgError::NonFinite { row: i, col: i });
            }
            if v == 0.0 {
                return Err(LinalgError::Singular { col: i });
            }
            u_min = u_min.min(v.abs());
            u_max = u_max.max(v.abs());
        }
        self.diag.clear();
        self.diag.extend_from_slice(d);
        self.path = Path::Diagonal;
        self.accept(if n == 0 { 1.0 } else { u_min / u_max })
    }

    /// Solves `M x = f` with the last factorization.
    pub fn solve(&self, f: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        if f.len() != self.n {
            return Err(LinalgError::DimensionMismatch { expected: self.n, found: f.len() });
        }
        if x.len() != self.n {
            return Err(LinalgError::DimensionMismatch { expected: self.n, found: x.len() });
        }
        x.copy_from_slice(f);
        self.solve_in_place(x)
    }

    /// Solves `M x = f` in place: `x` holds `f` on entry and the solution on return.
    pub fn solve_in_place(&self, x: &mut [f64]) -> Result<(), LinalgError> {
        if x.len() != self.n {
            return Err(LinalgError::DimensionMismatch { expected: self.n, found: x.len() });
        }
        match self.path {
            Path::None => return Err(LinalgError::NotFactored),
            Path::Dense => self.dense.solve_in_place(x),
            Path::Banded => self.band.solve_in_place(x),
            Path::Diagonal => {
                for (xi, di) in x.iter_mut().zip(&self.diag) {
                    *xi /= di;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random numbers in [-1, 1] (xorshift).
    fn rand_vec(len: usize, seed: u64) -> Vec<f64> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        (0..len)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            })
            .collect()
    }

    #[track_caller]
    fn check_solve(n: usize, a: &[f64], expect_band: Option<(usize, usize)>) {
        let mut solver = LinearSolver::new(n);
        solver.factor(a).unwrap();
        assert_eq!(solver.bandwidth(), expect_band);
        let x_true = rand_vec(n, 7);
        let mut f = vec![0.0; n];
        for i in 0..n {
            f[i] = (0..n).map(|j| a[i * n + j] * x_true[j]).sum();
        }
        let mut x = vec![0.0; n];
        solver.solve(&f, &mut x).unwrap();
        let err = x.iter().zip(&x_true).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-10 * n as f64, "n = {n}: error {err}");
        // Against nalgebra's LU.
        let m = nalgebra::DMatrix::from_row_slice(n, n, a);
        let xn = m.lu().solve(&nalgebra::DVector::from_column_slice(&f)).unwrap();
        for i in 0..n {
            assert!((xn[i] - x[i]).abs() < 1e-9, "differs from nalgebra at {i}");
        }
    }

    #[test]
    fn dense_random_matches_nalgebra() {
        for &n in &[1, 2, 5, 17, 40] {
            check_solve(n, &rand_vec(n * n, n as u64), None);
        }
    }

    #[test]
    fn banded_needs_pivoting() {
        // Tridiagonal with a tiny diagonal: pivoting must swap rows.
        let n = 50;
        let mut a = vec![0.0; n * n];
        let r = rand_vec(3 * n, 3);
        for i in 0..n {
            a[i * n + i] = 1e-3 * r[i];
            if i + 1 < n {
                a[i * n + i + 1] = 1.0 + r[n + i].abs();
                a[(i + 1) * n + i] = 1.0 + r[2 * n + i].abs();
            }
        }
        check_solve(n, &a, Some((1, 1)));
        // Pentadiagonal, unsymmetric bandwidth.
        let mut a = vec![0.0; n * n];
        let r = rand_vec(n * n, 5);
        for i in 0..n {
            for j in i.saturating_sub(2)..(i + 2).min(n) {
                a[i * n + j] = r[i * n + j] + if i == j { 4.0 } else { 0.0 };
            }
        }
        check_solve(n, &a, Some((2, 1)));
    }

    #[test]
    fn chain_of_thousand_masses_is_banded() {
        // Mass matrix of a chain: tridiagonal, solved on the banded path.
        let n = 1000;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i * n + i] = 2.0;
            if i + 1 < n {
                a[i * n + i + 1] = -1.0;
                a[(i + 1) * n + i] = -1.0;
            }
        }
        let mut solver = LinearSolver::new(n);
        solver.factor(&a).unwrap();
        assert_eq!(solver.bandwidth(), Some((1, 1)));
        let f = vec![1.0; n];
        let mut x = vec![0.0; n];
        solver.solve(&f, &mut x).unwrap();
        // Exact solution of the discrete Poisson problem: x_i = (i+1)(n-i)/2.
        for (i, xi) in x.iter().enumerate() {
            let exact = ((i + 1) * (n - i)) as f64 / 2.0;
            assert!((xi - exact).abs() < 1e-8 * exact, "{i}: {xi} vs {exact}");
        }
    }

    /// A diagonal matrix is divided by, through `factor` (n > 4) or
    /// `factor_diagonal`, with the same errors as LU; small matrices take the
    /// unrolled LU, which gives the general loop's results bit for bit.
    #[test]
    fn diagonal_and_small_paths() {
        let n = 1000;
        let d: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut dense = vec![0.0; n * n];
        for i in 0..n {
            dense[i * n + i] = d[i];
        }
        let f = rand_vec(n, 7);
        let (mut a, mut b) = (LinearSolver::new(n), LinearSolver::new(n));
        a.factor(&dense).unwrap();
        b.factor_diagonal(&d).unwrap();
        assert_eq!(a.bandwidth(), Some((0, 0)));
        let (mut xa, mut xb) = (vec![0.0; n], vec![0.0; n]);
        a.solve(&f, &mut xa).unwrap();
        b.solve(&f, &mut xb).unwrap();
        assert_eq!(xa, xb);
        assert!(xa.iter().zip(&f).zip(&d).all(|((x, f), d)| (x * d - f).abs() < 1e-15 * f.abs().max(1.0)));
        assert!((b.pivot_ratio() - 1.0 / n as f64).abs() < 1e-15);
        let mut zero = d.clone();
        zero[5] = 0.0;
        assert!(matches!(b.factor_diagonal(&zero), Err(LinalgError::Singular { col: 5 })));
        assert!(matches!(b.solve(&f, &mut xb), Err(LinalgError::NotFactored)));
        assert!(matches!(b.factor_diagonal(&[1.0, 1e-15, 1.0][..]), Err(LinalgError::DimensionMismatch { .. })));
        let mut tiny = d.clone();
        tiny[0] = 1e-14;
        assert!(matches!(b.factor_diagonal(&tiny), Err(LinalgError::IllConditioned { .. })));
        tiny[0] = f64::NAN;
        assert!(matches!(b.factor_diagonal(&tiny), Err(LinalgError::NonFinite { row: 0, col: 0 })));
        // n = 1..4: unrolled LU against the general loop.
        for n in 1..=4 {
            let m = rand_vec(n * n, 11 + n as u64);
            let rhs = rand_vec(n, 3);
            let mut fixed = DenseLu::new(n);
            fixed.matrix_mut().copy_from_slice(&m);
            let mut general = fixed.clone();
            assert_eq!(fixed.factor().unwrap().to_bits(), general.factor_general().unwrap().to_bits());
            let (mut x1, mut x2) = (rhs.clone(), rhs.clone());
            fixed.solve_in_place(&mut x1);
            general.solve_general(&mut x2);
            assert_eq!(x1, x2, "n = {n}");
            assert_eq!(fixed.lu, general.lu);
        }
    }

    #[test]
    fn singular_and_ill_conditioned_are_errors() {
        let mut s = LinearSolver::new(2);
        assert_eq!(s.factor(&[1.0, 2.0, 2.0, 4.0]), Err(LinalgError::Singular { col: 1 }));
        let mut x = [0.0; 2];
        assert_eq!(s.solve(&[1.0, 1.0], &mut x), Err(LinalgError::NotFactored));
        assert!(matches!(s.factor(&[1.0, 1.0, 1.0, 1.0 + 1e-15]), Err(LinalgError::IllConditioned { .. })));
        assert!(matches!(s.factor(&[1.0, f64::NAN, 0.0, 1.0]), Err(LinalgError::NonFinite { row: 0, col: 1 })));
        assert!(matches!(s.factor(&[1.0; 3]), Err(LinalgError::DimensionMismatch { expected: 4, found: 3 })));
        let mut empty = LinearSolver::new(0);
        empty.factor(&[]).unwrap();
        empty.solve(&[], &mut []).unwrap();
    }
}
