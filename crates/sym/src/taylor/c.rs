//! C source for a Taylor program's orders: the same functions as
//! `cranelift.rs`, written for the system C compiler (`cc.rs`) in the
//! machine's full vector width.
//!
//! Cranelift's vectors are 128 bits wide, two lanes per instruction; the
//! processor may have wider ones (four lanes per AVX2 instruction, eight per
//! AVX-512 one). The source is written with GCC's vector extensions (which
//! clang shares): every value is an `lg_v` of `LG_W` lanes, `LG_W` chosen by
//! the preprocessor from what `-march=native` enables, and each order is one
//! function over `LG_W` lanes, called for each group of `LG_W` of the `L`
//! lanes. Written this way the compiler has nothing left to vectorize: it
//! compiles the source at `-O1` (a sixth of the time `-O3` took on the same
//! expansion written as `omp simd` loops over the lanes), and the code is as
//! fast and as compact, one copy of each order's code for every lane group.
//!
//! The arithmetic is the interpreter's, operation for operation and in the same
//! order: products are fused into multiply-adds exactly where the interpreter
//! fuses them (`lg_vfma`, where the host has FMA), every other operation is
//! rounded on its own (the source is compiled with contraction off), the
//! elementary functions at order 0 are the C library's (the ones Rust's `f64`
//! methods call, lane by lane), and sine and cosine are fdlibm's kernels as
//! `jit/trig.rs` inlines them. So a run gives the same numbers, bit for bit,
//! whichever of the interpreter, cranelift or the C compiler computed its
//! steps.

use super::program::{Instruction, SecondOrderLayout};
use crate::trig;
use std::fmt::Write as _;

/// The C source of a Taylor expansion: functions `part0` … `part{n−1}`, each
/// `void (double *coef, double *series)` like the native code's.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct CSource {
    /// What every file needs first (includes, macros, sine and cosine).
    pub(crate) prelude: String,
    /// Each function's definition.
    pub(crate) parts: Vec<String>,
}

impl CSource {
    /// The source as `files` files of about equal length (a prelude each),
    /// to be compiled side by side: the compiler's time grows with the length
    /// of what it reads, and each function is independent.
    pub(crate) fn files(&self, files: usize) -> Vec<String> {
        let files = files.clamp(1, self.parts.len().max(1));
        let mut out: Vec<String> = vec![self.prelude.clone(); files];
        let mut order: Vec<usize> = (0..self.parts.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(self.parts[i].len()));
        for i in order {
            // The shortest file takes the longest function left.
            let shortest = (0..files).min_by_key(|&f| out[f].len()).expect("at least one file");
            out[shortest].push_str(&self.parts[i]);
        }
        out
    }
}

/// The functions' names, by number.
pub(crate) fn part_name(i: usize) -> String {
    format!("part{i}")
}

/// The source of every order of `program` (function `k` computes order `k`),
/// for [`super::TaylorTape::compute`].
pub(crate) fn orders<const L: usize>(program: &[(u32, Instruction)], order: usize, fused: bool) -> CSource {
    let mut w = Writer::new(L, order + 1, fused);
    for k in 0..=order {
        w.function(k, |w| w.orders(program, k));
    }
    w.finish()
}

/// The source of a second-order expansion: function `k` computes order `k`
/// of the tape, then (at order 0) `A[0]⁻¹`, then order `k` of y'' and `k + 1`
/// of y and y' (see `TaylorTape::set_second_order`), so that the functions
/// run in turn make the whole expansion.
pub(crate) fn second_order<const L: usize>(
    program: &[(u32, Instruction)],
    order: usize,
    layout: &SecondOrderLayout,
    fused: bool,
) -> CSource {
    let mut w = Writer::new(L, order + 1, fused);
    for k in 0..order {
        w.function(k, |w| {
            w.orders(program, k);
            if k == 0 {
                w.invert(layout);
            }
            w.couple(layout, k);
        });
    }
    w.finish()
}

/// A double as a C literal that reads back as the same number.
fn lit(x: f64) -> String {
    if x.is_nan() {
        "NAN".into()
    } else if x.is_infinite() {
        if x > 0.0 { "INFINITY" } else { "(-INFINITY)" }.into()
    } else {
        // Rust prints the shortest decimal that reads back exactly; C
        // compilers round decimal literals correctly.
        let text = format!("{x:?}");
        if x < 0.0 || (x == 0.0 && x.is_sign_negative()) {
            format!("({text})")
        } else {
            text
        }
    }
}

/// Writes the source: one function at a time, each value a `const lg_v`
/// temporary (all `LG_W` lanes of a group at once), but for the library's
/// functions, called lane by lane in a loop over the group.
struct Writer {
    out: String,
    lanes: usize,
    stride: usize,
    fused: bool,
    /// Temporaries made in the current function.
    temps: usize,
    /// Whether a loop over the lanes of the group is open.
    scalar: bool,
    /// The functions written so far.
    parts: Vec<String>,
}

