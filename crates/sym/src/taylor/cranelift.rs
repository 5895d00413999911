//! Native code for a Taylor program: one straight-line machine function per
//! Taylor order, compiled with cranelift (`native.rs` holds it).
//!
//! The function of order `k` computes order `k` of every variable slot on
//! every lane, exactly the recurrences of the interpreter (`interpret.rs`, `tape.rs`) with every loop
//! unrolled (the order, the convolution bounds and the lanes are known when
//! compiling), reading and writing the tape's coefficient buffer in place,
//! two lanes per instruction where the lanes pair up. Cranelift's optimizer
//! is off and its register allocator is the single-pass one
//! ([`Codegen::Quick`]): the code is straight-line arithmetic on loaded
//! values, which neither can improve, and they would triple the compile time,
//! which a short run pays in full. For a linearly implicit second-order
//! system `A y'' = b` ([`second_order`]) each order's function
//! includes the coupling, so the functions run in turn make the whole
//! expansion. The functions are compiled on two threads ([`compile_shared`]);
//! for one trajectory the caller steps with the interpreter as soon as it
//! has no function left to take, while the helper finishes its last
//! ([`compile_shared_then`],
//! [`crate::TaylorTape::compile_second_order_in_background`]).
//! The interpreter stays the reference and the fallback; both
//! do the same operations in the same order, fusing the same multiply-adds
//! where the host has FMA, so that they agree to the last bit and a run
//! gives the same numbers whichever of the two computed each step.

use super::program::{Instruction, SecondOrderLayout};
use crate::expr::Func;
use crate::jit::shared::{compile_shared, compile_shared_then, Part};
use crate::jit::{codegen, define_function, offset, unary, Codegen, Imports, JitError, ATAN2, POWF};
use crate::native::host_has_fma;
use cranelift_codegen::ir::{condcodes::FloatCC, types, AbiParam, InstBuilder, MemFlagsData, Signature, Value};
use cranelift_frontend::FunctionBuilder;
use cranelift_jit::JITModule;
use cranelift_module::{FuncId, Linkage, Module};

/// Every order of `program`, one function each, compiled on two threads:
/// function `i` computes order `order − i` (the longest first).
pub(super) fn orders<const L: usize>(program: Vec<(u32, Instruction)>, order: usize) -> Result<Vec<Part>, JitError> {
    compile_shared(order + 1, Codegen::Quick, move |module, i| {
        let k = order - i;
        let sig = signature(module);
        define::<L>(module, &format!("order{k}"), &sig, order, |e| e.orders(&program, k))
    })
}

/// The whole expansion of a linearly implicit second-order system `A y'' = b`:
/// orders `0..p` of the program, each followed by the coupling that yields the
/// state's next order, one function per order (function `i` computes order
/// `p − 1 − i`), compiled on two threads ([`compile_shared`]: compiling costs
/// more than a thousand steps of a small system).
pub(super) fn second_order<const L: usize>(
    program: Vec<(u32, Instruction)>,
    order: usize,
    layout: SecondOrderLayout,
) -> Result<Vec<Part>, JitError> {
    compile_shared(order, Codegen::Quick, second_order_functions::<L>(program, order, layout, || true))
}

/// [`second_order`] for a caller that steps on meanwhile
/// ([`compile_shared_then`]): returns when no function is left for this thread
/// to compile; `publish` gets the functions (or the error) from whichever
/// thread finishes last. The helper gives up as soon as `wanted()` turns false.
pub(super) fn second_order_then<const L: usize>(
    program: Vec<(u32, Instruction)>,
    order: usize,
    layout: SecondOrderLayout,
    wanted: impl Fn() -> bool + Send + Sync + 'static,
    publish: impl FnOnce(Result<Vec<Part>, JitError>) + Send + 'static,
) {
    compile_shared_then(order, Codegen::Quick, second_order_functions::<L>(program, order, layout, wanted), publish)
}

