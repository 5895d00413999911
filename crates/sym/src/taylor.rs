//! Taylor-mode evaluation of a tape: the Taylor coefficients of every output,
//! order by order, from the Taylor coefficients of the inputs.
//!
//! This is the engine of the Taylor integrator (Jorba & Zou 2005; heyoka):
//! along a solution `y(t)` of an ODE each tape slot is a function of `t`, and
//! its normalized coefficients `x[k] = x⁽ᵏ⁾(t₀)/k!` follow from the operands'
//! by the classical recurrences (products are Cauchy convolutions, quotients
//! and functions are solved from `w' = g(u) u'`). Order `k` of every slot needs
//! only orders `0..=k` of its operands, so an ODE integrator sets the state's
//! order `k`, calls [`TaylorTape::compute`] for order `k`, and reads the right-
//! hand side's order `k`, which is the state's order `k + 1` times `k + 1`.
//!
//! Slots that depend only on constants and constant inputs (the parameters)
//! are evaluated once by [`TaylorTape::refresh_constants`] and enter the
//! recurrences as scalars: `c·u` costs `O(1)` per order instead of the `O(k)`
//! of a convolution. Integer powers become chains of products (no division by
//! a base that may vanish), and `u^v` becomes `exp(v·ln u)`.
//!
//! A linearly implicit second-order system `A(y, y', t) y'' = b(y, y', t)`
//! whose `A` and `b` are the tape's outputs ([`LinearSecondOrder`]) expands
//! whole: [`TaylorTape::set_second_order`], then
//! [`TaylorTape::expand_second_order`] per expansion point, interpreted until
//! native code is compiled ([`TaylorTape::compile_second_order`], or
//! [`TaylorTape::compile_second_order_in_background`] for one lane, which
//! steps on meanwhile: for one lane both give the same numbers to the last
//! bit, so it does not matter which computed a step).
//!
//! Every coefficient is an array of `L` lanes: `L` independent trajectories
//! run in lock step, and the loops over lanes vectorize.

use crate::eval::{Op, Tape};
use crate::expr::Func;
use crate::native::{host_has_fma, CBuild, CcError, JitError};
use crate::taylor_jit::{NativeTaylor, NATIVE_MAX_WORK};
use std::sync::{Arc, OnceLock};

/// Which code computes a tape's Taylor expansions ([`TaylorTape::code`]).
#[derive(Clone, Debug, PartialEq)]
pub enum TaylorCode {
    /// The interpreter.
    Interpreted,
    /// Native code from cranelift, two lanes per instruction.
    Cranelift,
    /// Native code from the system C compiler, at the machine's vector width.
    C(CBuild),
}

/// Where the parts of a linearly implicit second-order system `A y'' = b`
/// sit among the slots (see [`TaylorTape::compile_second_order`]).
#[derive(Clone, Debug)]
pub(crate) struct SecondOrderLayout {
    pub(crate) n: usize,
    /// `(row, column)` of the entries of A the tape outputs first.
    pub(crate) entries: Vec<(usize, usize)>,
    /// Slots of y and y' (inputs 0..2n; t, input 2n, is the caller's).
    pub(crate) y: Vec<u32>,
    pub(crate) dy: Vec<u32>,
    /// Slots of A's entries and of b (outputs).
    pub(crate) matrix: Vec<u32>,
    pub(crate) rhs: Vec<u32>,
    /// Which entries of A vary along a trajectory.
    pub(crate) varying: Vec<bool>,
    /// Extra slots: y'' (n) and A[0]⁻¹ (n for a diagonal A, n² otherwise).
    pub(crate) second: Vec<u32>,
    pub(crate) inverse: Vec<u32>,
    /// A[0]⁻¹ by reciprocals ([`crate::ClosedFormInverse::Diagonal`]), not
    /// by the adjugate.
    pub(crate) diagonal: bool,
}

/// One coefficient of one slot on every lane.
pub type Lanes<const L: usize> = [f64; L];

/// A variable instruction of the Taylor tape; operands are slots, `c` names a
/// constant slot (read at order 0 only).
#[derive(Clone, Copy, Debug)]
pub(crate) enum T {
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Square(u32),
    /// `v + c`
    AddC(u32, u32),
    /// `v - c`
    SubVC(u32, u32),
    /// `c - v`
    SubCV(u32, u32),
    /// `v * c`
    MulC(u32, u32),
    /// `v / c`
    DivVC(u32, u32),
    /// `c / v`
    DivCV(u32, u32),
    Sqrt(u32),
    /// `v ^ c` for a non-integer constant exponent.
    PowC(u32, u32),
    /// `exp u`; `du` is `Deriv(u)`.
    Exp {
        u: u32,
        du: u32,
    },
    Log(u32),
    /// `k·u[k]` at order k: the coefficients of `t·u'(t)`, shared by the
    /// recurrences `w' = u'·g` of exp, sin, cos, sinh, cosh, tan and tanh.
    Deriv(u32),
    /// sin and cos of `u`: this slot is sin, `cos` the other.
    Sin {
        u: u32,
        du: u32,
        cos: u32,
    },
    /// The cosine half of a [`T::Sin`], computed with it.
    CosOf,
    /// sinh and cosh of `u`, like [`T::Sin`].
    Sinh {
        u: u32,
        du: u32,
        cosh: u32,
    },
    /// `tan u`, `aux = 1 + tan²u`; `sign = -1` gives `tanh u`, `aux = 1 - tanh²u`.
    Tan {
        u: u32,
        du: u32,
        aux: u32,
        sign: f64,
    },
    /// Written by its `Tan`.
    Aux,
    /// `asin u` (`sign = 1`) or `acos u` (`sign = -1`); `root = √(1 - u²)`,
    /// `inner = 1 - u²`.
    Asin {
        u: u32,
        inner: u32,
        root: u32,
        sign: f64,
    },
    /// `atan u`, `aux = 1 + u²`.
    Atan {
        u: u32,
        aux: u32,
    },
    /// `atan2(y, x)`, `aux = x² + y²`.
    Atan2 {
        y: u32,
        x: u32,
        aux: u32,
    },
    Abs(u32),
}

/// A tape evaluated in Taylor mode on `L` lanes. See the module documentation.
#[derive(Clone, Debug)]
pub struct TaylorTape<const L: usize> {
    order: usize,
    /// `coef[slot * (order + 1) + k]`: the k-th normalized coefficient.
    coef: Vec<Lanes<L>>,
    /// Constant instructions, evaluated by `refresh_constants`: (slot, op over slots).
    constants: Vec<(u32, Op)>,
    /// Variable instructions in order: (slot, instruction).
    program: Vec<(u32, T)>,
    /// The slot of each input.
    input_slots: Vec<u32>,
    /// Whether each input varies along a trajectory.
    variable_inputs: Vec<bool>,
    /// The slot of each output.
    outputs: Vec<u32>,
    /// Whether each slot is constant.
    constant: Vec<bool>,
    /// The orders as native code, shared by clones ([`TaylorTape::compile_native`]).
    native: Option<Arc<NativeTaylor>>,
    /// The whole expansion of a linearly implicit second-order system
    /// ([`TaylorTape::set_second_order`]).
    second_order: Option<SecondOrder>,
    /// Scratch of the interpreted second-order expansion: one order of `b`.
    rhs: Vec<Lanes<L>>,
    /// Whether the interpreter fuses the multiply-adds that native code
    /// fuses (where the host has FMA), so that both give the same numbers.
    fused: bool,
}

/// The native code of a second-order expansion, or why there is none; set
/// once, by the compilation, and shared by the clones of a tape.
type NativeCell = OnceLock<Result<NativeTaylor, JitError>>;

/// The whole expansion of a second-order system: where its parts sit among
/// the slots, and its native code once compiled.
#[derive(Clone, Debug)]
struct SecondOrder {
    layout: Arc<SecondOrderLayout>,
    native: Arc<NativeCell>,
    /// Whether a compilation was started (and will set `native`).
    compiling: bool,
}

/// A linearly implicit second-order system of ODEs,
/// `A(y, y', t) y'' = b(y, y', t)` with `y ∈ ℝⁿ`, as a tape computes it: the
/// tape's inputs start with `y` (n), `y'` (n) and `t` (any further inputs are
/// constant), and its outputs are the entries of `A` at `entries`, then `b`
/// (n). [`TaylorTape::compile_second_order`] compiles its Taylor expansion.
#[derive(Clone, Copy, Debug)]
pub struct LinearSecondOrder<'a> {
    /// `n`, the dimension of `y`.
    pub dim: usize,
    /// `(row, column)` of the entries of `A` the tape outputs, in their order;
    /// the entries not named are zero.
    pub entries: &'a [(usize, usize)],
    /// How `A` at the expansion point is inverted.
    pub inverse: ClosedFormInverse,
}

/// How a Taylor expansion of `A y'' = b` inverts `A[0]`, the matrix at the
/// expansion point, once per expansion ([`LinearSecondOrder::inverse`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClosedFormInverse {
    /// Reciprocals of the diagonal: every entry of `A` is on the diagonal.
    Diagonal,
    /// The adjugate over the determinant, for `n` up to
    /// [`ClosedFormInverse::ADJUGATE_MAX_DIM`].
    Adjugate,
}

