//! The equations a linearization reads, compiled once over the active
//! coordinates: M, f and their derivatives, the constraints' B, c and their
//! derivatives, ∂M/∂q, ∂f/∂u, and the size of each residual's terms; their
//! numbers at a state ([`Numbers`]); the matrix K of the equations with
//! multipliers ([`kkt`]) and the choice of dependent columns of B ([`pivots`]).

use super::LinearizeError;
use crate::derive::Derivation;
use crate::error::ModelError;
use crate::model::ConstraintKind;
use nalgebra::{DMatrix, DVector};
use sym::{ExprId, Pool, Tape};

/// A column of the constraint Jacobian is a pivot only when its part outside
/// the pivots already chosen is above this fraction of the largest column.
const PIVOT: f64 = 1e-9;

/// The compiled equations and their derivatives over the active coordinates.
pub(super) struct Compiled {
    /// All coordinates of the model.
    pub(super) big_n: usize,
    /// Active coordinate indices.
    pub(super) act: Vec<usize>,
    /// Constraints.
    pub(super) m: usize,
    /// Holonomic constraint indices (into the constraint list).
    pub(super) hol: Vec<usize>,
    pub(super) tape: Tape,
    pub(super) inputs: Vec<f64>,
    pub(super) out: Vec<f64>,
    /// Whether ∂M/∂q is compiled (with constraints only).
    pub(super) with_mq: bool,
    /// The model's inputs u (their symbols held at u₀ in everything compiled).
    pub(super) n_u: usize,
}

/// The numbers at one state.
pub(super) struct Numbers {
    pub(super) m: DMatrix<f64>,
    pub(super) f: DVector<f64>,
    pub(super) fq: DMatrix<f64>,
    pub(super) fv: DMatrix<f64>,
    pub(super) b: DMatrix<f64>,
    /// Per constraint k: ∂B_ki/∂q_j.
    pub(super) bq: Vec<DMatrix<f64>>,
    pub(super) c: DVector<f64>,
    pub(super) cq: DMatrix<f64>,
    pub(super) cv: DMatrix<f64>,
    pub(super) phi: DVector<f64>,
    /// Per coordinate j: ∂M/∂q_j.
    pub(super) mq: Vec<DMatrix<f64>>,
    /// ∂f/∂u (n × inputs).
    pub(super) fu: DMatrix<f64>,
    /// Σ|terms| of f, of c and of the holonomic constraints.
    pub(super) f_terms: DVector<f64>,
    pub(super) c_terms: DVector<f64>,
    pub(super) phi_terms: DVector<f64>,
}

impl Compiled {
    pub(super) fn new(d: &Derivation, act: Vec<usize>) -> Result<Compiled, LinearizeError> {
        let mut pool: Pool = d.pool().clone();
        let cons = &d.constraints.list;
        let m = cons.len();
        let hol: Vec<usize> = (0..m).filter(|&k| cons[k].kind == ConstraintKind::Holonomic).collect();
        let with_mq = m > 0;
        let mut roots: Vec<ExprId> = Vec::new();
        for &i in &act {
            for &j in &act {
                roots.push(d.mass_matrix[i][j]);
            }
        }
        for &i in &act {
            roots.push(d.forcing[i]);
        }
        for wrt in [&d.q, &d.qd] {
            for &i in &act {
                for &j in &act {
                    let e = pool.diff(d.forcing[i], wrt[j]);
                    roots.push(e);
                }
            }
        }
        for c in cons {
            for &i in &act {
                roots.push(c.jacobian[i]);
            }
        }
        for c in cons {
            for &i in &act {
                for &j in &act {
                    let e = pool.diff(c.jacobian[i], d.q[j]);
                    roots.push(e);
                }
            }
        }
        for c in cons {
            roots.push(c.acceleration_rhs);
        }
        for wrt in [&d.q, &d.qd] {
            for c in cons {
                for &j in &act {
                    let e = pool.diff(c.acceleration_rhs, wrt[j]);
                    roots.push(e);
                }
            }
        }
        for &k in &hol {
            roots.push(cons[k].expr);
        }
        if with_mq {
            for &j in &act {
                for &i in &act {
                    for &l in &act {
                        let e = pool.diff(d.mass_matrix[i][l], d.q[j]);
                        roots.push(e);
                    }
                }
            }
        }
        // The inputs: B = ∂f/∂u, and u held at u₀ (their values at t = 0) in all of it.
        for &i in &act {
            roots.extend(d.input_matrix[i].iter().copied());
        }
        // The size of each residual's terms: Σ|terms| of f, of c and of the
        // holonomic constraints (the scale their rounding and cancellation live on).
        let abs_terms = |pool: &mut Pool, e: ExprId| -> ExprId {
            let terms: Vec<ExprId> = match pool.node(e) {
                sym::Node::Add(t) => t.to_vec(),
                _ => vec![e],
            };
            let abs: Vec<ExprId> = terms.into_iter().map(|t| pool.func(sym::Func::Abs, t)).collect();
            pool.add(&abs)
        };
        for &i in &act {
            let e = abs_terms(&mut pool, d.forcing[i]);
            roots.push(e);
        }
        for c in cons {
            let e = abs_terms(&mut pool, c.acceleration_rhs);
            roots.push(e);
        }
        for &k in &hol {
            let e = abs_terms(&mut pool, cons[k].expr);
            roots.push(e);
        }
        let n_u = d.inputs.len();
        if n_u > 0 {
            let u0 = input_values(d)?;
            let held: rustc_hash::FxHashMap<ExprId, ExprId> =
                d.inputs.iter().zip(&u0).map(|(&u, &v)| (u, crate::source::number_expr(&mut pool, v))).collect();
            for r in &mut roots {
                *r = pool.substitute(*r, &held);
            }
        }
        let tape = Tape::compile(&pool, &roots, d.layout.symbols()).map_err(|e| LinearizeError::NotAutonomous {
            reason: format!("the equations of motion cannot be evaluated: {e}"),
        })?;
        let out = vec![0.0; roots.len()];
        Ok(Compiled { big_n: d.q.len(), act, m, hol, tape, inputs: d.layout.values(), out, with_mq, n_u })
    }

