//! `sin` and `cos` as lagrange computes them everywhere: fdlibm's argument
//! reduction and kernels, branch-free, on plain `f64` ([`sin_cos_f64`], which the
//! tape interpreter, the Taylor recurrences and every evaluation call). The native
//! code emits the same operations in the same order (`jit/trig.rs`, cranelift IR;
//! `taylor/c.rs`, C), so all of them give the same numbers bit for bit. A leaf:
//! it imports nothing of the crate.
//!
//!
//! The code emits both functions of one argument `x` from one reduction:
//!
//! 1. Reduction (Cody–Waite with fdlibm's three-part π/2). `n` is `x·2/π`
//!    rounded to the nearest integer (by adding and subtracting 1.5·2⁵², which
//!    also leaves `n mod 4` in the low bits), and `x − n·π/2` is formed as the
//!    unevaluated sum `y0 + y1` from `π/2 = P1 + P2 + P3 + P3T`. `P1`, `P2` and
//!    `P3` have at most 33 significant bits, so for `|n| ≤ 2¹⁹` the products
//!    `n·Pk` are exact, `x − n·P1` is exact (Sterbenz), and the rounding
//!    errors of the other sums are kept (TwoSum). Where fdlibm decides from
//!    the cancellation how many parts to use, this always uses all of them,
//!    which is at least as accurate and has no branch; `y0` is ready early
//!    and `y1` is only needed at the end of the kernels, so the long path is
//!    short. Valid for `|x| <` [`INLINE_MAX`] = 2¹⁹·π/2, fdlibm's "medium"
//!    range; the caller sends larger and non-finite `x` to the library.
//! 2. Kernels: fdlibm's `__kernel_sin(y0, y1, 1)` and `__kernel_cos(y0, y1)`,
//!    the minimax polynomials on [−π/4, π/4] with their coefficients and
//!    their outer formulas (the `S1` term and the tail `y1` apart, the split
//!    `qx` of `1 − z/2`). The inner polynomials in `z = y0²` are evaluated by
//!    Estrin's scheme instead of Horner's: half the dependent steps, which
//!    makes a sine about 4 ns faster here, at no measurable cost in accuracy
//!    (their rounding enters the result some 2⁻⁶ smaller than the result's
//!    own). The branch of `__kernel_cos` on `|y0|` (which only chooses `qx`)
//!    is a `select`.
//! 3. The quadrant `n mod 4` picks `(sin, cos)` among `(s, c)`, `(c, −s)`,
//!    `(−s, −c)`, `(−c, s)` with `select`s.
//!
//! The arithmetic is the same whether one or both results are used, so
//! `sin(u)` does not depend on whether the tape also holds `cos(u)`. Every
//! operation is sign-symmetric, so `sin(−x) = −sin(x)` and `cos(−x) = cos(x)`
//! bit for bit, and `sin(±0) = ±0`. Measured against glibc's `sin` and `cos`
//! (the tests of `jit/trig.rs`), the results differ by at most one ulp, in about 3% of
//! cases.

/// `|x|` below which the reduction is exact enough (the emitted code is used): 2¹⁹·π/2, so that `|n| ≤ 2¹⁹`.
pub(crate) const INLINE_MAX: f64 = 524_288.0 * std::f64::consts::FRAC_PI_2;

/// 2/π (fdlibm `invpio2`).
pub(crate) const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
/// 1.5·2⁵²: adding and subtracting it rounds to an integer (|·| < 2⁵¹).
pub(crate) const TO_INT: f64 = 6_755_399_441_055_744.0;
/// π/2 = P1 + P2 + P3 + P3T to about 2⁻¹⁶⁰ (fdlibm `pio2_1`, `pio2_2`,
/// `pio2_3`, `pio2_3t`); P1, P2, P3 have 31, 32 and 28 significant bits.
pub(crate) const P1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
pub(crate) const P2: f64 = f64::from_bits(0x3DD0_B461_1A60_0000);
pub(crate) const P3: f64 = f64::from_bits(0x3BA3_198A_2E00_0000);
pub(crate) const P3T: f64 = f64::from_bits(0x397B_839A_2520_49C1);

// fdlibm's coefficients are quoted as published (21 digits).
#[allow(clippy::excessive_precision)]
/// `__kernel_sin`: sin(x) ≈ x + S1·x³ + … + S6·x¹³ on [−π/4, π/4].
pub(crate) const S: [f64; 6] = [
    -1.666_666_666_666_663_243_48e-1,
    8.333_333_333_322_489_461_24e-3,
    -1.984_126_982_985_794_931_34e-4,
    2.755_731_370_707_006_767_89e-6,
    -2.505_076_025_340_686_341_95e-8,
    1.589_690_995_211_550_102_21e-10,
];

