//! Native code for a [`Tape`]: the tape's instruction list compiled to one
//! machine function with cranelift.
//!
//! [`Compiled::new`] translates the tape one instruction at a time into
//! cranelift SSA values (the tape already removed repeated subexpressions
//! across all its roots, and cranelift's optimizer runs on top for tapes up
//! to [`OPTIMIZE_MAX_OPS`] instructions), loads the inputs from and stores the
//! outputs to the caller's slices where they are used and computed, and keeps
//! every intermediate in a register or a spill slot chosen by the register
//! allocator instead of the tape's slot array. Instructions are emitted
//! depth-first from the outputs so that intermediates die young, which keeps
//! the register allocator's time near linear in the tape's length. [`Compiled::eval`] is then one
//! indirect call. The tape stays the reference and the fallback where
//! cranelift has no backend: both compute the same IEEE operations in the same
//! order and call the same `f64` functions, so they agree bit for bit.
//!
//! `sin` and `cos` are inline code ([`trig`]: fdlibm's reduction and kernels,
//! within 1 ulp of libm; `sin(u)` and `cos(u)` share one reduction; the tape
//! and every other evaluation use the same arithmetic, `trig::sin_cos_f64`), for
//! arguments below 2¹⁹·π/2; larger and non-finite ones go to the library in
//! a cold block at each call site. A tape with more than [`OUTLINE_TRIG`] of
//! them calls one wrapper of `trig::sin_cos_f64` for each pair instead, which
//! keeps a long trigonometric tape's compile time in proportion to its length.
//! (A variant that compiled a second, call-free
//! copy of the function for the hot path was measured 10 ns faster per
//! double-pendulum call, but doubled compile time, which a run of 10⁵ calls
//! does not win back.) Tapes with them are compiled without cranelift's
//! optimizer, which took longer on the trigonometric code than it saved. The
//! other elementary functions (`exp`, `atan2`,
//! `powf`, ...) are calls to `extern "C"` wrappers of the `f64` methods,
//! registered as symbols of the JIT module. `sqrt`, `abs`, negation and the
//! arithmetic are native instructions, and integer powers are unrolled binary
//! exponentiation (the same multiplications as `f64::powi`).

// Running JIT-compiled code can only be done through a raw function pointer.
// The unsafe surface is four small blocks, each with its safety argument:
// the pointer cast in `Compiled::new`, the call in `Compiled::eval` (buffer
// lengths checked just before), freeing the code in `Drop`, and the two
// stores of `lagrange_sin_cos` into the slot its caller passes.
#![allow(unsafe_code)]

pub(crate) mod shared;
pub(crate) mod trig;

use crate::eval::{Op, Tape};
use crate::expr::Func;
pub(crate) use crate::native::JitError;
use crate::native::QUICK_MIN_OPS;
use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{
    types, AbiParam, BlockArg, FuncRef, InstBuilder, MemFlagsData, Signature, StackSlot, StackSlotData, StackSlotKind,
    UserFuncName, Value,
};
use cranelift_codegen::isa::OwnedTargetIsa;
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{default_libcall_names, FuncId, Linkage, Module};
use rustc_hash::FxHashMap;
use std::sync::{Mutex, OnceLock, PoisonError};

/// The signature of every compiled function: `inputs` points to
/// `n_inputs` values, `outputs` to `n_outputs` values.
type RawFn = unsafe extern "C" fn(inputs: *const f64, outputs: *mut f64);

/// A tape compiled to native code. Evaluation takes `&self`, so one
/// `Compiled` serves several threads at once.
///
/// ```
/// let mut pool = sym::Pool::default();
/// let e = pool.parse("x*sin(y) + y^3").unwrap();
/// let (x, y) = (pool.symbol("x"), pool.symbol("y"));
/// let tape = sym::Tape::compile(&pool, &[e], &[x, y]).unwrap();
/// let native = sym::Compiled::new(&tape).unwrap();
/// let mut out = [0.0];
/// native.eval(&[2.0, 0.5], &mut out);
/// assert_eq!(out[0], 2.0 * 0.5f64.sin() + 0.125);
/// ```
pub struct Compiled {
    /// Owns the executable memory `func` points into; taken only in `Drop`.
    /// The mutex is never locked: it only makes the module (which is `Send`
    /// but not `Sync`) shareable, since `eval` never touches it.
    module: Mutex<Option<JITModule>>,
    func: RawFn,
    n_inputs: usize,
    n_outputs: usize,
    n_ops: usize,
}

impl std::fmt::Debug for Compiled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Compiled")
            .field("n_inputs", &self.n_inputs)
            .field("n_outputs", &self.n_outputs)
            .field("n_ops", &self.n_ops)
            .finish_non_exhaustive()
    }
}

/// Tapes longer than this are compiled without cranelift's optimizer
/// (`opt_level=none`). The tape is already free of repeated subexpressions, so
/// the optimizer gains little, and its time grows faster than linearly on long
/// tapes: one of 14 000 instructions (a sum over a thousand coupled terms)
/// compiles in 25 ms without it and 650 ms with it.
pub const OPTIMIZE_MAX_OPS: usize = 4096;

