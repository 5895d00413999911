//! Dynamics: a derivation compiled to numbers, in the three forms the
//! integrators want, plus the invariants to audit along a run.
//!
//! - Lagrange form, state `[q, q']`: `q'' = M⁻¹ f`, solving `M q'' = f` at every
//!   call (M is never inverted symbolically).
//! - Hamilton form, state `[q, p]`: `q' = M⁻¹(p − b)`, `p' = ∂L/∂q − ∂R/∂q' + Q`
//!   at that q'. Symplectic implicit methods (Gauss–Legendre) need canonical
//!   variables, and this gives them for any L quadratic in the velocities.
//! - Separable form, state `[q, p]`: M constant and the forcing free of
//!   velocities, so `q' = M⁻¹p` with M factored once and `p' = f(q, t)`; the
//!   explicit symplectic compositions need this split.
//!
//! Every expression a run needs is compiled into one [`Tape`] per use, with the
//! parameters as inputs. Entry point: [`Dynamics::new`], then [`Dynamics::system`].
//!
//! Structure is kept: the kernels output only the entries of M that are not
//! identically zero, and a diagonal M (a chain of masses) is solved by division,
//! so a right-hand side costs O(N) there instead of the O(N²) of writing a dense
//! M and the O(N³) of factoring it. The Hamilton kernel is compiled on first use
//! (a Lagrange-form run never pays for it).

use crate::derive::Derivation;
use crate::error::ModelError;
use crate::probe;
use crate::run::series::LagrangeSeries;
use num::{LinearSolver, OdeSystem, RhsError, SeparableSystem};
use rustc_hash::FxHashSet;
use std::sync::{Arc, OnceLock};
use sym::{Compiled, ExprId, Tape};

/// The state variables a system integrates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// `[q, q']`, accelerations from `M q'' = f`.
    Lagrange,
    /// `[q, p]`, Hamilton's equations evaluated numerically.
    Hamilton,
    /// `[q, p]` with `H = ½pᵀM⁻¹p + V(q, t)`, M constant.
    Separable,
}

impl Form {
    /// Its name for summaries.
    pub fn name(self) -> &'static str {
        match self {
            Form::Lagrange => "lagrange",
            Form::Hamilton => "hamilton",
            Form::Separable => "separable",
        }
    }
}

/// A quantity evaluated along a run.
#[derive(Debug, Clone)]
pub struct Invariant {
    /// Its name (`H`, `E`, `p_th`).
    pub name: String,
    /// The expression in (q, q', t).
    pub expr: ExprId,
}

/// One group of expressions evaluated together: native code from the JIT, or
/// the tape interpreter where the JIT is not available on this machine.
#[derive(Debug, Clone)]
pub(crate) enum Kernel {
    Native(Arc<Compiled>),
    Interpreted(Tape),
}

impl Kernel {
    pub(crate) fn new(tape: Tape) -> Kernel {
        match Compiled::new(&tape) {
            Ok(native) => Kernel::Native(Arc::new(native)),
            Err(_) => Kernel::Interpreted(tape),
        }
    }

    pub(crate) fn eval(&mut self, inputs: &[f64], outputs: &mut [f64]) {
        match self {
            Kernel::Native(native) => native.eval(inputs, outputs),
            Kernel::Interpreted(tape) => tape.eval(inputs, outputs),
        }
    }
}

/// A kernel compiled when it is first needed; clones share the native code
/// (compiled once for all of them), each keeps its own tape for the fallback.
///
/// With a warm-up of `n`, each clone interprets its first `n` evaluations and
/// compiles only then: a group evaluated a thousand times in a run (the
/// invariants at the output samples) costs less interpreted than compiled. The
/// native code agrees with the tape bit for bit.
#[derive(Debug, Clone)]
pub(crate) struct LazyKernel {
    tape: Tape,
    native: Arc<OnceLock<Option<Arc<Compiled>>>>,
    warm_up: usize,
}

/// Evaluations of the invariants interpreted before they are compiled: about
/// the cost of compiling them for a small model.
const INVARIANTS_WARM_UP: usize = 4000;

impl LazyKernel {
    fn new(tape: Tape) -> LazyKernel {
        LazyKernel::with_warm_up(tape, 0)
    }