#[allow(clippy::excessive_precision)]
/// `__kernel_cos`: cos(x) ≈ 1 − x²/2 + C1·x⁴ + … + C6·x¹⁴ on [−π/4, π/4].
pub(crate) const C: [f64; 6] = [
    4.166_666_666_666_660_190_37e-2,
    -1.388_888_888_887_410_957_49e-3,
    2.480_158_728_947_672_941_78e-5,
    -2.755_731_435_139_066_330_35e-7,
    2.087_572_321_298_174_827_90e-9,
    -1.135_964_755_778_819_482_65e-11,
];

/// `|x| < 0.3` in `__kernel_cos` (high word below 0x3FD33333): `qx = 0`.
pub(crate) const COS_SMALL: f64 = f64::from_bits(0x3FD3_3333_0000_0000);
/// `|x| > 0.78125` in `__kernel_cos` (high word above 0x3FE90000): `qx = 0.28125`.
pub(crate) const COS_LARGE: f64 = f64::from_bits(0x3FE9_0001_0000_0000);

/// `(sin x, cos x)` as the emitted code computes them, bit for bit:
/// the same operations in the same order, so that the tape interpreter (and
/// everything else that evaluates an expression) and native code give the
/// same numbers. Beyond [`INLINE_MAX`] and for non-finite `x`, the library,
/// as native code calls it there.
pub(crate) fn sin_cos_f64(x: f64) -> (f64, f64) {
    // NaN goes to the library too.
    if x.is_nan() || x.abs() >= INLINE_MAX {
        return (x.sin(), x.cos());
    }
    let (y0, y1, quadrant) = reduce_f64(x);
    let (s, c) = (kernel_sin_f64(y0, y1), kernel_cos_f64(y0, y1));
    let odd = quadrant & 1 != 0;
    let (sin_abs, cos_abs) = if odd { (c, s) } else { (s, c) };
    let sin = if quadrant & 2 != 0 { -sin_abs } else { sin_abs };
    let cos = if quadrant.wrapping_add(1) & 2 != 0 { -cos_abs } else { cos_abs };
    (sin, cos)
}

/// The reduction: `x − n·π/2` as `y0 + y1`, and `n` (its low bits the quadrant).
fn reduce_f64(x: f64) -> (f64, f64, i64) {
    let shifted = x * INV_PIO2 + TO_INT;
    let n = shifted - TO_INT;
    let quadrant = shifted.to_bits() as i64;
    let r1 = x - n * P1;
    let (w2, w3) = (n * P2, n * P3);
    let hi = w2 + w3;
    let lo = w3 - (hi - w2);
    let (y0, e) = two_diff_f64(r1, hi);
    let y1 = e - (lo + n * P3T);
    (y0, y1, quadrant)
}

/// `a − c` and its rounding error (TwoSum).
fn two_diff_f64(a: f64, c: f64) -> (f64, f64) {
    let s = a - c;
    let a_part = s + c;
    let c_part = a_part - s;
    (s, (a - a_part) + (c_part - c))
}

/// A polynomial in `z` by Estrin's scheme (the emitted code pairs its terms the same way).
fn polynomial_f64(z: f64, coefficients: &[f64]) -> f64 {
    let mut terms = [0.0; 6];
    let mut len = 0;
    for pair in coefficients.chunks(2) {
        terms[len] = match pair.get(1) {
            Some(&c1) => z * c1 + pair[0],
            None => pair[0],
        };
        len += 1;
    }
    let mut power = z;
    while len > 1 {
        power *= power;
        let mut next = 0;
        for i in (0..len).step_by(2) {
            terms[next] = if i + 1 < len { terms[i + 1] * power + terms[i] } else { terms[i] };
            next += 1;
        }
        len = next;
    }
    terms[0]
}

/// fdlibm's `__kernel_sin(x, y, 1)`.
fn kernel_sin_f64(x: f64, y: f64) -> f64 {
    let z = x * x;
    let v = z * x;
    let r = polynomial_f64(z, &S[1..]);
    let u = y * 0.5 - v * r;
    x - ((z * u - y) - v * S[0])
}

/// fdlibm's `__kernel_cos(x, y)`.
fn kernel_cos_f64(x: f64, y: f64) -> f64 {
    let z = x * x;
    let r = z * polynomial_f64(z, &C);
    let ax = x.abs();
    let qx = if ax < COS_SMALL {
        0.0
    } else if ax >= COS_LARGE {
        0.281_25
    } else {
        let high = ax.to_bits() as i64 & (-1_i64 << 32);
        f64::from_bits(high.wrapping_add(-0x0020_0000_0000_0000_i64) as u64)
    };
    (1.0 - qx) - ((z * 0.5 - qx) - (z * r - x * y))
}
