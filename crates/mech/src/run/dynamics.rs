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

/// The same for a tape the JIT compiles in one quick pass
/// ([`sym::QUICK_MIN_OPS`]): per instruction that costs about as much as
/// interpreting it a hundred times (a 50-rod chain's H interpreted at every
/// sample took a third of its run).
const QUICK_INVARIANTS_WARM_UP: usize = 100;

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

    /// Compiles the native code now (once for all clones), so that its time
    /// counts where the caller wants it: in a run's setup, not its first step.
    fn prepare(&self) {
        self.native.get_or_init(|| Compiled::new(&self.tape).ok().map(Arc::new));
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
    /// q'' (n) from `[q, q', t, params]` by the articulated-body algorithm, where
    /// the model is a tree and that costs fewer operations than M, f and their
    /// solve ([`crate::run::tree`]); the Lagrange form then uses it.
    accelerations: Option<LazyKernel>,
    /// Hamilton's form, two kernels: M's stored entries and `b` (n) from `[q, t, params]`
    /// (free of q'), and `∂L/∂q − ∂R/∂q' + Q` (n) from `[q, q', t, params]`. Split so that
    /// each right-hand side computes each group once.
    hamilton: Option<(LazyKernel, LazyKernel)>,
    /// What the Hamilton kernels are built from, on first use (a Lagrange-form
    /// run never pays for their expressions); None unless L is quadratic in q'.
    hamilton_source: Option<Arc<HamiltonSource>>,
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
        let accelerations = tree_kernel(pool, d, &mass_forcing_tape, &pattern, input_syms);

        // Which symbols M and f contain, from one traversal each (a chain of a
        // thousand masses has a thousand entries and two thousand symbols).
        let in_mass: FxHashSet<ExprId> = pool.reachable(&stored).into_iter().collect();
        let in_forcing: FxHashSet<ExprId> = pool.reachable(&d.forcing).into_iter().collect();
        let quadratic = d.qd.iter().all(|v| !in_mass.contains(v));
        let constant_mass = d.q.iter().chain(&d.qd).chain([&d.t]).all(|v| !in_mass.contains(v));
        let velocity_free_forcing = d.qd.iter().all(|v| !in_forcing.contains(v));
        let zero_vel: probe::Subst = d.qd.iter().map(|&v| (v, pool.zero())).collect();
        // Asked only when the rest holds: a substitution per momentum is long on a large model.
        let separable = quadratic
            && constant_mass
            && velocity_free_forcing
            && d.momenta.iter().all(|&p| {
                let b = pool.substitute(p, &zero_vel);
                probe::is_zero(pool, b)
            });
        let exprs: Vec<ExprId> = invariants.iter().map(|i| i.expr).collect();
        let invariants_tape = Tape::compile(pool, &exprs, input_syms).expect("derivation symbols are inputs");
        let warm_up =
            if invariants_tape.len() > sym::QUICK_MIN_OPS { QUICK_INVARIANTS_WARM_UP } else { INVARIANTS_WARM_UP };
        let invariants_tape = LazyKernel::with_warm_up(invariants_tape, warm_up);

        let hamilton_source = quadratic.then(|| {
            Arc::new(HamiltonSource {
                pool: pool_owned,
                inputs: input_syms.to_vec(),
                stored,
                momenta: d.momenta.clone(),
                coordinate_gradient: d.coordinate_gradient.clone(),
                lagrangian: d.lagrangian,
                q: d.q.clone(),
                qd: d.qd.clone(),
                forces: d.forces.clone(),
                dissipation: d.dissipation,
                kernels: OnceLock::new(),
            })
        });

        Dynamics {
            n,
            inputs,
            scratch: vec![0.0; pattern.len() + n],
            pattern,
            mass_forcing,
            mass_forcing_tape,
            accelerations,
            hamilton_source,
            hamilton: None,
            invariants_tape,
            invariants,
            separable,
            quadratic,
            coordinate_names: d.model.coordinates.iter().map(|c| c.name.clone()).collect(),
        }
    }

    /// Hamilton's two kernels, built on first use.
    fn hamilton_kernels(&mut self) -> &mut (LazyKernel, LazyKernel) {
        if self.hamilton.is_none() {
            let source = self.hamilton_source.as_ref().expect("Hamilton form needs L quadratic in q'");
            self.hamilton = Some(source.kernels().clone());
        }
        self.hamilton.as_mut().expect("set above")
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

    /// True when the Lagrange form's accelerations come from the
    /// articulated-body kernel ([`crate::run::tree`]) rather than `M q'' = f`.
    pub fn uses_articulated_body(&self) -> bool {
        self.accelerations.is_some()
    }

    /// True when Hamilton's form is available (L quadratic in the velocities).
    pub fn has_hamilton_form(&self) -> bool {
        self.quadratic && self.hamilton_source.is_some()
    }

    /// The invariants audited along a run.
    pub fn invariants(&self) -> &[Invariant] {
        &self.invariants
    }

    /// A first-order system in the given form.
    pub fn system(&self, form: Form) -> System {
        let n = self.n;
        let e = self.pattern.len();
        if let (Form::Lagrange, Some(tree)) = (form, &self.accelerations) {
            tree.prepare();
        }
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

/// The expressions of Hamilton's form, built and compiled when a run first
/// asks for them: M's stored entries and b = p at q' = 0 (from `[q, t,
/// params]`), and ∂L/∂q − ∂R/∂q' + Q (from `[q, q', t, params]`).
#[derive(Debug)]
struct HamiltonSource {
    /// The pool of [`Dynamics::new`], holding every expression below.
    pool: sym::Pool,
    inputs: Vec<ExprId>,
    stored: Vec<ExprId>,
    momenta: Vec<ExprId>,
    coordinate_gradient: Option<Vec<ExprId>>,
    lagrangian: ExprId,
    q: Vec<ExprId>,
    qd: Vec<ExprId>,
    forces: Vec<ExprId>,
    dissipation: Option<ExprId>,
    /// The two kernels, once built (clones share their native code).
    kernels: OnceLock<(LazyKernel, LazyKernel)>,
}

impl HamiltonSource {
    fn kernels(&self) -> &(LazyKernel, LazyKernel) {
        self.kernels.get_or_init(|| {
            let mut pool = self.pool.clone();
            let pool = &mut pool;
            let zero_vel: probe::Subst = self.qd.iter().map(|&v| (v, pool.zero())).collect();
            let mut outs: Vec<ExprId> = self.stored.clone();
            for &p in &self.momenta {
                outs.push(pool.substitute(p, &zero_vel));
            }
            let mut rates = Vec::with_capacity(self.q.len());
            for i in 0..self.q.len() {
                let dl_dq = match &self.coordinate_gradient {
                    Some(gradient) => gradient[i],
                    None => pool.diff(self.lagrangian, self.q[i]),
                };
                let mut terms = vec![dl_dq, self.forces[i]];
                if let Some(r) = self.dissipation {
                    let dr = pool.diff(r, self.qd[i]);
                    terms.push(pool.neg(dr));
                }
                rates.push(pool.add(&terms));
            }
            let compile = |pool: &sym::Pool, outs: &[ExprId]| {
                LazyKernel::new(Tape::compile(pool, outs, &self.inputs).expect("derivation symbols are inputs"))
            };
            (compile(pool, &outs), compile(pool, &rates))
        })
    }
}

/// Fewer coordinates than this and runs always solve `M q'' = f`: at that
/// size M and its solve cost little, and the notes' examples keep their
/// numbers to the last bit.
const TREE_MIN_COORDINATES: usize = 5;

/// The articulated-body kernel of `d` ([`crate::run::tree`]) where the model
/// is a tree and its tape is shorter than M's and f's plus the operations of
/// their solve (a division per row for a diagonal M, else an LU's 2n³/3 and
/// the substitutions' 2n²).
fn tree_kernel(
    pool: &mut sym::Pool,
    d: &Derivation,
    dense: &Tape,
    pattern: &MassPattern,
    inputs: &[ExprId],
) -> Option<LazyKernel> {
    let n = d.q.len();
    if n < TREE_MIN_COORDINATES {
        return None;
    }
    let tape = articulated_body_tape(pool, d, inputs)?;
    let solve = if pattern.diagonal { n } else { 2 * n * n * n / 3 + 2 * n * n };
    (tape.len() < dense.len() + solve).then(|| LazyKernel::new(tape))
}

/// The tape of q'' by the articulated-body algorithm, where `d`'s model is a tree.
fn articulated_body_tape(pool: &mut sym::Pool, d: &Derivation, inputs: &[ExprId]) -> Option<Tape> {
    let program = crate::run::tree::program(pool, d)?;
    Tape::compile_with_definitions(pool, &program.definitions, &program.accelerations, inputs).ok()
}

/// The quantities audited along a run: H, every conserved momentum, and the
/// energy E where it differs from H.
pub fn invariants_of(d: &Derivation) -> Vec<Invariant> {
    let h = match (d.energy, d.hamiltonian_is_energy, &d.coordinate_gradient) {
        // On the shared path h = Σ q'p − L carries the momenta's adjoints; where H
        // is proven to be T + U that is evaluated instead (a humanoid's: 14 600
        // instructions against 165 000, at every row of a run).
        (Some(e), Some(true), Some(_)) => e,
        _ => d.energy_function,
    };
    let mut invariants = vec![Invariant { name: "H".into(), expr: h }];
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
                let e = self.dynamics.pattern.len();
                let (tape, _) = self.dynamics.hamilton_kernels();
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
        let e = self.dynamics.pattern.len();
        let (tape, _) = self.dynamics.hamilton_kernels();
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
                if let Some(tree) = &mut self.dynamics.accelerations {
                    dy[..n].copy_from_slice(&y[n..]);
                    tree.eval(&self.inputs, &mut dy[n..]);
                    if let Some(index) = dy.iter().position(|v| !v.is_finite()) {
                        return Err(RhsError::NonFinite { index });
                    }
                    return Ok(());
                }
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
                let e = self.dynamics.pattern.len();
                let (_, tape) = self.dynamics.hamilton_kernels();
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

    /// q'' of the articulated-body kernel and of `M q'' = f` at a state.
    fn both_accelerations(dy: &Dynamics, y: &[f64], t: f64) -> (Vec<f64>, Vec<f64>) {
        let n = dy.n;
        let mut tree = vec![0.0; 2 * n];
        dy.system(Form::Lagrange).rhs(t, y, &mut tree).unwrap();
        let mut dense_dynamics = dy.clone();
        dense_dynamics.accelerations = None;
        let mut dense = vec![0.0; 2 * n];
        dense_dynamics.system(Form::Lagrange).rhs(t, y, &mut dense).unwrap();
        (tree[n..].to_vec(), dense[n..].to_vec())
    }

    /// Trees of every kind of node the kernel knows, each against `M q'' = f`
    /// at random states.
    #[test]
    fn the_articulated_body_kernel_gives_the_accelerations_of_m_and_f() {
        let chain = |n: usize| {
            let coords: Vec<String> = (1..=n).map(|i| format!("\"th{i}\"")).collect();
            let mut text = format!("gravity = \"g\"\ncoordinates = [{}]\n[parameters]\ng = 9.81\n", coords.join(", "));
            let (mut xs, mut ys) = (Vec::new(), Vec::new());
            for k in 1..=n {
                text += &format!("m{k} = {}\nl{k} = {}\n", 1.0 + 0.1 * k as f64, 1.0 - 0.05 * k as f64);
            }
            for k in 1..=n {
                xs.push(format!("l{k}*sin(th{k})"));
                ys.push(format!("-l{k}*cos(th{k})"));
                text += &format!(
                    "[[particles]]\nmass = \"m{k}\"\nposition = [\"{}\", \"{}\"]\n",
                    xs.join(" + "),
                    ys.join(" + ")
                );
            }
            text
        };
        let rods = |n: usize, extra: &str| {
            let coords: Vec<String> = (0..n).map(|i| format!("\"a{i}\"")).collect();
            let mut text = format!(
                "gravity = \"g\"\ncoordinates = [{}]\n{extra}[parameters]\nm = 1.3\nl = 0.7\ng = 9.81\nk = 2.0\nc = 0.3\n",
                coords.join(", ")
            );
            for i in 0..n {
                text += &format!("[[bodies]]\nname = \"r{i}\"\nmass = \"m\"\ninertia = \"m*l^2/3\"\nangle = \"a{i}\"\ncenter_of_mass = [\"0.1\", \"-l/2\"]\n");
                if i > 0 {
                    text += &format!("parent = \"r{}\"\nposition = [\"0\", \"-l\"]\n", i - 1);
                }
            }
            text
        };
        let spatial = |n: usize| {
            let mut coords = Vec::new();
            for i in 0..n {
                coords.extend([format!("\"p{i}\""), format!("\"t{i}\""), format!("\"s{i}\"")]);
            }
            let mut text = format!(
                "gravity = \"g\"\ncoordinates = [{}]\n[parameters]\nm = 1.0\nl = 1.0\ng = 9.81\n",
                coords.join(", ")
            );
            for i in 0..n {
                text += &format!(
                    "[[bodies]]\nname = \"b{i}\"\nmass = \"m\"\ninertia = [[\"0.3*m*l^2\", \"0.05\", \"0\"], [\"0.05\", \"m*l^2/4\", \"0.02\"], [\"0\", \"0.02\", \"m*l^2/5\"]]\nangles = [\"p{i}\", \"t{i}\", \"s{i}\"]\ncenter_of_mass = [\"0.1\", \"0\", \"-l/2\"]\n"
                );
                if i > 0 {
                    text += &format!("parent = \"b{}\"\nposition = [\"0.2\", \"0\", \"-l\"]\n", i - 1);
                }
            }
            text
        };
        // A cart on a moving rail with a double rod on it, a spring, damping and a force.
        let cart = "gravity = \"g\"\ncoordinates = [\"x\", \"a\", \"b\", \"c\", \"d\"]\n\
            potential = \"k*x^2/2 + k*a^2\"\ndissipation = \"damp*(x'^2 + b'^2)/2\"\n\
            [forces]\nd = \"sin(t)\"\n\
            [parameters]\ng = 9.81\nk = 3.0\ndamp = 0.2\n\
            [[bodies]]\nname = \"cart\"\nmass = \"2\"\nposition = [\"x\", \"0.1*sin(t)\"]\n\
            [[bodies]]\nname = \"rod\"\nparent = \"cart\"\nmass = \"1\"\ninertia = \"0.3\"\nangle = \"a\"\ncenter_of_mass = [\"0\", \"-0.5\"]\n\
            [[bodies]]\nname = \"slider\"\nparent = \"rod\"\nmass = \"0.5\"\ninertia = \"0.02\"\nposition = [\"0\", \"-1 - b\"]\n\
            [[bodies]]\nname = \"arm\"\nparent = \"slider\"\nmass = \"0.4\"\ninertia = \"0.05\"\nangle = \"c\"\ncenter_of_mass = [\"0.3\", \"0\"]\n\
            [[bodies]]\nname = \"tip\"\nparent = \"arm\"\nmass = \"0.2\"\ninertia = \"0.01\"\nangle = \"d\"\nposition = [\"0.6\", \"0\"]\ncenter_of_mass = [\"0.2\", \"0.1\"]\n";
        let models = [
            ("particle chain", chain(7)),
            ("rod chain", rods(6, "")),
            ("damped rods", rods(5, "dissipation = \"c*(a0'^2 + a3'^2)\"\npotential = \"k*(a1 - a2)^2\"\n")),
            ("spatial chain", spatial(3)),
            ("cart", cart.to_string()),
        ];
        let mut rng = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let urdf = |file: &str, floating: bool| format!("urdf = \"{file}\"\nfloating_base = {floating}\n");
        let robots = [
            ("spatial arm", urdf("spatial_arm.urdf", false)),
            ("planar arm", urdf("planar_arm.urdf", false)),
            ("floating body", urdf("floating_body.urdf", false)),
            ("cart pendulum", urdf("cart_pendulum.urdf", false)),
        ];
        for (name, text) in models.into_iter().chain(robots) {
            let files = |path: &str| {
                let folder = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/urdf/");
                std::fs::read_to_string(format!("{folder}{path}")).map_err(|e| e.to_string())
            };
            let model = crate::Model::parse_with(&text, &[], &files).expect("the model parses");
            let d = Derivation::new(model).expect("the model derives");
            let mut dy = Dynamics::new(&d);
            if dy.accelerations.is_none() {
                // Below the size where runs use it: made all the same.
                assert!(dy.n < TREE_MIN_COORDINATES, "{name}: no tree kernel");
                let mut pool = d.pool().clone();
                let tape = articulated_body_tape(&mut pool, &d, d.layout.symbols()).expect("a tree");
                dy.accelerations = Some(LazyKernel::new(tape));
            }
            for _ in 0..3 {
                let y: Vec<f64> = (0..2 * dy.n).map(|_| uniform()).collect();
                let t = uniform();
                let (tree, dense) = both_accelerations(&dy, &y, t);
                let scale = dense.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
                for (i, (a, b)) in tree.iter().zip(&dense).enumerate() {
                    assert!((a - b).abs() < 1e-10 * scale, "{name}: q''[{i}] {a} against {b}");
                }
            }
        }
    }

    #[test]
    fn a_singular_mass_matrix_is_an_error_not_a_number() {
        let dy = dynamics("coordinates = [\"x\"]\nkinetic = \"x^2*x'^2/2\"\n");
        let mut sys = dy.system(Form::Lagrange);
        let mut out = [0.0; 2];
        assert!(matches!(sys.rhs(0.0, &[0.0, 1.0], &mut out), Err(RhsError::Singular { .. })));
    }
}