    fn with_warm_up(tape: Tape, warm_up: usize) -> LazyKernel {
        LazyKernel { tape, native: Arc::new(OnceLock::new()), warm_up }
    }

    pub(crate) fn eval(&mut self, inputs: &[f64], outputs: &mut [f64]) {
        if self.warm_up > 0 {
            self.warm_up -= 1;
            return self.tape.eval(inputs, outputs);
        }
        match self.native.get_or_init(|| Compiled::new(&self.tape).ok().map(Arc::new)) {
            Some(native) => native.eval(inputs, outputs),
            None => self.tape.eval(inputs, outputs),
        }
    }

    /// One evaluation that does not call for native code: that code where it
    /// is compiled already, the interpreter otherwise (a check at the start
    /// of a run must not pay for compiling what the run may never use; the
    /// Taylor method, for one, expands its own tape).
    pub(crate) fn eval_once(&mut self, inputs: &[f64], outputs: &mut [f64]) {
        match self.native.get() {
            Some(Some(native)) => native.eval(inputs, outputs),
            _ => self.tape.eval(inputs, outputs),
        }
    }
}

/// Where the entries of M that are not identically zero sit.
#[derive(Debug, Clone)]
struct MassPattern {
    n: usize,
    /// `(row, column)` of each stored entry, row-major order.
    entries: Arc<Vec<(usize, usize)>>,
    /// Every stored entry is on the diagonal.
    diagonal: bool,
}

impl MassPattern {
    fn len(&self) -> usize {
        self.entries.len()
    }

    /// Writes the stored entries `values` into the dense row-major `dense`
    /// (whose other entries stay zero).
    fn scatter(&self, values: &[f64], dense: &mut [f64]) {
        for (&(i, j), &v) in self.entries.iter().zip(values) {
            dense[i * self.n + j] = v;
        }
    }
}

/// The compiled dynamics of a derivation. See the module documentation.
#[derive(Debug, Clone)]
pub struct Dynamics {
    n: usize,
    /// Input vector template: `[q, q', t, parameters]`.
    inputs: Vec<f64>,
    /// The stored entries of M.
    pattern: MassPattern,
    /// Outputs M's stored entries (`pattern`) and `f` (n) from `[q, q', t, params]`.
    mass_forcing: LazyKernel,
    /// The tape of `mass_forcing`, for Taylor expansions ([`crate::run::series`]).
    mass_forcing_tape: Arc<Tape>,
    /// Hamilton's form, two kernels: M's stored entries and `b` (n) from `[q, t, params]`
    /// (free of q'), and `∂L/∂q − ∂R/∂q' + Q` (n) from `[q, q', t, params]`. Split so that
    /// each right-hand side computes each group once.
    hamilton: Option<(LazyKernel, LazyKernel)>,
    /// Scratch for [`Dynamics::eval_mass_forcing`].
    scratch: Vec<f64>,
    /// Outputs the invariants from `[q, q', t, params]`.
    invariants_tape: LazyKernel,
    invariants: Vec<Invariant>,
    /// Whether H = ½pᵀM⁻¹p + V(q, t) with M constant.
    separable: bool,
    /// Whether L is quadratic in the velocities (M free of q').
    quadratic: bool,
    coordinate_names: Vec<String>,
}

