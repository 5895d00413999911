//! Test models with known answers (diffsol's `test_models`), shared by the unit
//! tests (`crate::test_models`, compiled with `cfg(test)`) and the integration tests
//! (`tests/common` includes this file). The paths go through `num`, which names
//! this crate in both.
#![allow(dead_code)]

use num::{OdeSystem, RhsError, SeparableSystem};

/// Harmonic oscillator `x'' = -x`, as `y = [x, v]` or `q = x, p = v`, with its
/// Taylor series computed by hand: `x[k+1] = v[k]/(k+1)`, `v[k+1] = -x[k]/(k+1)`.
pub struct Oscillator;

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    }
    fn taylor_series(&mut self, _t: f64, y: &[f64], order: usize, s: &mut [f64]) -> Option<Result<(), RhsError>> {
        s[..2].copy_from_slice(y);
        for k in 0..order {
            let kf = (k + 1) as f64;
            s[2 * (k + 1)] = s[2 * k + 1] / kf;
            s[2 * (k + 1) + 1] = -s[2 * k] / kf;
        }
        Some(Ok(()))
    }
}

impl SeparableSystem for Oscillator {
    fn n(&self) -> usize {
        1
    }
    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
        dq[0] = p[0];
        Ok(())
    }
    fn force(&mut self, _t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
        dp[0] = -q[0];
        Ok(())
    }
}

/// Kepler problem `H = |p|²/2 − 1/|q|` (μ = 1).
pub struct Kepler;

impl SeparableSystem for Kepler {
    fn n(&self) -> usize {
        2
    }
    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
        dq.copy_from_slice(p);
        Ok(())
    }
    fn force(&mut self, _t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
        let r2 = q[0] * q[0] + q[1] * q[1];
        let r3 = r2 * r2.sqrt();
        dp[0] = -q[0] / r3;
        dp[1] = -q[1] / r3;
        Ok(())
    }
}

/// Kepler initial state at periapsis with eccentricity `e` (a = 1, period 2π).
pub fn kepler_start(e: f64) -> [f64; 4] {
    [1.0 - e, 0.0, 0.0, ((1.0 + e) / (1.0 - e)).sqrt()]
}

pub fn kepler_energy(y: &[f64]) -> f64 {
    0.5 * (y[2] * y[2] + y[3] * y[3]) - 1.0 / (y[0] * y[0] + y[1] * y[1]).sqrt()
}

/// Pendulum `H = p²/2 − cos q`.
pub struct Pendulum;

impl SeparableSystem for Pendulum {
    fn n(&self) -> usize {
        1
    }
    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
        dq[0] = p[0];
        Ok(())
    }
    fn force(&mut self, _t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
        dp[0] = -q[0].sin();
        Ok(())
    }
}

pub fn pendulum_energy(y: &[f64]) -> f64 {
    0.5 * y[1] * y[1] - y[0].cos()
}

/// Van der Pol `x'' = μ(1 − x²)x' − x`, stiff for large μ (period ≈ (3 − 2 ln 2)μ);
/// analytic Jacobian.
pub struct VanDerPol(pub f64);

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        dy[0] = y[1];
        dy[1] = self.0 * (1.0 - y[0] * y[0]) * y[1] - y[0];
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), RhsError> {
        jac[0] = 0.0;
        jac[1] = 1.0;
        jac[2] = -2.0 * self.0 * y[0] * y[1] - 1.0;
        jac[3] = self.0 * (1.0 - y[0] * y[0]);
        Ok(())
    }
}

/// Robertson's chemical kinetics, the classic stiff test (Jacobian by differences).
pub struct Robertson;

impl OdeSystem for Robertson {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        dy[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
        dy[2] = 3e7 * y[1] * y[1];
        dy[1] = -dy[0] - dy[2];
        Ok(())
    }
}

/// Max-norm distance.
pub fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Observed order from errors at step `h` and `h/2`.
pub fn order(e_h: f64, e_half: f64) -> f64 {
    (e_h / e_half).log2()
}
