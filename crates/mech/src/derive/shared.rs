//! The equations of motion of a large model, kept as one shared DAG.
//!
//! The expanded path (`energies` and `equations_of_motion` in the parent
//! module) simplifies every coefficient of M and forms the forcing from
//! Christoffel symbols, each written out: the printed results are short and
//! collected, but for a chain of many bodies, or a robot whose joints turn
//! about skew axes, the coefficients grow with the product of the chain's
//! depth and its coordinates and the work with a high power of both.
//!
//! This path builds what the notes write by hand, on the kinematics as the
//! tree gives them and without expanding anything:
//!
//! ```text
//! v = tangent of the positions along q → q', t → 1       (forward mode)
//! L = T − U,      p = ∂L/∂q',   ∂L/∂q                     (reverse mode, one pass each)
//! M_ij = ∂p_i/∂q_j',   f_i = ∂L/∂q_i − (d/dt p_i at q'' = 0) − ∂R/∂q_i' + Q_i
//! ```
//!
//! Every result is a node of one DAG whose size grows with the model, so the
//! cost does too: a chain of n links gives a DAG of order n² nodes (M has n²
//! entries) where the expanded coefficients grow as n⁴ and more. Facts about
//! these expressions (is ∂L/∂q zero, is T homogeneous) are decided by the
//! canonical form and by numbers ([`probe::decide_zero`] with expansion only
//! for short expressions): what neither shows stays undecided.

use super::quadratic::Quadratic;
use super::{body, Energies, External, Motion, Symbols};
use crate::model::frames::Frame;
use crate::model::Model;
use crate::probe::{self, Decision, Subst};
use rustc_hash::FxHashMap;
use sym::{ExprId, Pool};

/// Largest tree of an expression the shared path tries to prove zero by
/// rewriting ([`Pool::is_identically_zero`] expands); longer ones are only
/// refuted by numbers, or undecided.
const MAX_PROVEN_TREE: u64 = 2_000;

/// [`probe::decide_zero`] for the shared path's long expressions.
pub(super) fn decide_zero(pool: &mut Pool, e: ExprId) -> Decision {
    if pool.tree_size(e) <= MAX_PROVEN_TREE {
        return probe::decide_zero(pool, e);
    }
    probe::decide_zero_without_rewriting(pool, e)
}

/// More coordinates than this, moved by bodies or particles, and a model is
/// derived on the shared path from the start: the expanded path's bound would
/// stop it anyway, after walking expressions that grow as n⁴ (a tenth of a
/// second at 20 rods, seconds at 100).
const SHARED_COORDINATES: usize = 30;

/// Whether a model goes to the shared path without trying the expanded one:
/// many coordinates moved by a tree of bodies or by particles. A model given
/// by its Lagrangian (a long sum of short terms, such as a chain of springs)
/// expands in linear time and keeps the expanded path.
pub(super) fn wanted(model: &Model) -> bool {
    model.lagrangian.is_none()
        && (!model.bodies.is_empty() || !model.particles.is_empty())
        && model.coordinates.len() > SHARED_COORDINATES
}

/// The seeds of the total time derivative at q'' = 0: q → q', t → 1.
fn time_seeds(pool: &Pool, s: &Symbols) -> FxHashMap<ExprId, ExprId> {
    let mut seeds: FxHashMap<ExprId, ExprId> = s.q.iter().copied().zip(s.qd.iter().copied()).collect();
    seeds.insert(s.t, pool.one());
    seeds
}

/// T, U and L of a model, as the tree gives them (bodies' T from their ω and
/// the tangent of their reference point, particles' ½ m |x'|²), nothing
/// simplified; the form (M, b, L₀) is filled in by [`motion`].
pub(super) fn energies(pool: &mut Pool, model: &Model, s: &Symbols, frames: &[Frame]) -> Energies {
    let mut bodies = Vec::new();
    if let Some(l) = &model.lagrangian {
        return Energies {
            kinetic: None,
            potential: None,
            lagrangian: l.expr,
            form: None,
            sparsity: None,
            bodies,
            shared: true,
        };
    }
    // Every position's velocity in one forward pass, so the tree's shared
    // kinematics (a parent's origin and axes) get one tangent each.
    let mut roots: Vec<ExprId> = frames.iter().flat_map(|f| f.origin).collect();
    for part in &model.particles {
        roots.extend(part.position.iter().copied());
    }
    let seeds = time_seeds(pool, s);
    let velocities = pool.tangent(&roots, &seeds);
    let mut k_terms = Vec::new();
    let mut u_terms = Vec::new();
    for (i, (b, frame)) in model.bodies.iter().zip(frames).enumerate() {
        let v_ref = [velocities[3 * i], velocities[3 * i + 1], velocities[3 * i + 2]];
        let terms = body::terms_with_velocity(pool, b, frame, v_ref, model.gravity.as_ref());
        k_terms.push(terms.kinetic);
        u_terms.extend(terms.potential);
        bodies.push(body::motion_as_is(b, frame, &terms));
    }
    let half = pool.rational(1, 2);
    let mut at = 3 * frames.len();
    for part in &model.particles {
        let dim = part.position.len();
        let squares: Vec<ExprId> = velocities[at..at + dim].iter().map(|&v| pool.powi(v, 2)).collect();
        at += dim;
        let sq = pool.add(&squares);
        k_terms.push(pool.mul(&[half, part.mass, sq]));
        if let Some(g) = &model.gravity {
            u_terms.push(g.potential(pool, part.mass, &part.position));
        }
        if let Some(u) = part.potential {
            u_terms.push(u);
        }
    }
    if let Some(k) = &model.kinetic {
        k_terms.push(k.expr);
    }
    if let Some(u) = &model.potential {
        u_terms.push(u.expr);
    }
    let kinetic = pool.add(&k_terms);
    let potential = pool.add(&u_terms);
    let lagrangian = pool.sub(kinetic, potential);
    Energies {
        kinetic: Some(kinetic),
        potential: Some(potential),
        lagrangian,
        form: None,
        sparsity: None,
        bodies,
        shared: true,
    }
}

