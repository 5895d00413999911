//! The public Taylor tape ([`TaylorTape`]): the program's coefficients on `L`
//! lanes, computed order by order by the interpreter or by native code, and
//! the whole expansion of a linearly implicit second-order system.

use super::interpret::{derivative_quotient, derived, derived_pair, fma, fms, lanes, madd, order_zero, weighted};
use super::native::{NativeTaylor, NATIVE_MAX_WORK};
use super::program::{self, ClosedFormInverse, Instruction, Lanes, LinearSecondOrder, Program, SecondOrderLayout};
use crate::eval::{Op, Tape};
use crate::native::{host_has_fma, CBuild, CcError, JitError};
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

/// A tape evaluated in Taylor mode on `L` lanes. See the module documentation.
#[derive(Clone, Debug)]
pub struct TaylorTape<const L: usize> {
    order: usize,
    /// `coef[slot * (order + 1) + k]`: the k-th normalized coefficient.
    coef: Vec<Lanes<L>>,
    /// Constant instructions, evaluated by `refresh_constants`: (slot, op over slots).
    constants: Vec<(u32, Op)>,
    /// Variable instructions in order: (slot, instruction).
    program: Vec<(u32, Instruction)>,
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

impl<const L: usize> TaylorTape<L> {
    /// Prepares `tape` for Taylor coefficients up to `order`. `variable[k]` tells
    /// whether input `k` varies along a trajectory (state, time) or is constant
    /// (a parameter); every input starts at 0 on every lane.
    pub fn new(tape: &Tape, order: usize, variable: &[bool]) -> TaylorTape<L> {
        assert_eq!(variable.len(), tape.n_inputs(), "one flag per input");
        let Program { constants, program, constant, input_slots, outputs } = program::build(tape, variable);
        TaylorTape {
            order,
            coef: vec![[0.0; L]; constant.len() * (order + 1)],
            constants,
            program,
            input_slots,
            variable_inputs: variable.to_vec(),
            outputs,
            constant,
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
        self.native = Some(Arc::new(NativeTaylor::orders_c::<L>(&self.program, self.order, self.buffer_len())?));
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
        self.native = Some(Arc::new(NativeTaylor::new::<L>(&self.program, self.order, self.buffer_len())?));
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
                Instruction::Add(..)
                | Instruction::Sub(..)
                | Instruction::Neg(_)
                | Instruction::AddC(..)
                | Instruction::SubVC(..)
                | Instruction::SubCV(..)
                | Instruction::MulC(..)
                | Instruction::DivVC(..)
                | Instruction::Abs(_)
                | Instruction::Deriv(_)
                | Instruction::CosOf
                | Instruction::Aux => 1,
                Instruction::Sin { .. }
                | Instruction::Sinh { .. }
                | Instruction::Tan { .. }
                | Instruction::Asin { .. }
                | Instruction::Atan2 { .. } => 2 * (k + 1),
                _ => k + 1,
            })
            .sum()
    }