impl ClosedFormInverse {
    /// The largest `n` whose adjugate is written out.
    pub const ADJUGATE_MAX_DIM: usize = 3;
}

struct Builder {
    constants: Vec<(u32, Op)>,
    program: Vec<(u32, T)>,
    constant: Vec<bool>,
    /// The (sin, cos) or (sinh, cosh) slots of an argument, made once for both.
    pairs: rustc_hash::FxHashMap<(u32, bool), (u32, u32)>,
    /// The `Deriv` slot of an argument.
    derivs: rustc_hash::FxHashMap<u32, u32>,
}

impl Builder {
    fn slot(&mut self, constant: bool) -> u32 {
        self.constant.push(constant);
        (self.constant.len() - 1) as u32
    }

    fn constant_op(&mut self, op: Op) -> u32 {
        let s = self.slot(true);
        self.constants.push((s, op));
        s
    }

    fn var(&mut self, t: T) -> u32 {
        let s = self.slot(false);
        self.program.push((s, t));
        s
    }

    fn is_const(&self, s: u32) -> bool {
        self.constant[s as usize]
    }

    fn mul(&mut self, a: u32, b: u32) -> u32 {
        match (self.is_const(a), self.is_const(b)) {
            (true, true) => self.constant_op(Op::Mul(a, b)),
            (false, true) => self.var(T::MulC(a, b)),
            (true, false) => self.var(T::MulC(b, a)),
            (false, false) if a == b => self.var(T::Square(a)),
            (false, false) => self.var(T::Mul(a, b)),
        }
    }

    fn recip(&mut self, a: u32) -> u32 {
        if self.is_const(a) {
            return self.constant_op(Op::Recip(a));
        }
        let one = self.constant_op(Op::Const(1f64.to_bits()));
        self.var(T::DivCV(one, a))
    }

    /// `base^n` by binary exponentiation.
    fn powi(&mut self, base: u32, n: i32) -> u32 {
        if self.is_const(base) {
            return self.constant_op(Op::Powi(base, n));
        }
        if n == 0 {
            return self.constant_op(Op::Const(1f64.to_bits()));
        }
        let mut m = n.unsigned_abs();
        let mut power = base;
        let mut acc: Option<u32> = None;
        loop {
            if m & 1 == 1 {
                acc = Some(match acc {
                    Some(a) => self.mul(a, power),
                    None => power,
                });
            }
            m >>= 1;
            if m == 0 {
                break;
            }
            power = self.mul(power, power);
        }
        let acc = acc.expect("n != 0 has a set bit");
        if n < 0 {
            self.recip(acc)
        } else {
            acc
        }
    }

    /// The slot of `Deriv(u)`, made once per argument.
    fn deriv(&mut self, u: u32) -> u32 {
        if let Some(&d) = self.derivs.get(&u) {
            return d;
        }
        let d = self.var(T::Deriv(u));
        self.derivs.insert(u, d);
        d
    }

    fn exp(&mut self, u: u32) -> u32 {
        let du = self.deriv(u);
        self.var(T::Exp { u, du })
    }

    fn func(&mut self, f: Func, u: u32) -> u32 {
        match f {
            Func::Sin | Func::Cos | Func::Sinh | Func::Cosh => {
                let circular = matches!(f, Func::Sin | Func::Cos);
                let (sin, cos) = match self.pairs.get(&(u, circular)) {
                    Some(&pair) => pair,
                    None => {
                        let du = self.deriv(u);
                        let sin = self.slot(false);
                        let cos = self.slot(false);
                        let op = if circular { T::Sin { u, du, cos } } else { T::Sinh { u, du, cosh: cos } };
                        self.program.push((sin, op));
                        self.program.push((cos, T::CosOf));
                        self.pairs.insert((u, circular), (sin, cos));
                        (sin, cos)
                    }
                };
                if matches!(f, Func::Sin | Func::Sinh) {
                    sin
                } else {
                    cos
                }
            }
            Func::Tan | Func::Tanh => {
                let du = self.deriv(u);
                let w = self.slot(false);
                let aux = self.slot(false);
                let sign = if f == Func::Tan { 1.0 } else { -1.0 };
                self.program.push((w, T::Tan { u, du, aux, sign }));
                self.program.push((aux, T::Aux));
                w
            }
            Func::Asin | Func::Acos => {
                let inner = self.slot(false);
                let root = self.slot(false);
                let w = self.slot(false);
                self.program.push((inner, T::Aux));
                self.program.push((root, T::Aux));
                let sign = if f == Func::Asin { 1.0 } else { -1.0 };
                self.program.push((w, T::Asin { u, inner, root, sign }));
                w
            }
            Func::Atan => {
                let aux = self.slot(false);
                self.program.push((aux, T::Aux));
                self.var(T::Atan { u, aux })
            }
            Func::Exp => self.exp(u),
            Func::Log => self.var(T::Log(u)),
            Func::Abs => self.var(T::Abs(u)),
        }
    }
}

impl<const L: usize> TaylorTape<L> {
    /// Prepares `tape` for Taylor coefficients up to `order`. `variable[k]` tells
    /// whether input `k` varies along a trajectory (state, time) or is constant
    /// (a parameter); every input starts at 0 on every lane.
    pub fn new(tape: &Tape, order: usize, variable: &[bool]) -> TaylorTape<L> {
        assert_eq!(variable.len(), tape.n_inputs(), "one flag per input");
        let mut b = Builder {
            constants: Vec::new(),
            program: Vec::new(),
            constant: Vec::new(),
            pairs: Default::default(),
            derivs: Default::default(),
        };
        let mut input_slots = vec![0; tape.n_inputs()];
        // The Taylor slot of each tape slot.
        let mut map: Vec<u32> = Vec::with_capacity(tape.len());
        for op in tape.ops() {
            let m = |s: u32| map[s as usize];
            let all_const = |b: &Builder, slots: &[u32]| slots.iter().all(|&s| b.is_const(m(s)));
            let slot = match *op {
                Op::Input(k) => {
                    let s = b.slot(!variable[k as usize]);
                    input_slots[k as usize] = s;
                    s
                }
                Op::Const(bits) => b.constant_op(Op::Const(bits)),
                // Every operand constant: evaluated once, as the tape would.
                Op::Add(x, y) | Op::Sub(x, y) | Op::Mul(x, y) | Op::Div(x, y) | Op::Powf(x, y) | Op::Atan2(x, y)
                    if all_const(&b, &[x, y]) =>
                {
                    b.constant_op(remap(*op, &map))
                }
                Op::Neg(x) | Op::Recip(x) | Op::Square(x) | Op::Powi(x, _) | Op::Sqrt(x) | Op::Func(_, x)
                    if all_const(&b, &[x]) =>
                {
                    b.constant_op(remap(*op, &map))
                }
                Op::Add(x, y) => match (b.is_const(m(x)), b.is_const(m(y))) {
                    (true, _) => b.var(T::AddC(m(y), m(x))),
                    (_, true) => b.var(T::AddC(m(x), m(y))),
                    _ => b.var(T::Add(m(x), m(y))),
                },
                Op::Sub(x, y) => match (b.is_const(m(x)), b.is_const(m(y))) {
                    (true, _) => b.var(T::SubCV(m(x), m(y))),
                    (_, true) => b.var(T::SubVC(m(x), m(y))),
                    _ => b.var(T::Sub(m(x), m(y))),
                },
                Op::Mul(x, y) => b.mul(m(x), m(y)),
                Op::Div(x, y) => match (b.is_const(m(x)), b.is_const(m(y))) {
                    (true, _) => b.var(T::DivCV(m(x), m(y))),
                    (_, true) => b.var(T::DivVC(m(x), m(y))),
                    _ => b.var(T::Div(m(x), m(y))),
                },
                Op::Neg(x) => b.var(T::Neg(m(x))),
                Op::Recip(x) => b.recip(m(x)),
                Op::Square(x) => b.var(T::Square(m(x))),
                Op::Powi(x, n) => b.powi(m(x), n),
                Op::Powf(x, y) if b.is_const(m(y)) => b.var(T::PowC(m(x), m(y))),
                Op::Powf(x, y) => {
                    // x^y = exp(y ln x)
                    let ln =
                        if b.is_const(m(x)) { b.constant_op(Op::Func(Func::Log, m(x))) } else { b.var(T::Log(m(x))) };
                    let prod = b.mul(m(y), ln);
                    b.exp(prod)
                }
                Op::Sqrt(x) => b.var(T::Sqrt(m(x))),
                Op::Func(f, x) => b.func(f, m(x)),
                Op::Atan2(y, x) => {
                    let aux = b.slot(false);
                    b.program.push((aux, T::Aux));
                    b.var(T::Atan2 { y: m(y), x: m(x), aux })
                }
            };
            map.push(slot);
        }
        let n_slots = b.constant.len();
        TaylorTape {
            order,
            coef: vec![[0.0; L]; n_slots * (order + 1)],
            constants: b.constants,
            program: b.program,
            input_slots,
            variable_inputs: variable.to_vec(),
            outputs: tape.output_slots().iter().map(|&s| map[s as usize]).collect(),
            constant: b.constant,
            native: None,
            second_order: None,
            rhs: Vec::new(),
            fused: host_has_fma(),
        }
    }

