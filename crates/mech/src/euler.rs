//! Euler angles in the notes' convention (section 3.2.4, appendix A.5), and
//! the other eleven rotation sequences engineers use.
//!
//! α turns about the space z axis, β about the new x axis, γ about the newest
//! z axis. `D = D_γ·D_β·D_α` takes the components of a vector in the fixed
//! frame S_f to its components in the body frame S_b: `r_b = D·r_f`, so the
//! rows of `D` are the body axes written in the fixed frame and `Dᵀ` takes
//! body components back to space. The body-frame angular velocity is
//!
//! ```text
//! ω₁ = α' sin β sin γ + β' cos γ
//! ω₂ = α' sin β cos γ − β' sin γ
//! ω₃ = α' cos β + γ'
//! ```
//!
//! A [`Sequence`] names the three axes of the turns (`"zxz"` is the notes';
//! `"xyz"` the Tait–Bryan roll, pitch and yaw of most engineering models):
//! `D = R_c(γ)·R_b(β)·R_a(α)` with `R_k(θ)` the turn of the frame by θ about
//! its axis k, and ω = γ' e_c + β' R_c(γ) e_b + α' R_c(γ) R_b(β) e_a in body
//! components. The notes' sequence keeps its written-out forms above.
//!
//! Both the symbolic forms (for derivations) and the numeric ones (for
//! placing the parts of a body and for recording ω along a run) live here so
//! that one convention serves every command.

use sym::{ExprId, Func, Pool};

/// A 3×3 matrix of expressions, row-major.
pub type ExprMatrix = [[ExprId; 3]; 3];

/// The axes of the three turns (0 = x, 1 = y, 2 = z), each turn about an
/// axis other than the one before: six proper Euler sequences (first axis =
/// last) and six Tait–Bryan ones (three different axes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sequence(pub [usize; 3]);

impl Sequence {
    /// The notes' z-x-z angles.
    pub const NOTES: Sequence = Sequence([2, 0, 2]);

    /// Reads `"zxz"`, `"xyz"`, … (case-insensitive); None for anything else.
    pub fn parse(text: &str) -> Option<Sequence> {
        let axes: Vec<usize> = text
            .chars()
            .map(|c| match c.to_ascii_lowercase() {
                'x' => Some(0),
                'y' => Some(1),
                'z' => Some(2),
                _ => None,
            })
            .collect::<Option<_>>()?;
        match axes.as_slice() {
            &[a, b, c] if a != b && b != c => Some(Sequence([a, b, c])),
            _ => None,
        }
    }

    /// Whether the first and last turns are about the same axis (proper
    /// Euler angles: the gimbal singularity is at sin β = 0; Tait–Bryan
    /// angles have it at cos β = 0).
    pub fn proper(self) -> bool {
        self.0[0] == self.0[2]
    }

    /// Its name, `"zxz"`.
    pub fn name(self) -> String {
        self.0.iter().map(|&k| ['x', 'y', 'z'][k]).collect()
    }
}

/// The turn of the frame by θ about its axis k (components in the old frame
/// to components in the new), given sin θ and cos θ: the pattern of
/// `D_α = [[c, s, 0], [−s, c, 0], [0, 0, 1]]` about z.
fn turn<T: Copy>(k: usize, s: T, c: T, neg_s: T, zero: T, one: T) -> [[T; 3]; 3] {
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let mut m = [[zero; 3]; 3];
    m[k][k] = one;
    m[i][i] = c;
    m[j][j] = c;
    m[i][j] = s;
    m[j][i] = neg_s;
    m
}

/// The turn about axis k by `angle`, as expressions.
pub(crate) fn turn_expr(pool: &mut Pool, k: usize, angle: ExprId) -> ExprMatrix {
    let (s, c) = (pool.func(Func::Sin, angle), pool.func(Func::Cos, angle));
    let neg_s = pool.neg(s);
    let (zero, one) = (pool.zero(), pool.one());
    turn(k, s, c, neg_s, zero, one)
}

/// The turn about axis k by `angle`, numerically.
fn turn_f64(k: usize, angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    turn(k, s, c, -s, 0.0, 1.0)
}

/// `D = R_c(γ)·R_b(β)·R_a(α)` of any sequence, as expressions.
pub fn rotation_of(pool: &mut Pool, seq: Sequence, [al, be, ga]: [ExprId; 3]) -> ExprMatrix {
    if seq == Sequence::NOTES {
        return rotation(pool, al, be, ga);
    }
    let [a, b, c] = seq.0;
    let (r_a, r_b, r_c) = (turn_expr(pool, a, al), turn_expr(pool, b, be), turn_expr(pool, c, ga));
    let ba = mat_mul(pool, &r_b, &r_a);
    mat_mul(pool, &r_c, &ba)
}