/// Emits the code of one function. Values are `f64` (width 1) or `f64x2`
/// (width 2, two lanes per instruction); `lane` arguments name the first lane
/// of a group of `width`.
struct Emitter<'a, 'b, const L: usize> {
    module: &'a mut JITModule,
    b: FunctionBuilder<'b>,
    imports: Imports,
    base: Value,
    /// The caller's series (second-order expansions).
    series: Value,
    stride: usize,
    width: usize,
    /// Whether the host fuses multiply-adds (the interpreter then fuses the
    /// same ones).
    fma: bool,
}

/// Two lanes per instruction when the lanes pair up (SSE2 on x86-64, NEON on
/// aarch64: cranelift's vectors are 128 bits wide).
fn vector_width(lanes: usize) -> usize {
    if lanes.is_multiple_of(2) {
        2
    } else {
        1
    }
}

impl<const L: usize> Emitter<'_, '_, L> {
    fn ty(&self) -> types::Type {
        if self.width == 2 {
            types::F64X2
        } else {
            types::F64
        }
    }

    /// The groups of lanes at the current width: their first lanes.
    fn groups(&self) -> impl Iterator<Item = usize> {
        (0..L).step_by(self.width)
    }

    fn index(&self, slot: u32, j: usize, lane: usize) -> usize {
        (slot as usize * self.stride + j) * L + lane
    }

    /// Coefficient `j` of `slot` at `lane`, loaded where it is used: keeping the
    /// values of this order in registers instead makes the allocator spill
    /// (measured slower), and short live ranges keep compilation fast.
    fn ld(&mut self, slot: u32, j: usize, lane: usize) -> Result<Value, JitError> {
        let at = offset(self.index(slot, j, lane))?;
        let ty = self.ty();
        Ok(self.b.ins().load(ty, MemFlagsData::trusted(), self.base, at))
    }

    /// Stores `v` as component `at` (of `[y, y']` for all orders, order-major)
    /// of the caller's series, at `lane`.
    fn st_series(&mut self, at: usize, lane: usize, v: Value) -> Result<(), JitError> {
        let at = offset(at * L + lane)?;
        self.b.ins().store(MemFlagsData::trusted(), v, self.series, at);
        Ok(())
    }

    fn st(&mut self, slot: u32, j: usize, lane: usize, v: Value) -> Result<(), JitError> {
        let at = offset(self.index(slot, j, lane))?;
        self.b.ins().store(MemFlagsData::trusted(), v, self.base, at);
        Ok(())
    }

    fn c(&mut self, x: f64) -> Value {
        let v = self.b.ins().f64const(x);
        if self.width == 2 {
            self.b.ins().splat(types::F64X2, v)
        } else {
            v
        }
    }

    fn call(&mut self, name: &'static str, args: &[Value]) -> Result<Value, JitError> {
        self.imports.call(self.module, &mut self.b, name, args)
    }

    fn func(&mut self, f: Func, x: Value) -> Result<Value, JitError> {
        self.call(unary(f).0, &[x])
    }

    /// `(sin x, cos x)` as `Compiled` computes them ([`Imports::sin_cos`]).
    fn sin_cos(&mut self, x: Value) -> Result<(Value, Value), JitError> {
        let [s, c] = self.imports.sin_cos(self.module, &mut self.b, x, [true, true])?;
        Ok((s.expect("asked for"), c.expect("asked for")))
    }

    /// `acc + x·y`, fused where the host has FMA (one rounding, as the
    /// interpreter's `madd`).
    fn mul_add(&mut self, x: Value, y: Value, acc: Value) -> Value {
        if self.fma {
            self.b.ins().fma(x, y, acc)
        } else {
            let p = self.b.ins().fmul(x, y);
            self.b.ins().fadd(acc, p)
        }
    }

    /// `Σ_{j ∈ js} weight(j) · a[j] · b[k−j]`, started from zero.
    fn sum(
        &mut self,
        a: u32,
        b: u32,
        k: usize,
        js: impl Iterator<Item = usize>,
        weight: impl Fn(usize) -> Option<f64>,
        lane: usize,
    ) -> Result<Value, JitError> {
        let mut acc = self.c(0.0);
        for j in js {
            let (x, y) = (self.ld(a, j, lane)?, self.ld(b, k - j, lane)?);
            let x = match weight(j) {
                Some(w) => {
                    let w = self.c(w);
                    self.b.ins().fmul(w, x)
                }
                None => x,
            };
            acc = self.mul_add(x, y, acc);
        }
        Ok(acc)
    }