impl Dynamics {
    /// Compiles the expressions of a derivation.
    pub fn new(d: &Derivation) -> Dynamics {
        let n = d.q.len();
        let invariants = invariants_of(d);
        // The derivation's pool is frozen: the Hamilton kernels' expressions are
        // built in a copy.
        let mut pool_owned = d.pool().clone();
        let pool = &mut pool_owned;
        let input_syms = d.layout.symbols();
        let inputs = d.layout.values();

        let mut entries = Vec::new();
        let mut stored: Vec<ExprId> = Vec::new();
        for (i, row) in d.mass_matrix.iter().enumerate() {
            for (j, &m) in row.iter().enumerate() {
                if !pool.is_zero(m) {
                    entries.push((i, j));
                    stored.push(m);
                }
            }
        }
        let diagonal = entries.iter().all(|&(i, j)| i == j);
        let pattern = MassPattern { n, entries: Arc::new(entries), diagonal };
        let mut outs: Vec<ExprId> = stored.clone();
        outs.extend(&d.forcing);
        let mass_forcing_tape =
            Arc::new(Tape::compile(pool, &outs, input_syms).expect("derivation symbols are inputs"));
        // Compiled on first use: a Taylor run never evaluates it.
        let mass_forcing = LazyKernel::new((*mass_forcing_tape).clone());

        // Which symbols M and f contain, from one traversal each (a chain of a
        // thousand masses has a thousand entries and two thousand symbols).
        let in_mass: FxHashSet<ExprId> = pool.reachable(&stored).into_iter().collect();
        let in_forcing: FxHashSet<ExprId> = pool.reachable(&d.forcing).into_iter().collect();
        let quadratic = d.qd.iter().all(|v| !in_mass.contains(v));
        let hamilton = quadratic.then(|| {
            let zero_vel: probe::Subst = d.qd.iter().map(|&v| (v, pool.zero())).collect();
            let mut outs: Vec<ExprId> = stored.clone();
            for &p in &d.momenta {
                outs.push(pool.substitute(p, &zero_vel));
            }
            let mut rates = Vec::with_capacity(n);
            for i in 0..n {
                let mut terms = vec![pool.diff(d.lagrangian, d.q[i]), d.forces[i]];
                if let Some(r) = d.dissipation {
                    let dr = pool.diff(r, d.qd[i]);
                    terms.push(pool.neg(dr));
                }
                rates.push(pool.add(&terms));
            }
            let compile = |pool: &sym::Pool, outs: &[ExprId]| {
                LazyKernel::new(Tape::compile(pool, outs, input_syms).expect("derivation symbols are inputs"))
            };
            (compile(pool, &outs), compile(pool, &rates))
        });
        let constant_mass = d.q.iter().chain(&d.qd).chain([&d.t]).all(|v| !in_mass.contains(v));
        let velocity_free_forcing = d.qd.iter().all(|v| !in_forcing.contains(v));
        let zero_vel: probe::Subst = d.qd.iter().map(|&v| (v, pool.zero())).collect();
        let no_linear_momentum = d.momenta.iter().all(|&p| {
            let b = pool.substitute(p, &zero_vel);
            probe::is_zero(pool, b)
        });
        let separable = quadratic && constant_mass && velocity_free_forcing && no_linear_momentum;

        let exprs: Vec<ExprId> = invariants.iter().map(|i| i.expr).collect();
        let invariants_tape = LazyKernel::with_warm_up(
            Tape::compile(pool, &exprs, input_syms).expect("derivation symbols are inputs"),
            INVARIANTS_WARM_UP,
        );

        Dynamics {
            n,
            inputs,
            scratch: vec![0.0; pattern.len() + n],
            pattern,
            mass_forcing,
            mass_forcing_tape,
            hamilton,
            invariants_tape,
            invariants,
            separable,
            quadratic,
            coordinate_names: d.model.coordinates.iter().map(|c| c.name.clone()).collect(),
        }
    }

    /// The number of coordinates.
    pub fn n_coords(&self) -> usize {
        self.n
    }

    /// The coordinate names.
    pub fn coordinate_names(&self) -> &[String] {
        &self.coordinate_names
    }

    /// True when H = ½pᵀM⁻¹p + V(q, t) with a constant M.
    pub fn is_separable(&self) -> bool {
        self.separable
    }

    /// True when the equations of motion are analytic where defined (no `abs`):
    /// a Taylor series of the motion then describes it up to its radius.
    pub fn is_analytic(&self) -> bool {
        self.mass_forcing_tape.is_analytic()
    }

    /// True when Hamilton's form is available (L quadratic in the velocities).
    pub fn has_hamilton_form(&self) -> bool {
        self.quadratic && self.hamilton.is_some()
    }

    /// The invariants audited along a run.
    pub fn invariants(&self) -> &[Invariant] {
        &self.invariants
    }