pub(crate) fn mat_mul(pool: &mut Pool, a: &ExprMatrix, b: &ExprMatrix) -> ExprMatrix {
    let mut c = [[pool.zero(); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(a[i][k], b[k][j])).collect();
            c[i][j] = pool.add(&terms);
        }
    }
    c
}

/// The body-frame angular velocity of any sequence, as expressions:
/// γ' e_c + β' R_c(γ) e_b + α' R_c(γ) R_b(β) e_a.
pub fn angular_velocity_of(pool: &mut Pool, seq: Sequence, angles: [ExprId; 3], rates: [ExprId; 3]) -> [ExprId; 3] {
    if seq == Sequence::NOTES {
        return angular_velocity(pool, angles, rates);
    }
    let [a, b, c] = seq.0;
    let r_c = turn_expr(pool, c, angles[2]);
    let r_b = turn_expr(pool, b, angles[1]);
    let r_cb = mat_mul(pool, &r_c, &r_b);
    let mut omega = [pool.zero(); 3];
    for (i, w) in omega.iter_mut().enumerate() {
        let mut terms = Vec::new();
        if i == c {
            terms.push(rates[2]);
        }
        terms.push(pool.mul2(rates[1], r_c[i][b]));
        terms.push(pool.mul2(rates[0], r_cb[i][a]));
        *w = pool.add(&terms);
    }
    omega
}

/// The numeric `D` of any sequence.
pub fn rotation_of_f64(seq: Sequence, [al, be, ga]: [f64; 3]) -> [[f64; 3]; 3] {
    if seq == Sequence::NOTES {
        return rotation_f64(al, be, ga);
    }
    let [a, b, c] = seq.0;
    mat_mul_f64(&turn_f64(c, ga), &mat_mul_f64(&turn_f64(b, be), &turn_f64(a, al)))
}

/// The numeric body-frame angular velocity of any sequence.
#[cfg(test)]
pub fn angular_velocity_of_f64(seq: Sequence, [_, be, ga]: [f64; 3], rates: [f64; 3]) -> [f64; 3] {
    if seq == Sequence::NOTES {
        return angular_velocity_f64(be, ga, rates);
    }
    let [a, b, c] = seq.0;
    let (r_c, r_b) = (turn_f64(c, ga), turn_f64(b, be));
    let r_cb = mat_mul_f64(&r_c, &r_b);
    std::array::from_fn(|i| {
        let own = if i == c { rates[2] } else { 0.0 };
        own + rates[1] * r_c[i][b] + rates[0] * r_cb[i][a]
    })
}