    /// Prepares the whole Taylor expansion of the linearly implicit
    /// second-order system `system` ([`LinearSecondOrder`]: `A y'' = b` read
    /// off this tape), run by [`expand_second_order`](Self::expand_second_order):
    /// interpreted until native code is compiled
    /// ([`compile_second_order`](Self::compile_second_order),
    /// [`compile_second_order_in_background`](Self::compile_second_order_in_background)).
    ///
    /// The Cauchy product gives `A[0] y''[k] = b[k] − Σ_{j=1..k} A[j] y''[k−j]`
    /// at each order `k`, and `y[k+1] = y'[k]/(k+1)`, `y'[k+1] = y''[k]/(k+1)`;
    /// `A[0]` is inverted once per expansion as `system.inverse` says.
    ///
    /// # Panics
    ///
    /// When the tape's inputs and outputs are not those `system` describes, or
    /// `system.inverse` does not apply to it (see [`ClosedFormInverse`]).
    pub fn set_second_order(&mut self, system: &LinearSecondOrder<'_>) {
        let LinearSecondOrder { dim: n, entries, inverse } = *system;
        assert!(self.input_slots.len() > 2 * n, "inputs y, y', t come first");
        assert!(self.variable_inputs[..=2 * n].iter().all(|&v| v), "y, y' and t vary");
        assert_eq!(self.outputs.len(), entries.len() + n, "outputs: the entries of A, then b");
        assert!(entries.iter().all(|&(i, j)| i < n && j < n), "entries of A lie in its n × n");
        match inverse {
            ClosedFormInverse::Diagonal => {
                assert!(entries.iter().all(|&(i, j)| i == j), "ClosedFormInverse::Diagonal: an entry off the diagonal")
            }
            ClosedFormInverse::Adjugate => {
                let max = ClosedFormInverse::ADJUGATE_MAX_DIM;
                assert!(n <= max, "ClosedFormInverse::Adjugate: n = {n} > {max}")
            }
        }
        let diagonal = inverse == ClosedFormInverse::Diagonal;
        let stride = self.order + 1;
        // A tape prepared again keeps its extra slots.
        let first = match &self.second_order {
            Some(s) => s.layout.second[0] as usize,
            None => self.coef.len() / stride,
        };
        let extra = n + if diagonal { n } else { n * n };
        let slots: Vec<u32> = (first..first + extra).map(|s| s as u32).collect();
        let (second, inverse_slots) = slots.split_at(n);
        let layout = SecondOrderLayout {
            n,
            entries: entries.to_vec(),
            y: self.input_slots[..n].to_vec(),
            dy: self.input_slots[n..2 * n].to_vec(),
            matrix: self.outputs[..entries.len()].to_vec(),
            rhs: self.outputs[entries.len()..].to_vec(),
            varying: (0..entries.len()).map(|e| !self.output_is_constant(e)).collect(),
            second: second.to_vec(),
            inverse: inverse_slots.to_vec(),
            diagonal,
        };
        self.coef.resize((first + extra) * stride, [0.0; L]);
        self.rhs = vec![[0.0; L]; n];
        self.second_order =
            Some(SecondOrder { layout: Arc::new(layout), native: Arc::new(OnceLock::new()), compiling: false });
    }

    /// Undoes [`set_second_order`](Self::set_second_order): the tape is
    /// computed order by order again.
    pub fn clear_second_order(&mut self) {
        if let Some(s) = self.second_order.take() {
            self.coef.truncate(s.layout.second[0] as usize * (self.order + 1));
        }
    }

    /// Whether native code for the second-order expansion would be too large
    /// to pay for its compilation.
    fn second_order_too_large(&self) -> bool {
        let entries = self.second_order.as_ref().map_or(0, |s| s.layout.entries.len());
        self.native_work() + entries * (self.order + 1) * (self.order + 2) / 2 * L > NATIVE_MAX_WORK
    }

    /// [`set_second_order`](Self::set_second_order), then compiles the whole
    /// expansion into native code, each order's function with the coupling,
    /// so that the functions run in turn make the whole expansion (on this
    /// thread and a helper). Returns `Ok(false)` when the code would be too
    /// large to pay for its compilation; then, and on an error, the tape is
    /// left as it was.
    ///
    /// # Panics
    ///
    /// As [`set_second_order`](Self::set_second_order).
    pub fn compile_second_order(&mut self, system: &LinearSecondOrder<'_>) -> Result<bool, JitError> {
        self.set_second_order(system);
        if self.second_order_too_large() {
            self.clear_second_order();
            return Ok(false);
        }
        let (program, len) = (self.program.clone(), self.buffer_len());
        let s = self.second_order.as_mut().expect("set above");
        match NativeTaylor::second_order::<L>(program, self.order, (*s.layout).clone(), len) {
            Ok(native) => {
                let _ = s.native.set(Ok(native));
                s.compiling = true;
                Ok(true)
            }
            Err(e) => {
                self.clear_second_order();
                Err(e)
            }
        }
    }

    /// [`compile_second_order`](Self::compile_second_order) with the system C
    /// compiler instead of cranelift: code at the machine's full vector width
    /// (eight lanes per instruction with AVX-512, against cranelift's two),
    /// cached per source and machine, with the same numbers bit for bit.
    /// Returns `Ok(false)` when the code would be too large; then, and on an
    /// error (no compiler, say), the tape is left as it was.
    ///
    /// # Panics
    ///
    /// As [`set_second_order`](Self::set_second_order).
    pub fn compile_second_order_c(&mut self, system: &LinearSecondOrder<'_>) -> Result<bool, CcError> {
        self.set_second_order(system);
        if self.second_order_too_large() {
            self.clear_second_order();
            return Ok(false);
        }
        let len = self.buffer_len();
        let s = self.second_order.as_mut().expect("set above");
        match NativeTaylor::second_order_c::<L>(&self.program, self.order, &s.layout, len) {
            Ok(native) => {
                let _ = s.native.set(Ok(native));
                s.compiling = true;
                Ok(true)
            }
            Err(e) => {
                self.clear_second_order();
                Err(e)
            }
        }
    }

    /// [`compile_native`](Self::compile_native) with the system C compiler
    /// (see [`compile_second_order_c`](Self::compile_second_order_c)).
    pub fn compile_native_c(&mut self) -> Result<bool, CcError> {
        if self.native_work() > NATIVE_MAX_WORK {
            return Ok(false);
        }
        self.native = Some(Arc::new(NativeTaylor::orders_c(self)?));
        Ok(true)
    }

    /// Which code computes the expansions (once a compilation started in
    /// the background has finished; this does not wait for it).
    pub fn code(&self) -> TaylorCode {
        let native = match &self.second_order {
            Some(s) => s.native.get().and_then(|r| r.as_ref().ok()),
            None => self.native.as_deref(),
        };
        match native {
            None => TaylorCode::Interpreted,
            Some(n) => match n.c_build() {
                Some(build) => TaylorCode::C(build.clone()),
                None => TaylorCode::Cranelift,
            },
        }
    }

    /// Compiles the second-order expansion prepared by
    /// [`set_second_order`](Self::set_second_order) into native code on this
    /// thread and a helper, and returns as soon as this thread has no function
    /// left to take: the expansions run interpreted until the helper has
    /// finished its last, then natively. With the same numbers, bit for bit,
    /// so a run does not depend on when the code became ready. The helper
    /// gives up when every clone of this tape is gone. Returns false (nothing
    /// to wait for) when there is no second-order expansion or its code would
    /// be too large.
    pub fn compile_second_order_in_background(&mut self) -> bool {
        if self.second_order.is_none() || self.second_order_too_large() {
            return false;
        }
        let (program, order, len) = (self.program.clone(), self.order, self.buffer_len());
        let s = self.second_order.as_mut().expect("checked above");
        s.compiling = true;
        let layout = (*s.layout).clone();
        let cell = Arc::downgrade(&s.native);
        let wanted = cell.clone();
        NativeTaylor::second_order_then::<L>(
            program,
            order,
            layout,
            len,
            move || wanted.strong_count() > 0,
            move |result| {
                if let Some(cell) = cell.upgrade() {
                    let _ = cell.set(result);
                }
            },
        );
        true
    }

    /// Whether [`set_second_order`](Self::set_second_order) was called.
    pub fn is_second_order(&self) -> bool {
        self.second_order.is_some()
    }

    /// Waits for the compilation of the second-order expansion, if one was
    /// started; whether its expansions now run native code.
    pub fn wait_for_native(&self) -> bool {
        match &self.second_order {
            Some(s) if s.compiling => s.native.wait().is_ok(),
            _ => false,
        }
    }