    /// A first-order system in the given form.
    pub fn system(&self, form: Form) -> System {
        let n = self.n;
        let e = self.pattern.len();
        System {
            dynamics: self.clone(),
            form,
            inputs: self.inputs.clone(),
            out: vec![0.0; e + 2 * n],
            mass: vec![0.0; if self.pattern.diagonal { n } else { n * n }],
            lu: LinearSolver::new(n),
            work: vec![0.0; n],
            factored_once: false,
            series: None,
        }
    }

    /// The Taylor expansion of the Lagrange form to `order`, on `L` lanes, in native code.
    pub(crate) fn lagrange_series<const L: usize>(&self, order: usize) -> LagrangeSeries<L> {
        self.lagrange_series_with(order, true)
    }

    /// The same, interpreted unless `native`.
    pub(crate) fn lagrange_series_with<const L: usize>(&self, order: usize, native: bool) -> LagrangeSeries<L> {
        let p = &self.pattern;
        let mut series =
            LagrangeSeries::new(&self.mass_forcing_tape, self.n, p.entries.clone(), p.diagonal, order, native);
        let params: Vec<[f64; L]> = self.inputs[2 * self.n + 1..].iter().map(|&v| [v; L]).collect();
        series.set_parameters(&params);
        series
    }

    /// Evaluates M (row-major, n²) and f (n) at `inputs` = `[q, q', t, parameters]`
    /// (the constrained runs of `constrained.rs` reuse this kernel).
    pub(crate) fn eval_mass_forcing(&mut self, inputs: &[f64], out: &mut [f64]) {
        let (n, e) = (self.n, self.pattern.len());
        self.mass_forcing.eval(inputs, &mut self.scratch);
        out[..n * n].fill(0.0);
        self.pattern.scatter(&self.scratch[..e], &mut out[..n * n]);
        out[n * n..n * n + n].copy_from_slice(&self.scratch[e..e + n]);
    }

    /// The input template `[q, q', t, parameters]` with the parameters' values.
    pub(crate) fn input_template(&self) -> &[f64] {
        &self.inputs
    }

    /// Evaluates the invariants at (q, q', t) into `out`.
    pub fn eval_invariants(&mut self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) {
        let n = self.n;
        self.inputs[..n].copy_from_slice(q);
        self.inputs[n..2 * n].copy_from_slice(qd);
        self.inputs[2 * n] = t;
        self.invariants_tape.eval(&self.inputs, out);
    }
}

/// The quantities audited along a run: H, every conserved momentum, and the
/// energy E where it differs from H.
pub fn invariants_of(d: &Derivation) -> Vec<Invariant> {
    let mut invariants = vec![Invariant { name: "H".into(), expr: d.energy_function }];
    for c in &d.conserved {
        if c.name != "H" {
            invariants.push(Invariant { name: c.name.clone(), expr: c.expr });
        }
    }
    if let (Some(e), Some(false)) = (d.energy, d.hamiltonian_is_energy) {
        invariants.push(Invariant { name: "E".into(), expr: e });
    }
    invariants
}

/// A compiled first-order system, ready for an integrator. Scratch space is
/// allocated once; evaluations allocate nothing.
#[derive(Debug, Clone)]
pub struct System {
    dynamics: Dynamics,
    form: Form,
    inputs: Vec<f64>,
    out: Vec<f64>,
    mass: Vec<f64>,
    lu: LinearSolver,
    work: Vec<f64>,
    factored_once: bool,
    /// The Taylor expansion and its scratch, made on first use (Lagrange form).
    series: Option<Box<LagrangeSeries<1>>>,
}

impl System {
    /// Sets the parameter values (in the model's order) for the next
    /// evaluations: an ensemble over parameters reuses the compiled tapes.
    pub fn set_parameters(&mut self, values: &[f64]) {
        let start = 2 * self.dynamics.n + 1;
        self.inputs[start..start + values.len()].copy_from_slice(values);
        self.dynamics.inputs[start..start + values.len()].copy_from_slice(values);
        self.factored_once = false;
        if let Some(series) = &mut self.series {
            series.set_parameters(values.as_chunks::<1>().0);
        }
    }

