//! The problems the integrators solve: a general first-order system [`OdeSystem`]
//! (`y' = F(t, y)`) and a separable Hamiltonian system [`SeparableSystem`]
//! (`H = T(p) + V(q, t)`), plus [`finite_difference_jacobian`] and the adapter
//! [`Separable`] that views a separable system as a first-order one with state `[q, p]`.

use crate::error::RhsError;

/// A first-order system `y' = F(t, y)`.
pub trait OdeSystem {
    /// Number of state components.
    fn dim(&self) -> usize;

    /// Writes `F(t, y)` into `dy` (both of length [`dim`](Self::dim)).
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError>;

    /// Writes the Jacobian `dF/dy` at `(t, y)` into `jac`, row-major `dim × dim`
    /// (`jac[i * dim + j] = dF_i/dy_j`).
    ///
    /// The default uses forward differences ([`finite_difference_jacobian`]): `dim + 1`
    /// calls of [`rhs`](Self::rhs) and two scratch vectors of length `dim` allocated
    /// per call (Jacobians are evaluated rarely, next to an `O(dim³)` factorization).
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dim();
        let mut f0 = vec![0.0; n];
        let mut y_work = vec![0.0; n];
        let mut f_work = vec![0.0; n];
        self.rhs(t, y, &mut f0)?;
        finite_difference_jacobian(|y, dy| self.rhs(t, y, dy), y, &f0, jac, &mut y_work, &mut f_work)
    }

    /// Writes the normalized Taylor coefficients `y⁽ᵏ⁾(t)/k!`, `k = 0..=order`, of
    /// the solution through `(t, y)` into `series` (order `k` at
    /// `series[k * dim..(k + 1) * dim]`), for the Taylor integrator
    /// ([`crate::Taylor`]). `None` (the default) means the system cannot.
    fn taylor_series(&mut self, t: f64, y: &[f64], order: usize, series: &mut [f64]) -> Option<Result<(), RhsError>> {
        let _ = (t, y, order, series);
        None
    }
}

/// A separable Hamiltonian `H = T(p) + V(q, t)`: `q' = dT/dp(p)`, `p' = -dV/dq(q, t)`.
///
/// Solvers built on it use the state layout `y = [q_0..q_{n-1}, p_0..p_{n-1}]`.
pub trait SeparableSystem {
    /// Number of coordinates `n` (the state has `2n` components).
    fn n(&self) -> usize;

    /// Writes `dT/dp(p)` (the velocities `q'`) into `dq`.
    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError>;

    /// Writes `-dV/dq(q, t)` (the forces `p'`) into `dp`.
    fn force(&mut self, t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError>;
}

impl<S: OdeSystem + ?Sized> OdeSystem for &mut S {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        (**self).rhs(t, y, dy)
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        (**self).jacobian(t, y, jac)
    }
    fn taylor_series(&mut self, t: f64, y: &[f64], order: usize, series: &mut [f64]) -> Option<Result<(), RhsError>> {
        (**self).taylor_series(t, y, order, series)
    }
}

impl<S: OdeSystem + ?Sized> OdeSystem for Box<S> {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        (**self).rhs(t, y, dy)
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        (**self).jacobian(t, y, jac)
    }
    fn taylor_series(&mut self, t: f64, y: &[f64], order: usize, series: &mut [f64]) -> Option<Result<(), RhsError>> {
        (**self).taylor_series(t, y, order, series)
    }
}

impl<S: SeparableSystem + ?Sized> SeparableSystem for &mut S {
    fn n(&self) -> usize {
        (**self).n()
    }
    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
        (**self).velocity(p, dq)
    }
    fn force(&mut self, t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
        (**self).force(t, q, dp)
    }
}

impl<S: SeparableSystem + ?Sized> SeparableSystem for Box<S> {
    fn n(&self) -> usize {
        (**self).n()
    }
    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
        (**self).velocity(p, dq)
    }
    fn force(&mut self, t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
        (**self).force(t, q, dp)
    }
}

/// Views a [`SeparableSystem`] as an [`OdeSystem`] with state `[q, p]`, so every
/// method applies to it.
#[derive(Clone, Debug, Default)]
pub struct Separable<S>(pub S);

impl<S: SeparableSystem> OdeSystem for Separable<S> {
    fn dim(&self) -> usize {
        2 * self.0.n()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        let n = self.0.n();
        let (q, p) = y.split_at(n);
        let (dq, dp) = dy.split_at_mut(n);
        self.0.velocity(p, dq)?;
        self.0.force(t, q, dp)
    }
}

/// Forward-difference Jacobian of `f` at `y`, given `f0 = f(y)`, written row-major
/// into `jac` (`n × n`). `y_work` and `f_work` are scratch of length `n`.
///
/// The increment for component `j` is `sqrt(ε · max(1e-5, |y_j|))` (Hairer's choice
/// in RADAU5), which balances truncation against cancellation error.
pub fn finite_difference_jacobian(
    mut f: impl FnMut(&[f64], &mut [f64]) -> Result<(), RhsError>,
    y: &[f64],
    f0: &[f64],
    jac: &mut [f64],
    y_work: &mut [f64],
    f_work: &mut [f64],
) -> Result<(), RhsError> {
    let n = y.len();
    debug_assert!(f0.len() == n && jac.len() == n * n && y_work.len() == n && f_work.len() == n);
    y_work.copy_from_slice(y);
    for j in 0..n {
        let yj = y[j];
        let delta = (f64::EPSILON * yj.abs().max(1e-5)).sqrt();
        y_work[j] = yj + delta;
        // The increment actually applied, after rounding.
        let delta = y_work[j] - yj;
        f(y_work, f_work)?;
        for i in 0..n {
            jac[i * n + j] = (f_work[i] - f0[i]) / delta;
        }
        y_work[j] = yj;
    }
    Ok(())
}

/// Index of the first non-finite entry of `v`, if any.
///
/// One pass without an early exit first (it compiles to vector compares, where
/// `position` tests and branches entry by entry: a third of the time of the
/// Taylor method's step control went there), and the search only when
/// something is off.
pub(crate) fn first_non_finite(v: &[f64]) -> Option<usize> {
    if v.iter().fold(false, |any, x| any | !x.is_finite()) {
        v.iter().position(|x| !x.is_finite())
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Quad;
    impl OdeSystem for Quad {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
            dy[0] = y[0] * y[1];
            dy[1] = y[0].sin();
            Ok(())
        }
    }

    #[test]
    fn default_jacobian_matches_analytic() {
        let y = [0.7, -1.3];
        let mut jac = [0.0; 4];
        Quad.jacobian(0.0, &y, &mut jac).unwrap();
        let exact = [y[1], y[0], y[0].cos(), 0.0];
        for (a, b) in jac.iter().zip(exact) {
            assert!((a - b).abs() < 1e-7, "{jac:?} vs {exact:?}");
        }
    }
}