    /// The whole expansion of the second-order system: from order 0 of `y`, `y'`
    /// and orders 0 and 1 of `t` in the inputs' coefficients, writes orders
    /// `1..=order` of `y` and `y'` there and into `series` (order-major:
    /// `series[k·2n + i]` is order k of `[y, y'][i]`; the caller's order 0 is
    /// left as it is). Native code where it is compiled, the interpreter
    /// otherwise: for one lane, the same numbers.
    ///
    /// # Panics
    ///
    /// When [`set_second_order`](Self::set_second_order) was not called, or
    /// `series` is not `(order + 1)·2n` long.
    pub fn expand_second_order(&mut self, series: &mut [Lanes<L>]) {
        let s = self.second_order.as_ref().expect("set_second_order was called");
        if let Some(Ok(native)) = s.native.get() {
            native.run_all(self.coef.as_flattened_mut(), series.as_flattened_mut());
            return;
        }
        let layout = Arc::clone(&s.layout);
        assert_eq!(series.len(), (self.order + 1) * 2 * layout.n, "expand_second_order: wrong series length");
        #[cfg(target_arch = "x86_64")]
        if self.fused {
            // SAFETY: as in `compute`.
            #[allow(unsafe_code)]
            unsafe {
                return self.expand_fma(&layout, series);
            }
        }
        if self.fused {
            self.expand_interpreted::<true>(&layout, series)
        } else {
            self.expand_interpreted::<false>(&layout, series)
        }
    }

