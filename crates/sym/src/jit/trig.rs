//! `sin` and `cos` as inline cranelift IR, for [`Compiled`](super::Compiled):
//! the operations of [`crate::trig`] (fdlibm's reduction and kernels, whose
//! description and constants live there), emitted in the same order so that
//! native code gives the interpreter's numbers bit for bit.
//!
//! [`sin_cos`] emits both functions of one argument `x` from one reduction. The
//! arithmetic is the same whether one or both results are used, so `sin(u)` does
//! not depend on whether the tape also holds `cos(u)`. Measured against glibc's
//! `sin` and `cos` (the tests below), the results differ by at most one ulp, in
//! about 3% of cases.

use crate::trig::{C, COS_LARGE, COS_SMALL, INV_PIO2, P1, P2, P3, P3T, S, TO_INT};
use cranelift_codegen::ir::{condcodes::FloatCC, types, InstBuilder, MemFlagsData, Value};
use cranelift_frontend::FunctionBuilder;

/// Emits `(sin x, cos x)` for `|x| <` [`crate::trig::INLINE_MAX`] into the current block
/// (straight-line code; the caller handles other `x`).
pub(crate) fn sin_cos(b: &mut FunctionBuilder<'_>, x: Value) -> (Value, Value) {
    let (y0, y1, quadrant) = reduce(b, x);
    let s = kernel_sin(b, y0, y1);
    let c = kernel_cos(b, y0, y1);
    // n mod 4 = 0, 1, 2, 3: (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s).
    let odd = b.ins().band_imm_u(quadrant, 1);
    let sin_abs = b.ins().select(odd, c, s);
    let cos_abs = b.ins().select(odd, s, c);
    let sin_negative = b.ins().band_imm_u(quadrant, 2);
    let cos_negative = {
        let q1 = b.ins().iadd_imm_u(quadrant, 1);
        b.ins().band_imm_u(q1, 2)
    };
    let neg = b.ins().fneg(sin_abs);
    let sin = b.ins().select(sin_negative, neg, sin_abs);
    let neg = b.ins().fneg(cos_abs);
    let cos = b.ins().select(cos_negative, neg, cos_abs);
    (sin, cos)
}

/// `x − n·π/2 = y0 + y1` and `n` as an `i64` whose two low bits are
/// `n mod 4`.
///
/// `y0` is `x − n·P1 − (n·P2 + n·P3)` with one rounding at the end, so it is
/// ready after five operations, and `y1` the rest (that rounding's error, the
/// low part of `n·P2 + n·P3`, and `n·P3T`), which the kernels use only at
/// the end. `|y1|` is at most `ulp(y0)/2 + 2⁻⁶⁷`: tiny next to `y0` except
/// where `x` is within 2⁻¹⁵ of a multiple of π/2, and there the kernels are
/// linear in it (`sin(y0 + y1) ≈ y0 + y1`, `cos ≈ 1`).
fn reduce(b: &mut FunctionBuilder<'_>, x: Value) -> (Value, Value, Value) {
    let k = |b: &mut FunctionBuilder<'_>, c: f64| b.ins().f64const(c);
    let (inv_pio2, to_int) = (k(b, INV_PIO2), k(b, TO_INT));
    let t = b.ins().fmul(x, inv_pio2);
    let shifted = b.ins().fadd(t, to_int);
    let n = b.ins().fsub(shifted, to_int);
    let quadrant = b.ins().bitcast(types::I64, MemFlagsData::new(), shifted);
    // Exact: n·P1 has at most 51 bits, and x and n·P1 are within a factor 2
    // of each other (or n = 0).
    let p1 = k(b, P1);
    let w1 = b.ins().fmul(n, p1);
    let r1 = b.ins().fsub(x, w1);
    // n·P2 + n·P3 = hi + lo exactly (both products are exact; Fast2Sum, as
    // |n·P2| ≥ |n·P3|), computed while r1 is.
    let (p2, p3) = (k(b, P2), k(b, P3));
    let (w2, w3) = (b.ins().fmul(n, p2), b.ins().fmul(n, p3));
    let hi = b.ins().fadd(w2, w3);
    let w2_part = b.ins().fsub(hi, w2);
    let lo = b.ins().fsub(w3, w2_part);
    let (y0, e) = two_diff(b, r1, hi);
    // Subtracting what remains (rather than adding its negation) keeps
    // sin(−0) = −0.
    let p3t = k(b, P3T);
    let w4 = b.ins().fmul(n, p3t);
    let rest = b.ins().fadd(lo, w4);
    let y1 = b.ins().fsub(e, rest);
    (y0, y1, quadrant)
}

