//! A rigid body's part of a derivation: its kinetic energy, gravity potential,
//! and body-frame angular velocity and angular momentum, as expressions in
//! (q, q', t). See [`crate::model::body`] for the formulas and the reading.

use crate::derive::quadratic::{Parts, Vars};
use crate::euler;
use crate::model::frames::Frame;
use crate::model::{Body, Gravity};
use sym::{ExprId, Pool, Symbol};

/// What a body contributes to a derivation, as expressions in (q, q', t).
#[derive(Debug, Clone)]
pub struct BodyTerms {
    /// Its kinetic energy.
    pub kinetic: ExprId,
    /// M g z_cm (or −M g·r_cm for a field vector), when the model has gravity.
    pub potential: Option<ExprId>,
    /// Body-frame angular velocity (ω₁, ω₂, ω₃).
    pub omega: [ExprId; 3],
    /// Body-frame angular momentum about the reference point.
    pub angular_momentum: [ExprId; 3],
    /// The centre of mass in space.
    pub center: [ExprId; 3],
}

/// A body's angular velocity and angular momentum in a derivation (simplified),
/// and where it is.
#[derive(Debug, Clone)]
pub struct BodyMotion {
    /// The body's name.
    pub name: String,
    /// Body-frame angular velocity (ω₁, ω₂, ω₃), in (q, q').
    pub omega: [ExprId; 3],
    /// Body-frame angular momentum (L₁, L₂, L₃) about the reference point.
    pub angular_momentum: [ExprId; 3],
    /// The reference point in space, in (q, t).
    pub position: [ExprId; 3],
    /// The centre of mass in space, in (q, t).
    pub center: [ExprId; 3],
    /// The body axes e1, e2, e3 (rows) in space components, in q.
    pub axes: euler::ExprMatrix,
}

/// The kinetic energy, gravity potential, ω and L of a body in its frame (see the module text).
pub(crate) fn terms(
    pool: &mut Pool,
    body: &Body,
    frame: &Frame,
    q: &[ExprId],
    qd: &[ExprId],
    t: ExprId,
    gravity: Option<&Gravity>,
) -> BodyTerms {
    // v_ref = Σ ∂x/∂q_i q_i' + ∂x/∂t, space components.
    let v_ref = crate::model::frames::velocity(pool, &frame.origin, q, qd, t);
    terms_with_velocity(pool, body, frame, v_ref, gravity)
}

/// [`terms`] with the reference point's velocity (space components) given.
pub(crate) fn terms_with_velocity(
    pool: &mut Pool,
    body: &Body,
    frame: &Frame,
    v_ref: [ExprId; 3],
    gravity: Option<&Gravity>,
) -> BodyTerms {
    let (omega, d) = (frame.omega, frame.d);
    let moving = v_ref.iter().any(|&v| !pool.is_zero(v));
    let half = pool.rational(1, 2);
    let mut t_terms = Vec::new();
    // ½ωᵀIω.
    let i_omega: Vec<ExprId> = (0..3)
        .map(|i| {
            let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(body.inertia[i][j], omega[j])).collect();
            pool.add(&terms)
        })
        .collect();
    if body.principal {
        for k in 0..3 {
            let w2 = pool.powi(omega[k], 2);
            t_terms.push(pool.mul(&[half, body.inertia[k][k], w2]));
        }
    } else {
        for k in 0..3 {
            t_terms.push(pool.mul(&[half, omega[k], i_omega[k]]));
        }
    }
    let mut l = [i_omega[0], i_omega[1], i_omega[2]];
    if moving {
        // ½M|v_ref|².
        let sq: Vec<ExprId> = v_ref.iter().map(|&v| pool.powi(v, 2)).collect();
        let s = pool.add(&sq);
        t_terms.push(pool.mul(&[half, body.mass, s]));
        // v_b = D v_ref; M v_b·(ω × c); L += M c × v_b.
        let v_b: Vec<ExprId> = (0..3)
            .map(|i| {
                let terms: Vec<ExprId> = (0..3).map(|j| pool.mul2(d[i][j], v_ref[j])).collect();
                pool.add(&terms)
            })
            .collect();
        let cvec = body.center_of_mass;
        if cvec.iter().any(|&x| !pool.is_zero(x)) {
            let w_x_c = cross(pool, &omega, &cvec);
            let dots: Vec<ExprId> = (0..3).map(|k| pool.mul2(v_b[k], w_x_c[k])).collect();
            let dot = pool.add(&dots);
            t_terms.push(pool.mul2(body.mass, dot));
            let c_x_v = cross(pool, &cvec, &[v_b[0], v_b[1], v_b[2]]);
            for k in 0..3 {
                let extra = pool.mul2(body.mass, c_x_v[k]);
                l[k] = pool.add2(l[k], extra);
            }
        }
    }
    let kinetic = pool.add(&t_terms);
    // r_cm,i = x_ref,i + Σ_k D_ki c_k (the components of x_ref + Dᵀc).
    let center: [ExprId; 3] = std::array::from_fn(|i| {
        let mut x = vec![frame.origin[i]];
        for k in 0..3 {
            x.push(pool.mul2(d[k][i], body.center_of_mass[k]));
        }
        pool.add(&x)
    });
    let potential = gravity.map(|g| {
        // A planar model's positions are (x, y); a field's zero components are left out.
        let r_cm: Vec<ExprId> = (0..body.dimension)
            .map(|i| {
                let wanted = match g {
                    Gravity::Down(_) => i == body.dimension - 1,
                    Gravity::Field { components, .. } => !pool.is_zero(components[i].expr),
                };
                if wanted {
                    center[i]
                } else {
                    pool.zero()
                }
            })
            .collect();
        g.potential(pool, body.mass, &r_cm)
    });
    BodyTerms { kinetic, potential, omega, angular_momentum: l, center }
}

