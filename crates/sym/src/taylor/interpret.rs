//! The recurrences of the interpreter: order 0 of an instruction, and the
//! sums of the Cauchy products and of `w' = g(u) u'`, lane by lane, with the
//! multiply-adds fused exactly where native code fuses them. `tape.rs` runs
//! them over the program.

use super::program::{Instruction, Lanes};

/// Order 0 of a variable instruction: its ordinary value (and that of its
/// companion slots).
pub(super) fn order_zero<const L: usize>(c: &mut [Lanes<L>], op: Instruction, stride: usize) -> Lanes<L> {
    let s = |slot: u32| slot as usize * stride;
    match op {
        Instruction::Add(a, b) | Instruction::AddC(a, b) => lanes(|l| c[s(a)][l] + c[s(b)][l]),
        Instruction::Sub(a, b) | Instruction::SubVC(a, b) | Instruction::SubCV(a, b) => {
            lanes(|l| c[s(a)][l] - c[s(b)][l])
        }
        Instruction::Mul(a, b) | Instruction::MulC(a, b) => lanes(|l| c[s(a)][l] * c[s(b)][l]),
        Instruction::Div(a, b) | Instruction::DivVC(a, b) | Instruction::DivCV(a, b) => {
            lanes(|l| c[s(a)][l] / c[s(b)][l])
        }
        Instruction::Neg(a) => lanes(|l| -c[s(a)][l]),
        Instruction::Square(a) => lanes(|l| c[s(a)][l] * c[s(a)][l]),
        Instruction::Sqrt(a) => lanes(|l| c[s(a)][l].sqrt()),
        Instruction::PowC(a, e) => lanes(|l| c[s(a)][l].powf(c[s(e)][l])),
        Instruction::Exp { u, .. } => lanes(|l| c[s(u)][l].exp()),
        Instruction::Deriv(_) => [0.0; L],
        Instruction::Log(a) => lanes(|l| c[s(a)][l].ln()),
        Instruction::Abs(a) => lanes(|l| c[s(a)][l].abs()),
        Instruction::Sin { u, cos, .. } => {
            let (mut sin, mut cos_v) = ([0.0; L], [0.0; L]);
            for l in 0..L {
                (sin[l], cos_v[l]) = crate::trig::sin_cos_f64(c[s(u)][l]);
            }
            c[s(cos)] = cos_v;
            sin
        }
        Instruction::Sinh { u, cosh, .. } => {
            c[s(cosh)] = lanes(|l| c[s(u)][l].cosh());
            lanes(|l| c[s(u)][l].sinh())
        }
        Instruction::Tan { u, aux, sign, .. } => {
            let v = lanes(|l| if sign > 0.0 { c[s(u)][l].tan() } else { c[s(u)][l].tanh() });
            c[s(aux)] = lanes(|l| 1.0 + sign * v[l] * v[l]);
            v
        }
        Instruction::Asin { u, inner, root, sign } => {
            let inner_v = lanes(|l| 1.0 - c[s(u)][l] * c[s(u)][l]);
            c[s(inner)] = inner_v;
            c[s(root)] = lanes(|l| inner_v[l].sqrt());
            lanes(|l| if sign > 0.0 { c[s(u)][l].asin() } else { c[s(u)][l].acos() })
        }
        Instruction::Atan { u, aux } => {
            c[s(aux)] = lanes(|l| 1.0 + c[s(u)][l] * c[s(u)][l]);
            lanes(|l| c[s(u)][l].atan())
        }
        Instruction::Atan2 { y, x, aux } => {
            c[s(aux)] = lanes(|l| c[s(x)][l] * c[s(x)][l] + c[s(y)][l] * c[s(y)][l]);
            lanes(|l| c[s(y)][l].atan2(c[s(x)][l]))
        }
        Instruction::CosOf | Instruction::Aux => unreachable!("written by their instruction"),
    }
}

/// `Σ_{j=1..=k} du[j] b[k-j] / k` with `du[j] = j u[j]` (the recurrence of `w' = u' b`).
#[inline(always)]
pub(super) fn derived<const F: bool, const L: usize>(c: &[Lanes<L>], du: usize, b: usize, k: usize) -> Lanes<L> {
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
pub(super) fn derived_pair<const F: bool, const L: usize>(
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
pub(super) fn weighted<const F: bool, const L: usize>(
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
pub(super) fn derivative_quotient<const L: usize>(
    c: &[Lanes<L>],
    u: usize,
    d: usize,
    w: usize,
    k: usize,
    sign: f64,
) -> Lanes<L> {
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
pub(super) fn lanes<const L: usize>(f: impl Fn(usize) -> f64) -> Lanes<L> {
    std::array::from_fn(f)
}

/// `acc += a·b` lane by lane, fused (one rounding) when `F`: what native
/// code computes for a sum of products where the host has FMA.
#[inline(always)]
pub(super) fn madd<const F: bool, const L: usize>(acc: &mut Lanes<L>, a: &Lanes<L>, b: &Lanes<L>) {
    for l in 0..L {
        acc[l] = if F { a[l].mul_add(b[l], acc[l]) } else { acc[l] + a[l] * b[l] };
    }
}

/// `acc += a·b` lane by lane, two roundings (native code's explicit
/// product and sum).
#[inline(always)]
pub(super) fn fma<const L: usize>(acc: &mut Lanes<L>, a: &Lanes<L>, b: &Lanes<L>) {
    for l in 0..L {
        acc[l] += a[l] * b[l];
    }
}

#[inline(always)]
pub(super) fn fms<const L: usize>(acc: &mut Lanes<L>, a: &Lanes<L>, b: &Lanes<L>) {
    for l in 0..L {
        acc[l] -= a[l] * b[l];
    }
}