/// `a − c = s + e` exactly, with `s` the rounded difference (Knuth's TwoSum,
/// no condition on the magnitudes).
fn two_diff(b: &mut FunctionBuilder<'_>, a: Value, c: Value) -> (Value, Value) {
    let s = b.ins().fsub(a, c);
    let a_part = b.ins().fadd(s, c);
    let c_part = b.ins().fsub(a_part, s);
    let a_err = b.ins().fsub(a, a_part);
    let c_err = b.ins().fsub(c_part, c);
    let e = b.ins().fadd(a_err, c_err);
    (s, e)
}

/// `c0 + c1·z + … + cn·zⁿ` by Estrin's scheme: pairs `c2k + c2k+1·z` first,
/// then combined with `z²`, `z⁴`, … (half of Horner's dependent steps).
fn polynomial(b: &mut FunctionBuilder<'_>, z: Value, coefficients: &[f64]) -> Value {
    let mut terms: Vec<Value> = coefficients
        .chunks(2)
        .map(|pair| {
            let c0 = b.ins().f64const(pair[0]);
            match pair.get(1) {
                Some(&c1) => {
                    let c1 = b.ins().f64const(c1);
                    let m = b.ins().fmul(z, c1);
                    b.ins().fadd(m, c0)
                }
                None => c0,
            }
        })
        .collect();
    let mut power = z;
    while terms.len() > 1 {
        power = b.ins().fmul(power, power);
        terms = terms
            .chunks(2)
            .map(|pair| match *pair {
                [lo, hi] => {
                    let m = b.ins().fmul(hi, power);
                    b.ins().fadd(m, lo)
                }
                [lo] => lo,
                _ => unreachable!("chunks of two"),
            })
            .collect();
    }
    terms[0]
}

/// fdlibm `__kernel_sin(x, y, 1)`: `x − ((z·(y/2 − v·r) − y) − v·S1)`.
fn kernel_sin(b: &mut FunctionBuilder<'_>, x: Value, y: Value) -> Value {
    let z = b.ins().fmul(x, x);
    let v = b.ins().fmul(z, x);
    let r = polynomial(b, z, &S[1..]);
    let half = b.ins().f64const(0.5);
    let half_y = b.ins().fmul(y, half);
    let vr = b.ins().fmul(v, r);
    let u = b.ins().fsub(half_y, vr);
    let zu = b.ins().fmul(z, u);
    let zu_y = b.ins().fsub(zu, y);
    let s1 = b.ins().f64const(S[0]);
    let vs1 = b.ins().fmul(v, s1);
    let t = b.ins().fsub(zu_y, vs1);
    b.ins().fsub(x, t)
}

/// fdlibm `__kernel_cos(x, y)`: `(1 − qx) − ((z/2 − qx) − (z·r − x·y))`, with
/// `qx` 0 for `|x| < 0.3` (then this is fdlibm's first branch exactly),
/// 0.28125 for `|x| > 0.78125`, and `|x|/4` with its low word cleared between.
fn kernel_cos(b: &mut FunctionBuilder<'_>, x: Value, y: Value) -> Value {
    let z = b.ins().fmul(x, x);
    let poly = polynomial(b, z, &C);
    let r = b.ins().fmul(z, poly);
    let ax = b.ins().fabs(x);
    let qx = {
        let bits = b.ins().bitcast(types::I64, MemFlagsData::new(), ax);
        let high = b.ins().band_imm_s(bits, -1_i64 << 32);
        let quarter = b.ins().iadd_imm_s(high, -0x0020_0000_0000_0000_i64);
        let quarter = b.ins().bitcast(types::F64, MemFlagsData::new(), quarter);
        let (small, large) = (b.ins().f64const(COS_SMALL), b.ins().f64const(COS_LARGE));
        let is_small = b.ins().fcmp(FloatCC::LessThan, ax, small);
        let is_large = b.ins().fcmp(FloatCC::GreaterThanOrEqual, ax, large);
        let (zero, fixed) = (b.ins().f64const(0.0), b.ins().f64const(0.281_25));
        let qx = b.ins().select(is_large, fixed, quarter);
        b.ins().select(is_small, zero, qx)
    };
    let half = b.ins().f64const(0.5);
    let half_z = b.ins().fmul(z, half);
    let hz = b.ins().fsub(half_z, qx);
    let one = b.ins().f64const(1.0);
    let a = b.ins().fsub(one, qx);
    let zr = b.ins().fmul(z, r);
    let xy = b.ins().fmul(x, y);
    let tail = b.ins().fsub(zr, xy);
    let inner = b.ins().fsub(hz, tail);
    b.ins().fsub(a, inner)
}