/// How much work cranelift spends on a function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Codegen {
    /// `opt_level=speed` and the backtracking register allocator: short
    /// right-hand sides called many times.
    Optimized,
    /// No optimizer, backtracking allocator: long or trigonometric tapes.
    Plain,
    /// No optimizer and the single-pass register allocator: the long straight
    /// Taylor expansions. Their values are mostly loaded, combined once and
    /// stored, so the allocator's extra spills cost nothing measurable (1.01
    /// against 1.02 µs per double-pendulum step), while it about halves the
    /// compile time, which a short run pays in full (the double pendulum's
    /// whole process at t = 100: 11.9 to 10.6 ms). The right-hand sides of
    /// the other methods do lose with it: DOP853 runs 15% longer.
    Quick,
}

/// The host ISA for `codegen`, built once per process.
pub(crate) fn host_isa(codegen: Codegen) -> Result<OwnedTargetIsa, JitError> {
    static CELLS: [OnceLock<Result<OwnedTargetIsa, JitError>>; 3] = [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    CELLS[codegen as usize]
        .get_or_init(|| {
            let unsupported = |reason: String| JitError::UnsupportedHost { reason };
            let mut flags = settings::builder();
            for (name, value) in [
                ("opt_level", if codegen == Codegen::Optimized { "speed" } else { "none" }),
                ("regalloc_algorithm", if codegen == Codegen::Quick { "single_pass" } else { "backtracking" }),
                // cranelift-jit requires both (absolute addresses, far calls).
                ("use_colocated_libcalls", "false"),
                ("is_pic", "false"),
                // The IR comes from a verified tape; checking it again costs
                // compile time in optimized builds only.
                ("enable_verifier", if cfg!(debug_assertions) { "true" } else { "false" }),
            ] {
                flags.set(name, value).map_err(|e| unsupported(e.to_string()))?;
            }
            let isa = cranelift_native::builder().map_err(|e| unsupported(e.to_string()))?;
            isa.finish(settings::Flags::new(flags)).map_err(|e| unsupported(e.to_string()))
        })
        .clone()
}

/// Declares one `extern "C"` wrapper per elementary function, and the
/// table from [`Func`] to its symbol name and address.
macro_rules! unary_wrappers {
    ($($f:ident => $name:ident),* $(,)?) => {
        $(extern "C" fn $name(x: f64) -> f64 {
            Func::$f.apply(x)
        })*

        /// The symbol and address of the wrapper of `f`.
        pub(crate) fn unary(f: Func) -> (&'static str, *const u8) {
            match f {
                $(Func::$f => (stringify!($name), $name as *const u8),)*
            }
        }
    };
}

unary_wrappers! {
    Sin => lagrange_sin,
    Cos => lagrange_cos,
    Tan => lagrange_tan,
    Asin => lagrange_asin,
    Acos => lagrange_acos,
    Atan => lagrange_atan,
    Sinh => lagrange_sinh,
    Cosh => lagrange_cosh,
    Tanh => lagrange_tanh,
    Exp => lagrange_exp,
    Log => lagrange_log,
    Abs => lagrange_abs,
}

pub(crate) extern "C" fn lagrange_powf(x: f64, y: f64) -> f64 {
    x.powf(y)
}

pub(crate) extern "C" fn lagrange_atan2(y: f64, x: f64) -> f64 {
    y.atan2(x)
}

pub(crate) const POWF: &str = "lagrange_powf";
pub(crate) const ATAN2: &str = "lagrange_atan2";

/// Translates the tape into the body of one function.
struct Translator<'a, 'b> {
    module: &'a mut JITModule,
    b: FunctionBuilder<'b>,
    imports: Imports,
}

/// The wrappers a function calls, each declared in it once.
#[derive(Default)]
pub(crate) struct Imports {
    functions: FxHashMap<&'static str, FuncRef>,
    /// Whether `sin` and `cos` are calls to [`lagrange_sin_cos`] instead of
    /// inline code ([`OUTLINE_TRIG`]), and the slot it writes them to.
    outline_trig: Option<Option<StackSlot>>,
}

/// Above this many sines and cosines a tape calls [`lagrange_sin_cos`]
/// instead of writing each inline. Inline, one is some seventy instructions
/// in three blocks, and a long trigonometric tape (a chain of fifty links has
/// 1275 angle differences, each with its sine and cosine) spends seconds in
/// cranelift for them; the call is the same arithmetic (the interpreter's
/// [`crate::trig::sin_cos_f64`]), so the numbers are the tape's bit for bit, at a
/// few nanoseconds more per pair.
pub const OUTLINE_TRIG: usize = 256;

/// `sin x` and `cos x` from one argument reduction, written to `out[0]` and
/// `out[1]`: the call a long tape makes ([`OUTLINE_TRIG`]).
///
/// # Safety
///
/// `out` points to two writable, aligned `f64`s (the compiled code passes a
/// 16-byte stack slot of its own).
pub(crate) unsafe extern "C" fn lagrange_sin_cos(x: f64, out: *mut f64) {
    let (s, c) = crate::trig::sin_cos_f64(x);
    // SAFETY: the caller passes two writable, aligned f64s (see above).
    unsafe {
        out.write(s);
        out.add(1).write(c);
    }
}

pub(crate) const SIN_COS: &str = "lagrange_sin_cos";

impl Imports {
    /// Calls the wrapper `name` taking `args.len()` floats and returning one.
    pub(crate) fn call(
        &mut self,
        module: &mut JITModule,
        b: &mut FunctionBuilder<'_>,
        name: &'static str,
        args: &[Value],
    ) -> Result<Value, JitError> {
        let f = match self.functions.get(name) {
            Some(&f) => f,
            None => {
                let mut sig = module.make_signature();
                sig.params.extend(args.iter().map(|_| AbiParam::new(types::F64)));
                sig.returns.push(AbiParam::new(types::F64));
                let id = module.declare_function(name, Linkage::Import, &sig).map_err(codegen)?;
                let f = module.declare_func_in_func(id, b.func);
                self.functions.insert(name, f);
                f
            }
        };
        let call = b.ins().call(f, args);
        Ok(b.inst_results(call)[0])
    }

    /// `sin x` and `cos x`, those of the two that `want` asks for: inline
    /// ([`trig::sin_cos`]) for `|x| <` [`crate::trig::INLINE_MAX`], calls to the
    /// wrappers in a cold block otherwise (large, infinite or NaN `x`).
    pub(crate) fn sin_cos(
        &mut self,
        module: &mut JITModule,
        b: &mut FunctionBuilder<'_>,
        x: Value,
        want: [bool; 2],
    ) -> Result<[Option<Value>; 2], JitError> {
        if let Some(slot) = &mut self.outline_trig {
            let slot = *slot.get_or_insert_with(|| {
                b.create_sized_stack_slot(StackSlotData::new(StackSlotKind::ExplicitSlot, 16, 3))
            });
            let ptr = module.target_config().pointer_type();
            let out = b.ins().stack_addr(ptr, slot, 0);
            let f = match self.functions.get(SIN_COS) {
                Some(&f) => f,
                None => {
                    let mut sig = module.make_signature();
                    sig.params.push(AbiParam::new(types::F64));
                    sig.params.push(AbiParam::new(ptr));
                    let id = module.declare_function(SIN_COS, Linkage::Import, &sig).map_err(codegen)?;
                    let f = module.declare_func_in_func(id, b.func);
                    self.functions.insert(SIN_COS, f);
                    f
                }
            };
            b.ins().call(f, &[x, out]);
            let load = |b: &mut FunctionBuilder<'_>, k: i32| b.ins().stack_load(ptr, types::F64, slot, 8 * k);
            return Ok([want[0].then(|| load(b, 0)), want[1].then(|| load(b, 1))]);
        }
        let (inline, library, done) = (b.create_block(), b.create_block(), b.create_block());
        let results: Vec<Value> = want.iter().filter(|&&w| w).map(|_| b.append_block_param(done, types::F64)).collect();
        let ax = b.ins().fabs(x);
        let bound = b.ins().f64const(crate::trig::INLINE_MAX);
        let in_range = b.ins().fcmp(FloatCC::LessThan, ax, bound);
        b.ins().brif(in_range, inline, &[], library, &[]);
        b.set_cold_block(library);

        b.switch_to_block(inline);
        b.seal_block(inline);
        let (s, c) = trig::sin_cos(b, x);
        let args: Vec<BlockArg> =
            [s, c].into_iter().zip(want).filter(|&(_, w)| w).map(|(v, _)| BlockArg::Value(v)).collect();
        b.ins().jump(done, &args);

        b.switch_to_block(library);
        b.seal_block(library);
        let mut args = Vec::with_capacity(2);
        for (f, w) in [Func::Sin, Func::Cos].into_iter().zip(want) {
            if w {
                args.push(BlockArg::Value(self.call(module, b, unary(f).0, &[x])?));
            }
        }
        b.ins().jump(done, &args);

        b.switch_to_block(done);
        b.seal_block(done);
        let mut results = results.into_iter();
        Ok(want.map(|w| if w { results.next() } else { None }))
    }
}

impl Translator<'_, '_> {
    /// Calls the wrapper `name` taking `args.len()` floats and returning one.
    fn call(&mut self, name: &'static str, args: &[Value]) -> Result<Value, JitError> {
        self.imports.call(self.module, &mut self.b, name, args)
    }

    /// `sin x` and `cos x`, those of the two that `want` asks for ([`Imports::sin_cos`]).
    fn sin_cos(&mut self, x: Value, want: [bool; 2]) -> Result<[Option<Value>; 2], JitError> {
        self.imports.sin_cos(self.module, &mut self.b, x, want)
    }

    /// `x^n` by binary exponentiation: the multiplications of `f64::powi`
    /// (compiler-rt's `__powidf2`), at most 62 for any `i32`.
    fn powi(&mut self, x: Value, n: i32) -> Value {
        let mut m = n.unsigned_abs();
        let mut square = x;
        let mut acc: Option<Value> = None;
        loop {
            if m & 1 == 1 {
                acc = Some(match acc {
                    Some(a) => self.b.ins().fmul(a, square),
                    None => square,
                });
            }
            m >>= 1;
            if m == 0 {
                break;
            }
            square = self.b.ins().fmul(square, square);
        }
        let r = acc.unwrap_or_else(|| self.b.ins().f64const(1.0));
        if n < 0 {
            let one = self.b.ins().f64const(1.0);
            self.b.ins().fdiv(one, r)
        } else {
            r
        }
    }

    /// Emits the whole function: one value per tape instruction, each output
    /// stored as soon as it is computed.
    ///
    /// Live ranges are kept short, because the register allocator's time grows
    /// with them: the tape lists every input first, so an input is loaded (and a
    /// constant materialized) where an instruction uses it, not at its place in
    /// the tape, and an output is stored right after the instruction that
    /// computes it rather than all at the end. With two thousand inputs and
    /// outputs this makes compiling several times
    /// faster; the arithmetic is the same.
    fn body(&mut self, tape: &Tape, inputs: Value, outputs: Value) -> Result<(), JitError> {
        // Aligned, never trapping: the buffers are `f64` slices of checked length.
        let flags = MemFlagsData::trusted();
        let ops = tape.ops();
        let mut outputs_of: FxHashMap<u32, Vec<usize>> = FxHashMap::default();
        for (k, &s) in tape.output_slots().iter().enumerate() {
            outputs_of.entry(s).or_default().push(k);
        }
        // `None` for inputs, constants and instructions not emitted yet.
        let mut v: Vec<Option<Value>> = vec![None; tape.len()];
        let order = emission_order(tape);
        // sin(u) and cos(u) of one slot u share one argument reduction: the
        // first of the two to be emitted computes both. (The sine alone is the
        // same arithmetic, so a result does not depend on the other's presence.)
        let mut sin_cos_of: FxHashMap<u32, [Option<usize>; 2]> = FxHashMap::default();
        for &slot in &order {
            if let Op::Func(f @ (Func::Sin | Func::Cos), a) = ops[slot] {
                let pair = sin_cos_of.entry(a).or_default();
                pair[usize::from(f == Func::Cos)].get_or_insert(slot);
            }
        }
        for op in ops {
            if let Op::Input(k) = *op {
                assert!((k as usize) < tape.n_inputs(), "tape reads input {k} of {}", tape.n_inputs());
            }
        }
        let value = |b: &mut FunctionBuilder<'_>, v: &[Option<Value>], slot: u32| -> Result<Value, JitError> {
            Ok(match (v[slot as usize], ops[slot as usize]) {
                (Some(x), _) => x,
                (None, Op::Input(k)) => b.ins().load(types::F64, flags, inputs, offset(k as usize)?),
                (None, Op::Const(bits)) => b.ins().f64const(f64::from_bits(bits)),
                (None, _) => unreachable!("every other instruction has a value"),
            })
        };
        for slot in order {
            let op = &ops[slot];
            macro_rules! arg {
                ($a:expr) => {
                    value(&mut self.b, &v, $a)?
                };
            }
            let x = match *op {
                // Computed already, as the partner of a sine or cosine.
                _ if v[slot].is_some() => v[slot],
                Op::Input(_) | Op::Const(_) => None,
                Op::Add(a, c) => {
                    let (x, y) = (arg!(a), arg!(c));
                    Some(self.b.ins().fadd(x, y))
                }
                Op::Sub(a, c) => {
                    let (x, y) = (arg!(a), arg!(c));
                    Some(self.b.ins().fsub(x, y))
                }
                Op::Mul(a, c) => {
                    let (x, y) = (arg!(a), arg!(c));
                    Some(self.b.ins().fmul(x, y))
                }
                Op::Div(a, c) => {
                    let (x, y) = (arg!(a), arg!(c));
                    Some(self.b.ins().fdiv(x, y))
                }
                Op::Neg(a) => {
                    let x = arg!(a);
                    Some(self.b.ins().fneg(x))
                }
                Op::Recip(a) => {
                    let x = arg!(a);
                    let one = self.b.ins().f64const(1.0);
                    Some(self.b.ins().fdiv(one, x))
                }
                Op::Square(a) => {
                    let x = arg!(a);
                    Some(self.b.ins().fmul(x, x))
                }
                Op::Powi(a, n) => {
                    let x = arg!(a);
                    Some(self.powi(x, n))
                }
                Op::Powf(a, c) => {
                    let (x, y) = (arg!(a), arg!(c));
                    Some(self.call(POWF, &[x, y])?)
                }
                Op::Sqrt(a) => {
                    let x = arg!(a);
                    Some(self.b.ins().sqrt(x))
                }
                Op::Func(f @ (Func::Sin | Func::Cos), a) => {
                    let x = arg!(a);
                    let mine = usize::from(f == Func::Cos);
                    let partner = sin_cos_of[&a][1 - mine].filter(|&k| v[k].is_none() && k != slot);
                    let mut want = [false; 2];
                    want[mine] = true;
                    want[1 - mine] = partner.is_some();
                    let both = self.sin_cos(x, want)?;
                    if let Some(k) = partner {
                        v[k] = both[1 - mine];
                    }
                    both[mine]
                }
                Op::Func(Func::Abs, a) => {
                    let x = arg!(a);
                    Some(self.b.ins().fabs(x))
                }
                Op::Func(f, a) => {
                    let x = arg!(a);
                    Some(self.call(unary(f).0, &[x])?)
                }
                Op::Atan2(a, c) => {
                    let (y, x) = (arg!(a), arg!(c));
                    Some(self.call(ATAN2, &[y, x])?)
                }
            };
            v[slot] = x;
            if let Some(ks) = outputs_of.get(&(slot as u32)) {
                let x = value(&mut self.b, &v, slot as u32)?;
                for &k in ks {
                    self.b.ins().store(flags, x, outputs, offset(k)?);
                }
            }
        }
        self.b.ins().return_(&[]);
        Ok(())
    }
}