impl Writer {
    fn new(lanes: usize, stride: usize, fused: bool) -> Writer {
        Writer { out: String::new(), lanes, stride, fused, temps: 0, scalar: false, parts: Vec::new() }
    }

    fn finish(mut self) -> CSource {
        self.vector();
        CSource { prelude: prelude(self.lanes), parts: self.parts }
    }

    /// Function `i`: `part{i}_w`, the order's code for one group of `LG_W`
    /// lanes, and `part{i}`, which runs it on every group.
    fn function(&mut self, i: usize, body: impl FnOnce(&mut Writer)) {
        self.out.clear();
        self.temps = 0;
        let name = part_name(i);
        let _ = writeln!(
            self.out,
            "\nstatic LG_NOINLINE void {name}_w(double *restrict c, double *restrict s) {{\n    (void)s;"
        );
        body(self);
        self.vector();
        let _ = writeln!(
            self.out,
            "}}\nLG_EXPORT void {name}(double *restrict c, double *restrict s) {{\n    \
             for (int l = 0; l < LG_LANES; l += LG_W) {name}_w(c + l, s ? s + l : s);\n}}"
        );
        self.parts.push(std::mem::take(&mut self.out));
    }

    /// Opens a loop over the lanes of the group, where there is none.
    fn scalar(&mut self) {
        if !self.scalar {
            self.out.push_str("    for (int l = 0; l < LG_W; ++l) {\n");
            self.scalar = true;
        }
    }

    /// Closes the loop over the lanes, where one is open: back to vectors.
    fn vector(&mut self) {
        if self.scalar {
            self.out.push_str("    }\n");
            self.scalar = false;
        }
    }

    /// The index of coefficient `j` of `slot` on lane 0.
    fn index(&self, slot: u32, j: usize) -> usize {
        (slot as usize * self.stride + j) * self.lanes
    }

    /// Coefficient `j` of `slot`: on lane `l` in a loop over the lanes, the
    /// group's vector otherwise.
    fn ld(&self, slot: u32, j: usize) -> String {
        let i = self.index(slot, j);
        if self.scalar {
            format!("c[{i}+l]")
        } else {
            format!("LV({i})")
        }
    }

    /// The number `x` as a value of the current kind (a vector with every
    /// lane `x`, outside a loop over the lanes).
    fn splat(&self, x: &str) -> String {
        if self.scalar {
            x.to_string()
        } else {
            format!("LG_SPLAT({x})")
        }
    }

    /// `-x`, by its sign bit.
    fn neg(&self, x: &str) -> String {
        if self.scalar {
            format!("lg_neg({x})")
        } else {
            format!("lg_vneg({x})")
        }
    }

    /// A new temporary holding `expr`.
    fn let_(&mut self, expr: impl AsRef<str>) -> String {
        let name = format!("t{}", self.temps);
        self.temps += 1;
        let (kind, indent) = if self.scalar { ("double", "        ") } else { ("lg_v", "    ") };
        let _ = writeln!(self.out, "{indent}const {kind} {name} = {};", expr.as_ref());
        name
    }

    fn st(&mut self, slot: u32, j: usize, value: &str) {
        let at = self.ld(slot, j);
        let indent = if self.scalar { "        " } else { "    " };
        let _ = writeln!(self.out, "{indent}{at} = {value};");
    }

    /// `acc + x·y`, fused where the interpreter fuses (its `madd`).
    fn mul_add(&mut self, x: &str, y: &str, acc: &str) -> String {
        if self.fused {
            self.let_(format!("{}({x}, {y}, {acc})", self.fma()))
        } else {
            self.let_(format!("{acc} + {x} * {y}"))
        }
    }

    /// `Σ_{j ∈ js} weight(j) · a[j] · b[k−j]`, started from zero, each term
    /// a multiply-add (fused where the interpreter fuses). `weighted`: the
    /// weight of term `j` is `j`.
    fn sum(&mut self, a: u32, b: u32, k: usize, js: std::ops::RangeInclusive<usize>, weighted: bool) -> String {
        let fma = self.fused.then(|| self.fma());
        let zero = self.splat("0.0");
        self.chain(&zero, a, b, k, js, move |x, y, acc, j| {
            let x = if weighted { format!("{j} * {x}") } else { x.to_string() };
            if let Some(fma) = fma {
                format!("{fma}({x}, {y}, {acc})")
            } else {
                format!("{acc} + {x} * {y}")
            }
        })
    }

