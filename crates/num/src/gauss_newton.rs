//! Gauss–Newton for a residual with more equations than unknowns (or as many),
//! `r(x) = 0` in the least-squares sense, whose caller decides what counts as a
//! solution: [`gauss_newton`] over a [`LeastSquares`] problem.
//!
//! Each step differences the Jacobian forward, solves `J s = −r` by an SVD in
//! which singular values below [`GaussNewtonConfig::singular`] of the largest
//! count as zero (a flat direction gets no step), and backtracks on `|r|`. The
//! iteration ends as soon as the problem's own test ([`LeastSquares::accept`])
//! passes on a step that is already small, or when the steps have shrunk to
//! round-off; then the test gives the verdict. This is the search for an
//! operating point of `lagrange linearize`: its residual stacks accelerations
//! and constraints, whose scales only the problem knows, so the test is the
//! problem's (`newton` has a fixed one).
//!
//! nalgebra's SVD takes the rectangular Jacobian (`crate::newton`'s SVD is for
//! square ones).

use nalgebra::{DMatrix, DVector};

/// The tolerances of [`gauss_newton`]; see each default's reason.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussNewtonConfig {
    /// Most iterations. Default 100: a regular root takes a handful; a
    /// degenerate one (`r = x³`) converges linearly and stops at round-off or
    /// at the acceptance test well before.
    pub max_iterations: usize,
    /// Forward-difference step of the Jacobian, relative to `(1 + |x_j|)`.
    /// Default `1e-7`, about the square root of the rounding error: a Jacobian
    /// exact to eight digits (Newton then converges linearly with that factor).
    pub jacobian_step: f64,
    /// Converged when a step is below `step_tol·(1 + max|x|)`. Default `1e-13`:
    /// steps have shrunk to round-off.
    pub step_tol: f64,
    /// A step below `accept·(1 + max|x|)` is small enough to ask the problem's
    /// test ([`LeastSquares::accept`]), and iterating stops when it passes.
    /// Default `1e-8`: eight digits, what the acceptance test of `linearize`
    /// asks for.
    pub accept: f64,
    /// Singular values of `J` below this fraction of the largest count as zero.
    /// Default `1e-10`: a direction `J` scales ten digits less than the largest
    /// is flat to the accuracy of a differenced Jacobian.
    pub singular: f64,
    /// Backtracking halves the step until `|r|` falls; below this factor the
    /// step is taken whatever `|r|` does. Default `1e-4` (about 13 halvings).
    pub take_anyway: f64,
    /// The halving that has passed [`take_anyway`](Self::take_anyway) without a
    /// step (`r` undefined along it) gives up below this factor: the method
    /// stalls. Default `1e-6`.
    pub stall: f64,
    /// The method has run away when some `|x_j − x0_j| > max_excursion·(1 + |x0_j|)`.
    /// Default `1e3`: a point that far from the start is not the one asked for.
    pub max_excursion: f64,
}

impl GaussNewtonConfig {
    /// The defaults, usable in a `const`.
    pub const DEFAULT: GaussNewtonConfig = GaussNewtonConfig {
        max_iterations: 100,
        jacobian_step: 1e-7,
        step_tol: 1e-13,
        accept: 1e-8,
        singular: 1e-10,
        take_anyway: 1e-4,
        stall: 1e-6,
        max_excursion: 1e3,
    };
}

impl Default for GaussNewtonConfig {
    fn default() -> Self {
        GaussNewtonConfig::DEFAULT
    }
}

/// A residual and the test of a solution.
pub trait LeastSquares {
    /// The residual at x; None where it cannot be evaluated.
    fn residual(&mut self, x: &[f64]) -> Option<DVector<f64>>;

    /// Whether x (residual r, Jacobian, the step from there) is a solution; the
    /// error says why not, in the problem's words.
    fn accept(&mut self, x: &[f64], r: &DVector<f64>, jac: &DMatrix<f64>, step: &DVector<f64>) -> Result<(), String>;
}