/// The operands of an instruction.
fn operands(op: &Op) -> [Option<u32>; 2] {
    match *op {
        Op::Input(_) | Op::Const(_) => [None, None],
        Op::Add(a, c) | Op::Sub(a, c) | Op::Mul(a, c) | Op::Div(a, c) | Op::Powf(a, c) | Op::Atan2(a, c) => {
            [Some(a), Some(c)]
        }
        Op::Neg(a) | Op::Recip(a) | Op::Square(a) | Op::Powi(a, _) | Op::Sqrt(a) | Op::Func(_, a) => [Some(a), None],
    }
}

/// The instructions the outputs need, operands before the instruction using
/// them, in depth-first order from the outputs: a long sum `t1 + t2 + … + tn`
/// becomes `t1, t2, +, t3, +, …` instead of the tape's `t1 … tn, +, …, +`, so
/// that each term dies as soon as it is added (the tape lists every term of a
/// sum before the additions, which keeps all of them live at once). Shared
/// subexpressions come once, where they are first needed.
fn emission_order(tape: &Tape) -> Vec<usize> {
    let ops = tape.ops();
    let mut done = vec![false; ops.len()];
    let mut order = Vec::with_capacity(ops.len());
    // (slot, operands already pushed)
    let mut stack: Vec<(u32, bool)> = Vec::new();
    for &root in tape.output_slots() {
        stack.push((root, false));
        while let Some((slot, expanded)) = stack.pop() {
            if done[slot as usize] {
                continue;
            }
            if expanded {
                done[slot as usize] = true;
                order.push(slot as usize);
                continue;
            }
            stack.push((slot, true));
            // The first operand is emitted first: pushed last.
            let [a, c] = operands(&ops[slot as usize]);
            for operand in [c, a].into_iter().flatten() {
                if !done[operand as usize] {
                    stack.push((operand, false));
                }
            }
        }
    }
    order
}