    /// The fused multiply-add of the current kind of value.
    fn fma(&self) -> &'static str {
        if self.scalar {
            "fma"
        } else {
            "lg_vfma"
        }
    }

    /// `acc − Σ_{j ∈ js} a[j] · b[k−j]`, one rounding per operation.
    fn sub_sum(&mut self, acc: String, a: u32, b: u32, k: usize, js: std::ops::RangeInclusive<usize>) -> String {
        self.chain(&acc, a, b, k, js, |x, y, acc, _| format!("{acc} - {x} * {y}"))
    }

    /// A chain `acc ← step(a[j], b[k−j], acc, j)` over `js` from `init`,
    /// written out term by term: the compiler keeps it in registers and
    /// overlaps the chains of an order. (Written as loops over `j` it reads
    /// a tenth as long and compiles that much faster, but runs three times
    /// slower, measured on the double pendulum's map.)
    fn chain(
        &mut self,
        init: &str,
        a: u32,
        b: u32,
        k: usize,
        js: std::ops::RangeInclusive<usize>,
        step: impl Fn(&str, &str, &str, String) -> String,
    ) -> String {
        let mut acc = init.to_string();
        for j in js {
            let (x, y) = (self.ld(a, j), self.ld(b, k - j));
            acc = self.let_(step(&x, &y, &acc, lit(j as f64)));
        }
        if acc == init {
            acc = self.let_(init);
        }
        acc
    }

    fn derived(&mut self, du: u32, b: u32, k: usize) -> String {
        let acc = self.sum(du, b, k, 1..=k, false);
        self.let_(format!("{acc} / {}", lit(k as f64)))
    }

    fn derived_pair(&mut self, du: u32, a: u32, b: u32, k: usize) -> (String, String) {
        let (mut sa, mut sb) = (self.splat("0.0"), self.splat("0.0"));
        for j in 1..=k {
            let d = self.ld(du, j);
            let (x, y) = (self.ld(a, k - j), self.ld(b, k - j));
            sa = self.mul_add(&d, &x, &sa);
            sb = self.mul_add(&d, &y, &sb);
        }
        let kf = lit(k as f64);
        (self.let_(format!("{sa} / {kf}")), self.let_(format!("{sb} / {kf}")))
    }

    fn weighted(&mut self, a: u32, b: u32, k: usize, hi: usize) -> String {
        let acc = self.sum(a, b, k, 1..=hi, true);
        self.let_(format!("{acc} / {}", lit(k as f64)))
    }

    fn derivative_quotient(&mut self, u: u32, d: u32, w: u32, k: usize, sign: f64) -> String {
        let kf = k as f64;
        let mut acc = self.let_(format!("{} * {}", lit(sign * kf), self.ld(u, k)));
        for j in 1..k {
            let (x, y) = (self.ld(d, j), self.ld(w, k - j));
            let t = self.let_(format!("{} * {x}", lit((k - j) as f64)));
            let t = self.let_(format!("{t} * {y}"));
            acc = self.let_(format!("{acc} - {t}"));
        }
        let den = self.let_(format!("{} * {}", lit(kf), self.ld(d, 0)));
        self.let_(format!("{acc} / {den}"))
    }

    fn self_product(&mut self, a: u32, k: usize) -> String {
        self.sum(a, a, k, 0..=k, false)
    }

    /// Whether order 0 of `op` calls the C library (and so runs lane by lane).
    fn calls_library(op: Instruction) -> bool {
        matches!(
            op,
            Instruction::PowC(..)
                | Instruction::Exp { .. }
                | Instruction::Log(_)
                | Instruction::Sinh { .. }
                | Instruction::Tan { .. }
                | Instruction::Asin { .. }
                | Instruction::Atan { .. }
                | Instruction::Atan2 { .. }
        )
    }

    /// Order 0 of one instruction.
    fn order_zero(&mut self, w: u32, op: Instruction) {
        if matches!(op, Instruction::CosOf | Instruction::Aux) {
            return;
        }
        if Self::calls_library(op) {
            self.scalar();
        } else {
            self.vector();
        }
        let v = match op {
            Instruction::CosOf | Instruction::Aux => return,
            Instruction::Add(a, b) | Instruction::AddC(a, b) => {
                self.let_(format!("{} + {}", self.ld(a, 0), self.ld(b, 0)))
            }
            Instruction::Sub(a, b) | Instruction::SubVC(a, b) | Instruction::SubCV(a, b) => {
                self.let_(format!("{} - {}", self.ld(a, 0), self.ld(b, 0)))
            }
            Instruction::Mul(a, b) | Instruction::MulC(a, b) => {
                self.let_(format!("{} * {}", self.ld(a, 0), self.ld(b, 0)))
            }
            Instruction::Div(a, b) | Instruction::DivVC(a, b) | Instruction::DivCV(a, b) => {
                self.let_(format!("{} / {}", self.ld(a, 0), self.ld(b, 0)))
            }
            Instruction::Neg(a) => self.let_(self.neg(&self.ld(a, 0))),
            Instruction::Square(a) => {
                let x = self.let_(self.ld(a, 0));
                self.let_(format!("{x} * {x}"))
            }
            Instruction::Sqrt(a) => self.let_(format!("lg_vsqrt({})", self.ld(a, 0))),
            Instruction::PowC(a, e) => self.let_(format!("pow({}, {})", self.ld(a, 0), self.ld(e, 0))),
            Instruction::Exp { u, .. } => self.let_(format!("exp({})", self.ld(u, 0))),
            Instruction::Deriv(_) => self.let_(self.splat("0.0")),
            Instruction::Log(a) => self.let_(format!("log({})", self.ld(a, 0))),
            Instruction::Abs(a) => self.let_(format!("lg_vabs({})", self.ld(a, 0))),
            Instruction::Sin { u, cos, .. } => {
                let x = self.let_(self.ld(u, 0));
                let (sn, cs) = (format!("t{}", self.temps), format!("t{}", self.temps + 1));
                self.temps += 2;
                let _ = writeln!(self.out, "    lg_v {sn}, {cs};\n    lg_vsin_cos({x}, &{sn}, &{cs});");
                self.st(w, 0, &sn);
                self.st(cos, 0, &cs);
                // Beyond the inline range (and for NaN), the library, as the
                // interpreter calls it there.
                self.scalar();
                let x = self.let_(self.ld(u, 0));
                let _ = writeln!(
                    self.out,
                    "        if (!(fabs({x}) < {})) {{ {} = sin({x}); {} = cos({x}); }}",
                    lit(trig::INLINE_MAX),
                    self.ld(w, 0),
                    self.ld(cos, 0)
                );
                return;
            }
            Instruction::Sinh { u, cosh, .. } => {
                let x = self.let_(self.ld(u, 0));
                let ch = self.let_(format!("cosh({x})"));
                self.st(cosh, 0, &ch);
                self.let_(format!("sinh({x})"))
            }
            Instruction::Tan { u, aux, sign, .. } => {
                let x = self.let_(self.ld(u, 0));
                let v = self.let_(format!("{}({x})", if sign > 0.0 { "tan" } else { "tanh" }));
                let sq = self.let_(format!("{v} * {v}"));
                let t = self.let_(format!("{} * {sq}", lit(sign)));
                let a = self.let_(format!("1.0 + {t}"));
                self.st(aux, 0, &a);
                v
            }
            Instruction::Asin { u, inner, root, sign } => {
                let x = self.let_(self.ld(u, 0));
                let sq = self.let_(format!("{x} * {x}"));
                let i = self.let_(format!("1.0 - {sq}"));
                self.st(inner, 0, &i);
                let r = self.let_(format!("sqrt({i})"));
                self.st(root, 0, &r);
                self.let_(format!("{}({x})", if sign > 0.0 { "asin" } else { "acos" }))
            }
            Instruction::Atan { u, aux } => {
                let x = self.let_(self.ld(u, 0));
                let sq = self.let_(format!("{x} * {x}"));
                let a = self.let_(format!("1.0 + {sq}"));
                self.st(aux, 0, &a);
                self.let_(format!("atan({x})"))
            }
            Instruction::Atan2 { y, x, aux } => {
                let (yv, xv) = (self.let_(self.ld(y, 0)), self.let_(self.ld(x, 0)));
                let xx = self.let_(format!("{xv} * {xv}"));
                let yy = self.let_(format!("{yv} * {yv}"));
                let a = self.let_(format!("{xx} + {yy}"));
                self.st(aux, 0, &a);
                self.let_(format!("atan2({yv}, {xv})"))
            }
        };
        self.st(w, 0, &v);
    }

    /// Order `k ≥ 1` of one instruction.
    fn order_k(&mut self, w: u32, op: Instruction, k: usize) {
        let v = match op {
            Instruction::CosOf | Instruction::Aux => return,
            Instruction::Add(a, b) => self.let_(format!("{} + {}", self.ld(a, k), self.ld(b, k))),
            Instruction::Sub(a, b) => self.let_(format!("{} - {}", self.ld(a, k), self.ld(b, k))),
            Instruction::Neg(a) | Instruction::SubCV(_, a) => self.let_(self.neg(&self.ld(a, k))),
            Instruction::AddC(a, _) | Instruction::SubVC(a, _) => self.let_(self.ld(a, k)),
            Instruction::MulC(a, c) => self.let_(format!("{} * {}", self.ld(a, k), self.ld(c, 0))),
            Instruction::DivVC(a, c) => self.let_(format!("{} / {}", self.ld(a, k), self.ld(c, 0))),
            Instruction::Mul(a, b) => self.sum(a, b, k, 0..=k, false),
            Instruction::Square(a) => {
                let half = self.sum(a, a, k, 0..=k.div_ceil(2) - 1, false);
                let mut out = self.let_(format!("2.0 * {half}"));
                if k.is_multiple_of(2) {
                    let m = self.let_(self.ld(a, k / 2));
                    let sq = self.let_(format!("{m} * {m}"));
                    out = self.let_(format!("{out} + {sq}"));
                }
                out
            }
            Instruction::Div(a, b) => {
                let ak = self.let_(self.ld(a, k));
                let acc = self.sub_sum(ak, b, w, k, 1..=k);
                self.let_(format!("{acc} / {}", self.ld(b, 0)))
            }
            Instruction::DivCV(_, b) => {
                let zero = self.let_(self.splat("0.0"));
                let acc = self.sub_sum(zero, b, w, k, 1..=k);
                self.let_(format!("{acc} / {}", self.ld(b, 0)))
            }
            Instruction::Sqrt(a) => {
                let ak = self.let_(self.ld(a, k));
                let acc = self.sub_sum(ak, w, w, k, 1..=k - 1);
                let den = self.let_(format!("2.0 * {}", self.ld(w, 0)));
                self.let_(format!("{acc} / {den}"))
            }
            Instruction::PowC(a, e) => {
                let alpha = self.let_(self.ld(e, 0));
                let mut acc = self.let_(self.splat("0.0"));
                for j in 0..k {
                    let ak = self.let_(format!("{alpha} * {}", lit((k - j) as f64)));
                    let coeff = self.let_(format!("{ak} - {}", lit(j as f64)));
                    let t = self.let_(format!("{coeff} * {}", self.ld(a, k - j)));
                    let t = self.let_(format!("{t} * {}", self.ld(w, j)));
                    acc = self.let_(format!("{acc} + {t}"));
                }
                let den = self.let_(format!("{} * {}", lit(k as f64), self.ld(a, 0)));
                self.let_(format!("{acc} / {den}"))
            }
            Instruction::Deriv(a) => self.let_(format!("{} * {}", lit(k as f64), self.ld(a, k))),
            Instruction::Exp { du, .. } => self.derived(du, w, k),
            Instruction::Log(a) => {
                let s = self.weighted(w, a, k, k - 1);
                let num = self.let_(format!("{} - {s}", self.ld(a, k)));
                self.let_(format!("{num} / {}", self.ld(a, 0)))
            }
            Instruction::Sin { du, cos, .. } => {
                let (sin, c) = self.derived_pair(du, cos, w, k);
                let c = self.let_(self.neg(&c));
                self.st(cos, k, &c);
                sin
            }
            Instruction::Sinh { du, cosh, .. } => {
                let (sinh, c) = self.derived_pair(du, cosh, w, k);
                self.st(cosh, k, &c);
                sinh
            }
            Instruction::Tan { du, aux, sign, .. } => {
                let v = self.derived(du, aux, k);
                self.st(w, k, &v);
                let sq = self.self_product(w, k);
                let a = self.let_(format!("{} * {sq}", lit(sign)));
                self.st(aux, k, &a);
                v
            }
            Instruction::Asin { u, inner, root, sign } => {
                let sq = self.self_product(u, k);
                let i = self.let_(self.neg(&sq));
                self.st(inner, k, &i);
                let acc = self.sub_sum(i, root, root, k, 1..=k - 1);
                let den = self.let_(format!("2.0 * {}", self.ld(root, 0)));
                let r = self.let_(format!("{acc} / {den}"));
                self.st(root, k, &r);
                self.derivative_quotient(u, root, w, k, sign)
            }
            Instruction::Atan { u, aux } => {
                let sq = self.self_product(u, k);
                self.st(aux, k, &sq);
                self.derivative_quotient(u, aux, w, k, 1.0)
            }
            Instruction::Atan2 { y, x, aux } => {
                let mut sq = self.let_(self.splat("0.0"));
                for j in 0..=k {
                    let t = self.let_(format!("{} * {}", self.ld(x, j), self.ld(x, k - j)));
                    sq = self.let_(format!("{sq} + {t}"));
                    let t = self.let_(format!("{} * {}", self.ld(y, j), self.ld(y, k - j)));
                    sq = self.let_(format!("{sq} + {t}"));
                }
                self.st(aux, k, &sq);
                let mut acc = self.let_(self.splat("0.0"));
                for j in 0..k {
                    let p1 = self.let_(format!("{} * {}", self.ld(x, j), self.ld(y, k - j)));
                    let p2 = self.let_(format!("{} * {}", self.ld(y, j), self.ld(x, k - j)));
                    let t = self.let_(format!("{} * ({p1} - {p2})", lit((k - j) as f64)));
                    acc = self.let_(format!("{acc} + {t}"));
                }
                for j in 1..k {
                    let t = self.let_(format!("{} * {}", lit((k - j) as f64), self.ld(aux, j)));
                    let t = self.let_(format!("{t} * {}", self.ld(w, k - j)));
                    acc = self.let_(format!("{acc} - {t}"));
                }
                let den = self.let_(format!("{} * {}", lit(k as f64), self.ld(aux, 0)));
                self.let_(format!("{acc} / {den}"))
            }
            Instruction::Abs(a) => {
                let (a0, ak) = (self.ld(a, 0), self.let_(self.ld(a, k)));
                self.let_(format!("lg_vsel((lg_m)({a0} < LG_ZERO), lg_vneg({ak}), {ak})"))
            }
        };
        self.st(w, k, &v);
    }

    /// Order `k` of every instruction: in vectors, but for the library's
    /// functions at order 0, lane by lane.
    fn orders(&mut self, program: &[(u32, Instruction)], k: usize) {
        for &(w, op) in program {
            if k == 0 {
                self.order_zero(w, op);
            } else {
                self.vector();
                self.order_k(w, op, k);
            }
        }
    }

    /// `A[0]⁻¹` into its slots, by reciprocals or the adjugate over the
    /// determinant, as `TaylorTape::invert_interpreted`.
    fn invert(&mut self, s: &SecondOrderLayout) {
        self.vector();
        let n = s.n;
        if s.diagonal {
            for (e, &(i, _)) in s.entries.iter().enumerate() {
                let r = self.let_(format!("1.0 / {}", self.ld(s.matrix[e], 0)));
                self.st(s.inverse[i], 0, &r);
            }
            return;
        }
        let mut m = vec![self.splat("0.0"); n * n];
        for (e, &(i, j)) in s.entries.iter().enumerate() {
            m[i * n + j] = self.let_(self.ld(s.matrix[e], 0));
        }
        let at = |i: usize, j: usize| m[i * n + j].clone();
        let mut cof = vec![self.splat("0.0"); n * n];
        if n == 1 {
            cof[0] = self.splat("1.0");
        } else if n == 2 {
            cof[0] = at(1, 1);
            cof[1] = self.let_(self.neg(&at(1, 0)));
            cof[2] = self.let_(self.neg(&at(0, 1)));
            cof[3] = at(0, 0);
        } else {
            for i in 0..3 {
                for j in 0..3 {
                    let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
                    let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
                    let p1 = self.let_(format!("{} * {}", at(r0, c0), at(r1, c1)));
                    let p2 = self.let_(format!("{} * {}", at(r0, c1), at(r1, c0)));
                    cof[i * 3 + j] = self.let_(format!("{p1} - {p2}"));
                }
            }
        }
        let mut det = self.let_(format!("{} * {}", at(0, 0), cof[0]));
        for j in 1..n {
            let t = self.let_(format!("{} * {}", at(0, j), cof[j]));
            det = self.let_(format!("{det} + {t}"));
        }
        let r = self.let_(format!("1.0 / {det}"));
        for i in 0..n {
            for j in 0..n {
                let x = self.let_(format!("{} * {r}", cof[j * n + i]));
                self.st(s.inverse[i * n + j], 0, &x);
            }
        }
    }

    /// Order `k` of y'' and order `k + 1` of y and y', into the slots and the
    /// caller's series, as `TaylorTape::couple_interpreted`.
    fn couple(&mut self, s: &SecondOrderLayout, k: usize) {
        self.vector();
        let n = s.n;
        let mut rhs: Vec<String> = (0..n).map(|i| self.let_(self.ld(s.rhs[i], k))).collect();
        if k > 0 {
            for (e, &(row, col)) in s.entries.iter().enumerate() {
                if !s.varying[e] {
                    continue;
                }
                let acc = self.sum(s.matrix[e], s.second[col], k, 1..=k, false);
                rhs[row] = self.let_(format!("{} - {acc}", rhs[row]));
            }
        }
        let scale = lit(1.0 / (k + 1) as f64);
        let row = (k + 1) * 2 * n;
        for i in 0..n {
            let a = if s.diagonal {
                self.let_(format!("{} * {}", self.ld(s.inverse[i], 0), rhs[i]))
            } else {
                let mut acc = self.let_(format!("{} * {}", self.ld(s.inverse[i * n], 0), rhs[0]));
                for j in 1..n {
                    let r = self.ld(s.inverse[i * n + j], 0);
                    acc = self.mul_add(&r, &rhs[j], &acc);
                }
                acc
            };
            self.st(s.second[i], k, &a);
            let next_v = self.let_(format!("{a} * {scale}"));
            self.st(s.dy[i], k + 1, &next_v);
            let next_q = self.let_(format!("{} * {scale}", self.ld(s.dy[i], k)));
            self.st(s.y[i], k + 1, &next_q);
            let lanes = self.lanes;
            let _ = writeln!(self.out, "    SV({}) = {next_q};", (row + i) * lanes);
            let _ = writeln!(self.out, "    SV({}) = {next_v};", (row + n + i) * lanes);
        }
    }
}