    /// [`expand_interpreted`](Self::expand_interpreted) with fused
    /// multiply-adds compiled to the processor's instruction.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    fn expand_fma(&mut self, layout: &SecondOrderLayout, series: &mut [Lanes<L>]) {
        self.expand_interpreted::<true>(layout, series)
    }

    /// The second-order expansion, interpreted: the native code's steps.
    #[inline(always)]
    fn expand_interpreted<const F: bool>(&mut self, layout: &SecondOrderLayout, series: &mut [Lanes<L>]) {
        for k in 0..self.order {
            self.compute_interpreted::<F>(k);
            if k == 0 {
                self.invert_interpreted(layout);
            }
            self.couple_interpreted::<F>(layout, k, series);
        }
    }

    /// `A[0]⁻¹` on every lane into its slots, as the native code computes it
    /// (reciprocals, or the adjugate over the determinant).
    fn invert_interpreted(&mut self, s: &SecondOrderLayout) {
        let (n, stride) = (s.n, self.order + 1);
        let at = |slot: u32| slot as usize * stride;
        let c = &mut self.coef;
        for lane in 0..L {
            if s.diagonal {
                for (e, &(i, _)) in s.entries.iter().enumerate() {
                    c[at(s.inverse[i])][lane] = 1.0 / c[at(s.matrix[e])][lane];
                }
                continue;
            }
            let mut m = [[0.0; ClosedFormInverse::ADJUGATE_MAX_DIM]; ClosedFormInverse::ADJUGATE_MAX_DIM];
            for (e, &(i, j)) in s.entries.iter().enumerate() {
                m[i][j] = c[at(s.matrix[e])][lane];
            }
            // Cofactors C_ij; A⁻¹_ij = C_ji / det.
            let mut cof = [[0.0; ClosedFormInverse::ADJUGATE_MAX_DIM]; ClosedFormInverse::ADJUGATE_MAX_DIM];
            match n {
                1 => cof[0][0] = 1.0,
                2 => cof = [[m[1][1], -m[1][0], 0.0], [-m[0][1], m[0][0], 0.0], [0.0; 3]],
                _ => {
                    for i in 0..3 {
                        for j in 0..3 {
                            let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
                            let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
                            cof[i][j] = m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
                        }
                    }
                }
            }
            let mut det = m[0][0] * cof[0][0];
            for j in 1..n {
                det += m[0][j] * cof[0][j];
            }
            let r = 1.0 / det;
            for i in 0..n {
                for j in 0..n {
                    c[at(s.inverse[i * n + j])][lane] = cof[j][i] * r;
                }
            }
        }
    }

    /// Order `k` of y'' and order `k + 1` of y and y' (into the slots and
    /// `series`), as the native code computes them:
    /// `y''[k] = A[0]⁻¹ (b[k] − Σ_{j=1..k} A[j] y''[k−j])`.
    #[inline(always)]
    fn couple_interpreted<const F: bool>(&mut self, s: &SecondOrderLayout, k: usize, series: &mut [Lanes<L>]) {
        let (n, stride) = (s.n, self.order + 1);
        let at = |slot: u32, j: usize| slot as usize * stride + j;
        let c = &mut self.coef;
        let rhs = &mut self.rhs;
        for i in 0..n {
            rhs[i] = c[at(s.rhs[i], k)];
        }
        if k > 0 {
            for (e, &(row, col)) in s.entries.iter().enumerate() {
                if !s.varying[e] {
                    continue;
                }
                let mut acc = [0.0; L];
                for j in 1..=k {
                    madd::<F, L>(&mut acc, &c[at(s.matrix[e], j)], &c[at(s.second[col], k - j)]);
                }
                rhs[row] = lanes(|l| rhs[row][l] - acc[l]);
            }
        }
        let scale = 1.0 / (k + 1) as f64;
        let row = (k + 1) * 2 * n;
        for i in 0..n {
            let a = if s.diagonal {
                let r = c[at(s.inverse[i], 0)];
                lanes(|l| r[l] * rhs[i][l])
            } else {
                let r = c[at(s.inverse[i * n], 0)];
                let mut acc = lanes(|l| r[l] * rhs[0][l]);
                for j in 1..n {
                    madd::<F, L>(&mut acc, &c[at(s.inverse[i * n + j], 0)], &rhs[j]);
                }
                acc
            };
            c[at(s.second[i], k)] = a;
            let next_v = lanes(|l| a[l] * scale);
            c[at(s.dy[i], k + 1)] = next_v;
            let v = c[at(s.dy[i], k)];
            let next_q = lanes(|l| v[l] * scale);
            c[at(s.y[i], k + 1)] = next_q;
            series[row + i] = next_q;
            series[row + n + i] = next_v;
        }
    }

    /// Compiles every order to native code ([`crate::Compiled`]'s JIT), used by
    /// [`compute`](Self::compute) from then on. Returns `Ok(false)` and stays
    /// interpreted when the unrolled code would be too large to pay for its
    /// compilation, and an error when the host has no code generator.
    pub fn compile_native(&mut self) -> Result<bool, JitError> {
        if self.native_work() > NATIVE_MAX_WORK {
            return Ok(false);
        }
        self.native = Some(Arc::new(NativeTaylor::new(self)?));
        Ok(true)
    }

    /// The multiply-adds of one expansion on all lanes: `O(p)` for a linear
    /// instruction, `O(p²)` for a convolution. Native code is this long.
    fn native_work(&self) -> usize {
        (0..=self.order).map(|k| self.order_work(k)).sum::<usize>() * L
    }

    /// The multiply-adds of order `k` on one lane: one per linear instruction,
    /// `k + 1` per convolution (two for the pairs and the quotients by a root).
    pub(crate) fn order_work(&self, k: usize) -> usize {
        self.program
            .iter()
            .map(|(_, op)| match op {
                T::Add(..)
                | T::Sub(..)
                | T::Neg(_)
                | T::AddC(..)
                | T::SubVC(..)
                | T::SubCV(..)
                | T::MulC(..)
                | T::DivVC(..)
                | T::Abs(_)
                | T::Deriv(_)
                | T::CosOf
                | T::Aux => 1,
                T::Sin { .. } | T::Sinh { .. } | T::Tan { .. } | T::Asin { .. } | T::Atan2 { .. } => 2 * (k + 1),
                _ => k + 1,
            })
            .sum()
    }

    /// Whether [`compute`](Self::compute) runs native code.
    pub fn is_native(&self) -> bool {
        self.native.is_some()
    }

    /// The variable instructions, for the code generator.
    #[cfg(feature = "jit")]
    pub(crate) fn program(&self) -> &[(u32, T)] {
        &self.program
    }

    /// The number of `f64` in the coefficient buffer.
    pub(crate) fn buffer_len(&self) -> usize {
        self.coef.len() * L
    }

    /// The highest order computed.
    pub fn order(&self) -> usize {
        self.order
    }

    /// The number of variable instructions (a measure of the cost of one order).
    pub fn len(&self) -> usize {
        self.program.len()
    }

    /// True when no instruction varies (every output is constant).
    pub fn is_empty(&self) -> bool {
        self.program.is_empty()
    }

    /// Whether output `i` is constant along a trajectory.
    pub fn output_is_constant(&self, i: usize) -> bool {
        self.constant[self.outputs[i] as usize]
    }

    fn at(&self, slot: u32, k: usize) -> usize {
        slot as usize * (self.order + 1) + k
    }

    /// Sets constant input `k` on every lane; call [`refresh_constants`](Self::refresh_constants) after.
    pub fn set_constant_input(&mut self, k: usize, value: Lanes<L>) {
        debug_assert!(!self.variable_inputs[k]);
        let i = self.at(self.input_slots[k], 0);
        self.coef[i] = value;
    }

    /// Evaluates the constant slots from the constant inputs.
    pub fn refresh_constants(&mut self) {
        for idx in 0..self.constants.len() {
            let (slot, op) = self.constants[idx];
            let v = |s: u32, lane: usize| self.coef[self.at(s, 0)][lane];
            let mut out = [0.0; L];
            for (lane, o) in out.iter_mut().enumerate() {
                *o = match op {
                    Op::Input(_) => unreachable!("inputs are not instructions here"),
                    Op::Const(bits) => f64::from_bits(bits),
                    Op::Add(a, b) => v(a, lane) + v(b, lane),
                    Op::Sub(a, b) => v(a, lane) - v(b, lane),
                    Op::Mul(a, b) => v(a, lane) * v(b, lane),
                    Op::Div(a, b) => v(a, lane) / v(b, lane),
                    Op::Neg(a) => -v(a, lane),
                    Op::Recip(a) => 1.0 / v(a, lane),
                    Op::Square(a) => v(a, lane) * v(a, lane),
                    Op::Powi(a, n) => v(a, lane).powi(n),
                    Op::Powf(a, b) => v(a, lane).powf(v(b, lane)),
                    Op::Sqrt(a) => v(a, lane).sqrt(),
                    Op::Func(f, a) => f.apply(v(a, lane)),
                    Op::Atan2(a, b) => v(a, lane).atan2(v(b, lane)),
                };
            }
            let i = self.at(slot, 0);
            self.coef[i] = out;
        }
    }

    /// The coefficient buffer: order `k` of the slot at `index` is at `index + k`
    /// (see [`input_index`](Self::input_index), [`output_index`](Self::output_index)).
    pub fn coefficients(&self) -> &[Lanes<L>] {
        &self.coef
    }

    /// The coefficient buffer, to set the variable inputs' coefficients.
    pub fn coefficients_mut(&mut self) -> &mut [Lanes<L>] {
        &mut self.coef
    }

    /// Where order 0 of input `i` sits in [`coefficients`](Self::coefficients).
    pub fn input_index(&self, i: usize) -> usize {
        self.at(self.input_slots[i], 0)
    }

    /// Where order 0 of output `i` sits in [`coefficients`](Self::coefficients);
    /// a constant output's higher orders there are zero.
    pub fn output_index(&self, i: usize) -> usize {
        self.at(self.outputs[i], 0)
    }

    /// The coefficient of order `k` of variable input `i`, to be set before
    /// [`compute`](Self::compute) of order `k`.
    pub fn input_mut(&mut self, i: usize, k: usize) -> &mut Lanes<L> {
        debug_assert!(self.variable_inputs[i]);
        let at = self.at(self.input_slots[i], k);
        &mut self.coef[at]
    }

    /// The coefficient of order `k` of output `i` (zero above order 0 for a
    /// constant output), valid once order `k` is computed.
    pub fn output(&self, i: usize, k: usize) -> Lanes<L> {
        let slot = self.outputs[i];
        if self.constant[slot as usize] && k > 0 {
            return [0.0; L];
        }
        self.coef[self.at(slot, k)]
    }

    /// Computes order `k` of every variable slot. Orders `0..k` must have been
    /// computed, and the variable inputs' orders `0..=k` set.
    pub fn compute(&mut self, k: usize) {
        assert!(k <= self.order, "order {k} above the tape's {}", self.order);
        if let Some(native) = &self.native {
            native.run(k, self.coef.as_flattened_mut());
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if self.fused {
            // SAFETY: `fused` is set only where the processor has FMA
            // (`host_has_fma`), the one feature `compute_fma` enables.
            #[allow(unsafe_code)]
            unsafe {
                return self.compute_fma(k);
            }
        }
        if self.fused {
            self.compute_interpreted::<true>(k)
        } else {
            self.compute_interpreted::<false>(k)
        }
    }

    /// [`compute_interpreted`](Self::compute_interpreted) with fused
    /// multiply-adds compiled to the processor's instruction.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    fn compute_fma(&mut self, k: usize) {
        self.compute_interpreted::<true>(k)
    }

    /// Order `k` of every variable slot, interpreted; `F`: whether the
    /// multiply-adds that native code fuses are fused ([`madd`]).
    #[inline(always)]
    fn compute_interpreted<const F: bool>(&mut self, k: usize) {
        let stride = self.order + 1;
        for idx in 0..self.program.len() {
            let (out, op) = self.program[idx];
            let w = out as usize * stride;
            let c = &mut self.coef;
            let s = |slot: u32| slot as usize * stride;
            let value: Lanes<L> = if k == 0 {
                match op {
                    T::CosOf | T::Aux => continue,
                    _ => order_zero(c, op, stride),
                }
            } else {
                match op {
                    T::Add(a, b) => lanes(|l| c[s(a) + k][l] + c[s(b) + k][l]),
                    T::Sub(a, b) => lanes(|l| c[s(a) + k][l] - c[s(b) + k][l]),
                    T::Neg(a) => lanes(|l| -c[s(a) + k][l]),
                    T::AddC(a, _) | T::SubVC(a, _) => c[s(a) + k],
                    T::SubCV(_, a) => lanes(|l| -c[s(a) + k][l]),
                    T::MulC(a, b) => lanes(|l| c[s(a) + k][l] * c[s(b)][l]),
                    T::DivVC(a, b) => lanes(|l| c[s(a) + k][l] / c[s(b)][l]),
                    T::Mul(a, b) => {
                        let (a, b) = (s(a), s(b));
                        let mut acc = [0.0; L];
                        for (x, y) in c[a..=a + k].iter().zip(c[b..=b + k].iter().rev()) {
                            madd::<F, L>(&mut acc, x, y);
                        }
                        acc
                    }
                    T::Square(a) => {
                        let a = s(a);
                        let mut acc = [0.0; L];
                        for j in 0..k.div_ceil(2) {
                            madd::<F, L>(&mut acc, &c[a + j], &c[a + k - j]);
                        }
                        let mut out = lanes(|l| 2.0 * acc[l]);
                        if k.is_multiple_of(2) {
                            fma(&mut out, &c[a + k / 2], &c[a + k / 2]);
                        }
                        out
                    }
                    T::Div(a, b) => {
                        // w = a/b: w[k] = (a[k] - Σ_{j=1..k} b[j] w[k-j]) / b[0]
                        let (a, b) = (s(a), s(b));
                        let mut acc = c[a + k];
                        for j in 1..=k {
                            fms(&mut acc, &c[b + j], &c[w + k - j]);
                        }
                        lanes(|l| acc[l] / c[b][l])
                    }
                    T::DivCV(_, b) => {
                        let b = s(b);
                        let mut acc = [0.0; L];
                        for j in 1..=k {
                            fms(&mut acc, &c[b + j], &c[w + k - j]);
                        }
                        lanes(|l| acc[l] / c[b][l])
                    }
                    T::Sqrt(a) => {
                        // w² = a: w[k] = (a[k] - Σ_{j=1..k-1} w[j] w[k-j]) / (2 w[0])
                        let a = s(a);
                        let mut acc = c[a + k];
                        for j in 1..k {
                            fms(&mut acc, &c[w + j], &c[w + k - j]);
                        }
                        lanes(|l| acc[l] / (2.0 * c[w][l]))
                    }
                    T::PowC(a, e) => {
                        // a w' = α a' w: w[k] = Σ_{j=0..k-1} (α(k-j) - j) a[k-j] w[j] / (k a[0])
                        let (a, e) = (s(a), s(e));
                        let kf = k as f64;
                        let mut acc = [0.0; L];
                        for j in 0..k {
                            let (kj, jf) = ((k - j) as f64, j as f64);
                            for l in 0..L {
                                acc[l] += (c[e][l] * kj - jf) * c[a + k - j][l] * c[w + j][l];
                            }
                        }
                        lanes(|l| acc[l] / (kf * c[a][l]))
                    }
                    T::Deriv(a) => {
                        let kf = k as f64;
                        lanes(|l| kf * c[s(a) + k][l])
                    }
                    T::Exp { du, .. } => {
                        // w' = u' w: w[k] = Σ_{j=1..k} j u[j] w[k-j] / k
                        derived::<F, L>(c, s(du), w, k)
                    }
                    T::Log(a) => {
                        // a w' = a': w[k] = (a[k] - Σ_{j=1..k-1} j w[j] a[k-j] / k) / a[0]
                        let a = s(a);
                        let sum = weighted::<F, L>(c, w, a, k, 1, k - 1);
                        lanes(|l| (c[a + k][l] - sum[l]) / c[a][l])
                    }
                    T::Sin { du, cos, .. } => {
                        let (du, cs) = (s(du), s(cos));
                        let (sin, cos) = derived_pair::<F, L>(c, du, cs, w, k);
                        c[cs + k] = lanes(|l| -cos[l]);
                        sin
                    }
                    T::Sinh { du, cosh, .. } => {
                        let (du, ch) = (s(du), s(cosh));
                        let (sinh, cosh) = derived_pair::<F, L>(c, du, ch, w, k);
                        c[ch + k] = cosh;
                        sinh
                    }
                    T::Tan { du, aux, sign, .. } => {
                        // w' = u' (1 ± w²)
                        let (du, x) = (s(du), s(aux));
                        let v = derived::<F, L>(c, du, x, k);
                        c[w + k] = v;
                        let mut sq = [0.0; L];
                        for j in 0..=k {
                            madd::<F, L>(&mut sq, &c[w + j], &c[w + k - j]);
                        }
                        c[x + k] = lanes(|l| sign * sq[l]);
                        v
                    }
                    T::Asin { u, inner, root, sign } => {
                        // inner = 1 - u², root = √inner, root·w' = ±u'
                        let (u, i, r) = (s(u), s(inner), s(root));
                        let mut sq = [0.0; L];
                        for j in 0..=k {
                            madd::<F, L>(&mut sq, &c[u + j], &c[u + k - j]);
                        }
                        c[i + k] = lanes(|l| -sq[l]);
                        let mut acc = c[i + k];
                        for j in 1..k {
                            fms(&mut acc, &c[r + j], &c[r + k - j]);
                        }
                        c[r + k] = lanes(|l| acc[l] / (2.0 * c[r][l]));
                        derivative_quotient(c, u, r, w, k, sign)
                    }
                    T::Atan { u, aux } => {
                        // aux = 1 + u², aux·w' = u'
                        let (u, x) = (s(u), s(aux));
                        let mut sq = [0.0; L];
                        for j in 0..=k {
                            madd::<F, L>(&mut sq, &c[u + j], &c[u + k - j]);
                        }
                        c[x + k] = sq;
                        derivative_quotient(c, u, x, w, k, 1.0)
                    }
                    T::Atan2 { y, x, aux } => {
                        // aux = x² + y², aux·w' = x y' - y x'
                        let (y, x, d) = (s(y), s(x), s(aux));
                        let mut sq = [0.0; L];
                        for j in 0..=k {
                            fma(&mut sq, &c[x + j], &c[x + k - j]);
                            fma(&mut sq, &c[y + j], &c[y + k - j]);
                        }
                        c[d + k] = sq;
                        // z[k-1] = Σ_{j=0..k-1} (k-j) (x[j] y[k-j] - y[j] x[k-j])
                        let mut acc = [0.0; L];
                        for j in 0..k {
                            let kj = (k - j) as f64;
                            for l in 0..L {
                                acc[l] += kj * (c[x + j][l] * c[y + k - j][l] - c[y + j][l] * c[x + k - j][l]);
                            }
                        }
                        for j in 1..k {
                            let kj = (k - j) as f64;
                            for l in 0..L {
                                acc[l] -= kj * c[d + j][l] * c[w + k - j][l];
                            }
                        }
                        lanes(|l| acc[l] / (k as f64 * c[d][l]))
                    }
                    T::Abs(a) => {
                        let a = s(a);
                        lanes(|l| if c[a][l] < 0.0 { -c[a + k][l] } else { c[a + k][l] })
                    }
                    T::CosOf | T::Aux => continue,
                }
            };
            c[w + k] = value;
        }
    }
}