/// The byte offset of element `k` of an `f64` buffer.
pub(crate) fn offset(k: usize) -> Result<i32, JitError> {
    k.checked_mul(8)
        .and_then(|o| i32::try_from(o).ok())
        .ok_or_else(|| JitError::Codegen { message: format!("buffer index {k} exceeds the 2 GiB addressing limit") })
}

/// A JIT module for `codegen` with the elementary functions' wrappers as
/// symbols (the code of `Compiled` and of the Taylor expansions calls them).
pub(crate) fn new_module(codegen: Codegen) -> Result<JITModule, JitError> {
    let mut jb = JITBuilder::with_isa(host_isa(codegen)?, default_libcall_names());
    for f in Func::ALL {
        let (name, ptr) = unary(f);
        jb.symbol(name, ptr);
    }
    jb.symbol(POWF, lagrange_powf as *const u8);
    jb.symbol(ATAN2, lagrange_atan2 as *const u8);
    jb.symbol(SIN_COS, lagrange_sin_cos as *const u8);
    Ok(JITModule::new(jb))
}

pub(crate) fn codegen(e: impl std::fmt::Display) -> JitError {
    JitError::Codegen { message: e.to_string() }
}

/// Defines function `id` of `module` with signature `sig`: `body` gets the
/// builder in the entry block and the function's parameters, emits the code
/// (its return included) and hands the builder back.
pub(crate) fn define_function(
    module: &mut JITModule,
    id: FuncId,
    sig: &Signature,
    body: impl for<'b> FnOnce(&mut JITModule, FunctionBuilder<'b>, &[Value]) -> Result<FunctionBuilder<'b>, JitError>,
) -> Result<(), JitError> {
    let mut ctx = module.make_context();
    ctx.func.signature = sig.clone();
    ctx.func.name = UserFuncName::user(0, id.as_u32());
    let mut fctx = FunctionBuilderContext::new();
    {
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut fctx);
        let entry = b.create_block();
        b.append_block_params_for_function_params(entry);
        b.switch_to_block(entry);
        b.seal_block(entry);
        let params = b.block_params(entry).to_vec();
        let b = body(module, b, &params)?;
        b.finalize(module.target_config());
    }
    module.define_function(id, &mut ctx).map_err(codegen)?;
    module.clear_context(&mut ctx);
    Ok(())
}