/// The solution [`gauss_newton`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussNewtonSolution {
    /// The point.
    pub x: Vec<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// `|r|` there.
    pub residual: f64,
}

/// Why [`gauss_newton`] found no solution. The points are the iterate's.
#[derive(Clone, Debug, PartialEq)]
pub enum GaussNewtonError {
    /// The residual cannot be evaluated at the start.
    StartNotEvaluable,
    /// The residual cannot be evaluated at a difference point of the Jacobian.
    NotEvaluable,
    /// The SVD solve failed (the message is nalgebra's).
    Solve(String),
    /// The residual and the Jacobian both underflowed to zero after real steps.
    Underflow {
        /// Where.
        x: Vec<f64>,
    },
    /// Backtracking found no point where the residual falls or is defined.
    Stalls {
        /// Where.
        x: Vec<f64>,
    },
    /// The iterate left the start by more than [`GaussNewtonConfig::max_excursion`].
    RunsAway {
        /// Where.
        x: Vec<f64>,
    },
    /// The problem's test refused the last iterate.
    Refused(String),
}

/// The forward-difference Jacobian at x (residual r there) and the
/// Gauss–Newton step; flat directions get none.
pub fn gauss_newton_step(
    problem: &mut dyn LeastSquares,
    x: &[f64],
    r: &DVector<f64>,
    config: &GaussNewtonConfig,
) -> Result<(DMatrix<f64>, DVector<f64>), GaussNewtonError> {
    let nx = x.len();
    let mut jac = DMatrix::zeros(r.len(), nx);
    for j in 0..nx {
        let h = config.jacobian_step * (1.0 + x[j].abs());
        let mut xp = x.to_vec();
        xp[j] += h;
        let rp = problem.residual(&xp).ok_or(GaussNewtonError::NotEvaluable)?;
        jac.set_column(j, &((rp - r) / h));
    }
    if nx == 0 {
        return Ok((jac, DVector::zeros(0)));
    }
    let svd = jac.clone().svd(true, true);
    let smax = svd.singular_values.amax();
    let step = svd
        .solve(&(-r), config.singular * smax.max(f64::MIN_POSITIVE))
        .map_err(|e| GaussNewtonError::Solve(e.into()))?;
    Ok((jac, step))
}