    /// The initial state in this form from (q, q') at time t.
    pub fn initial_state(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<Vec<f64>, ModelError> {
        let n = self.dynamics.n;
        let mut y = Vec::with_capacity(2 * n);
        y.extend_from_slice(q);
        match self.form {
            Form::Lagrange => y.extend_from_slice(qd),
            Form::Hamilton | Form::Separable => {
                // p = M q' + b.
                self.set_inputs(t, q, qd);
                let (tape, _) = self.dynamics.hamilton.as_mut().expect("Hamilton form needs L quadratic in q'");
                let e = self.dynamics.pattern.len();
                tape.eval(&self.inputs, &mut self.out[..e + n]);
                let mut p = self.out[e..e + n].to_vec();
                for (&(i, j), m) in self.dynamics.pattern.entries.iter().zip(&self.out[..e]) {
                    p[i] += m * qd[j];
                }
                y.extend(p);
            }
        }
        Ok(y)
    }

    /// Converts a state of this form to (q, q') at time t.
    pub fn velocities(&mut self, t: f64, y: &[f64], qd: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dynamics.n;
        match self.form {
            Form::Lagrange => {
                qd.copy_from_slice(&y[n..]);
                Ok(())
            }
            Form::Hamilton | Form::Separable => self.hamilton_velocities(t, y, qd),
        }
    }

    /// The number of invariants [`System::invariants_at`] writes.
    pub fn n_invariants(&self) -> usize {
        self.dynamics.invariants.len()
    }

    /// Evaluates the invariants at a state of this form.
    pub fn invariants_at(&mut self, t: f64, y: &[f64], qd: &mut [f64], out: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dynamics.n;
        self.velocities(t, y, qd)?;
        let q: Vec<f64> = y[..n].to_vec();
        self.dynamics.eval_invariants(t, &q, qd, out);
        Ok(())
    }

    /// The mass matrix M(q, t) (row-major) at a state of this form.
    pub fn mass_matrix_at(&mut self, t: f64, y: &[f64]) -> Vec<f64> {
        let n = self.dynamics.n;
        self.inputs[..n].copy_from_slice(&y[..n]);
        for v in &mut self.inputs[n..2 * n] {
            *v = 0.0;
        }
        if self.form == Form::Lagrange {
            // M may depend on the velocities when L is not quadratic in them.
            self.inputs[n..2 * n].copy_from_slice(&y[n..]);
        }
        self.inputs[2 * n] = t;
        let e = self.dynamics.pattern.len();
        self.dynamics.mass_forcing.eval_once(&self.inputs, &mut self.out[..e + n]);
        let mut m = vec![0.0; n * n];
        self.dynamics.pattern.scatter(&self.out[..e], &mut m);
        m
    }

    /// Factors M from its stored entries at the front of `out`: divided by when
    /// diagonal, scattered into the dense scratch and factored otherwise.
    fn factor_mass(&mut self) -> Result<(), RhsError> {
        let pattern = &self.dynamics.pattern;
        let values = &self.out[..pattern.len()];
        if pattern.diagonal {
            self.mass.fill(0.0);
            for (&(i, _), &v) in pattern.entries.iter().zip(values) {
                self.mass[i] = v;
            }
            self.lu.factor_diagonal(&self.mass).map_err(RhsError::from)
        } else {
            pattern.scatter(values, &mut self.mass);
            self.lu.factor(&self.mass).map_err(RhsError::from)
        }
    }

    fn set_inputs(&mut self, t: f64, q: &[f64], qd: &[f64]) {
        let n = self.dynamics.n;
        self.inputs[..n].copy_from_slice(q);
        self.inputs[n..2 * n].copy_from_slice(qd);
        self.inputs[2 * n] = t;
    }

    /// q' = M⁻¹(p − b), leaving M and b at the front of `out`.
    fn hamilton_velocities(&mut self, t: f64, y: &[f64], qd: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dynamics.n;
        let (q, p) = y.split_at(n);
        self.inputs[..n].copy_from_slice(q);
        for v in &mut self.inputs[n..2 * n] {
            *v = 0.0;
        }
        self.inputs[2 * n] = t;
        let (tape, _) = self.dynamics.hamilton.as_mut().expect("Hamilton form needs L quadratic in q'");
        let e = self.dynamics.pattern.len();
        tape.eval(&self.inputs, &mut self.out[..e + n]);
        self.factor_mass()?;
        for i in 0..n {
            qd[i] = p[i] - self.out[e + i];
        }
        self.lu.solve_in_place(qd).map_err(RhsError::from)?;
        Ok(())
    }
}

impl OdeSystem for System {
    fn dim(&self) -> usize {
        2 * self.dynamics.n
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dynamics.n;
        match self.form {
            Form::Lagrange => {
                self.inputs[..2 * n].copy_from_slice(y);
                self.inputs[2 * n] = t;
                let e = self.dynamics.pattern.len();
                self.dynamics.mass_forcing.eval(&self.inputs, &mut self.out[..e + n]);
                self.factor_mass()?;
                dy[..n].copy_from_slice(&y[n..]);
                dy[n..].copy_from_slice(&self.out[e..e + n]);
                self.lu.solve_in_place(&mut dy[n..]).map_err(RhsError::from)?;
            }
            Form::Hamilton | Form::Separable => {
                let mut qd = std::mem::take(&mut self.work);
                let r = self.hamilton_velocities(t, y, &mut qd);
                if let Err(e) = r {
                    self.work = qd;
                    return Err(e);
                }
                // p' = ∂L/∂q − ∂R/∂q' + Q at q' = M⁻¹(p − b).
                self.inputs[n..2 * n].copy_from_slice(&qd);
                let (_, tape) = self.dynamics.hamilton.as_mut().expect("Hamilton form needs L quadratic in q'");
                let e = self.dynamics.pattern.len();
                tape.eval(&self.inputs, &mut self.out[e + n..e + 2 * n]);
                dy[..n].copy_from_slice(&qd);
                dy[n..].copy_from_slice(&self.out[e + n..e + 2 * n]);
                self.work = qd;
            }
        }
        if let Some(index) = dy.iter().position(|v| !v.is_finite()) {
            return Err(RhsError::NonFinite { index });
        }
        Ok(())
    }