/// Defines function `id` of `module` with signature `sig` as the code of `tape`.
fn define(module: &mut JITModule, id: FuncId, sig: &Signature, tape: &Tape) -> Result<(), JitError> {
    define_function(module, id, sig, |module, b, params| {
        let trig = tape.ops().iter().filter(|op| matches!(op, Op::Func(Func::Sin | Func::Cos, _))).count();
        let imports = Imports { outline_trig: (trig > OUTLINE_TRIG).then_some(None), ..Imports::default() };
        let mut t = Translator { module, b, imports };
        t.body(tape, params[0], params[1])?;
        Ok(t.b)
    })
}

impl Compiled {
    /// Compiles `tape` to one native function with the same inputs and
    /// outputs. Fails only when cranelift does not support the host (the
    /// caller then keeps using [`Tape::eval`]).
    pub fn new(tape: &Tape) -> Result<Compiled, JitError> {
        let trig = tape.ops().iter().any(|op| matches!(op, Op::Func(Func::Sin | Func::Cos, _)));
        let optimize = tape.len() <= OPTIMIZE_MAX_OPS && !trig;
        let mode = if optimize {
            Codegen::Optimized
        } else if tape.len() <= QUICK_MIN_OPS {
            Codegen::Plain
        } else {
            Codegen::Quick
        };
        let mut module = new_module(mode)?;

        let ptr = module.target_config().pointer_type();
        let mut sig: Signature = module.make_signature();
        sig.params.push(AbiParam::new(ptr));
        sig.params.push(AbiParam::new(ptr));
        let id = module.declare_function("tape", Linkage::Local, &sig).map_err(codegen)?;
        define(&mut module, id, &sig, tape)?;
        module.finalize_definitions().map_err(codegen)?;
        let code = module.get_finalized_function(id);
        // SAFETY: `code` is the entry of the function just defined with
        // signature `(ptr, ptr) -> ()` in the host's default calling
        // convention, which is `extern "C"` on every host cranelift-native
        // supports; the module that owns the code lives as long as `self`.
        let func = unsafe { std::mem::transmute::<*const u8, RawFn>(code) };
        Ok(Compiled {
            module: Mutex::new(Some(module)),
            func,
            n_inputs: tape.n_inputs(),
            n_outputs: tape.n_outputs(),
            n_ops: tape.len(),
        })
    }