/// Adds a body's kinetic energy to the quadratic form `parts`, coefficient by
/// coefficient, with the body's velocity columns J_i = ∂x_ref/∂q_i (space),
/// u_i = D J_i (body components) and ω = Σ W_i q_i' (body components):
///
/// ```text
/// M_ij += M J_i·J_j + M (u_i·(W_j × c) + u_j·(W_i × c)) + W_iᵀ I W_j
/// b_i  += M J_i·J_t + M u_t·(W_i × c)
/// T₀   += ½ M J_t·J_t
/// ```
///
/// which is T of the module text written out. Built this way, no coefficient
/// ever holds more than its own terms: the whole T, expanded and collected
/// again, grows with the product of a chain's depth and its coordinates.
pub(crate) fn kinetic_form(pool: &mut Pool, body: &Body, frame: &Frame, v: &Vars, parts: &mut Parts) {
    let n = v.q.len();
    let zero = pool.zero();
    let d = &frame.d;
    let column = |pool: &mut Pool, x: ExprId| -> [ExprId; 3] { frame.origin.map(|o| pool.diff(o, x)) };
    let jac: Vec<[ExprId; 3]> = v.q.iter().map(|&qi| column(pool, qi)).collect();
    let jt = column(pool, v.t);
    let body_components = |pool: &mut Pool, j: &[ExprId; 3]| -> [ExprId; 3] {
        std::array::from_fn(|i| {
            let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(d[i][k], j[k])).collect();
            pool.add(&terms)
        })
    };
    let u: Vec<[ExprId; 3]> = jac.iter().map(|j| body_components(pool, j)).collect();
    let ut = body_components(pool, &jt);
    let w: Vec<[ExprId; 3]> = v.qd.iter().map(|&x| frame.omega.map(|o| pool.diff(o, x))).collect();
    let c = body.center_of_mass;
    let offset = c.iter().any(|&x| !pool.is_zero(x));
    let w_x_c: Vec<[ExprId; 3]> = w.iter().map(|wi| if offset { cross(pool, wi, &c) } else { [zero; 3] }).collect();
    let i_w: Vec<[ExprId; 3]> = w
        .iter()
        .map(|wi| {
            std::array::from_fn(|a| {
                let terms: Vec<ExprId> = (0..3).map(|b| pool.mul2(body.inertia[a][b], wi[b])).collect();
                pool.add(&terms)
            })
        })
        .collect();
    let moves = |k: usize| jac[k] != [zero; 3] || w[k] != [zero; 3];
    let active: Vec<usize> = (0..n).filter(|&k| moves(k)).collect();
    let dot = |pool: &mut Pool, a: &[ExprId; 3], b: &[ExprId; 3]| -> ExprId {
        let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(a[k], b[k])).collect();
        pool.add(&terms)
    };
    for (x, &i) in active.iter().enumerate() {
        for &j in &active[x..] {
            let mut terms = vec![dot(pool, &jac[i], &jac[j])];
            if offset {
                terms.push(dot(pool, &u[i], &w_x_c[j]));
                terms.push(dot(pool, &u[j], &w_x_c[i]));
            }
            let translation = pool.add(&terms);
            let translation = pool.mul2(body.mass, translation);
            let rotation = dot(pool, &w[i], &i_w[j]);
            let entry = pool.add2(translation, rotation);
            if !pool.is_zero(entry) {
                parts.push_m(i, j, entry);
            }
        }
        if jt != [zero; 3] {
            let mut terms = vec![dot(pool, &jac[i], &jt)];
            if offset {
                terms.push(dot(pool, &ut, &w_x_c[i]));
            }
            let sum = pool.add(&terms);
            let entry = pool.mul2(body.mass, sum);
            if !pool.is_zero(entry) {
                parts.push_b(i, entry);
            }
        }
    }
    if jt != [zero; 3] {
        let half = pool.rational(1, 2);
        let sq = dot(pool, &jt, &jt);
        let entry = pool.mul(&[half, body.mass, sq]);
        parts.push_l0(entry);
    }
}