/// The head of every source: the vector type and its operations for the
/// machine, and fdlibm's sine and cosine as `jit/trig.rs` computes them (its
/// constants, its operations in its order) on vectors.
fn prelude(lanes: usize) -> String {
    let mut p = format!(
        "/* Generated by lagrange: the Taylor expansion of one model. */\n\
         #include <math.h>\n\
         #include <stdint.h>\n\
         #include <string.h>\n\
         #if defined(_WIN32)\n\
         #define LG_EXPORT __declspec(dllexport)\n\
         #else\n\
         #define LG_EXPORT __attribute__((visibility(\"default\")))\n\
         #endif\n\
         #define LG_NOINLINE __attribute__((noinline))\n\
         #define LG_INLINE static inline __attribute__((always_inline))\n\
         /* The lanes of a call, and the lanes of one vector: the widest the\n\
         \x20  processor has that divides them. */\n\
         #define LG_LANES {lanes}\n\
         #if defined(__AVX512F__) && LG_LANES % 8 == 0\n\
         #define LG_W 8\n\
         #elif defined(__AVX__) && LG_LANES % 4 == 0\n\
         #define LG_W 4\n\
         #else\n\
         #define LG_W 2\n\
         #endif\n\
         typedef double lg_v __attribute__((vector_size(8 * LG_W), aligned(8), may_alias));\n\
         typedef long long lg_m __attribute__((vector_size(8 * LG_W)));\n\
         #define LV(i) (*(lg_v *)&c[i])\n\
         #define SV(i) (*(lg_v *)&s[i])\n\
         #define LG_ZERO ((lg_v){{0}})\n\
         /* x on every lane (x - 0 is x, -0 and NaN included). */\n\
         #define LG_SPLAT(x) ((x) - LG_ZERO)\n\
         #define LG_SIGN ((long long)0x8000000000000000ULL)\n\
         /* The fused multiply-add of every lane: one instruction where the\n\
         \x20  compiler names it, the C library's fma() lane by lane otherwise. */\n\
         #if defined(__clang__)\n\
         #if __has_builtin(__builtin_elementwise_fma)\n\
         #define lg_vfma(a, b, c) __builtin_elementwise_fma((a), (b), (c))\n\
         #endif\n\
         #elif defined(__GNUC__) && defined(__x86_64__)\n\
         #if LG_W == 8\n\
         #define lg_vfma(a, b, c) ((lg_v)__builtin_ia32_vfmaddpd512_mask((a), (b), (c), (unsigned char)-1, 4))\n\
         #elif LG_W == 4 && defined(__FMA__)\n\
         #define lg_vfma(a, b, c) ((lg_v)__builtin_ia32_vfmaddpd256((a), (b), (c)))\n\
         #elif LG_W == 2 && defined(__FMA__)\n\
         #define lg_vfma(a, b, c) ((lg_v)__builtin_ia32_vfmaddpd((a), (b), (c)))\n\
         #endif\n\
         #endif\n\
         #ifndef lg_vfma\n\
         LG_INLINE lg_v lg_vfma(lg_v a, lg_v b, lg_v c) {{ lg_v r; for (int i = 0; i < LG_W; ++i) r[i] = fma(a[i], b[i], c[i]); return r; }}\n\
         #endif\n\
         static inline double lg_bits(uint64_t b) {{ double x; memcpy(&x, &b, 8); return x; }}\n\
         static inline uint64_t lg_to_bits(double x) {{ uint64_t b; memcpy(&b, &x, 8); return b; }}\n\
         /* -x by its sign bit: a C compiler may fold `-fma(a, b, c)` into\n\
         \x20  `-(a*b) - c`, which differs where the sum is an exact zero. */\n\
         static inline double lg_neg(double x) {{ return lg_bits(lg_to_bits(x) ^ 0x8000000000000000ULL); }}\n\
         LG_INLINE lg_v lg_vneg(lg_v x) {{ return (lg_v)((lg_m)x ^ LG_SIGN); }}\n\
         LG_INLINE lg_v lg_vabs(lg_v x) {{ return (lg_v)((lg_m)x & ~LG_SIGN); }}\n\
         /* m ? a : b, lane by lane (m: all ones or all zeros). */\n\
         LG_INLINE lg_v lg_vsel(lg_m m, lg_v a, lg_v b) {{ return (lg_v)(((lg_m)a & m) | ((lg_m)b & ~m)); }}\n\
         LG_INLINE lg_v lg_vsqrt(lg_v x) {{ lg_v r; for (int i = 0; i < LG_W; ++i) r[i] = sqrt(x[i]); return r; }}\n"
    );
    let poly = |z: &str, coefficients: &[f64]| -> String {
        // Estrin's scheme, paired as `trig::polynomial`.
        let mut terms: Vec<String> = coefficients
            .chunks(2)
            .map(|pair| match pair.get(1) {
                Some(&c1) => format!("({z} * {} + {})", lit(c1), lit(pair[0])),
                None => lit(pair[0]),
            })
            .collect();
        let mut power = z.to_string();
        while terms.len() > 1 {
            power = format!("({power} * {power})");
            terms = terms
                .chunks(2)
                .map(|pair| match pair {
                    [lo, hi] => format!("({hi} * {power} + {lo})"),
                    [lo] => lo.clone(),
                    _ => unreachable!("chunks of two"),
                })
                .collect();
        }
        terms.remove(0)
    };
    let _ = write!(
        p,
        "/* sin and cos for |x| < 2^19 pi/2 (jit/trig.rs), lane by lane. */\n\
         LG_INLINE void lg_vsin_cos(lg_v x, lg_v *sin_out, lg_v *cos_out) {{\n\
         \x20   const lg_v shifted = x * {inv} + {to_int};\n\
         \x20   const lg_v n = shifted - {to_int};\n\
         \x20   const lg_m quadrant = (lg_m)shifted;\n\
         \x20   const lg_v r1 = x - n * {p1};\n\
         \x20   const lg_v w2 = n * {p2}, w3 = n * {p3};\n\
         \x20   const lg_v hi = w2 + w3;\n\
         \x20   const lg_v lo = w3 - (hi - w2);\n\
         \x20   const lg_v y0 = r1 - hi;\n\
         \x20   const lg_v a_part = y0 + hi;\n\
         \x20   const lg_v c_part = a_part - y0;\n\
         \x20   const lg_v e = (r1 - a_part) + (c_part - hi);\n\
         \x20   const lg_v y1 = e - (lo + n * {p3t});\n\
         \x20   const lg_v z = y0 * y0;\n\
         \x20   const lg_v v = z * y0;\n\
         \x20   const lg_v rs = {poly_s};\n\
         \x20   const lg_v u = y1 * 0.5 - v * rs;\n\
         \x20   const lg_v s = y0 - ((z * u - y1) - v * {s0});\n\
         \x20   const lg_v rc = z * {poly_c};\n\
         \x20   const lg_v ax = lg_vabs(y0);\n\
         \x20   const lg_v quarter = (lg_v)(((lg_m)ax & (long long)0xFFFFFFFF00000000ULL) - 0x0020000000000000LL);\n\
         \x20   const lg_v qx = lg_vsel((lg_m)(ax < {small}), LG_ZERO, lg_vsel((lg_m)(ax >= {large}), LG_SPLAT(0.28125), quarter));\n\
         \x20   const lg_v c = (1.0 - qx) - ((z * 0.5 - qx) - (z * rc - y0 * y1));\n\
         \x20   const lg_m odd = (lg_m)((quadrant & 1) != 0);\n\
         \x20   const lg_v sin_abs = lg_vsel(odd, c, s);\n\
         \x20   const lg_v cos_abs = lg_vsel(odd, s, c);\n\
         \x20   *sin_out = lg_vsel((lg_m)((quadrant & 2) != 0), lg_vneg(sin_abs), sin_abs);\n\
         \x20   *cos_out = lg_vsel((lg_m)(((quadrant + 1) & 2) != 0), lg_vneg(cos_abs), cos_abs);\n\
         }}\n",
        inv = lit(trig::INV_PIO2),
        to_int = lit(trig::TO_INT),
        p1 = lit(trig::P1),
        p2 = lit(trig::P2),
        p3 = lit(trig::P3),
        p3t = lit(trig::P3T),
        poly_s = poly("z", &trig::S[1..]),
        s0 = lit(trig::S[0]),
        poly_c = poly("z", &trig::C),
        small = lit(trig::COS_SMALL),
        large = lit(trig::COS_LARGE),
    );
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_read_back() {
        for x in [0.5, -0.25, 1e-300, 1.0 / 3.0, -0.0, 6_755_399_441_055_744.0, trig::INLINE_MAX] {
            let text = lit(x);
            let inner = text.trim_start_matches('(').trim_end_matches(')');
            assert_eq!(inner.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{text}");
        }
        assert_eq!(lit(f64::INFINITY), "INFINITY");
    }

    #[test]
    fn a_product_is_one_fused_sum_per_term() {
        let mut w = Writer::new(4, 3, true);
        let v = w.sum(0, 1, 2, 0..=2, false);
        assert_eq!(v, "t2");
        assert!(w.out.contains("lg_vfma(LV(0), LV(20), LG_SPLAT(0.0))"), "{}", w.out);
        assert!(w.out.contains("lg_vfma(LV(4), LV(16), t0)"), "{}", w.out);
        assert!(w.out.contains("lg_vfma(LV(8), LV(12), t1)"), "{}", w.out);
    }
}