    /// `Σ_{j=1..=k} du[j] b[k−j] / k`, `du[j] = j u[j]` (the recurrence of `w' = u' b`).
    fn derived(&mut self, du: u32, b: u32, k: usize, lane: usize) -> Result<Value, JitError> {
        let acc = self.sum(du, b, k, 1..=k, |_| None, lane)?;
        let kf = self.c(k as f64);
        Ok(self.b.ins().fdiv(acc, kf))
    }

    /// [`derived`](Self::derived) for two slots `a` and `b` at once (sin
    /// and cos): the same sums, each `du[j]` loaded once for both.
    fn derived_pair(&mut self, du: u32, a: u32, b: u32, k: usize, lane: usize) -> Result<(Value, Value), JitError> {
        let (mut sa, mut sb) = (self.c(0.0), self.c(0.0));
        for j in 1..=k {
            let d = self.ld(du, j, lane)?;
            let x = self.ld(a, k - j, lane)?;
            sa = self.mul_add(d, x, sa);
            let y = self.ld(b, k - j, lane)?;
            sb = self.mul_add(d, y, sb);
        }
        let kf = self.c(k as f64);
        Ok((self.b.ins().fdiv(sa, kf), self.b.ins().fdiv(sb, kf)))
    }

    /// `acc − Σ_{j ∈ js} a[j] · b[k−j]`.
    fn sub_sum(
        &mut self,
        acc: Value,
        a: u32,
        b: u32,
        k: usize,
        js: std::ops::Range<usize>,
        lane: usize,
    ) -> Result<Value, JitError> {
        let mut acc = acc;
        for j in js {
            let (x, y) = (self.ld(a, j, lane)?, self.ld(b, k - j, lane)?);
            let term = self.b.ins().fmul(x, y);
            acc = self.b.ins().fsub(acc, term);
        }
        Ok(acc)
    }

    /// `Σ_{j=1..=k} j a[j] b[k−j] / k` (the recurrence of `w' = a' b`).
    fn weighted(&mut self, a: u32, b: u32, k: usize, hi: usize, lane: usize) -> Result<Value, JitError> {
        let acc = self.sum(a, b, k, 1..=hi, |j| Some(j as f64), lane)?;
        let kf = self.c(k as f64);
        Ok(self.b.ins().fdiv(acc, kf))
    }

    /// `(sign·k·u[k] − Σ_{j=1..k−1} (k−j) d[j] w[k−j]) / (k d[0])`.
    fn derivative_quotient(
        &mut self,
        u: u32,
        d: u32,
        w: u32,
        k: usize,
        sign: f64,
        lane: usize,
    ) -> Result<Value, JitError> {
        let kf = k as f64;
        let uk = self.ld(u, k, lane)?;
        let skf = self.c(sign * kf);
        let mut acc = self.b.ins().fmul(skf, uk);
        for j in 1..k {
            let kj = self.c((k - j) as f64);
            let (x, y) = (self.ld(d, j, lane)?, self.ld(w, k - j, lane)?);
            let t = self.b.ins().fmul(kj, x);
            let t = self.b.ins().fmul(t, y);
            acc = self.b.ins().fsub(acc, t);
        }
        let kc = self.c(kf);
        let d0 = self.ld(d, 0, lane)?;
        let den = self.b.ins().fmul(kc, d0);
        Ok(self.b.ins().fdiv(acc, den))
    }

    /// Σ_{j=0..=k} a[j] a[k−j] (zero-started, as the interpreter's `fma` loop).
    fn self_product(&mut self, a: u32, k: usize, lane: usize) -> Result<Value, JitError> {
        self.sum(a, a, k, 0..=k, |_| None, lane)
    }

