//! Newton's method for small systems `F(x) = 0`: [`newton`] with the Jacobian given,
//! [`newton_fd`] with it by forward differences. Each step solves `J s = −F` with
//! [`LinearSolver`] and is damped by backtracking on `|F|²`; where `J` is singular (a
//! flat direction, such as a free translation of a molecule for `F = ∇U`) the step is
//! the minimum-norm least-squares one, `s = −J⁺F` with the pseudo-inverse from a
//! one-sided Jacobi SVD of `J` (singular values below `singular_ratio·σ_max` count as
//! zero), which takes no step along the flat direction.

use crate::error::NewtonError;
use crate::linalg::LinearSolver;

/// Options of [`newton`]; see each default's reason.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonConfig {
    /// Most iterations. Default 200: quadratic convergence needs a handful, a
    /// degenerate root (`F = x³`) converges linearly, by a factor 2/3 per step, and
    /// needs about 90 from `x = 1` to round-off.
    pub max_iterations: usize,
    /// `J` counts as singular when the ratio of its smallest to largest LU pivot is
    /// below this, and then its singular values below this fraction of the largest
    /// count as zero. Default `1e-12`: a solve would keep at most four digits, and a
    /// flat direction of a Hessian built from round-off shows `1e-16`.
    pub singular_ratio: f64,
    /// Converged when a step is below `step_tol·(1 + |x|)`. Default `1e-14`: steps
    /// shrink to round-off of `x` (quadratically at a regular root, geometrically at a
    /// degenerate one).
    pub step_tol: f64,
    /// A vanishing step is a root only if `|F| ≤ residual_tol·max(max|J_ij|, 1)·(1 + |x|)`,
    /// otherwise the method stalls. Default `1e-8`: the residual a root known to
    /// about eight digits leaves, which a degenerate root may be limited to.
    pub residual_tol: f64,
    /// Sufficient decrease (Armijo) of a damped step `t·s`: `|F|²` must fall by a
    /// factor `1 − armijo·t`. Default `1e-4`, the usual choice (Dennis & Schnabel).
    pub armijo: f64,
    /// Below this damping factor the step is taken whatever `|F|` does. Default
    /// `1e-4` (about 13 halvings): a smaller step would not leave the point.
    pub min_damping: f64,
    /// The method has run away when `|x − x₀| > max_excursion·(1 + |x₀|)`. Default
    /// `1e3`: a root that far from the guess is not the one asked for.
    pub max_excursion: f64,
}

impl Default for NewtonConfig {
    fn default() -> Self {
        NewtonConfig {
            max_iterations: 200,
            singular_ratio: 1e-12,
            step_tol: 1e-14,
            residual_tol: 1e-8,
            armijo: 1e-4,
            min_damping: 1e-4,
            max_excursion: 1e3,
        }
    }
}