#[cfg(test)]
pub(super) mod tests {
    use crate::eval::Tape;
    use crate::expr::Pool;
    use crate::jit::Compiled;
    use crate::trig::{sin_cos_f64, COS_LARGE, COS_SMALL, INLINE_MAX};
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

    /// The distance from `a` to `b` in units in the last place: how many
    /// doubles lie between them, plus one, with −0 and +0 one number; 0 for
    /// two NaNs and `u64::MAX` for one.
    pub(crate) fn ulps(a: f64, b: f64) -> u64 {
        if a.is_nan() || b.is_nan() {
            return if a.is_nan() && b.is_nan() { 0 } else { u64::MAX };
        }
        let ordered = |x: f64| {
            let bits = x.to_bits() as i64;
            if bits < 0 {
                i64::MIN - bits
            } else {
                bits
            }
        };
        ordered(a).abs_diff(ordered(b))
    }

    /// `sin x` and `cos x` compiled three ways: together (one shared
    /// reduction), and each alone.
    struct Natives {
        both: Compiled,
        sin: Compiled,
        cos: Compiled,
    }

    impl Natives {
        fn new() -> Natives {
            let compile = |text: &str| {
                let mut pool = Pool::default();
                let roots: Vec<_> = text.split(';').map(|r| pool.parse(r).unwrap()).collect();
                let x = pool.symbol("x");
                Compiled::new(&Tape::compile(&pool, &roots, &[x]).unwrap()).unwrap()
            };
            Natives { both: compile("sin(x); cos(x)"), sin: compile("sin(x)"), cos: compile("cos(x)") }
        }

        /// `(sin x, cos x)`, after checking that the three functions agree
        /// bit for bit.
        fn eval(&self, x: f64) -> (f64, f64) {
            let (mut both, mut sin, mut cos) = ([0.0; 2], [0.0], [0.0]);
            self.both.eval(&[x], &mut both);
            self.sin.eval(&[x], &mut sin);
            self.cos.eval(&[x], &mut cos);
            let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
            assert!(same(both[0], sin[0]) && same(both[1], cos[0]), "x = {x:e}: {both:?} {sin:?} {cos:?}");
            (both[0], both[1])
        }
    }

    /// The largest ulp distance from `f64::sin` and `f64::cos` over `xs`, how
    /// many results differ at all, and how many there are (two per `x`).
    /// Panics beyond 2 ulps, or if `x ↦ −x` is not odd (sin) and even (cos)
    /// bit for bit.
    fn errors(natives: &Natives, xs: impl IntoIterator<Item = f64>) -> (u64, usize, usize) {
        let (mut worst, mut off, mut n) = (0, 0, 0);
        for x in xs {
            let (s, c) = natives.eval(x);
            let (es, ec) = (ulps(s, x.sin()), ulps(c, x.cos()));
            assert!(
                es <= 2 && ec <= 2,
                "x = {x:e} ({:#x}): sin {s:e} vs {:e}, cos {c:e} vs {:e}",
                x.to_bits(),
                x.sin(),
                x.cos()
            );
            // Odd and even, bit for bit.
            let (ms, mc) = natives.eval(-x);
            assert_eq!((ms.to_bits(), mc.to_bits()), ((-s).to_bits(), c.to_bits()), "x = {x:e}");
            worst = worst.max(es).max(ec);
            off += usize::from(es > 0) + usize::from(ec > 0);
            n += 2;
        }
        (worst, off, n)
    }

