//! Euler angles in the notes' convention (section 3.2.4, appendix A.5).
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
//! Both the symbolic forms (for derivations) and the numeric ones (for
//! placing the parts of a body and for recording ω along a run) live here so
//! that one convention serves every command.

use sym::{ExprId, Func, Pool};

/// A 3×3 matrix of expressions, row-major.
pub type ExprMatrix = [[ExprId; 3]; 3];

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