    /// The number of inputs expected by [`Compiled::eval`].
    pub fn n_inputs(&self) -> usize {
        self.n_inputs
    }

    /// The number of outputs written by [`Compiled::eval`].
    pub fn n_outputs(&self) -> usize {
        self.n_outputs
    }

    /// The number of tape instructions this function was compiled from.
    pub fn len(&self) -> usize {
        self.n_ops
    }

    /// True when the tape had no instruction.
    pub fn is_empty(&self) -> bool {
        self.n_ops == 0
    }

    /// Evaluates every root, as [`Tape::eval`] does, without allocating.
    ///
    /// # Panics
    ///
    /// When `inputs.len()` is not [`Compiled::n_inputs`] or `outputs.len()`
    /// not [`Compiled::n_outputs`].
    pub fn eval(&self, inputs: &[f64], outputs: &mut [f64]) {
        assert_eq!(inputs.len(), self.n_inputs, "Compiled::eval: wrong number of inputs");
        assert_eq!(outputs.len(), self.n_outputs, "Compiled::eval: wrong number of outputs");
        // SAFETY: the function reads `inputs[k]` only for the tape's
        // `Input(k)`, and `k < n_inputs` was asserted when it was compiled;
        // it writes `outputs[k]` exactly for `k < n_outputs`. Both lengths
        // were just checked, the slices are valid, aligned and do not
        // overlap (one is `&mut`). The code is alive while `self` is (it is
        // freed only in `Drop`), calls nothing but the safe wrappers above,
        // and never unwinds.
        unsafe { (self.func)(inputs.as_ptr(), outputs.as_mut_ptr()) }
    }
}

