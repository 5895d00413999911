//! The Taylor program: a tape's instructions rewritten as recurrences over
//! slots ([`Instruction`]), constant slots apart, with the layout of a
//! linearly implicit second-order system among the slots. The interpreter
//! (`interpret.rs`, `tape.rs`), cranelift (`cranelift.rs`) and C (`c.rs`) all
//! read this program, and nothing else of each other.

use crate::eval::{Op, Tape};
use crate::expr::Func;

/// One coefficient of one slot on every lane.
pub type Lanes<const L: usize> = [f64; L];

/// A variable instruction of the Taylor tape; operands are slots, `c` names a
/// constant slot (read at order 0 only).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Instruction {
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
    /// The cosine half of a [`Instruction::Sin`], computed with it.
    CosOf,
    /// sinh and cosh of `u`, like [`Instruction::Sin`].
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
    program: Vec<(u32, Instruction)>,
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

    fn var(&mut self, t: Instruction) -> u32 {
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
            (false, true) => self.var(Instruction::MulC(a, b)),
            (true, false) => self.var(Instruction::MulC(b, a)),
            (false, false) if a == b => self.var(Instruction::Square(a)),
            (false, false) => self.var(Instruction::Mul(a, b)),
        }
    }

    fn recip(&mut self, a: u32) -> u32 {
        if self.is_const(a) {
            return self.constant_op(Op::Recip(a));
        }
        let one = self.constant_op(Op::Const(1f64.to_bits()));
        self.var(Instruction::DivCV(one, a))
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
        let d = self.var(Instruction::Deriv(u));
        self.derivs.insert(u, d);
        d
    }

    fn exp(&mut self, u: u32) -> u32 {
        let du = self.deriv(u);
        self.var(Instruction::Exp { u, du })
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
                        let op = if circular {
                            Instruction::Sin { u, du, cos }
                        } else {
                            Instruction::Sinh { u, du, cosh: cos }
                        };
                        self.program.push((sin, op));
                        self.program.push((cos, Instruction::CosOf));
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
                self.program.push((w, Instruction::Tan { u, du, aux, sign }));
                self.program.push((aux, Instruction::Aux));
                w
            }
            Func::Asin | Func::Acos => {
                let inner = self.slot(false);
                let root = self.slot(false);
                let w = self.slot(false);
                self.program.push((inner, Instruction::Aux));
                self.program.push((root, Instruction::Aux));
                let sign = if f == Func::Asin { 1.0 } else { -1.0 };
                self.program.push((w, Instruction::Asin { u, inner, root, sign }));
                w
            }
            Func::Atan => {
                let aux = self.slot(false);
                self.program.push((aux, Instruction::Aux));
                self.var(Instruction::Atan { u, aux })
            }
            Func::Exp => self.exp(u),
            Func::Log => self.var(Instruction::Log(u)),
            Func::Abs => self.var(Instruction::Abs(u)),
        }
    }
}

/// A tape's instructions as Taylor recurrences over slots: what
/// [`super::TaylorTape::new`] builds from.
pub(super) struct Program {
    /// Constant instructions, evaluated once per change of the constant inputs.
    pub(super) constants: Vec<(u32, Op)>,
    /// Variable instructions in order: (slot, instruction).
    pub(super) program: Vec<(u32, Instruction)>,
    /// Whether each slot is constant.
    pub(super) constant: Vec<bool>,
    /// The slot of each input and of each output.
    pub(super) input_slots: Vec<u32>,
    pub(super) outputs: Vec<u32>,
}

/// The program of `tape`; `variable[k]` tells whether input `k` varies along
/// a trajectory.
pub(super) fn build(tape: &Tape, variable: &[bool]) -> Program {
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
                (true, _) => b.var(Instruction::AddC(m(y), m(x))),
                (_, true) => b.var(Instruction::AddC(m(x), m(y))),
                _ => b.var(Instruction::Add(m(x), m(y))),
            },
            Op::Sub(x, y) => match (b.is_const(m(x)), b.is_const(m(y))) {
                (true, _) => b.var(Instruction::SubCV(m(x), m(y))),
                (_, true) => b.var(Instruction::SubVC(m(x), m(y))),
                _ => b.var(Instruction::Sub(m(x), m(y))),
            },
            Op::Mul(x, y) => b.mul(m(x), m(y)),
            Op::Div(x, y) => match (b.is_const(m(x)), b.is_const(m(y))) {
                (true, _) => b.var(Instruction::DivCV(m(x), m(y))),
                (_, true) => b.var(Instruction::DivVC(m(x), m(y))),
                _ => b.var(Instruction::Div(m(x), m(y))),
            },
            Op::Neg(x) => b.var(Instruction::Neg(m(x))),
            Op::Recip(x) => b.recip(m(x)),
            Op::Square(x) => b.var(Instruction::Square(m(x))),
            Op::Powi(x, n) => b.powi(m(x), n),
            Op::Powf(x, y) if b.is_const(m(y)) => b.var(Instruction::PowC(m(x), m(y))),
            Op::Powf(x, y) => {
                // x^y = exp(y ln x)
                let ln = if b.is_const(m(x)) {
                    b.constant_op(Op::Func(Func::Log, m(x)))
                } else {
                    b.var(Instruction::Log(m(x)))
                };
                let prod = b.mul(m(y), ln);
                b.exp(prod)
            }
            Op::Sqrt(x) => b.var(Instruction::Sqrt(m(x))),
            Op::Func(f, x) => b.func(f, m(x)),
            Op::Atan2(y, x) => {
                let aux = b.slot(false);
                b.program.push((aux, Instruction::Aux));
                b.var(Instruction::Atan2 { y: m(y), x: m(x), aux })
            }
        };
        map.push(slot);
    }
    Program {
        constants: b.constants,
        program: b.program,
        outputs: tape.output_slots().iter().map(|&s| map[s as usize]).collect(),
        constant: b.constant,
        input_slots,
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