    /// The Taylor expansion in Lagrange form ([`crate::run::series`]); the other forms have none.
    fn taylor_series(&mut self, t: f64, y: &[f64], order: usize, out: &mut [f64]) -> Option<Result<(), RhsError>> {
        if self.form != Form::Lagrange {
            return None;
        }
        if self.series.as_ref().is_none_or(|s| s.order() != order) {
            self.series = Some(Box::new(self.dynamics.lagrange_series::<1>(order)));
        }
        let series = self.series.as_mut().expect("made above");
        // One lane: `[f64; 1]` is laid out as `f64`, so the slices are viewed, not copied.
        let (y_lanes, _) = y.as_chunks::<1>();
        let (out_lanes, _) = out.as_chunks_mut::<1>();
        let result = series.expand([t], y_lanes, out_lanes);
        Some(result)
    }
}

impl SeparableSystem for System {
    fn n(&self) -> usize {
        self.dynamics.n
    }

    fn velocity(&mut self, p: &[f64], dq: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dynamics.n;
        if !self.factored_once {
            // M is constant: evaluate and factor it once.
            for v in &mut self.inputs[..=2 * n] {
                *v = 0.0;
            }
            let e = self.dynamics.pattern.len();
            self.dynamics.mass_forcing.eval(&self.inputs, &mut self.out[..e + n]);
            self.factor_mass()?;
            self.factored_once = true;
        }
        dq.copy_from_slice(p);
        self.lu.solve_in_place(dq).map_err(RhsError::from)?;
        Ok(())
    }