/// Order 0 of a variable instruction: its ordinary value (and that of its
/// companion slots).
fn order_zero<const L: usize>(c: &mut [Lanes<L>], op: T, stride: usize) -> Lanes<L> {
    let s = |slot: u32| slot as usize * stride;
    match op {
        T::Add(a, b) | T::AddC(a, b) => lanes(|l| c[s(a)][l] + c[s(b)][l]),
        T::Sub(a, b) | T::SubVC(a, b) | T::SubCV(a, b) => lanes(|l| c[s(a)][l] - c[s(b)][l]),
        T::Mul(a, b) | T::MulC(a, b) => lanes(|l| c[s(a)][l] * c[s(b)][l]),
        T::Div(a, b) | T::DivVC(a, b) | T::DivCV(a, b) => lanes(|l| c[s(a)][l] / c[s(b)][l]),
        T::Neg(a) => lanes(|l| -c[s(a)][l]),
        T::Square(a) => lanes(|l| c[s(a)][l] * c[s(a)][l]),
        T::Sqrt(a) => lanes(|l| c[s(a)][l].sqrt()),
        T::PowC(a, e) => lanes(|l| c[s(a)][l].powf(c[s(e)][l])),
        T::Exp { u, .. } => lanes(|l| c[s(u)][l].exp()),
        T::Deriv(_) => [0.0; L],
        T::Log(a) => lanes(|l| c[s(a)][l].ln()),
        T::Abs(a) => lanes(|l| c[s(a)][l].abs()),
        T::Sin { u, cos, .. } => {
            let (mut sin, mut cos_v) = ([0.0; L], [0.0; L]);
            for l in 0..L {
                (sin[l], cos_v[l]) = crate::trig::sin_cos_f64(c[s(u)][l]);
            }
            c[s(cos)] = cos_v;
            sin
        }
        T::Sinh { u, cosh, .. } => {
            c[s(cosh)] = lanes(|l| c[s(u)][l].cosh());
            lanes(|l| c[s(u)][l].sinh())
        }
        T::Tan { u, aux, sign, .. } => {
            let v = lanes(|l| if sign > 0.0 { c[s(u)][l].tan() } else { c[s(u)][l].tanh() });
            c[s(aux)] = lanes(|l| 1.0 + sign * v[l] * v[l]);
            v
        }
        T::Asin { u, inner, root, sign } => {
            let inner_v = lanes(|l| 1.0 - c[s(u)][l] * c[s(u)][l]);
            c[s(inner)] = inner_v;
            c[s(root)] = lanes(|l| inner_v[l].sqrt());
            lanes(|l| if sign > 0.0 { c[s(u)][l].asin() } else { c[s(u)][l].acos() })
        }
        T::Atan { u, aux } => {
            c[s(aux)] = lanes(|l| 1.0 + c[s(u)][l] * c[s(u)][l]);
            lanes(|l| c[s(u)][l].atan())
        }
        T::Atan2 { y, x, aux } => {
            c[s(aux)] = lanes(|l| c[s(x)][l] * c[s(x)][l] + c[s(y)][l] * c[s(y)][l]);
            lanes(|l| c[s(y)][l].atan2(c[s(x)][l]))
        }
        T::CosOf | T::Aux => unreachable!("written by their instruction"),
    }
}

/// `Σ_{j=1..=k} du[j] b[k-j] / k` with `du[j] = j u[j]` (the recurrence of `w' = u' b`).
#[inline(always)]
fn derived<const F: bool, const L: usize>(c: &[Lanes<L>], du: usize, b: usize, k: usize) -> Lanes<L> {
    let mut acc = [0.0; L];
    for (d, x) in c[du + 1..=du + k].iter().zip(c[b..b + k].iter().rev()) {
        madd::<F, L>(&mut acc, d, x);
    }
    let kf = k as f64;
    lanes(|l| acc[l] / kf)
}

/// [`derived`] for two slots `a` and `b` at once (sin and cos, sinh and
/// cosh): the same sums, two independent chains in one loop.
#[inline(always)]
fn derived_pair<const F: bool, const L: usize>(
    c: &[Lanes<L>],
    du: usize,
    a: usize,
    b: usize,
    k: usize,
) -> (Lanes<L>, Lanes<L>) {
    let (mut sa, mut sb) = ([0.0; L], [0.0; L]);
    let terms = c[du + 1..=du + k].iter().zip(c[a..a + k].iter().rev()).zip(c[b..b + k].iter().rev());
    for ((d, x), y) in terms {
        madd::<F, L>(&mut sa, d, x);
        madd::<F, L>(&mut sb, d, y);
    }
    let kf = k as f64;
    (lanes(|l| sa[l] / kf), lanes(|l| sb[l] / kf))
}

/// `Σ_{j=lo..=hi} j a[j] b[k-j] / k` (the recurrence of `w' = a' b`).
#[inline(always)]
fn weighted<const F: bool, const L: usize>(
    c: &[Lanes<L>],
    a: usize,
    b: usize,
    k: usize,
    lo: usize,
    hi: usize,
) -> Lanes<L> {
    let mut acc = [0.0; L];
    for j in lo..=hi {
        let jf = j as f64;
        let weighted: Lanes<L> = lanes(|l| jf * c[a + j][l]);
        madd::<F, L>(&mut acc, &weighted, &c[b + k - j]);
    }
    let kf = k as f64;
    lanes(|l| acc[l] / kf)
}

/// `w[k]` from `d·w' = sign·u'`:
/// `w[k] = (sign·k·u[k] - Σ_{j=1..k-1} (k-j) d[j] w[k-j]) / (k d[0])`.
#[inline(always)]
fn derivative_quotient<const L: usize>(c: &[Lanes<L>], u: usize, d: usize, w: usize, k: usize, sign: f64) -> Lanes<L> {
    let kf = k as f64;
    let mut acc: Lanes<L> = lanes(|l| sign * kf * c[u + k][l]);
    for j in 1..k {
        let kj = (k - j) as f64;
        for l in 0..L {
            acc[l] -= kj * c[d + j][l] * c[w + k - j][l];
        }
    }
    lanes(|l| acc[l] / (kf * c[d][l]))
}

#[inline(always)]
fn lanes<const L: usize>(f: impl Fn(usize) -> f64) -> Lanes<L> {
    std::array::from_fn(f)
}

/// `acc += a·b` lane by lane, fused (one rounding) when `F`: what native
/// code computes for a sum of products where the host has FMA.
#[inline(always)]
fn madd<const F: bool, const L: usize>(acc: &mut Lanes<L>, a: &Lanes<L>, b: &Lanes<L>) {
    for l in 0..L {
        acc[l] = if F { a[l].mul_add(b[l], acc[l]) } else { acc[l] + a[l] * b[l] };
    }
}

/// `acc += a·b` lane by lane, two roundings (native code's explicit
/// product and sum).
#[inline(always)]
fn fma<const L: usize>(acc: &mut Lanes<L>, a: &Lanes<L>, b: &Lanes<L>) {
    for l in 0..L {
        acc[l] += a[l] * b[l];
    }
}