    /// Order 0 of one instruction on one lane.
    fn order_zero(&mut self, w: u32, op: Instruction, lane: usize) -> Result<(), JitError> {
        let v = match op {
            Instruction::CosOf | Instruction::Aux => return Ok(()),
            Instruction::Add(a, b) | Instruction::AddC(a, b) => {
                let (x, y) = (self.ld(a, 0, lane)?, self.ld(b, 0, lane)?);
                self.b.ins().fadd(x, y)
            }
            Instruction::Sub(a, b) | Instruction::SubVC(a, b) | Instruction::SubCV(a, b) => {
                let (x, y) = (self.ld(a, 0, lane)?, self.ld(b, 0, lane)?);
                self.b.ins().fsub(x, y)
            }
            Instruction::Mul(a, b) | Instruction::MulC(a, b) => {
                let (x, y) = (self.ld(a, 0, lane)?, self.ld(b, 0, lane)?);
                self.b.ins().fmul(x, y)
            }
            Instruction::Div(a, b) | Instruction::DivVC(a, b) | Instruction::DivCV(a, b) => {
                let (x, y) = (self.ld(a, 0, lane)?, self.ld(b, 0, lane)?);
                self.b.ins().fdiv(x, y)
            }
            Instruction::Neg(a) => {
                let x = self.ld(a, 0, lane)?;
                self.b.ins().fneg(x)
            }
            Instruction::Square(a) => {
                let x = self.ld(a, 0, lane)?;
                self.b.ins().fmul(x, x)
            }
            Instruction::Sqrt(a) => {
                let x = self.ld(a, 0, lane)?;
                self.b.ins().sqrt(x)
            }
            Instruction::PowC(a, e) => {
                let (x, y) = (self.ld(a, 0, lane)?, self.ld(e, 0, lane)?);
                self.call(POWF, &[x, y])?
            }
            Instruction::Exp { u, .. } => {
                let x = self.ld(u, 0, lane)?;
                self.func(Func::Exp, x)?
            }
            Instruction::Deriv(_) => self.c(0.0),
            Instruction::Log(a) => {
                let x = self.ld(a, 0, lane)?;
                self.func(Func::Log, x)?
            }
            Instruction::Abs(a) => {
                let x = self.ld(a, 0, lane)?;
                self.b.ins().fabs(x)
            }
            Instruction::Sin { u, cos, .. } => {
                let x = self.ld(u, 0, lane)?;
                let (sin, c) = self.sin_cos(x)?;
                self.st(cos, 0, lane, c)?;
                sin
            }
            Instruction::Sinh { u, cosh, .. } => {
                let x = self.ld(u, 0, lane)?;
                let c = self.func(Func::Cosh, x)?;
                self.st(cosh, 0, lane, c)?;
                self.func(Func::Sinh, x)?
            }
            Instruction::Tan { u, aux, sign, .. } => {
                let x = self.ld(u, 0, lane)?;
                let v = self.func(if sign > 0.0 { Func::Tan } else { Func::Tanh }, x)?;
                let (one, s) = (self.c(1.0), self.c(sign));
                let sq = self.b.ins().fmul(v, v);
                let t = self.b.ins().fmul(s, sq);
                let a = self.b.ins().fadd(one, t);
                self.st(aux, 0, lane, a)?;
                v
            }
            Instruction::Asin { u, inner, root, sign } => {
                let x = self.ld(u, 0, lane)?;
                let one = self.c(1.0);
                let sq = self.b.ins().fmul(x, x);
                let i = self.b.ins().fsub(one, sq);
                self.st(inner, 0, lane, i)?;
                let r = self.b.ins().sqrt(i);
                self.st(root, 0, lane, r)?;
                self.func(if sign > 0.0 { Func::Asin } else { Func::Acos }, x)?
            }
            Instruction::Atan { u, aux } => {
                let x = self.ld(u, 0, lane)?;
                let one = self.c(1.0);
                let sq = self.b.ins().fmul(x, x);
                let a = self.b.ins().fadd(one, sq);
                self.st(aux, 0, lane, a)?;
                self.func(Func::Atan, x)?
            }
            Instruction::Atan2 { y, x, aux } => {
                let (yv, xv) = (self.ld(y, 0, lane)?, self.ld(x, 0, lane)?);
                let xx = self.b.ins().fmul(xv, xv);
                let yy = self.b.ins().fmul(yv, yv);
                let a = self.b.ins().fadd(xx, yy);
                self.st(aux, 0, lane, a)?;
                self.call(ATAN2, &[yv, xv])?
            }
        };
        self.st(w, 0, lane, v)
    }