/// The momenta, M and f by the passes of the module text, and the form
/// (M, b, L₀) of L when M is free of the velocities (L quadratic in them).
pub(super) fn motion(pool: &mut Pool, s: &Symbols, e: &mut Energies, ext: &External) -> Motion {
    let (n, q, qd) = (s.n(), &s.q, &s.qd);
    let l = e.lagrangian;
    let momenta = pool.gradient(l, qd);
    let dl_dq = pool.gradient(l, q);
    let mut mass_matrix = vec![vec![pool.zero(); n]; n];
    for i in 0..n {
        for j in i..n {
            let m = pool.diff(momenta[i], qd[j]);
            mass_matrix[i][j] = m;
            mass_matrix[j][i] = m;
        }
    }
    let seeds = time_seeds(pool, s);
    let rates = pool.tangent(&momenta, &seeds);
    let forcing: Vec<ExprId> = (0..n)
        .map(|i| {
            let mut terms = vec![dl_dq[i], ext.forces[i]];
            terms.push(pool.neg(rates[i]));
            if let Some(r) = ext.dissipation {
                let d = pool.diff(r, qd[i]);
                terms.push(pool.neg(d));
            }
            pool.add(&terms)
        })
        .collect();
    let equations = super::assemble_equations(pool, &mass_matrix, &forcing, &s.qdd);
    let entries: Vec<ExprId> = mass_matrix.iter().flatten().copied().collect();
    let quadratic = free_of_all(pool, &entries, qd);
    if quadratic {
        let zero_vel: Subst = qd.iter().map(|&v| (v, pool.zero())).collect();
        let b = momenta.iter().map(|&p| pool.substitute(p, &zero_vel)).collect();
        let l0 = pool.substitute(l, &zero_vel);
        e.form = Some(Quadratic { m: mass_matrix.clone(), b, l0 });
    }
    Motion { momenta, mass_matrix, forcing, equations, dl_dq }
}

/// True when no root contains any of `symbols`: one walk of the roots' DAG,
/// where a [`Pool::free_of`] per root and symbol walks it n³ times for M.
fn free_of_all(pool: &Pool, roots: &[ExprId], symbols: &[ExprId]) -> bool {
    let symbols: rustc_hash::FxHashSet<ExprId> = symbols.iter().copied().collect();
    !pool.reachable(roots).iter().any(|id| symbols.contains(id))
}

#[cfg(test)]
mod tests {
    use super::super::{Derivation, Path};
    use crate::probe::Rng;
    use crate::Model;

    /// Models of every kind the shared path meets: bodies (hinged, planar,
    /// Euler angles, Tait–Bryan), particles, time-dependent constraints, a
    /// velocity-dependent potential, dissipation, forces, inputs, and a
    /// Lagrangian given as such.
    const MODELS: [(&str, &str); 13] = [
        ("double pendulum", include_str!("../../../../examples/double_pendulum.toml")),
        ("heavy top", include_str!("../../../../examples/tops/heavy_top.toml")),
        ("torqued body", include_str!("../../../../examples/tops/torqued_body.toml")),
        ("free body xyz", include_str!("../../../../examples/tops/free_body_xyz.toml")),
        ("physical pendulum", include_str!("../../../../examples/tops/physical_pendulum.toml")),
        ("rotating wire", include_str!("../../../../examples/rotating_wire_gravity.toml")),
        ("charged particle", include_str!("../../../../examples/charged_particle.toml")),
        ("damped", include_str!("../../../../examples/damped_oscillator.toml")),
        ("driven", include_str!("../../../../examples/driven_oscillator.toml")),
        ("cart pendulum", include_str!("../../../../examples/cart_pendulum.toml")),
        ("compound pendulum", include_str!("../../../../examples/compound_pendulum.toml")),
        ("spatial chain", SPATIAL_CHAIN),
        ("kepler (a Lagrangian)", include_str!("../../../../examples/kepler.toml")),
    ];