/// A root found by [`newton`].
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonSolution {
    /// The root.
    pub x: Vec<f64>,
    /// Newton steps taken.
    pub iterations: usize,
    /// `|F(x)|` there.
    pub residual: f64,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Solves `F(x) = 0` from `x0` by damped Newton. `system(x, f, jac)` writes `F(x)` into
/// `f` and the row-major Jacobian `∂F_i/∂x_j` into `jac` (`jac[i * n + j]`).
///
/// ```
/// // x² + y² = 4, x = y.
/// let sol = num::newton(
///     |x, f, j| {
///         f[0] = x[0] * x[0] + x[1] * x[1] - 4.0;
///         f[1] = x[0] - x[1];
///         j.copy_from_slice(&[2.0 * x[0], 2.0 * x[1], 1.0, -1.0]);
///     },
///     &[1.0, 0.5],
///     &num::NewtonConfig::default(),
/// )
/// .unwrap();
/// assert!((sol.x[0] - 2f64.sqrt()).abs() < 1e-14 && (sol.x[1] - 2f64.sqrt()).abs() < 1e-14);
/// ```
pub fn newton(
    mut system: impl FnMut(&[f64], &mut [f64], &mut [f64]),
    x0: &[f64],
    config: &NewtonConfig,
) -> Result<NewtonSolution, NewtonError> {
    let n = x0.len();
    let mut x = x0.to_vec();
    let (mut f, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
    let (mut f_trial, mut jac_trial, mut trial) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n]);
    let mut step = vec![0.0; n];
    let mut svd = Svd::new(n);
    let mut lu = LinearSolver::new(n).with_pivot_threshold(config.singular_ratio);
    system(&x, &mut f, &mut jac);
    let size0 = 1.0 + norm(x0);
    for iter in 0..=config.max_iterations {
        if !f.iter().chain(&jac).all(|v| v.is_finite()) {
            return Err(NewtonError::NotFinite { x, iterations: iter });
        }
        let fnorm = norm(&f);
        let jscale = jac.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let xscale = 1.0 + norm(&x);
        if fnorm == 0.0 {
            return Ok(NewtonSolution { x, iterations: iter, residual: fnorm });
        }
        if iter == config.max_iterations {
            break;
        }
        for i in 0..n {
            step[i] = -f[i];
        }
        if lu.factor(&jac).is_err() || lu.solve_in_place(&mut step).is_err() {
            svd.factor(&jac);
            svd.solve_min_norm(&f, config.singular_ratio, &mut step);
            step.iter_mut().for_each(|s| *s = -*s);
        }
        if norm(&step) <= config.step_tol * xscale {
            if fnorm <= config.residual_tol * jscale.max(1.0) * xscale {
                return Ok(NewtonSolution { x, iterations: iter, residual: fnorm });
            }
            return Err(NewtonError::Stalled { x, residual: fnorm });
        }
        // Backtracking on |F|².
        let mut t = 1.0;
        let merit = fnorm * fnorm;
        loop {
            for i in 0..n {
                trial[i] = x[i] + t * step[i];
            }
            system(&trial, &mut f_trial, &mut jac_trial);
            let m2: f64 = f_trial.iter().map(|v| v * v).sum();
            if m2.is_finite() && (m2 <= (1.0 - config.armijo * t) * merit || t < config.min_damping) {
                std::mem::swap(&mut x, &mut trial);
                std::mem::swap(&mut f, &mut f_trial);
                std::mem::swap(&mut jac, &mut jac_trial);
                break;
            }
            t *= 0.5;
        }
        let excursion = x.iter().zip(x0).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
        if excursion > config.max_excursion * size0 {
            return Err(NewtonError::RunAway { x });
        }
    }
    let residual = norm(&f);
    Err(NewtonError::NoConvergence { x, iterations: config.max_iterations, residual })
}

/// Most sweeps of the one-sided Jacobi SVD; it converges quadratically, in 6 to 10
/// sweeps for any small matrix.
const SVD_MAX_SWEEPS: usize = 60;

/// A pair of columns counts as orthogonal when `|a_p·a_q| ≤ SVD_ORTHOGONAL·|a_p||a_q|`:
/// at round-off, a rotation would change nothing.
const SVD_ORTHOGONAL: f64 = f64::EPSILON;

/// A one-sided Jacobi (Hestenes) SVD of a small square matrix, `A = U Σ Vᵀ`: plane
/// rotations from the right orthogonalize the columns of `A`, which then are `U Σ`,
/// and accumulate into `V`. Accurate in every singular value, and storage reused.
struct Svd {
    n: usize,
    /// `U Σ`, column-major (`us[j * n + i]` is row `i` of column `j`).
    us: Vec<f64>,
    /// `V`, column-major.
    v: Vec<f64>,
}

impl Svd {
    fn new(n: usize) -> Self {
        Svd { n, us: vec![0.0; n * n], v: vec![0.0; n * n] }
    }

    /// Factors the row-major `a`.
    fn factor(&mut self, a: &[f64]) {
        let n = self.n;
        for i in 0..n {
            for j in 0..n {
                self.us[j * n + i] = a[i * n + j];
                self.v[j * n + i] = if i == j { 1.0 } else { 0.0 };
            }
        }
        for _ in 0..SVD_MAX_SWEEPS {
            let mut rotated = false;
            for p in 0..n {
                for q in p + 1..n {
                    let (cp, cq) = (&self.us[p * n..(p + 1) * n], &self.us[q * n..(q + 1) * n]);
                    let alpha: f64 = cp.iter().map(|x| x * x).sum();
                    let beta: f64 = cq.iter().map(|x| x * x).sum();
                    let gamma: f64 = cp.iter().zip(cq).map(|(x, y)| x * y).sum();
                    if gamma == 0.0 || gamma.abs() <= SVD_ORTHOGONAL * (alpha * beta).sqrt() {
                        continue;
                    }
                    rotated = true;
                    let zeta = (beta - alpha) / (2.0 * gamma);
                    let t = zeta.signum() / (zeta.abs() + zeta.hypot(1.0));
                    let c = 1.0 / t.hypot(1.0);
                    let s = c * t;
                    for m in [&mut self.us, &mut self.v] {
                        for i in 0..n {
                            let (x, y) = (m[p * n + i], m[q * n + i]);
                            m[p * n + i] = c * x - s * y;
                            m[q * n + i] = s * x + c * y;
                        }
                    }
                }
            }
            if !rotated {
                break;
            }
        }
    }