fn cross(pool: &mut Pool, a: &[ExprId; 3], b: &[ExprId; 3]) -> [ExprId; 3] {
    let mut c = [pool.zero(); 3];
    for (k, (i, j)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
        let x = pool.mul2(a[i], b[j]);
        let y = pool.mul2(a[j], b[i]);
        c[k] = pool.sub(x, y);
    }
    c
}

/// A body's ω and L as the kinematics give them, not simplified (for models too
/// large to simplify).
pub(crate) fn motion_as_is(body: &Body, frame: &Frame, terms: &BodyTerms) -> BodyMotion {
    BodyMotion {
        name: body.name.clone(),
        omega: terms.omega,
        angular_momentum: terms.angular_momentum,
        position: frame.origin,
        center: terms.center,
        axes: frame.d,
    }
}

/// Simplifies a body's ω and L for printing and recording.
pub(crate) fn motion(
    pool: &mut Pool,
    body: &Body,
    frame: &Frame,
    terms: &BodyTerms,
    is_var: &dyn Fn(Symbol) -> bool,
) -> BodyMotion {
    let omega = terms.omega.map(|w| pool.simplify_in(w, is_var));
    let angular_momentum = terms.angular_momentum.map(|l| pool.simplify_in(l, is_var));
    BodyMotion {
        name: body.name.clone(),
        omega,
        angular_momentum,
        position: frame.origin,
        center: terms.center,
        axes: frame.d,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Derivation, Model};

    /// Body-frame points (mass, r) of a rigid cluster, not coplanar.
    const POINTS: [(f64, [f64; 3]); 4] =
        [(1.0, [0.3, -0.2, 0.5]), (2.0, [-0.4, 0.1, 0.2]), (0.5, [0.1, 0.6, -0.3]), (1.5, [0.2, 0.3, 0.4])];

    fn env<'a>(vals: &'a [(&'a str, f64)]) -> impl Fn(&str) -> Option<f64> + 'a {
        move |n| vals.iter().find(|(k, _)| *k == n).map(|(_, v)| *v)
    }

    /// The body's T (with the cross term M v_ref·(ω×r) and a full tensor) equals
    /// the particles' T of the same rigid cluster, for a reference point that moves
    /// with the coordinates and the time.
    #[test]
    fn body_kinetic_energy_is_the_sum_over_its_points() {
        let total: f64 = POINTS.iter().map(|p| p.0).sum();
        let mut com = [0.0; 3];
        let mut inertia = [[0.0; 3]; 3];
        for (m, r) in POINTS {
            let r2 = r.iter().map(|x| x * x).sum::<f64>();
            for i in 0..3 {
                com[i] += m * r[i] / total;
                for j in 0..3 {
                    inertia[i][j] += m * (if i == j { r2 } else { 0.0 } - r[i] * r[j]);
                }
            }
        }
        // The reference point moves with a coordinate, an Euler angle and the time.
        let position = ["x + 0.2*sin(be)", "0.3*x^2", "t"];
        let tensor: Vec<String> = inertia
            .iter()
            .map(|row| format!("[{}]", row.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>().join(", ")))
            .collect();
        let body_model = format!(
            "coordinates = [\"x\", \"al\", \"be\", \"ga\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n[[bodies]]\nmass = {total:?}\ninertia = [{}]\nangles = [\"al\", \"be\", \"ga\"]\nposition = [\"x + 0.2*sin(be)\", \"0.3*x^2\", \"t\"]\ncenter_of_mass = [{:?}, {:?}, {:?}]\n",
            tensor.join(", "),
            com[0],
            com[1],
            com[2]
        );
        // Particles at x_ref + Dᵀr, with D written out in the notes' convention.
        let d = [
            [
                "cos(ga)*cos(al) - sin(ga)*cos(be)*sin(al)",
                "cos(ga)*sin(al) + sin(ga)*cos(be)*cos(al)",
                "sin(ga)*sin(be)",
            ],
            [
                "-sin(ga)*cos(al) - cos(ga)*cos(be)*sin(al)",
                "-sin(ga)*sin(al) + cos(ga)*cos(be)*cos(al)",
                "cos(ga)*sin(be)",
            ],
            ["sin(be)*sin(al)", "-sin(be)*cos(al)", "cos(be)"],
        ];
        let mut particle_model =
            String::from("coordinates = [\"x\", \"al\", \"be\", \"ga\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n");
        for (m, r) in POINTS {
            let comps: Vec<String> = (0..3)
                .map(|j| {
                    let terms: Vec<String> = (0..3).map(|i| format!("({:?})*({})", r[i], d[i][j])).collect();
                    format!("\"{} + {}\"", position[j], terms.join(" + "))
                })
                .collect();
            particle_model.push_str(&format!("[[particles]]\nmass = {m:?}\nposition = [{}]\n", comps.join(", ")));
        }
        let body = Derivation::new(Model::parse(&body_model, &[]).unwrap()).unwrap();
        let parts = Derivation::new(Model::parse(&particle_model, &[]).unwrap()).unwrap();
        for state in [[0.3, 0.4, 1.1, -0.7, 0.8, -1.2, 0.5, 2.0, 0.7], [-1.0, 2.0, 0.3, 1.9, -0.4, 0.3, -2.2, 0.1, 1.3]]
        {
            let names = ["x", "al", "be", "ga", "x'", "al'", "be'", "ga'", "t"];
            let mut vals: Vec<(&str, f64)> = names.iter().copied().zip(state).collect();
            vals.push(("g", 9.81));
            let e = env(&vals);
            for (what, a, b) in [
                ("T", body.kinetic.unwrap(), parts.kinetic.unwrap()),
                ("U", body.potential.unwrap(), parts.potential.unwrap()),
            ] {
                let (a, b) = (body.pool().eval(a, &e).unwrap(), parts.pool().eval(b, &e).unwrap());
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{what}: body {a} vs particles {b}");
            }
            // The body's form (M, b, T₀ built coefficient by coefficient) gives
            // the equations of motion of the particles' T written out.
            for i in 0..4 {
                let mut pairs = vec![(format!("f_{i}"), body.forcing()[i], parts.forcing()[i])];
                for j in 0..4 {
                    pairs.push((format!("M_{i}{j}"), body.mass_matrix()[i][j], parts.mass_matrix()[i][j]));
                }
                for (what, a, b) in pairs {
                    let (a, b) = (body.pool().eval(a, &e).unwrap(), parts.pool().eval(b, &e).unwrap());
                    assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{what}: body {a} vs particles {b}");
                }
            }
            // L about the reference point, body components: Σ m r_k × v_k with
            // v_k = D v_ref + ω × r_k (body components), v_ref = (x' + 0.2 cos β β', 0.6 x x', 1).
            let [x, al, be, ga, xd, ald, bed, gad, _] = state;
            let dm = euler::rotation_f64(al, be, ga);
            let w = euler::angular_velocity_f64(be, ga, [ald, bed, gad]);
            let v_ref = [xd + 0.2 * be.cos() * bed, 0.6 * x * xd, 1.0];
            let vb: Vec<f64> = (0..3).map(|i| (0..3).map(|j| dm[i][j] * v_ref[j]).sum()).collect();
            let cross = |a: [f64; 3], b: [f64; 3]| {
                [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            };
            let mut l = [0.0; 3];
            for (m, r) in POINTS {
                let wr = cross(w, r);
                let v = [vb[0] + wr[0], vb[1] + wr[1], vb[2] + wr[2]];
                let rv = cross(r, v);
                for k in 0..3 {
                    l[k] += m * rv[k];
                }
            }
            for k in 0..3 {
                let a = body.pool().eval(body.bodies[0].angular_momentum[k], &e).unwrap();
                assert!((a - l[k]).abs() < 1e-10 * (1.0 + l[k].abs()), "L{}: {a} vs {}", k + 1, l[k]);
            }
            for i in 0..4 {
                let (a, b) =
                    (body.pool().eval(body.momenta[i], &e).unwrap(), parts.pool().eval(parts.momenta[i], &e).unwrap());
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "p_{i}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn angular_momentum_of_a_pivoted_top_is_i_omega() {
        let text = "coordinates = [\"al\", \"be\", \"ga\"]\n[parameters]\nI = 2.0\nI3 = 0.7\n[[bodies]]\nmass = 1\ninertia = [\"I\", \"I\", \"I3\"]\nangles = [\"al\", \"be\", \"ga\"]\ncenter_of_mass = [0, 0, 0.4]\n";
        let d = Derivation::new(Model::parse(text, &[]).unwrap()).unwrap();
        let b = &d.bodies[0];
        let p = d.pool();
        assert_eq!(p.display(b.angular_momentum[2]).to_string(), "I3*(ga' + al'*cos(be))");
        assert_eq!(p.display(b.omega[0]).to_string(), "al'*sin(be)*sin(ga) + be'*cos(ga)");
    }
}