    /// Evaluates at the full q and q' (every coordinate).
    pub(super) fn eval(&mut self, q: &[f64], qd: &[f64]) -> Numbers {
        let (n, m, big) = (self.act.len(), self.m, self.big_n);
        self.inputs[..big].copy_from_slice(q);
        self.inputs[big..2 * big].copy_from_slice(qd);
        self.tape.eval(&self.inputs, &mut self.out);
        let mut k = 0;
        let out = &self.out;
        let mut take = |rows: usize, cols: usize| -> DMatrix<f64> {
            let mat = DMatrix::from_row_slice(rows, cols, &out[k..k + rows * cols]);
            k += rows * cols;
            mat
        };
        let mm = take(n, n);
        let f = take(n, 1).column(0).into_owned();
        let fq = take(n, n);
        let fv = take(n, n);
        let b = take(m, n);
        let bq: Vec<DMatrix<f64>> = (0..m).map(|_| take(n, n)).collect();
        let c = take(m, 1).column(0).into_owned();
        let cq = take(m, n);
        let cv = take(m, n);
        let phi = take(self.hol.len(), 1).column(0).into_owned();
        let mq: Vec<DMatrix<f64>> = if self.with_mq { (0..n).map(|_| take(n, n)).collect() } else { Vec::new() };
        let fu = take(n, self.n_u);
        let f_terms = take(n, 1).column(0).into_owned();
        let c_terms = take(m, 1).column(0).into_owned();
        let phi_terms = take(self.hol.len(), 1).column(0).into_owned();
        Numbers { m: mm, f, fq, fv, b, bq, c, cq, cv, phi, mq, fu, f_terms, c_terms, phi_terms }
    }
}

/// The inputs' values u₀ at t = 0 (parameters at their values), about which
/// the motion is linearized.
fn input_values(d: &Derivation) -> Result<Vec<f64>, LinearizeError> {
    let model = &d.model;
    model
        .inputs
        .iter()
        .map(|u| {
            let env = |n: &str| if n == "t" { Some(0.0) } else { model.parameter(n) };
            model
                .pool
                .eval(u.value.expr, &env)
                .map_err(|e| LinearizeError::from(ModelError::at(u.value.span.clone(), e.to_string())))
        })
        .collect()
}

/// K = [[M, −Bᵀ], [B, 0]].
pub(super) fn kkt(nb: &Numbers) -> DMatrix<f64> {
    let (n, m) = (nb.m.nrows(), nb.b.nrows());
    let mut k = DMatrix::zeros(n + m, n + m);
    k.view_mut((0, 0), (n, n)).copy_from(&nb.m);
    k.view_mut((0, n), (n, m)).copy_from(&(-nb.b.transpose()));
    k.view_mut((n, 0), (m, n)).copy_from(&nb.b);
    k
}

/// Columns of `b` that make a square invertible block: `forced` first, then
/// the others by size of their part outside the chosen span, `avoid` last.
pub(super) fn pivots(b: &DMatrix<f64>, forced: &[usize], avoid: &[usize]) -> Option<Vec<usize>> {
    let (m, n) = (b.nrows(), b.ncols());
    let scale = (0..n).map(|j| b.column(j).norm()).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut chosen: Vec<usize> = Vec::new();
    let residual = |basis: &[DVector<f64>], j: usize| -> DVector<f64> {
        let mut r = b.column(j).into_owned();
        for e in basis {
            let p = e.dot(&r);
            r -= e * p;
        }
        r
    };
    for &j in forced {
        let r = residual(&basis, j);
        if r.norm() <= PIVOT * scale {
            return None;
        }
        basis.push(r.normalize());
        chosen.push(j);
    }
    for pass in 0..2 {
        while chosen.len() < m {
            let best = (0..n)
                .filter(|j| !chosen.contains(j) && (avoid.contains(j) == (pass == 1)))
                .map(|j| (j, residual(&basis, j).norm()))
                .filter(|&(_, r)| r > PIVOT * scale)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((j, _)) = best else { break };
            let r = residual(&basis, j);
            basis.push(r.normalize());
            chosen.push(j);
        }
    }
    (chosen.len() == m).then_some(chosen)
}