#[inline(always)]
fn fms<const L: usize>(acc: &mut Lanes<L>, a: &Lanes<L>, b: &Lanes<L>) {
    for l in 0..L {
        acc[l] -= a[l] * b[l];
    }
}

/// An instruction of the tape with its operand slots renamed.
fn remap(op: Op, map: &[u32]) -> Op {
    let m = |s: u32| map[s as usize];
    match op {
        Op::Input(k) => Op::Input(k),
        Op::Const(b) => Op::Const(b),
        Op::Add(a, b) => Op::Add(m(a), m(b)),
        Op::Sub(a, b) => Op::Sub(m(a), m(b)),
        Op::Mul(a, b) => Op::Mul(m(a), m(b)),
        Op::Div(a, b) => Op::Div(m(a), m(b)),
        Op::Neg(a) => Op::Neg(m(a)),
        Op::Recip(a) => Op::Recip(m(a)),
        Op::Square(a) => Op::Square(m(a)),
        Op::Powi(a, n) => Op::Powi(m(a), n),
        Op::Powf(a, b) => Op::Powf(m(a), m(b)),
        Op::Sqrt(a) => Op::Sqrt(m(a)),
        Op::Func(f, a) => Op::Func(f, m(a)),
        Op::Atan2(a, b) => Op::Atan2(m(a), m(b)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{ExprId, Pool};

    /// Checks the Taylor coefficients of `text` along x(t) = x0 + t, y(t) = y0 - t
    /// (and the constant parameter a) against repeated symbolic derivatives.
    fn check<const L: usize>(text: &str, x0: [f64; L], y0: f64, a: f64) {
        let interpreted = check_with::<L>(text, x0, y0, a, false);
        let native = check_with::<L>(text, x0, y0, a, true);
        // Native code and interpreter agree to rounding.
        for (k, (i, n)) in interpreted.iter().zip(&native).enumerate() {
            for l in 0..L {
                let close = (i[l] - n[l]).abs() <= 1e-12 * i[l].abs().max(1e-300) || i[l] == n[l];
                assert!(close, "{text}: order {k} lane {l}: interpreted {} native {}", i[l], n[l]);
            }
        }
    }

    /// The output's coefficients, checked against the derivatives.
    fn check_with<const L: usize>(text: &str, x0: [f64; L], y0: f64, a: f64, native: bool) -> Vec<Lanes<L>> {
        let order = 6;
        let mut p = Pool::default();
        let e = p.parse(text).unwrap();
        let (x, y, pa) = (p.symbol("x"), p.symbol("y"), p.symbol("a"));
        let mut tape_t = Tape::compile(&p, &[e], &[x, y, pa]).unwrap();
        let mut taylor = TaylorTape::<L>::new(&tape_t, order, &[true, true, false]);
        if native {
            assert!(taylor.compile_native().unwrap());
            assert!(taylor.is_native());
        }
        taylor.set_constant_input(2, [a; L]);
        taylor.refresh_constants();
        // d/dt = d/dx - d/dy along the line.
        let mut derivs = vec![e];
        for k in 1..=order {
            let dx = p.diff(derivs[k - 1], x);
            let dy = p.diff(derivs[k - 1], y);
            derivs.push(p.sub(dx, dy));
        }
        let mut tape_d = Tape::compile(&p, &derivs, &[x, y, pa]).unwrap();
        for k in 0..=order {
            *taylor.input_mut(0, k) = [if k == 0 {
                0.0
            } else if k == 1 {
                1.0
            } else {
                0.0
            }; L];
            if k == 0 {
                *taylor.input_mut(0, 0) = x0;
            }
            *taylor.input_mut(1, k) = [if k == 0 {
                y0
            } else if k == 1 {
                -1.0
            } else {
                0.0
            }; L];
            taylor.compute(k);
        }
        let mut factorial = 1.0;
        for k in 0..=order {
            if k > 0 {
                factorial *= k as f64;
            }
            for lane in 0..L {
                let mut exact = vec![0.0; order + 1];
                tape_d.eval(&[x0[lane], y0, a], &mut exact);
                let want = exact[k] / factorial;
                let got = taylor.output(0, k)[lane];
                let tol = 1e-9 * (1.0 + want.abs());
                assert!((got - want).abs() <= tol, "{text}: order {k} lane {lane}: {got} vs {want}");
            }
        }
        let mut value = [0.0];
        tape_t.eval(&[x0[0], y0, a], &mut value);
        assert!((taylor.output(0, 0)[0] - value[0]).abs() <= 1e-12 * (1.0 + value[0].abs()));
        (0..=order).map(|k| taylor.output(0, k)).collect()
    }

    #[test]
    fn coefficients_match_repeated_derivatives() {
        for text in [
            "x*y + a*x - y/a + 3",
            "x/y",
            "a/x + x^3 - y^-2 + 2*x^2*y",
            "sin(x)*cos(y) + cos(x - y)",
            "tan(x) + tanh(y) + sinh(x)*cosh(y)",
            "asin(x/3) + acos(y/4) + atan(x*y)",
            "exp(x)*log(y) + sqrt(y)",
            "x^1.5 + y^(1/3) + x^y + a^x",
            "atan2(y, x) + abs(x - y)",
            "a*exp(-x^2)/(1 + y^2)",
        ] {
            check::<1>(text, [0.7], 2.3, 1.7);
            check::<4>(text, [0.3, 0.9, 1.1, 1.4], 2.3, 1.7);
        }
    }

    #[test]
    fn constants_are_computed_once_and_scale_instead_of_convolving() {
        let mut p = Pool::default();
        let e = p.parse("a*b*x + a^2").unwrap();
        let (x, a, b) = (p.symbol("x"), p.symbol("a"), p.symbol("b"));
        let tape = Tape::compile(&p, &[e], &[x, a, b]).unwrap();
        let t = TaylorTape::<1>::new(&tape, 4, &[true, false, false]);
        assert!(t.program.iter().all(|(_, op)| !matches!(op, T::Mul(..) | T::Square(..))));
        let e = p.parse("a*b").unwrap();
        let tape = Tape::compile(&p, &[e], &[x, a, b]).unwrap();
        let mut t = TaylorTape::<1>::new(&tape, 4, &[true, false, false]);
        assert!(t.is_empty() && t.output_is_constant(0));
        t.set_constant_input(1, [2.0]);
        t.set_constant_input(2, [3.0]);
        t.refresh_constants();
        assert_eq!((t.output(0, 0), t.output(0, 3)), ([6.0], [0.0]));
    }

    /// Expands `A(y, y', t) y'' = b` with `b = −A y` (A given by its entries'
    /// text in `y1, y2, …`, their primes and `t`), whose solutions solve
    /// `y'' = −y` whatever A is, on two lanes, and checks the series against
    /// `y = y₀ cos τ + y₀' sin τ` (coefficients at most 1, so the tolerance
    /// is absolute).
    #[track_caller]
    fn check_second_order(n: usize, entries: &[((usize, usize), &str)], inverse: ClosedFormInverse) {
        let order = 10;
        let mut p = Pool::default();
        let names: Vec<String> = (1..=n).map(|i| format!("y{i}")).collect();
        let mut inputs: Vec<ExprId> = names.iter().map(|y| p.symbol(y)).collect();
        inputs.extend(names.iter().map(|y| p.velocity(y)));
        inputs.push(p.symbol("t"));
        let mut outputs: Vec<ExprId> = entries.iter().map(|(_, a)| p.parse(a).unwrap()).collect();
        for i in 0..n {
            let terms: Vec<String> = entries
                .iter()
                .filter(|((r, _), _)| *r == i)
                .map(|((_, c), a)| format!("({a})*{}", names[*c]))
                .collect();
            let b = p.parse(&format!("-({})", terms.join(" + "))).unwrap();
            outputs.push(b);
        }
        let tape = Tape::compile(&p, &outputs, &inputs).unwrap();
        let mut taylor = TaylorTape::<2>::new(&tape, order, &vec![true; 2 * n + 1]);
        let places: Vec<(usize, usize)> = entries.iter().map(|&(at, _)| at).collect();
        let system = LinearSecondOrder { dim: n, entries: &places, inverse };
        assert_eq!(taylor.compile_second_order(&system), Ok(true));
        assert!(taylor.is_second_order());
        taylor.refresh_constants();
        let start: Vec<Lanes<2>> = (0..2 * n).map(|i| [0.3 + 0.2 * i as f64, -0.4 + 0.1 * i as f64]).collect();
        let t0 = [0.5, -0.25];
        for (i, y) in start.iter().enumerate() {
            let at = taylor.input_index(i);
            taylor.coefficients_mut()[at] = *y;
        }
        let at = taylor.input_index(2 * n);
        taylor.coefficients_mut()[at] = t0;
        taylor.coefficients_mut()[at + 1] = [1.0; 2];
        let mut series = vec![[0.0; 2]; (order + 1) * 2 * n];
        series[..2 * n].copy_from_slice(&start);
        taylor.expand_second_order(&mut series);
        // The k-th coefficients of cos τ and sin τ.
        let mut factorial = 1.0;
        for k in 0..=order {
            if k > 0 {
                factorial *= k as f64;
            }
            let sign = if (k / 2) % 2 == 0 { 1.0 } else { -1.0 };
            let (cos, sin) = if k % 2 == 0 { (sign / factorial, 0.0) } else { (0.0, sign / factorial) };
            // y[k] = y₀ cos[k] + y₀' sin[k]; y'[k] = y₀' cos[k] − y₀ sin[k].
            for i in 0..n {
                for l in 0..2 {
                    let (y0, v0) = (start[i][l], start[n + i][l]);
                    let want = [y0 * cos + v0 * sin, v0 * cos - y0 * sin];
                    for (part, want) in want.into_iter().enumerate() {
                        let got = series[k * 2 * n + part * n + i][l];
                        let close = (got - want).abs() <= 1e-14;
                        assert!(close, "order {k}, component {i}/{part}, lane {l}: {got} vs {want}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_linearly_implicit_second_order_system_expands_whole() {
        use ClosedFormInverse::{Adjugate, Diagonal};
        check_second_order(1, &[((0, 0), "2 + y1^2")], Diagonal);
        check_second_order(1, &[((0, 0), "2 + y1'*t")], Adjugate);
        check_second_order(3, &[((0, 0), "2"), ((1, 1), "3 + cos(y1)"), ((2, 2), "1 + t^2")], Diagonal);
        check_second_order(2, &[((0, 0), "2 + y1'^2"), ((0, 1), "y2"), ((1, 0), "sin(t)"), ((1, 1), "3")], Adjugate);
        let dense3 = [
            ((0, 0), "4 + y3^2"),
            ((0, 1), "y1"),
            ((0, 2), "1"),
            ((1, 0), "t"),
            ((1, 1), "5"),
            ((2, 0), "1"),
            ((2, 1), "y2'"),
            ((2, 2), "6 + cos(y1)"),
        ];
        check_second_order(3, &dense3, Adjugate);
    }

    /// The coefficient buffer after orders `0..=order` along x = x0 + t,
    /// y = y0 − t, computed by `code` ("interpreter", "cranelift" or "c").
    fn orders_by<const L: usize>(text: &str, x0: [f64; L], y0: f64, a: f64, code: &str) -> Vec<Lanes<L>> {
        let order = 7;
        let mut p = Pool::default();
        let e = p.parse(text).unwrap();
        let (x, y, pa) = (p.symbol("x"), p.symbol("y"), p.symbol("a"));
        let tape = Tape::compile(&p, &[e], &[x, y, pa]).unwrap();
        let mut taylor = TaylorTape::<L>::new(&tape, order, &[true, true, false]);
        match code {
            "cranelift" => assert!(taylor.compile_native().unwrap()),
            "c" => {
                assert_eq!(taylor.compile_native_c(), Ok(true));
                assert!(matches!(taylor.code(), TaylorCode::C(_)));
            }
            _ => assert_eq!(taylor.code(), TaylorCode::Interpreted),
        }
        taylor.set_constant_input(2, [a; L]);
        taylor.refresh_constants();
        for k in 0..=order {
            *taylor.input_mut(0, k) = match k {
                0 => x0,
                1 => [1.0; L],
                _ => [0.0; L],
            };
            *taylor.input_mut(1, k) = [[y0, -1.0][k.min(1)] * f64::from(u8::from(k < 2)); L];
            taylor.compute(k);
        }
        taylor.coefficients().to_vec()
    }

    /// Whether two buffers hold the same bits (NaN payloads aside).
    fn same_bits<const L: usize>(a: &[Lanes<L>], b: &[Lanes<L>]) -> Option<(usize, usize)> {
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            for l in 0..L {
                if x[l].to_bits() != y[l].to_bits() && !(x[l].is_nan() && y[l].is_nan()) {
                    return Some((i, l));
                }
            }
        }
        None
    }

    /// The system C compiler's code computes what the interpreter computes,
    /// bit for bit, for every instruction, on 8 lanes: inside and beyond the
    /// inline range of sine and cosine, and through NaN.
    #[test]
    fn c_code_gives_the_interpreters_bits() {
        let x0 = [0.7, -1.3, 2.9, 1e-3, 1.0e6, -3.0e7, f64::NAN, 0.25];
        for text in [
            "x*y + a*x - y/a + 3",
            "x/y + 1/x",
            "a/x + x^3 - y^-2 + 2*x^2*y + x^2",
            "sin(x)*cos(y) + cos(x - y) + sin(3*x)",
            "tan(x/1e7) + tanh(y) + sinh(x/1e7)*cosh(y)",
            "asin(x/1e8) + acos(y/4) + atan(x*y)",
            "exp(x/1e7)*log(y) + sqrt(y)",
            "x^1.5 + y^(1/3) + x^y + a^x",
            "atan2(y, x) + abs(x - y)",
            "a*exp(-x^2)/(1 + y^2)",
        ] {
            let reference = orders_by::<8>(text, x0, 2.3, 1.7, "interpreter");
            for code in ["cranelift", "c"] {
                let got = orders_by::<8>(text, x0, 2.3, 1.7, code);
                if let Some((i, l)) = same_bits(&reference, &got) {
                    panic!("{text}: {code} differs at {i} lane {l}: {} vs {}", got[i][l], reference[i][l]);
                }
            }
        }
    }

    /// The whole second-order expansion in C: the interpreter's bits.
    #[test]
    fn c_code_expands_a_second_order_system_with_the_interpreters_bits() {
        use ClosedFormInverse::{Adjugate, Diagonal};
        let dense3 = [
            ((0, 0), "4 + y3^2"),
            ((0, 1), "y1"),
            ((0, 2), "1"),
            ((1, 0), "t"),
            ((1, 1), "5"),
            ((2, 0), "1"),
            ((2, 1), "y2'"),
            ((2, 2), "6 + cos(y1)"),
        ];
        type Entries<'a> = &'a [((usize, usize), &'a str)];
        let cases: [(usize, Entries<'_>, ClosedFormInverse); 3] = [
            (3, &[((0, 0), "2"), ((1, 1), "3 + cos(y1)"), ((2, 2), "1 + t^2")], Diagonal),
            (2, &[((0, 0), "2 + y1'^2"), ((0, 1), "y2"), ((1, 0), "sin(t)"), ((1, 1), "3")], Adjugate),
            (3, &dense3, Adjugate),
        ];
        for (n, entries, inverse) in cases {
            let order = 9;
            let mut p = Pool::default();
            let names: Vec<String> = (1..=n).map(|i| format!("y{i}")).collect();
            let mut inputs: Vec<ExprId> = names.iter().map(|y| p.symbol(y)).collect();
            inputs.extend(names.iter().map(|y| p.velocity(y)));
            inputs.push(p.symbol("t"));
            let mut outputs: Vec<ExprId> = entries.iter().map(|(_, a)| p.parse(a).unwrap()).collect();
            for i in 0..n {
                outputs.push(p.parse(&format!("sin(y{}) - y{}'^2 * exp(t/9)", i + 1, n - i)).unwrap());
            }
            let tape = Tape::compile(&p, &outputs, &inputs).unwrap();
            let places: Vec<(usize, usize)> = entries.iter().map(|&(at, _)| at).collect();
            let system = LinearSecondOrder { dim: n, entries: &places, inverse };
            let run = |c: bool| {
                let mut taylor = TaylorTape::<8>::new(&tape, order, &vec![true; 2 * n + 1]);
                if c {
                    assert_eq!(taylor.compile_second_order_c(&system), Ok(true));
                    assert!(matches!(taylor.code(), TaylorCode::C(_)));
                } else {
                    taylor.set_second_order(&system);
                }
                taylor.refresh_constants();
                let start: Vec<Lanes<8>> =
                    (0..2 * n).map(|i| std::array::from_fn(|l| 0.3 + 0.2 * i as f64 - 0.15 * l as f64)).collect();
                for (i, y) in start.iter().enumerate() {
                    let at = taylor.input_index(i);
                    taylor.coefficients_mut()[at] = *y;
                }
                let at = taylor.input_index(2 * n);
                taylor.coefficients_mut()[at] = std::array::from_fn(|l| 0.5 - 0.3 * l as f64);
                taylor.coefficients_mut()[at + 1] = [1.0; 8];
                let mut series = vec![[0.0; 8]; (order + 1) * 2 * n];
                series[..2 * n].copy_from_slice(&start);
                taylor.expand_second_order(&mut series);
                (series, taylor.coefficients().to_vec())
            };
            let (want_series, want_coef) = run(false);
            let (series, coef) = run(true);
            assert_eq!(same_bits(&want_series, &series), None, "n = {n}: series");
            assert_eq!(same_bits(&want_coef, &coef), None, "n = {n}: coefficients");
        }
    }

    #[test]
    fn the_exponential_of_t_has_coefficients_one_over_k_factorial() {
        let mut p = Pool::default();
        let e = p.parse("exp(t)").unwrap();
        let t = p.symbol("t");
        let tape = Tape::compile(&p, &[e], &[t]).unwrap();
        let mut taylor = TaylorTape::<1>::new(&tape, 20, &[true]);
        let mut factorial = 1.0;
        for k in 0..=20 {
            *taylor.input_mut(0, k) = [if k == 1 { 1.0 } else { 0.0 }];
            taylor.compute(k);
            if k > 0 {
                factorial *= k as f64;
            }
            let got = taylor.output(0, k)[0];
            assert!((got * factorial - 1.0).abs() < 1e-13, "order {k}: {got}");
        }
    }
}