/// Gauss–Newton from `x0` with backtracking on `|r|`, ended by the problem's
/// test (see the module's comment).
pub fn gauss_newton(
    problem: &mut dyn LeastSquares,
    x0: &[f64],
    config: &GaussNewtonConfig,
) -> Result<GaussNewtonSolution, GaussNewtonError> {
    let mut x = x0.to_vec();
    let mut r = problem.residual(&x).ok_or(GaussNewtonError::StartNotEvaluable)?;
    let mut it = 0;
    loop {
        let (jac, step) = gauss_newton_step(problem, &x, &r, config)?;
        let size = 1.0 + x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let done =
            x.is_empty() || step.amax() <= config.step_tol * size || r.amax() == 0.0 || it == config.max_iterations;
        // Stop as soon as the point passes the test (or at the end, with its verdict).
        if !done && step.amax() <= config.accept * size && problem.accept(&x, &r, &jac, &step).is_ok() {
            // One more step (quadratic convergence: to rounding) when it does not worsen r.
            let xt: Vec<f64> = x.iter().zip(step.iter()).map(|(a, s)| a + s).collect();
            if let Some(rt) = problem.residual(&xt).filter(|rt| rt.norm() <= r.norm()) {
                return Ok(GaussNewtonSolution { x: xt, iterations: it + 1, residual: rt.norm() });
            }
            return Ok(GaussNewtonSolution { x, iterations: it, residual: r.norm() });
        }
        if done {
            // Residuals that vanish only by underflow (e^x far out) leave a
            // zero residual and a zero Jacobian after real steps.
            if it > 0 && r.amax() == 0.0 && jac.amax() == 0.0 {
                return Err(GaussNewtonError::Underflow { x });
            }
            problem.accept(&x, &r, &jac, &step).map_err(GaussNewtonError::Refused)?;
            return Ok(GaussNewtonSolution { x, iterations: it, residual: r.norm() });
        }
        it += 1;
        let mut t = 1.0;
        loop {
            let xt: Vec<f64> = x.iter().zip(step.iter()).map(|(a, s)| a + t * s).collect();
            if let Some(rt) = problem.residual(&xt) {
                if rt.norm() < r.norm() || t < config.take_anyway {
                    x = xt;
                    r = rt;
                    break;
                }
            }
            t *= 0.5;
            if t < config.stall {
                return Err(GaussNewtonError::Stalls { x });
            }
        }
        if x.iter().zip(x0).any(|(a, b)| (a - b).abs() > config.max_excursion * (1.0 + b.abs())) {
            return Err(GaussNewtonError::RunsAway { x });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The circle x² + y² = 1 and the line y = x, with a third, consistent
    /// equation x = y: a root at (1/√2, 1/√2), the test being |r| ≤ 1e-12.
    struct Circle;

    impl LeastSquares for Circle {
        fn residual(&mut self, x: &[f64]) -> Option<DVector<f64>> {
            Some(DVector::from_vec(vec![x[0] * x[0] + x[1] * x[1] - 1.0, x[1] - x[0], x[0] - x[1]]))
        }

        fn accept(&mut self, _: &[f64], r: &DVector<f64>, _: &DMatrix<f64>, _: &DVector<f64>) -> Result<(), String> {
            if r.norm() <= 1e-12 {
                Ok(())
            } else {
                Err(format!("|r| = {:e}", r.norm()))
            }
        }
    }

    #[test]
    fn it_finds_a_root_of_an_overdetermined_consistent_system() {
        let s = gauss_newton(&mut Circle, &[1.0, 0.2], &GaussNewtonConfig::default()).unwrap();
        let h = 0.5f64.sqrt();
        assert!((s.x[0] - h).abs() < 1e-12 && (s.x[1] - h).abs() < 1e-12, "{s:?}");
        assert!(s.iterations < 10, "{s:?}");
    }

    /// x² + 1 = 0 has no real root: the test refuses where the steps end.
    struct NoRoot;

    impl LeastSquares for NoRoot {
        fn residual(&mut self, x: &[f64]) -> Option<DVector<f64>> {
            Some(DVector::from_vec(vec![x[0] * x[0] + 1.0]))
        }

        fn accept(&mut self, _: &[f64], r: &DVector<f64>, _: &DMatrix<f64>, _: &DVector<f64>) -> Result<(), String> {
            Err(format!("|r| = {}", r.norm()))
        }
    }

    #[test]
    fn the_problem_s_test_gives_the_verdict_where_no_root_is() {
        let e = gauss_newton(&mut NoRoot, &[0.5], &GaussNewtonConfig::default()).unwrap_err();
        assert!(matches!(&e, GaussNewtonError::Refused(why) if why.starts_with("|r| = 1")), "{e:?}");
    }

    /// A residual undefined beyond x = 1 (a square root of 1 − x) whose root
    /// is past it: backtracking cannot step.
    struct Wall;

    impl LeastSquares for Wall {
        fn residual(&mut self, x: &[f64]) -> Option<DVector<f64>> {
            (x[0] <= 1.0).then(|| DVector::from_vec(vec![x[0] - 2.0 + 1e-3 * (1.0 - x[0]).sqrt()]))
        }

        fn accept(&mut self, _: &[f64], _: &DVector<f64>, _: &DMatrix<f64>, _: &DVector<f64>) -> Result<(), String> {
            Err("no".into())
        }
    }

    #[test]
    fn a_residual_undefined_along_the_step_stalls() {
        let e = gauss_newton(&mut Wall, &[0.999_999_999], &GaussNewtonConfig::default()).unwrap_err();
        assert!(matches!(e, GaussNewtonError::Stalls { .. } | GaussNewtonError::NotEvaluable), "{e:?}");
    }
}