    /// Order `k ≥ 1` of one instruction on one lane.
    fn order_k(&mut self, w: u32, op: Instruction, k: usize, lane: usize) -> Result<(), JitError> {
        let v = match op {
            Instruction::CosOf | Instruction::Aux => return Ok(()),
            Instruction::Add(a, b) => {
                let (x, y) = (self.ld(a, k, lane)?, self.ld(b, k, lane)?);
                self.b.ins().fadd(x, y)
            }
            Instruction::Sub(a, b) => {
                let (x, y) = (self.ld(a, k, lane)?, self.ld(b, k, lane)?);
                self.b.ins().fsub(x, y)
            }
            Instruction::Neg(a) | Instruction::SubCV(_, a) => {
                let x = self.ld(a, k, lane)?;
                self.b.ins().fneg(x)
            }
            Instruction::AddC(a, _) | Instruction::SubVC(a, _) => self.ld(a, k, lane)?,
            Instruction::MulC(a, c) => {
                let (x, y) = (self.ld(a, k, lane)?, self.ld(c, 0, lane)?);
                self.b.ins().fmul(x, y)
            }
            Instruction::DivVC(a, c) => {
                let (x, y) = (self.ld(a, k, lane)?, self.ld(c, 0, lane)?);
                self.b.ins().fdiv(x, y)
            }
            Instruction::Mul(a, b) => self.sum(a, b, k, 0..=k, |_| None, lane)?,
            Instruction::Square(a) => {
                let half = self.sum(a, a, k, 0..k.div_ceil(2), |_| None, lane)?;
                let two = self.c(2.0);
                let mut out = self.b.ins().fmul(two, half);
                if k.is_multiple_of(2) {
                    let m = self.ld(a, k / 2, lane)?;
                    let sq = self.b.ins().fmul(m, m);
                    out = self.b.ins().fadd(out, sq);
                }
                out
            }
            Instruction::Div(a, b) => {
                let ak = self.ld(a, k, lane)?;
                let acc = self.sub_sum(ak, b, w, k, 1..k + 1, lane)?;
                let b0 = self.ld(b, 0, lane)?;
                self.b.ins().fdiv(acc, b0)
            }
            Instruction::DivCV(_, b) => {
                let zero = self.c(0.0);
                let acc = self.sub_sum(zero, b, w, k, 1..k + 1, lane)?;
                let b0 = self.ld(b, 0, lane)?;
                self.b.ins().fdiv(acc, b0)
            }
            Instruction::Sqrt(a) => {
                let ak = self.ld(a, k, lane)?;
                let acc = self.sub_sum(ak, w, w, k, 1..k, lane)?;
                let (two, w0) = (self.c(2.0), self.ld(w, 0, lane)?);
                let den = self.b.ins().fmul(two, w0);
                self.b.ins().fdiv(acc, den)
            }
            Instruction::PowC(a, e) => {
                let alpha = self.ld(e, 0, lane)?;
                let mut acc = self.c(0.0);
                for j in 0..k {
                    let (kj, jf) = (self.c((k - j) as f64), self.c(j as f64));
                    let ak = self.b.ins().fmul(alpha, kj);
                    let coeff = self.b.ins().fsub(ak, jf);
                    let (x, y) = (self.ld(a, k - j, lane)?, self.ld(w, j, lane)?);
                    let t = self.b.ins().fmul(coeff, x);
                    let t = self.b.ins().fmul(t, y);
                    acc = self.b.ins().fadd(acc, t);
                }
                let (kf, a0) = (self.c(k as f64), self.ld(a, 0, lane)?);
                let den = self.b.ins().fmul(kf, a0);
                self.b.ins().fdiv(acc, den)
            }
            Instruction::Deriv(a) => {
                let (kf, x) = (self.c(k as f64), self.ld(a, k, lane)?);
                self.b.ins().fmul(kf, x)
            }
            Instruction::Exp { du, .. } => self.derived(du, w, k, lane)?,
            Instruction::Log(a) => {
                let s = self.weighted(w, a, k, k - 1, lane)?;
                let ak = self.ld(a, k, lane)?;
                let num = self.b.ins().fsub(ak, s);
                let a0 = self.ld(a, 0, lane)?;
                self.b.ins().fdiv(num, a0)
            }
            Instruction::Sin { du, cos, .. } => {
                let (sin, c) = self.derived_pair(du, cos, w, k, lane)?;
                let c = self.b.ins().fneg(c);
                self.st(cos, k, lane, c)?;
                sin
            }
            Instruction::Sinh { du, cosh, .. } => {
                let (sinh, c) = self.derived_pair(du, cosh, w, k, lane)?;
                self.st(cosh, k, lane, c)?;
                sinh
            }
            Instruction::Tan { du, aux, sign, .. } => {
                let v = self.derived(du, aux, k, lane)?;
                self.st(w, k, lane, v)?;
                let sq = self.self_product(w, k, lane)?;
                let s = self.c(sign);
                let a = self.b.ins().fmul(s, sq);
                self.st(aux, k, lane, a)?;
                v
            }
            Instruction::Asin { u, inner, root, sign } => {
                let sq = self.self_product(u, k, lane)?;
                let i = self.b.ins().fneg(sq);
                self.st(inner, k, lane, i)?;
                let acc = self.sub_sum(i, root, root, k, 1..k, lane)?;
                let (two, r0) = (self.c(2.0), self.ld(root, 0, lane)?);
                let den = self.b.ins().fmul(two, r0);
                let r = self.b.ins().fdiv(acc, den);
                self.st(root, k, lane, r)?;
                self.derivative_quotient(u, root, w, k, sign, lane)?
            }
            Instruction::Atan { u, aux } => {
                let sq = self.self_product(u, k, lane)?;
                self.st(aux, k, lane, sq)?;
                self.derivative_quotient(u, aux, w, k, 1.0, lane)?
            }
            Instruction::Atan2 { y, x, aux } => {
                let mut sq = self.c(0.0);
                for j in 0..=k {
                    let (x1, x2) = (self.ld(x, j, lane)?, self.ld(x, k - j, lane)?);
                    let t = self.b.ins().fmul(x1, x2);
                    sq = self.b.ins().fadd(sq, t);
                    let (y1, y2) = (self.ld(y, j, lane)?, self.ld(y, k - j, lane)?);
                    let t = self.b.ins().fmul(y1, y2);
                    sq = self.b.ins().fadd(sq, t);
                }
                self.st(aux, k, lane, sq)?;
                let mut acc = self.c(0.0);
                for j in 0..k {
                    let kj = self.c((k - j) as f64);
                    let (xj, ykj) = (self.ld(x, j, lane)?, self.ld(y, k - j, lane)?);
                    let (yj, xkj) = (self.ld(y, j, lane)?, self.ld(x, k - j, lane)?);
                    let p1 = self.b.ins().fmul(xj, ykj);
                    let p2 = self.b.ins().fmul(yj, xkj);
                    let diff = self.b.ins().fsub(p1, p2);
                    let t = self.b.ins().fmul(kj, diff);
                    acc = self.b.ins().fadd(acc, t);
                }
                for j in 1..k {
                    let kj = self.c((k - j) as f64);
                    let (dj, wkj) = (self.ld(aux, j, lane)?, self.ld(w, k - j, lane)?);
                    let t = self.b.ins().fmul(kj, dj);
                    let t = self.b.ins().fmul(t, wkj);
                    acc = self.b.ins().fsub(acc, t);
                }
                let (kf, d0) = (self.c(k as f64), self.ld(aux, 0, lane)?);
                let den = self.b.ins().fmul(kf, d0);
                self.b.ins().fdiv(acc, den)
            }
            Instruction::Abs(a) => {
                let (a0, ak) = (self.ld(a, 0, lane)?, self.ld(a, k, lane)?);
                let zero = self.c(0.0);
                let negative = self.b.ins().fcmp(FloatCC::LessThan, a0, zero);
                let minus = self.b.ins().fneg(ak);
                if self.width == 2 {
                    let mask = self.b.ins().bitcast(types::F64X2, MemFlagsData::new(), negative);
                    self.b.ins().bitselect(mask, minus, ak)
                } else {
                    self.b.ins().select(negative, minus, ak)
                }
            }
        };
        self.st(w, k, lane, v)
    }
}