impl Drop for Compiled {
    fn drop(&mut self) {
        let module = self.module.get_mut().unwrap_or_else(PoisonError::into_inner).take();
        if let Some(module) = module {
            // SAFETY: `self.func` is the only pointer into this module's
            // memory and is never called again: `drop` has `&mut self`, so no
            // `eval` is running, and `self` is gone afterwards.
            unsafe { module.free_memory() }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Pool;

    /// The names of the inputs of every case, in order, and their values.
    const INPUTS: [(&str, f64); 4] = [("x", 0.7), ("y", -1.3), ("z", 2.5), ("q'", 0.25)];

    /// Compiles `text` (roots separated by `;`) both ways and checks that the
    /// native code gives bit for bit what the tape gives (whose `sin` and
    /// `cos` are the native code's, `trig::sin_cos_f64`), and `expect`.
    #[track_caller]
    fn check(text: &str, expect: &[f64]) {
        let mut pool = Pool::default();
        let roots: Vec<_> = text.split(';').map(|r| pool.parse(r).unwrap()).collect();
        let inputs: Vec<_> = INPUTS.iter().map(|(n, _)| pool.parse(n).unwrap()).collect();
        let values: Vec<f64> = INPUTS.iter().map(|&(_, v)| v).collect();
        let mut tape = Tape::compile(&pool, &roots, &inputs).unwrap();
        let native = Compiled::new(&tape).unwrap();
        assert_eq!((native.n_inputs(), native.n_outputs()), (4, roots.len()));
        let (mut by_tape, mut by_jit) = (vec![0.0; roots.len()], vec![f64::NAN; roots.len()]);
        tape.eval(&values, &mut by_tape);
        native.eval(&values, &mut by_jit);
        for k in 0..roots.len() {
            let (a, b) = (by_tape[k], by_jit[k]);
            assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "root {k} of {text}: tape {a} jit {b}");
        }
        // `expect` is plain Rust, whose `powi` with a constant exponent may
        // round differently (about n ulps) and whose `sin` is libm's (an ulp
        // away at most), hence the loose tolerance.
        let close =
            |a: f64, b: f64| a == b || (a - b).abs() <= 1e-13 * a.abs().max(b.abs()) || (a.is_nan() && b.is_nan());
        assert!(by_jit.iter().zip(expect).all(|(&a, &b)| close(a, b)), "{text}: {by_jit:?} != {expect:?}");
    }

    #[test]
    fn arithmetic() {
        let (x, y, z, v) = (0.7f64, -1.3f64, 2.5f64, 0.25f64);
        check("x + y; x - y; x*y*z; x/y; -z; 1/z; x^2", &[x + y, x - y, x * y * z, x / y, -z, 1.0 / z, x * x]);
        check("x*y - z/q' + 3", &[x * y - z / v + 3.0]);
        check("2; pi; x", &[2.0, std::f64::consts::PI, x]);
    }

    #[test]
    fn integer_and_fractional_powers() {
        let (x, y, z) = (0.7f64, -1.3f64, 2.5f64);
        check("x^3; y^7; z^-5; x^0", &[x.powi(3), y.powi(7), z.powi(-5), 1.0]);
        check("z^300; z^-300; y^999", &[z.powi(300), z.powi(-300), y.powi(999)]);
        check("z^(1/2); z^(-1/2); z^(3/2); sqrt(x)", &[z.sqrt(), 1.0 / z.sqrt(), z.sqrt().powi(3), x.sqrt()]);
        check("z^x; z^(1/3)", &[z.powf(x), z.powf(1.0 / 3.0)]);
    }

    #[test]
    fn the_most_negative_exponent_compiles() {
        let mut pool = Pool::default();
        let x = pool.symbol("x");
        let e = pool.powi(x, i64::MIN);
        let mut tape = Tape::compile(&pool, &[e], &[x]).unwrap();
        let native = Compiled::new(&tape).unwrap();
        for (x, want) in [(1.0, 1.0), (-1.0, 1.0), (2.0, 0.0), (0.5, f64::INFINITY)] {
            let (mut by_tape, mut by_jit) = ([0.0], [0.0]);
            tape.eval(&[x], &mut by_tape);
            native.eval(&[x], &mut by_jit);
            assert_eq!((by_tape[0], by_jit[0]), (want, want), "x = {x}");
        }
    }

    #[test]
    fn elementary_functions() {
        let (x, y) = (0.7f64, -1.3f64);
        check(
            "sin(x); cos(y); tan(x); asin(x); acos(x); atan(y)",
            &[x.sin(), y.cos(), x.tan(), x.asin(), x.acos(), y.atan()],
        );
        check(
            "sinh(y); cosh(x); tanh(y); exp(y); log(x); abs(y)",
            &[y.sinh(), x.cosh(), y.tanh(), y.exp(), x.ln(), y.abs()],
        );
        check("atan2(y, x); atan2(x, y)", &[y.atan2(x), x.atan2(y)]);
    }

    #[test]
    fn domain_errors_give_nan_and_infinity_as_the_tape_does() {
        // x is 0.7: x - 0.7 is zero at the input, not in the text (the parser refuses 1/0).
        check(
            "log(y); sqrt(y); asin(z); 1/(x - 0.7); y^(1/2)",
            &[f64::NAN, f64::NAN, f64::NAN, f64::INFINITY, f64::NAN],
        );
    }

    #[test]
    fn shared_subexpressions_and_no_inputs_or_outputs() {
        let s = 0.7f64.sin() * -1.3;
        check("sin(x)*y; sin(x)*y + 1; (sin(x)*y)^2", &[s, s + 1.0, s * s]);
        // A tape with no inputs, and one with no outputs.
        let mut pool = Pool::default();
        let e = pool.parse("2*pi").unwrap();
        let native = Compiled::new(&Tape::compile(&pool, &[e], &[]).unwrap()).unwrap();
        let mut out = [0.0];
        native.eval(&[], &mut out);
        assert_eq!(out, [std::f64::consts::TAU]);
        let none = Compiled::new(&Tape::compile(&pool, &[], &[]).unwrap()).unwrap();
        none.eval(&[], &mut []);
        assert!(none.is_empty());
    }

    /// A tape beyond [`OPTIMIZE_MAX_OPS`] (compiled without the optimizer, in
    /// depth-first order) still gives the tape's numbers: bit for bit without
    /// sines, to 1e-13 with them.
    #[test]
    fn long_tapes_compile_unoptimized_and_agree() {
        let terms: Vec<String> = (1..=1500).map(|k| format!("{k}*sin(x + {k})*y^2/(z + {k})")).collect();
        let text = format!("{}; x*y; {}; {}", terms.join(" + "), terms[..700].join(" - "), terms[800..].join(" - "));
        let mut pool = Pool::default();
        let roots: Vec<_> = text.split(';').map(|r| pool.parse(r).unwrap()).collect();
        let inputs: Vec<_> = INPUTS.iter().map(|(n, _)| pool.parse(n).unwrap()).collect();
        let values: Vec<f64> = INPUTS.iter().map(|&(_, v)| v).collect();
        let mut tape = Tape::compile(&pool, &roots, &inputs).unwrap();
        assert!(tape.len() > OPTIMIZE_MAX_OPS, "{} instructions", tape.len());
        let native = Compiled::new(&tape).unwrap();
        let (mut by_tape, mut by_jit) = ([0.0; 4], [f64::NAN; 4]);
        tape.eval(&values, &mut by_tape);
        native.eval(&values, &mut by_jit);
        for (a, b) in by_tape.into_iter().zip(by_jit) {
            assert!((a - b).abs() <= 1e-13 * a.abs(), "{by_tape:?} {by_jit:?}");
        }
        assert_eq!(by_jit[1], 0.7 * -1.3);
        // Without sines: bit for bit.
        let terms: Vec<String> = (1..=1500).map(|k| format!("{k}*exp(x + {k})*y^2/(z + {k})")).collect();
        let mut pool = Pool::default();
        let root = pool.parse(&terms.join(" + ")).unwrap();
        let inputs: Vec<_> = INPUTS.iter().map(|(n, _)| pool.parse(n).unwrap()).collect();
        let mut tape = Tape::compile(&pool, &[root], &inputs).unwrap();
        assert!(tape.len() > OPTIMIZE_MAX_OPS, "{} instructions", tape.len());
        let native = Compiled::new(&tape).unwrap();
        let (mut by_tape, mut by_jit) = ([0.0], [f64::NAN]);
        tape.eval(&values, &mut by_tape);
        native.eval(&values, &mut by_jit);
        assert_eq!(by_tape[0].to_bits(), by_jit[0].to_bits(), "{by_tape:?} {by_jit:?}");
    }

    /// A tape with more than [`OUTLINE_TRIG`] sines and cosines calls
    /// `lagrange_sin_cos` for them and still gives the tape's numbers bit for
    /// bit, for small, huge and non-finite arguments alike.
    #[test]
    fn many_sines_are_calls_with_the_tapes_numbers() {
        let terms: Vec<String> =
            (1..=OUTLINE_TRIG).map(|k| format!("sin(x*{k})*cos(y - {k}) + cos(x*z*{k})")).collect();
        let text = format!("{}; sin(z*1e9) + cos(z*1e9); sin(log(y)); cos(exp(z*1000))", terms.join(" + "));
        let mut pool = Pool::default();
        let roots: Vec<_> = text.split(';').map(|r| pool.parse(r).unwrap()).collect();
        let inputs: Vec<_> = INPUTS.iter().map(|(n, _)| pool.parse(n).unwrap()).collect();
        let values: Vec<f64> = INPUTS.iter().map(|&(_, v)| v).collect();
        let mut tape = Tape::compile(&pool, &roots, &inputs).unwrap();
        let trig = tape.ops().iter().filter(|op| matches!(op, Op::Func(Func::Sin | Func::Cos, _))).count();
        assert!(trig > OUTLINE_TRIG, "{trig} sines and cosines");
        let native = Compiled::new(&tape).unwrap();
        let (mut by_tape, mut by_jit) = ([0.0; 4], [0.0; 4]);
        tape.eval(&values, &mut by_tape);
        native.eval(&values, &mut by_jit);
        for (a, b) in by_tape.into_iter().zip(by_jit) {
            assert!(a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan(), "{by_tape:?} {by_jit:?}");
        }
        assert!(by_jit[2].is_nan() && by_jit[3].is_nan(), "{by_jit:?}");
    }

    #[test]
    fn compiled_functions_are_shared_between_threads() {
        fn send_sync<T: Send + Sync>(_: &T) {}
        let mut pool = Pool::default();
        let e = pool.parse("x*cos(x)").unwrap();
        let x = pool.symbol("x");
        let native = Compiled::new(&Tape::compile(&pool, &[e], &[x]).unwrap()).unwrap();
        send_sync(&native);
        std::thread::scope(|s| {
            for k in 0..2 {
                let native = &native;
                s.spawn(move || {
                    let (x, mut out) = (k as f64, [0.0]);
                    native.eval(&[x], &mut out);
                    assert!((out[0] - x * x.cos()).abs() <= 1e-15, "{} vs {}", out[0], x * x.cos());
                });
            }
        });
    }
}