fn mat_mul_f64(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The rotation `D = D_γ·D_β·D_α` from fixed-frame to body-frame components,
/// as expressions in the three angle expressions.
pub fn rotation(pool: &mut Pool, al: ExprId, be: ExprId, ga: ExprId) -> ExprMatrix {
    let (sa, ca) = (pool.func(Func::Sin, al), pool.func(Func::Cos, al));
    let (sb, cb) = (pool.func(Func::Sin, be), pool.func(Func::Cos, be));
    let (sg, cg) = (pool.func(Func::Sin, ga), pool.func(Func::Cos, ga));
    let mut prod = |factors: &[ExprId]| pool.mul(factors);
    // Rows: the body axes e₁, e₂, e₃ in fixed-frame components.
    let r00 = [prod(&[cg, ca]), prod(&[sg, cb, sa])];
    let r01 = [prod(&[cg, sa]), prod(&[sg, cb, ca])];
    let r02 = prod(&[sg, sb]);
    let r10 = [prod(&[sg, ca]), prod(&[cg, cb, sa])];
    let r11 = [prod(&[sg, sa]), prod(&[cg, cb, ca])];
    let r12 = prod(&[cg, sb]);
    let r20 = prod(&[sb, sa]);
    let r21 = prod(&[sb, ca]);
    let r22 = cb;
    let m_r00_1 = pool.neg(r00[1]);
    let m_r10_0 = pool.neg(r10[0]);
    let m_r10_1 = pool.neg(r10[1]);
    let m_r11_0 = pool.neg(r11[0]);
    let m_r21 = pool.neg(r21);
    [
        [pool.add2(r00[0], m_r00_1), pool.add2(r01[0], r01[1]), r02],
        [pool.add2(m_r10_0, m_r10_1), pool.add2(m_r11_0, r11[1]), r12],
        [r20, m_r21, r22],
    ]
}

/// The body-frame angular velocity (ω₁, ω₂, ω₃) from the angles and their rates.
pub fn angular_velocity(pool: &mut Pool, [_al, be, ga]: [ExprId; 3], [ald, bed, gad]: [ExprId; 3]) -> [ExprId; 3] {
    let (sb, cb) = (pool.func(Func::Sin, be), pool.func(Func::Cos, be));
    let (sg, cg) = (pool.func(Func::Sin, ga), pool.func(Func::Cos, ga));
    let a1 = pool.mul(&[ald, sb, sg]);
    let b1 = pool.mul2(bed, cg);
    let w1 = pool.add2(a1, b1);
    let a2 = pool.mul(&[ald, sb, cg]);
    let b2 = pool.mul2(bed, sg);
    let w2 = pool.sub(a2, b2);
    let a3 = pool.mul2(ald, cb);
    let w3 = pool.add2(a3, gad);
    [w1, w2, w3]
}

/// The numeric rotation `D = D_γ·D_β·D_α` (fixed → body components); its rows
/// are the body axes in fixed-frame components.
pub fn rotation_f64(al: f64, be: f64, ga: f64) -> [[f64; 3]; 3] {
    let (sa, ca) = al.sin_cos();
    let (sb, cb) = be.sin_cos();
    let (sg, cg) = ga.sin_cos();
    [
        [cg * ca - sg * cb * sa, cg * sa + sg * cb * ca, sg * sb],
        [-sg * ca - cg * cb * sa, -sg * sa + cg * cb * ca, cg * sb],
        [sb * sa, -sb * ca, cb],
    ]
}

/// The numeric body-frame angular velocity from β, γ and the three rates.
pub fn angular_velocity_f64(be: f64, ga: f64, [ald, bed, gad]: [f64; 3]) -> [f64; 3] {
    let (sb, cb) = be.sin_cos();
    let (sg, cg) = ga.sin_cos();
    [ald * sb * sg + bed * cg, ald * sb * cg - bed * sg, ald * cb + gad]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matmul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    /// The product of the notes' three elementary rotations, written out.
    fn notes_product(al: f64, be: f64, ga: f64) -> [[f64; 3]; 3] {
        let (sa, ca) = al.sin_cos();
        let (sb, cb) = be.sin_cos();
        let (sg, cg) = ga.sin_cos();
        let d_a = [[ca, sa, 0.0], [-sa, ca, 0.0], [0.0, 0.0, 1.0]];
        let d_b = [[1.0, 0.0, 0.0], [0.0, cb, sb], [0.0, -sb, cb]];
        let d_g = [[cg, sg, 0.0], [-sg, cg, 0.0], [0.0, 0.0, 1.0]];
        matmul(&d_g, &matmul(&d_b, &d_a))
    }

    #[test]
    fn numeric_rotation_is_the_product_of_the_three_turns() {
        for &(a, b, g) in &[(0.3, 1.1, -0.7), (2.0, 0.2, 5.0), (-1.0, 3.0, 0.5)] {
            let d = rotation_f64(a, b, g);
            let e = notes_product(a, b, g);
            for i in 0..3 {
                for j in 0..3 {
                    assert!((d[i][j] - e[i][j]).abs() < 1e-15, "{i}{j}");
                }
            }
        }
    }

    #[test]
    fn symbolic_rotation_matches_numeric() {
        let mut pool = Pool::default();
        let (al, be, ga) = (pool.symbol("al"), pool.symbol("be"), pool.symbol("ga"));
        let d = rotation(&mut pool, al, be, ga);
        let (a, b, g) = (0.4, 2.2, -1.3);
        let env = |n: &str| match n {
            "al" => Some(a),
            "be" => Some(b),
            "ga" => Some(g),
            _ => None,
        };
        let e = rotation_f64(a, b, g);
        for i in 0..3 {
            for j in 0..3 {
                let v = pool.eval(d[i][j], &env).unwrap();
                assert!((v - e[i][j]).abs() < 1e-15);
            }
        }
    }

    const ALL: [&str; 12] = ["zxz", "xyx", "yzy", "zyz", "xzx", "yxy", "xyz", "yzx", "zxy", "xzy", "zyx", "yxz"];

    /// ω from D by finite differences: Ḋ·Dᵀ = −[ω]× in body components.
    fn omega_from_rotation(seq: Sequence, q: [f64; 3], rates: [f64; 3]) -> [f64; 3] {
        let h = 1e-6;
        let at = |s: f64| rotation_of_f64(seq, std::array::from_fn(|k| q[k] + s * rates[k] * h));
        let (dp, dm, d) = (at(1.0), at(-1.0), at(0.0));
        let dd: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| (dp[i][j] - dm[i][j]) / (2.0 * h)));
        let dt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| d[j][i]));
        let w = matmul(&dd, &dt);
        [w[1][2], w[2][0], w[0][1]]
    }

    #[test]
    fn every_sequence_is_a_rotation_whose_rate_is_its_angular_velocity() {
        assert_eq!(ALL.iter().filter_map(|s| Sequence::parse(s)).count(), 12);
        for bad in ["zzx", "xy", "xyzx", "abc", ""] {
            assert_eq!(Sequence::parse(bad), None, "{bad}");
        }
        let (q, rates) = ([0.4, 1.2, -0.9], [0.7, -0.3, 1.9]);
        let mut pool = Pool::default();
        let names = ["al", "be", "ga", "ald", "bed", "gad"];
        let syms: Vec<ExprId> = names.iter().map(|n| pool.symbol(n)).collect();
        let values = [q[0], q[1], q[2], rates[0], rates[1], rates[2]];
        let env = |n: &str| names.iter().position(|m| *m == n).map(|i| values[i]);
        for name in ALL {
            let seq = Sequence::parse(name).unwrap();
            assert_eq!(seq.name(), name);
            let d = rotation_of_f64(seq, q);
            let ddt = matmul(&d, &std::array::from_fn(|i| std::array::from_fn(|j| d[j][i])));
            for i in 0..3 {
                for j in 0..3 {
                    let id = if i == j { 1.0 } else { 0.0 };
                    assert!((ddt[i][j] - id).abs() < 1e-14, "{name}: D·Dᵀ");
                }
            }
            let w = angular_velocity_of_f64(seq, q, rates);
            let fd = omega_from_rotation(seq, q, rates);
            let sym_d = rotation_of(&mut pool, seq, [syms[0], syms[1], syms[2]]);
            let sym_w = angular_velocity_of(&mut pool, seq, [syms[0], syms[1], syms[2]], [syms[3], syms[4], syms[5]]);
            for k in 0..3 {
                assert!((w[k] - fd[k]).abs() < 1e-8, "{name}: ω{}: {} vs {}", k + 1, w[k], fd[k]);
                assert!((pool.eval(sym_w[k], &env).unwrap() - w[k]).abs() < 1e-14, "{name}: symbolic ω{}", k + 1);
                for j in 0..3 {
                    assert!((pool.eval(sym_d[k][j], &env).unwrap() - d[k][j]).abs() < 1e-14, "{name}: D{k}{j}");
                }
            }
        }
        // The notes' sequence through the general product: the written-out forms.
        let general = mat_mul_f64(&turn_f64(2, q[2]), &mat_mul_f64(&turn_f64(0, q[1]), &turn_f64(2, q[0])));
        let notes = rotation_f64(q[0], q[1], q[2]);
        for i in 0..3 {
            for j in 0..3 {
                assert!((general[i][j] - notes[i][j]).abs() < 1e-15);
            }
        }
    }

    /// ω from the rotation itself: [ω]× = −Ḋ·Dᵀ in body components, by finite differences.
    #[test]
    fn angular_velocity_matches_the_rate_of_the_rotation() {
        let (a, b, g) = (0.4, 1.2, -0.9);
        let (ad, bd, gd) = (0.7, -0.3, 1.9);
        let h = 1e-6;
        let dp = rotation_f64(a + ad * h, b + bd * h, g + gd * h);
        let dm = rotation_f64(a - ad * h, b - bd * h, g - gd * h);
        let d = rotation_f64(a, b, g);
        let mut dd = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                dd[i][j] = (dp[i][j] - dm[i][j]) / (2.0 * h);
            }
        }
        let dt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| d[j][i]));
        let w = matmul(&dd, &dt); // Ḋ·Dᵀ = −[ω]×
        let omega = [w[1][2], w[2][0], w[0][1]];
        let expected = angular_velocity_f64(b, g, [ad, bd, gd]);
        for k in 0..3 {
            assert!((omega[k] - expected[k]).abs() < 1e-8, "ω{}: {} vs {}", k + 1, omega[k], expected[k]);
        }
    }
}