impl<const L: usize> Emitter<'_, '_, L> {
    /// Order `k` of every instruction on every lane: order 0 lane by lane (it
    /// calls the elementary functions), higher orders two lanes at a time
    /// where the lanes pair up.
    fn orders(&mut self, program: &[(u32, Instruction)], k: usize) -> Result<(), JitError> {
        self.width = if k == 0 { 1 } else { vector_width(L) };
        for &(w, op) in program {
            for lane in self.groups().collect::<Vec<_>>() {
                if k == 0 {
                    self.order_zero(w, op, lane)?;
                } else {
                    self.order_k(w, op, k, lane)?;
                }
            }
        }
        Ok(())
    }
}

impl<const L: usize> Emitter<'_, '_, L> {
    /// A[0]⁻¹ on every lane, by the adjugate (n ≤ 3) or reciprocals (diagonal).
    fn invert(&mut self, s: &SecondOrderLayout) -> Result<(), JitError> {
        self.width = 1;
        let n = s.n;
        for lane in 0..L {
            if s.diagonal {
                for (e, &(i, _)) in s.entries.iter().enumerate() {
                    let (one, m) = (self.c(1.0), self.ld(s.matrix[e], 0, lane)?);
                    let r = self.b.ins().fdiv(one, m);
                    self.st(s.inverse[i], 0, lane, r)?;
                }
                continue;
            }
            let mut m = vec![None; n * n];
            for (e, &(i, j)) in s.entries.iter().enumerate() {
                m[i * n + j] = Some(self.ld(s.matrix[e], 0, lane)?);
            }
            let zero = self.c(0.0);
            let m: Vec<Value> = m.into_iter().map(|x| x.unwrap_or(zero)).collect();
            let at = |i: usize, j: usize| m[i * n + j];
            // Cofactors C_ij; A⁻¹_ij = C_ji / det.
            let mut cof = vec![zero; n * n];
            if n == 1 {
                cof[0] = self.c(1.0);
            } else if n == 2 {
                cof[0] = at(1, 1);
                cof[1] = self.b.ins().fneg(at(1, 0));
                cof[2] = self.b.ins().fneg(at(0, 1));
                cof[3] = at(0, 0);
            } else {
                for i in 0..3 {
                    for j in 0..3 {
                        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
                        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
                        // The cyclic minor carries its sign.
                        let p1 = self.b.ins().fmul(at(r0, c0), at(r1, c1));
                        let p2 = self.b.ins().fmul(at(r0, c1), at(r1, c0));
                        cof[i * 3 + j] = self.b.ins().fsub(p1, p2);
                    }
                }
            }
            let mut det = self.b.ins().fmul(at(0, 0), cof[0]);
            for j in 1..n {
                let t = self.b.ins().fmul(at(0, j), cof[j]);
                det = self.b.ins().fadd(det, t);
            }
            let one = self.c(1.0);
            let r = self.b.ins().fdiv(one, det);
            for i in 0..n {
                for j in 0..n {
                    let x = self.b.ins().fmul(cof[j * n + i], r);
                    self.st(s.inverse[i * n + j], 0, lane, x)?;
                }
            }
        }
        Ok(())
    }