    /// Whether [`compute`](Self::compute) runs native code.
    pub fn is_native(&self) -> bool {
        self.native.is_some()
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
                    Instruction::CosOf | Instruction::Aux => continue,
                    _ => order_zero(c, op, stride),
                }
            } else {
                match op {
                    Instruction::Add(a, b) => lanes(|l| c[s(a) + k][l] + c[s(b) + k][l]),
                    Instruction::Sub(a, b) => lanes(|l| c[s(a) + k][l] - c[s(b) + k][l]),
                    Instruction::Neg(a) => lanes(|l| -c[s(a) + k][l]),
                    Instruction::AddC(a, _) | Instruction::SubVC(a, _) => c[s(a) + k],
                    Instruction::SubCV(_, a) => lanes(|l| -c[s(a) + k][l]),
                    Instruction::MulC(a, b) => lanes(|l| c[s(a) + k][l] * c[s(b)][l]),
                    Instruction::DivVC(a, b) => lanes(|l| c[s(a) + k][l] / c[s(b)][l]),
                    Instruction::Mul(a, b) => {
                        let (a, b) = (s(a), s(b));
                        let mut acc = [0.0; L];
                        for (x, y) in c[a..=a + k].iter().zip(c[b..=b + k].iter().rev()) {
                            madd::<F, L>(&mut acc, x, y);
                        }
                        acc
                    }
                    Instruction::Square(a) => {
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
                    Instruction::Div(a, b) => {
                        // w = a/b: w[k] = (a[k] - Σ_{j=1..k} b[j] w[k-j]) / b[0]
                        let (a, b) = (s(a), s(b));
                        let mut acc = c[a + k];
                        for j in 1..=k {
                            fms(&mut acc, &c[b + j], &c[w + k - j]);
                        }
                        lanes(|l| acc[l] / c[b][l])
                    }
                    Instruction::DivCV(_, b) => {
                        let b = s(b);
                        let mut acc = [0.0; L];
                        for j in 1..=k {
                            fms(&mut acc, &c[b + j], &c[w + k - j]);
                        }
                        lanes(|l| acc[l] / c[b][l])
                    }
                    Instruction::Sqrt(a) => {
                        // w² = a: w[k] = (a[k] - Σ_{j=1..k-1} w[j] w[k-j]) / (2 w[0])
                        let a = s(a);
                        let mut acc = c[a + k];
                        for j in 1..k {
                            fms(&mut acc, &c[w + j], &c[w + k - j]);
                        }
                        lanes(|l| acc[l] / (2.0 * c[w][l]))
                    }
                    Instruction::PowC(a, e) => {
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
                    Instruction::Deriv(a) => {
                        let kf = k as f64;
                        lanes(|l| kf * c[s(a) + k][l])
                    }
                    Instruction::Exp { du, .. } => {
                        // w' = u' w: w[k] = Σ_{j=1..k} j u[j] w[k-j] / k
                        derived::<F, L>(c, s(du), w, k)
                    }
                    Instruction::Log(a) => {
                        // a w' = a': w[k] = (a[k] - Σ_{j=1..k-1} j w[j] a[k-j] / k) / a[0]
                        let a = s(a);
                        let sum = weighted::<F, L>(c, w, a, k, 1, k - 1);
                        lanes(|l| (c[a + k][l] - sum[l]) / c[a][l])
                    }
                    Instruction::Sin { du, cos, .. } => {
                        let (du, cs) = (s(du), s(cos));
                        let (sin, cos) = derived_pair::<F, L>(c, du, cs, w, k);
                        c[cs + k] = lanes(|l| -cos[l]);
                        sin
                    }
                    Instruction::Sinh { du, cosh, .. } => {
                        let (du, ch) = (s(du), s(cosh));
                        let (sinh, cosh) = derived_pair::<F, L>(c, du, ch, w, k);
                        c[ch + k] = cosh;
                        sinh
                    }
                    Instruction::Tan { du, aux, sign, .. } => {
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
                    Instruction::Asin { u, inner, root, sign } => {
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
                    Instruction::Atan { u, aux } => {
                        // aux = 1 + u², aux·w' = u'
                        let (u, x) = (s(u), s(aux));
                        let mut sq = [0.0; L];
                        for j in 0..=k {
                            madd::<F, L>(&mut sq, &c[u + j], &c[u + k - j]);
                        }
                        c[x + k] = sq;
                        derivative_quotient(c, u, x, w, k, 1.0)
                    }
                    Instruction::Atan2 { y, x, aux } => {
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
                    Instruction::Abs(a) => {
                        let a = s(a);
                        lanes(|l| if c[a][l] < 0.0 { -c[a + k][l] } else { c[a + k][l] })
                    }
                    Instruction::CosOf | Instruction::Aux => continue,
                }
            };
            c[w + k] = value;
        }
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
        assert!(t.program.iter().all(|(_, op)| !matches!(op, Instruction::Mul(..) | Instruction::Square(..))));
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