    /// A deterministic generator of uniform numbers in [0, 1) (SplitMix64).
    fn uniform(seed: u64) -> impl Iterator<Item = f64> {
        let mut state = seed;
        std::iter::repeat_with(move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64
        })
    }

    /// The scalar mirror gives the native code's bits everywhere: random
    /// arguments over the whole inline range and beyond, near multiples of
    /// π/4, tiny, signed zeros and non-finite.
    #[test]
    fn the_scalar_mirror_is_the_native_code_bit_for_bit() {
        let natives = Natives::new();
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let near_quarter_pi = (0..20_000i64).flat_map(|k| {
            let x = (k * 53) as f64 * FRAC_PI_4;
            (-2..=2i64).map(move |d| f64::from_bits(x.to_bits().wrapping_add_signed(d)))
        });
        let xs = uniform(5)
            .take(100_000)
            .map(|u| (2.0 * u - 1.0) * 1e3)
            .chain(uniform(6).take(50_000).map(|u| (2.0 * u - 1.0) * INLINE_MAX * 1.01))
            .chain(near_quarter_pi)
            .chain([0.0, -0.0, 1e-300, -5e-324, 0.3, 0.78125, COS_SMALL, COS_LARGE, f64::INFINITY, f64::NAN, 1e300]);
        for x in xs {
            for x in [x, -x] {
                let (s, c) = natives.eval(x);
                let (ms, mc) = sin_cos_f64(x);
                assert!(
                    same(s, ms) && same(c, mc),
                    "x = {x:e} ({:#x}): native {s:e} {c:e}, mirror {ms:e} {mc:e}",
                    x.to_bits()
                );
            }
        }
    }

    #[test]
    fn random_arguments_are_within_an_ulp_of_libm() {
        let natives = Natives::new();
        let wide = uniform(1).take(100_000).map(|u| (2.0 * u - 1.0) * 1e5);
        let (worst, off, n) = errors(&natives, wide);
        eprintln!("[-1e5, 1e5]: {off} of {n} results differ from libm, by at most {worst} ulp");
        assert!(worst <= 1 && off * 20 < n, "{off} of {n} off, worst {worst} ulp");
        // The whole inline range, and the kernels' own range.
        let (worst, off, n) = errors(&natives, uniform(2).take(20_000).map(|u| (2.0 * u - 1.0) * INLINE_MAX));
        eprintln!("[-2^19 pi/2, 2^19 pi/2]: {off} of {n} differ, by at most {worst} ulp");
        assert!(worst <= 1 && off * 20 < n, "{off} of {n} off, worst {worst} ulp");
        let (worst, off, n) = errors(&natives, uniform(3).take(20_000).map(|u| (2.0 * u - 1.0) * FRAC_PI_4));
        eprintln!("[-pi/4, pi/4]: {off} of {n} differ, by at most {worst} ulp");
        assert!(worst <= 1 && off * 20 < n, "{off} of {n} off, worst {worst} ulp");
    }

    /// Near multiples of π/4 and π/2, where the reduction cancels (π/2) or the
    /// quadrant changes (π/4), up to the end of the inline range.
    #[test]
    fn multiples_of_quarter_pi_and_their_neighbours() {
        let natives = Natives::new();
        let ks = (0..4000i64).chain((0..4000).map(|j| j * 1_048_573 % 1_048_576)).chain([1_048_575]);
        let xs = ks.flat_map(|k| {
            let x = k as f64 * FRAC_PI_4;
            (-3..=3i64).map(move |d| f64::from_bits(x.to_bits().wrapping_add_signed(d)))
        });
        let xs: Vec<f64> = xs.filter(|x| x.abs() < INLINE_MAX).collect();
        assert!(xs.len() > 50_000);
        let (worst, off, n) = errors(&natives, xs.iter().copied());
        eprintln!("near k pi/4: {off} of {n} differ, by at most {worst} ulp");
        assert!(worst <= 1, "worst {worst} ulp");
        // The double nearest to 6·π/2... is the one whose sine is smallest;
        // its cosine is ±1 and its sine has the reduction's full accuracy.
        for k in [1.0, 2.0, 3.0, 4.0, 6.0, 100.0, 355.0, 524_287.0] {
            let x = k * FRAC_PI_2;
            let (s, c) = natives.eval(x);
            assert!(
                ulps(s, x.sin()) <= 1 && ulps(c, x.cos()) <= 1,
                "x = {k}·pi/2: {s:e} {c:e} vs {:e} {:e}",
                x.sin(),
                x.cos()
            );
        }
    }

    #[test]
    fn tiny_arguments_and_signed_zeros() {
        let natives = Natives::new();
        // Below 2^-27, sin x = x and cos x = 1 after rounding.
        for x in [1e-300, 1e-20, 1e-9, 7e-9, 5e-324, 1e-310, f64::MIN_POSITIVE, 2.5e-308] {
            for x in [x, -x] {
                let (s, c) = natives.eval(x);
                assert_eq!((s.to_bits(), c), (x.to_bits(), 1.0), "x = {x:e}");
            }
        }
        let (worst, _, _) = errors(&natives, [8e-9, 3e-8, 1e-7, 1e-5, 1e-3]);
        assert!(worst <= 1, "worst {worst} ulp");
        let (s, c) = natives.eval(0.0);
        assert_eq!((s.to_bits(), c.to_bits()), (0f64.to_bits(), 1f64.to_bits()));
        let (s, c) = natives.eval(-0.0);
        assert_eq!((s.to_bits(), c.to_bits()), ((-0f64).to_bits(), 1f64.to_bits()));
    }

    /// A sine is the same bits in a tape alone, next to an argument out of
    /// range, and in a tape long enough to be compiled without the optimizer.
    #[test]
    fn results_do_not_depend_on_the_rest_of_the_tape() {
        let mut pool = Pool::default();
        let (x, y) = (pool.symbol("x"), pool.symbol("y"));
        let roots = [pool.parse("sin(x)").unwrap(), pool.parse("cos(y)").unwrap()];
        let pair = Compiled::new(&Tape::compile(&pool, &roots, &[x, y]).unwrap()).unwrap();
        let terms: Vec<String> = (1..=1200).map(|k| format!("{k}*cos(y + {k})/(y + {k})")).collect();
        let long = pool.parse(&terms.join(" + ")).unwrap();
        let roots = [roots[0], long];
        let tape = Tape::compile(&pool, &roots, &[x, y]).unwrap();
        assert!(tape.len() > crate::jit::OPTIMIZE_MAX_OPS);
        let long = Compiled::new(&tape).unwrap();
        let natives = Natives::new();
        for x in uniform(4).take(2000).map(|u| (2.0 * u - 1.0) * 1e3) {
            let alone = natives.eval(x).0;
            for y in [0.5, 1e7, f64::INFINITY, f64::NAN] {
                let mut out = [0.0; 2];
                pair.eval(&[x, y], &mut out);
                assert_eq!(out[0].to_bits(), alone.to_bits(), "x = {x:e}, y = {y}");
                assert_eq!(out[1].is_nan(), y.is_nan() || y.is_infinite());
                if y == 1e7 {
                    assert_eq!(out[1].to_bits(), y.cos().to_bits());
                }
                long.eval(&[x, y], &mut out);
                assert_eq!(out[0].to_bits(), alone.to_bits(), "x = {x:e}, y = {y}");
            }
        }
    }

    /// Beyond the inline range and for non-finite arguments the library is
    /// called: the same bits as `f64::sin` and `f64::cos`, NaN for ±∞ and NaN.
    #[test]
    fn large_and_non_finite_arguments_call_the_library() {
        let natives = Natives::new();
        let just_beyond = [INLINE_MAX, INLINE_MAX.next_up(), 1e6, 1e8, 1e15, 1e22, 6381956970095103.0 * 2f64.powi(797)];
        for x in just_beyond.into_iter().chain([f64::MAX, 1e300]).flat_map(|x| [x, -x]) {
            let (s, c) = natives.eval(x);
            assert_eq!((s.to_bits(), c.to_bits()), (x.sin().to_bits(), x.cos().to_bits()), "x = {x:e}");
        }
        for x in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN] {
            let (s, c) = natives.eval(x);
            assert!(s.is_nan() && c.is_nan(), "x = {x}: {s} {c}");
        }
        // Just inside the bound: inline, still within an ulp.
        let (worst, _, _) = errors(&natives, (1..1000).map(|k| f64::from_bits(INLINE_MAX.to_bits() - k)));
        assert!(worst <= 1, "worst {worst} ulp");
    }
}