    /// Order `k` of y'' and order `k + 1` of y and y':
    /// `y''[k] = A[0]⁻¹ (b[k] − Σ_{j=1..k} A[j] y''[k−j])`, `y[k+1] = y'[k]/(k+1)`,
    /// `y'[k+1] = y''[k]/(k+1)`.
    fn couple(&mut self, s: &SecondOrderLayout, k: usize) -> Result<(), JitError> {
        self.width = vector_width(L);
        let n = s.n;
        for lane in self.groups().collect::<Vec<_>>() {
            let mut rhs = Vec::with_capacity(n);
            for i in 0..n {
                rhs.push(self.ld(s.rhs[i], k, lane)?);
            }
            for (e, &(row, col)) in s.entries.iter().enumerate() {
                if !s.varying[e] {
                    continue;
                }
                if k == 0 {
                    continue;
                }
                let mut acc = self.c(0.0);
                for j in 1..=k {
                    let (aj, y2) = (self.ld(s.matrix[e], j, lane)?, self.ld(s.second[col], k - j, lane)?);
                    acc = self.mul_add(aj, y2, acc);
                }
                rhs[row] = self.b.ins().fsub(rhs[row], acc);
            }
            let scale = self.c(1.0 / (k + 1) as f64);
            for i in 0..n {
                let a = if s.diagonal {
                    let r = self.ld(s.inverse[i], 0, lane)?;
                    self.b.ins().fmul(r, rhs[i])
                } else {
                    let r = self.ld(s.inverse[i * n], 0, lane)?;
                    let mut acc = self.b.ins().fmul(r, rhs[0]);
                    for j in 1..n {
                        let r = self.ld(s.inverse[i * n + j], 0, lane)?;
                        acc = self.mul_add(r, rhs[j], acc);
                    }
                    acc
                };
                self.st(s.second[i], k, lane, a)?;
                let next_v = self.b.ins().fmul(a, scale);
                self.st(s.dy[i], k + 1, lane, next_v)?;
                let v = self.ld(s.dy[i], k, lane)?;
                let next_q = self.b.ins().fmul(v, scale);
                self.st(s.y[i], k + 1, lane, next_q)?;
                // And into the caller's series, order-major: `[y, y']` of order k + 1.
                let row = (k + 1) * 2 * n;
                self.st_series(row + i, lane, next_q)?;
                self.st_series(row + n + i, lane, next_v)?;
            }
        }
        Ok(())
    }
}