    /// Two bodies, each turned by three angles relative to its parent, with
    /// offsets and a full inertia tensor: nothing composes or cancels.
    const SPATIAL_CHAIN: &str = r#"
coordinates = ["a0", "b0", "c0", "a1", "b1", "c1"]
gravity = "g"
[parameters]
m = 1.2
l = 0.7
g = 9.81
[[bodies]]
name = "b0"
mass = "m"
inertia = [["0.25", "0.01", "0"], ["0.01", "0.2", "0.02"], ["0", "0.02", "0.1"]]
angles = ["a0", "b0", "c0"]
center_of_mass = ["0.1", "0", "-l/2"]
[[bodies]]
name = "b1"
parent = "b0"
position = ["0", "0.05", "-l"]
mass = "m"
inertia = ["m*l^2/3", "m*l^2/4", "m*l^2/10"]
angles = ["a1", "b1", "c1"]
sequence = "xyz"
center_of_mass = ["0", "0", "-l/2"]
"#;

    /// Along both paths, every result has the same value at random states, and
    /// every verdict the shared path decides is the expanded path's.
    #[test]
    fn the_shared_path_derives_what_the_expanded_path_does() {
        for (name, text) in MODELS {
            let model = Model::parse(text, &[]).unwrap_or_else(|e| panic!("{name}: {e:?}"));
            let along = |model: Model, path: Path| {
                Derivation::derive(model, path).unwrap_or_else(|e| panic!("{name}: {path:?}: {e:?}"))
            };
            let expanded = along(model.clone(), Path::Expanded);
            let shared = along(model, Path::Shared);
            let mut rng = Rng::new(7);
            for _ in 0..3 {
                let mut values: Vec<(String, f64)> = Vec::new();
                for p in &expanded.model().parameters {
                    values.push((p.name.clone(), p.value));
                }
                for c in expanded.coordinate_names() {
                    for (suffix, lo, hi) in [("", -1.5, 1.5), ("'", -2.0, 2.0), ("''", -2.0, 2.0)] {
                        values.push((format!("{c}{suffix}"), rng.range(lo, hi)));
                    }
                }
                values.push(("t".into(), rng.range(0.0, 3.0)));
                for u in &expanded.model().inputs {
                    values.push((u.name.clone(), rng.range(-1.0, 1.0)));
                }
                let env = |n: &str| values.iter().find(|(k, _)| k == n).map(|(_, v)| *v);
                let same = |what: &str, a: sym::ExprId, b: sym::ExprId| {
                    let x = expanded.pool().eval(a, &env).unwrap();
                    let y = shared.pool().eval(b, &env).unwrap();
                    assert!((x - y).abs() <= 1e-9 * (1.0 + x.abs()), "{name}: {what}: expanded {x}, shared {y}");
                };
                same("L", expanded.lagrangian(), shared.lagrangian());
                same("h", expanded.energy_function(), shared.energy_function());
                if let (Some(a), Some(b)) = (expanded.energy(), shared.energy()) {
                    same("E", a, b);
                }
                let n = expanded.q().len();
                for i in 0..n {
                    same(&format!("p_{i}"), expanded.momenta()[i], shared.momenta()[i]);
                    same(&format!("f_{i}"), expanded.forcing()[i], shared.forcing()[i]);
                    same(&format!("E_{i}"), expanded.equations()[i], shared.equations()[i]);
                    for j in 0..n {
                        same(&format!("M_{i}{j}"), expanded.mass_matrix()[i][j], shared.mass_matrix()[i][j]);
                    }
                    for (k, (&a, &b)) in expanded.input_matrix()[i].iter().zip(&shared.input_matrix()[i]).enumerate() {
                        same(&format!("B_{i}{k}"), a, b);
                    }
                }
            }
            // A coordinate cyclic only by trigonometric identities (the top's
            // precession angle under gravity) is undecided on the shared path,
            // never claimed either way.
            let names = expanded.coordinate_names();
            for i in 0..names.len() {
                let claimed = shared.cyclic().contains(&i);
                let undecided = shared.verdicts().cyclic.iter().any(
                    |r| matches!(r, super::super::CyclicReason::Undecided { coordinate } if coordinate == names[i]),
                );
                match expanded.cyclic().contains(&i) {
                    true => assert!(claimed || undecided, "{name}: {} is cyclic", names[i]),
                    false => assert!(!claimed, "{name}: {} is not cyclic", names[i]),
                }
            }
            if let Some(is) = shared.hamiltonian_is_energy() {
                assert_eq!(expanded.hamiltonian_is_energy(), Some(is), "{name}: H = E");
            }
            assert_eq!(expanded.hamiltonian_conserved(), shared.hamiltonian_conserved(), "{name}: H conserved");
            assert!(shared.hamiltonian().is_none(), "{name}: the shared path does not invert M");
        }
    }
}