    /// `x = A⁺ b`, the singular values below `cutoff·σ_max` taken as zero.
    fn solve_min_norm(&self, b: &[f64], cutoff: f64, x: &mut [f64]) {
        let n = self.n;
        let sigma = |j: usize| self.us[j * n..(j + 1) * n].iter().map(|v| v * v).sum::<f64>().sqrt();
        let sigma_max = (0..n).map(sigma).fold(0.0f64, f64::max);
        x.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..n {
            let s = sigma(j);
            if s == 0.0 || s <= cutoff * sigma_max {
                continue;
            }
            // U_jᵀ b / σ_j = (UΣ)_jᵀ b / σ_j².
            let coef = self.us[j * n..(j + 1) * n].iter().zip(b).map(|(u, b)| u * b).sum::<f64>() / (s * s);
            for i in 0..n {
                x[i] += coef * self.v[j * n + i];
            }
        }
    }
}

/// Relative step of the forward differences of [`newton_fd`]: `√ε` balances the
/// truncation error (∝ h) against round-off (∝ ε/h), leaving about eight digits.
pub const FD_RELATIVE_STEP: f64 = 1.490_116_119_384_765_6e-8;

/// [`newton`] with the Jacobian by forward differences, column `j` from a step
/// `FD_RELATIVE_STEP·max(|x_j|, 1)` (`n` extra evaluations per Jacobian).
/// `residual(x, f)` writes `F(x)` into `f`.
///
/// ```
/// let sol = num::newton_fd(|x, f| f[0] = x[0].cos() - x[0], &[1.0], &num::NewtonConfig::default()).unwrap();
/// assert!((sol.x[0] - 0.739_085_133_215_160_7).abs() < 1e-15);
/// ```
pub fn newton_fd(
    mut residual: impl FnMut(&[f64], &mut [f64]),
    x0: &[f64],
    config: &NewtonConfig,
) -> Result<NewtonSolution, NewtonError> {
    let n = x0.len();
    let (mut shifted, mut f_shifted) = (vec![0.0; n], vec![0.0; n]);
    let system = |x: &[f64], f: &mut [f64], jac: &mut [f64]| {
        residual(x, f);
        shifted.copy_from_slice(x);
        for j in 0..n {
            let h = FD_RELATIVE_STEP * x[j].abs().max(1.0);
            shifted[j] = x[j] + h;
            // The step actually taken, after rounding of x + h.
            let h = shifted[j] - x[j];
            residual(&shifted, &mut f_shifted);
            for i in 0..n {
                jac[i * n + j] = (f_shifted[i] - f[i]) / h;
            }
            shifted[j] = x[j];
        }
    };
    newton(system, x0, config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check(got: &[f64], want: &[f64]) {
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= 1e-12 * w.abs().max(1.0), "got {got:?}, want {want:?}");
        }
    }

    #[test]
    fn regular_roots_converge_quadratically() {
        let config = NewtonConfig::default();
        // Rosenbrock's gradient: the root (1, 1).
        let grad = |x: &[f64], f: &mut [f64], j: &mut [f64]| {
            f[0] = -2.0 * (1.0 - x[0]) - 400.0 * x[0] * (x[1] - x[0] * x[0]);
            f[1] = 200.0 * (x[1] - x[0] * x[0]);
            j.copy_from_slice(&[2.0 - 400.0 * x[1] + 1200.0 * x[0] * x[0], -400.0 * x[0], -400.0 * x[0], 200.0]);
        };
        let sol = newton(grad, &[-1.2, 1.0], &config).unwrap();
        check(&sol.x, &[1.0, 1.0]);
        // A linear system is solved in one step.
        let sol = newton(
            |x, f, j| {
                f[0] = 3.0 * x[0] + x[1] - 1.0;
                f[1] = x[0] - 2.0 * x[1];
                j.copy_from_slice(&[3.0, 1.0, 1.0, -2.0]);
            },
            &[5.0, -7.0],
            &config,
        )
        .unwrap();
        assert!(sol.iterations <= 2, "{sol:?}");
        check(&sol.x, &[2.0 / 7.0, 1.0 / 7.0]);
        // Differences find the same root.
        let sol = newton_fd(|x, f| f[0] = x[0] * x[0] - 2.0, &[1.0], &config).unwrap();
        check(&sol.x, &[2f64.sqrt()]);
    }

    #[test]
    fn a_flat_direction_gets_no_step() {
        // F = ∇U for U = (x − y)²/2, flat along x = y: from (3, 1) the minimum-norm
        // step goes to (2, 2).
        let sol = newton(
            |x, f, j| {
                f[0] = x[0] - x[1];
                f[1] = x[1] - x[0];
                j.copy_from_slice(&[1.0, -1.0, -1.0, 1.0]);
            },
            &[3.0, 1.0],
            &NewtonConfig::default(),
        )
        .unwrap();
        assert_eq!(sol.iterations, 1);
        check(&sol.x, &[2.0, 2.0]);
    }

    #[test]
    fn the_svd_solves_least_squares_with_minimum_norm() {
        let mut svd = Svd::new(3);
        // Rank 2: the third row is the sum of the first two.
        let a = [1.0, 2.0, 0.5, -1.0, 0.5, 3.0, 0.0, 2.5, 3.5];
        svd.factor(&a);
        let mut x = [0.0; 3];
        // b in the range of A: the solution solves A x = b exactly.
        let x_true = [0.3, -0.7, 1.1];
        let b: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i * 3 + j] * x_true[j]).sum()).collect();
        svd.solve_min_norm(&b, 1e-12, &mut x);
        let ax: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i * 3 + j] * x[j]).sum()).collect();
        check(&ax, &b);
        // The null space of A is spanned by the cross product of its first two rows;
        // the minimum-norm solution is orthogonal to it.
        let null = {
            let (r, s) = ([1.0, 2.0, 0.5], [-1.0, 0.5, 3.0]);
            [r[1] * s[2] - r[2] * s[1], r[2] * s[0] - r[0] * s[2], r[0] * s[1] - r[1] * s[0]]
        };
        let dot: f64 = x.iter().zip(null).map(|(x, n)| x * n).sum();
        assert!(dot.abs() < 1e-12, "{x:?} · {null:?} = {dot}");
        // A regular matrix: the plain solution.
        let a = [4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        svd.factor(&a);
        svd.solve_min_norm(&[1.0, 2.0, 3.0], 1e-12, &mut x);
        let ax: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i * 3 + j] * x[j]).sum()).collect();
        check(&ax, &[1.0, 2.0, 3.0]);
    }

    #[test]
    fn failures_are_reported() {
        let config = NewtonConfig::default();
        // No root: x ↦ exp(x) walks to −∞ by unit steps.
        let exp = |x: &[f64], f: &mut [f64], j: &mut [f64]| (f[0], j[0]) = (x[0].exp(), x[0].exp());
        let e = newton(exp, &[0.0], &NewtonConfig { max_excursion: 10.0, ..config }).unwrap_err();
        assert!(matches!(e, NewtonError::RunAway { .. }), "{e}");
        let e = newton(exp, &[0.0], &config).unwrap_err();
        assert!(matches!(e, NewtonError::NoConvergence { iterations: 200, .. }), "{e}");
        let e = newton(|x, f, j| (f[0], j[0]) = (1.0 / x[0], -1.0 / (x[0] * x[0])), &[0.0], &config).unwrap_err();
        assert!(matches!(e, NewtonError::NotFinite { iterations: 0, .. }), "{e}");
        let few = NewtonConfig { max_iterations: 3, ..config };
        let e = newton(|x, f, j| (f[0], j[0]) = (x[0].powi(3), 3.0 * x[0] * x[0]), &[1.0], &few).unwrap_err();
        assert!(matches!(e, NewtonError::NoConvergence { iterations: 3, .. }), "{e}");
        // ... which the default number of iterations overcomes.
        let sol = newton(|x, f, j| (f[0], j[0]) = (x[0].powi(3), 3.0 * x[0] * x[0]), &[1.0], &config).unwrap();
        assert!(sol.x[0].abs() < 1e-4, "{sol:?}");
    }
}