/// Defines function `i` of a second-order expansion (order `p − 1 − i`: the
/// longest first) with the coupling, while `wanted()` holds.
fn second_order_functions<const L: usize>(
    program: Vec<(u32, Instruction)>,
    order: usize,
    layout: SecondOrderLayout,
    wanted: impl Fn() -> bool + Send + Sync + 'static,
) -> impl Fn(&mut JITModule, usize) -> Result<FuncId, JitError> + Send + Sync + 'static {
    move |module, i| {
        if !wanted() {
            return Err(JitError::Codegen { message: "no longer wanted".into() });
        }
        let k = order - 1 - i;
        let sig = signature(module);
        define::<L>(module, &format!("expand{k}"), &sig, order, |e| {
            e.orders(&program, k)?;
            if k == 0 {
                e.invert(&layout)?;
            }
            e.couple(&layout, k)
        })
    }
}

/// The signature of every function here: `(coefficients: *mut f64, series:
/// *mut f64) -> ()`.
fn signature(module: &JITModule) -> Signature {
    let mut sig = module.make_signature();
    let pointer = AbiParam::new(module.target_config().pointer_type());
    sig.params.extend([pointer, pointer]);
    sig
}

/// Declares and defines function `name` of `module`, its body emitted by `body`.
fn define<const L: usize>(
    module: &mut JITModule,
    name: &str,
    sig: &Signature,
    order: usize,
    body: impl FnOnce(&mut Emitter<'_, '_, L>) -> Result<(), JitError>,
) -> Result<FuncId, JitError> {
    let id = module.declare_function(name, Linkage::Local, sig).map_err(codegen)?;
    define_function(module, id, sig, |module, b, params| {
        let mut e = Emitter::<L> {
            module,
            b,
            imports: Imports::default(),
            base: params[0],
            series: params[1],
            stride: order + 1,
            width: 1,
            fma: host_has_fma(),
        };
        body(&mut e)?;
        e.b.ins().return_(&[]);
        Ok(e.b)
    })?;
    Ok(id)
}