    fn force(&mut self, t: f64, q: &[f64], dp: &mut [f64]) -> Result<(), RhsError> {
        let n = self.dynamics.n;
        self.inputs[..n].copy_from_slice(q);
        for v in &mut self.inputs[n..2 * n] {
            *v = 0.0;
        }
        self.inputs[2 * n] = t;
        let e = self.dynamics.pattern.len();
        self.dynamics.mass_forcing.eval(&self.inputs, &mut self.out[..e + n]);
        dp.copy_from_slice(&self.out[e..e + n]);
        if let Some(index) = dp.iter().position(|v| !v.is_finite()) {
            return Err(RhsError::NonFinite { index: n + index });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dynamics(text: &str) -> Dynamics {
        Dynamics::new(&crate::test_models::derive(text))
    }

    #[test]
    fn every_form_gives_the_pendulum_equation() {
        let dy = dynamics(crate::test_models::PENDULUM);
        assert!(dy.is_separable(), "M = m l^2 is constant and f depends on th alone");
        let (th, om): (f64, f64) = (0.7, -0.3);
        let expect = -9.81 / 1.5 * th.sin();
        let mut out = [0.0; 2];
        let mut lag = dy.system(Form::Lagrange);
        lag.rhs(0.0, &[th, om], &mut out).unwrap();
        assert!((out[0] - om).abs() < 1e-15 && (out[1] - expect).abs() < 1e-12, "{out:?}");
        let mut ham = dy.system(Form::Hamilton);
        let y = ham.initial_state(0.0, &[th], &[om]).unwrap();
        assert!((y[1] - 2.0 * 1.5 * 1.5 * om).abs() < 1e-12, "p = m l^2 th'");
        ham.rhs(0.0, &y, &mut out).unwrap();
        assert!((out[0] - om).abs() < 1e-12);
        assert!((out[1] - 2.0 * 1.5 * 1.5 * expect).abs() < 1e-10, "p' = m l^2 th''");
        let mut sep = dy.system(Form::Separable);
        let (mut dq, mut dp) = ([0.0], [0.0]);
        sep.velocity(&y[1..], &mut dq).unwrap();
        sep.force(0.0, &y[..1], &mut dp).unwrap();
        assert!((dq[0] - om).abs() < 1e-12 && (dp[0] - out[1]).abs() < 1e-10);
    }

    /// A chain's M is diagonal: the kernel outputs its N diagonal entries (not
    /// N²), the solve divides, and every form gives the spring forces.
    #[test]
    fn a_diagonal_mass_matrix_is_stored_and_solved_as_such() {
        let chain = "coordinates = [\"x1\", \"x2\", \"x3\"]\n\
            lagrangian = \"m1*x1'^2/2 + m2*x2'^2/2 + m3*x3'^2/2 - k*(x1^2 + (x2 - x1)^2 + (x3 - x2)^2 + x3^2)/2\"\n\
            [parameters]\nm1 = 1.0\nm2 = 2.0\nm3 = 4.0\nk = 3.0\n";
        let dy = dynamics(chain);
        assert!(dy.pattern.diagonal && dy.pattern.len() == 3, "{:?}", dy.pattern);
        assert!(dy.is_separable());
        let (x, v) = ([0.3, -0.2, 0.5], [0.1, 0.2, -0.3]);
        let k = 3.0;
        let acc = [-k * (2.0 * x[0] - x[1]), -k * (2.0 * x[1] - x[0] - x[2]) / 2.0, -k * (2.0 * x[2] - x[1]) / 4.0];
        let mut y = x.to_vec();
        y.extend(v);
        let mut out = [0.0; 6];
        dy.system(Form::Lagrange).rhs(0.0, &y, &mut out).unwrap();
        for i in 0..3 {
            assert!((out[i] - v[i]).abs() < 1e-15 && (out[3 + i] - acc[i]).abs() < 1e-14, "{out:?}");
        }
        let mut ham = dy.system(Form::Hamilton);
        let yh = ham.initial_state(0.0, &x, &v).unwrap();
        assert_eq!(&yh[3..], &[0.1, 0.4, -1.2]);
        ham.rhs(0.0, &yh, &mut out).unwrap();
        let masses = [1.0, 2.0, 4.0];
        for i in 0..3 {
            assert!((out[i] - v[i]).abs() < 1e-15 && (out[3 + i] - masses[i] * acc[i]).abs() < 1e-13, "{out:?}");
        }
        assert_eq!(ham.mass_matrix_at(0.0, &yh), vec![1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 4.0]);
    }

    #[test]
    fn a_singular_mass_matrix_is_an_error_not_a_number() {
        let dy = dynamics("coordinates = [\"x\"]\nkinetic = \"x^2*x'^2/2\"\n");
        let mut sys = dy.system(Form::Lagrange);
        let mut out = [0.0; 2];
        assert!(matches!(sys.rhs(0.0, &[0.0, 1.0], &mut out), Err(RhsError::Singular { .. })));
    }
}
