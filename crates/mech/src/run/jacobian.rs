//! The Jacobian of the right-hand side `[q', q'']` of an unconstrained model
//! with respect to the state `[q, q']`, from the symbolic derivatives, for
//! stiff integrators of other programs (Python's `model.jac()` for
//! `scipy.integrate.solve_ivp`).
//!
//! With q'' = M⁻¹ f, differentiating `M q'' = f` gives
//! `M ∂q''/∂q = ∂f/∂q − (∂M/∂q) q''` and `M ∂q''/∂q' = ∂f/∂q'`: the
//! derivatives of the residual `R = f − M q''` with q'' held as symbols, n²
//! expressions per half instead of the n³ of ∂M/∂q. One tape gives M and f at
//! (t, q, q'), a second the derivatives of R at the q'' solved from them.

use crate::derive::Derivation;
use crate::error::{ModelError, ModelErrorKind};
use num::{LinearSolver, RhsError};
use sym::{ExprId, Tape};

/// The compiled Jacobian of one model (see the module comment).
#[derive(Debug, Clone)]
pub struct StateJacobian {
    n: usize,
    mass_forcing: Tape,
    residual: Tape,
    inputs: Vec<f64>,
    mf: Vec<f64>,
    dr: Vec<f64>,
    lu: LinearSolver,
}

impl StateJacobian {
    /// Compiles the Jacobian of `d`'s right-hand side; a constrained model is
    /// refused (its q'' depend on the multipliers as well).
    pub fn new(d: &Derivation) -> Result<StateJacobian, ModelError> {
        if !d.constraints.is_empty() {
            return Err(ModelError::whole(
                "the Jacobian of the right-hand side needs a model without constraints: its q'' depend on the multipliers as well",
            )
            .with_kind(ModelErrorKind::Unsupported));
        }
        d.model.check_inputs_applied()?;
        let n = d.q.len();
        let mut pool = d.pool().clone();
        let layout = d.layout.symbols();
        let compile = |pool: &sym::Pool, exprs: &[ExprId], symbols: &[ExprId]| {
            Tape::compile(pool, exprs, symbols)
                .map_err(|e| ModelError::whole(format!("the Jacobian cannot be compiled: {e}")))
        };
        let mut mf: Vec<ExprId> = d.mass_matrix.iter().flatten().copied().collect();
        mf.extend(&d.forcing);
        let mass_forcing = compile(&pool, &mf, layout)?;
        let mut derivatives = Vec::with_capacity(2 * n * n);
        let residuals: Vec<ExprId> = (0..n)
            .map(|i| {
                let mut terms = vec![d.forcing[i]];
                for l in 0..n {
                    let ma = pool.mul2(d.mass_matrix[i][l], d.qdd[l]);
                    terms.push(pool.neg(ma));
                }
                pool.add(&terms)
            })
            .collect();
        for wrt in [&d.q, &d.qd] {
            for &r in &residuals {
                for &x in wrt.iter() {
                    derivatives.push(pool.diff(r, x));
                }
            }
        }
        let symbols: Vec<ExprId> = layout.iter().chain(&d.qdd).copied().collect();
        let residual = compile(&pool, &derivatives, &symbols)?;
        let mut inputs = d.layout.values();
        inputs.extend(std::iter::repeat_n(0.0, n));
        Ok(StateJacobian {
            n,
            mass_forcing,
            residual,
            inputs,
            mf: vec![0.0; n * n + n],
            dr: vec![0.0; 2 * n * n],
            lu: LinearSolver::new(n),
        })
    }

    /// The state's length 2n.
    pub fn dim(&self) -> usize {
        2 * self.n
    }

    /// Sets a parameter's value (in the model's order).
    pub fn set_parameter(&mut self, k: usize, value: f64) {
        self.inputs[2 * self.n + 1 + k] = value;
    }

    /// ∂[q', q'']/∂[q, q'] at (t, y) into `out`, row by row (2n × 2n).
    pub fn eval(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), RhsError> {
        let n = self.n;
        assert_eq!((y.len(), out.len()), (2 * n, 4 * n * n), "a state of 2n and a 2n × 2n matrix");
        self.inputs[..2 * n].copy_from_slice(y);
        self.inputs[2 * n] = t;
        let at = self.inputs.len() - n;
        self.mass_forcing.eval(&self.inputs[..at], &mut self.mf);
        let (m, f) = self.mf.split_at_mut(n * n);
        self.lu.factor(m).map_err(RhsError::from)?;
        self.lu.solve_in_place(f).map_err(RhsError::from)?;
        self.inputs[at..].copy_from_slice(f);
        self.residual.eval(&self.inputs, &mut self.dr);
        out.fill(0.0);
        let width = 2 * n;
        for i in 0..n {
            out[i * width + n + i] = 1.0;
        }
        let mut column = vec![0.0; n];
        for half in 0..2 {
            for j in 0..n {
                for i in 0..n {
                    column[i] = self.dr[half * n * n + i * n + j];
                }
                self.lu.solve_in_place(&mut column).map_err(RhsError::from)?;
                for i in 0..n {
                    out[(n + i) * width + half * n + j] = column[i];
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_models::KEPLER;
    use num::OdeSystem;

    #[test]
    fn the_jacobian_agrees_with_differences_of_the_right_hand_side() {
        let d = Derivation::new(crate::Model::parse(KEPLER, &[]).unwrap()).unwrap();
        let mut jac = StateJacobian::new(&d).unwrap();
        let mut system = crate::Dynamics::new(&d).system(crate::Form::Lagrange);
        let y = [1.2, 0.3, 0.1, 0.8];
        let mut exact = vec![0.0; 16];
        jac.eval(0.2, &y, &mut exact).unwrap();
        let h = 1e-6;
        for j in 0..4 {
            let (mut up, mut down) = (y, y);
            up[j] += h;
            down[j] -= h;
            let (mut fu, mut fd) = ([0.0; 4], [0.0; 4]);
            system.rhs(0.2, &up, &mut fu).unwrap();
            system.rhs(0.2, &down, &mut fd).unwrap();
            for i in 0..4 {
                let numeric = (fu[i] - fd[i]) / (2.0 * h);
                assert!(
                    (exact[i * 4 + j] - numeric).abs() < 1e-7,
                    "({i}, {j}): {} against {numeric}",
                    exact[i * 4 + j]
                );
            }
        }
    }
}
