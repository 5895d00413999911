//! The accelerations of a tree of bodies and particles by the articulated-body
//! algorithm, generated for the model as one program of assignments.
//!
//! `M q'' = f` solved with a dense LU costs O(n³) per right-hand side, and M
//! and f themselves grow as n² for a chain; Featherstone's articulated-body
//! algorithm (RBDA, ch. 7) gives q'' of a kinematic tree in O(n). Here it is
//! written out for one model: every spatial quantity is a list of expressions
//! whose entries are assignments (`z = expr`), compiled by
//! [`sym::Tape::compile_with_definitions`] into one tape, so the zeros of a
//! planar model or of an axis-aligned joint fold away and what is left is the
//! model's own arithmetic.
//!
//! Each node of the tree is a body (its parent as the model file gives it)
//! or a particle (its parent found below) with a frame: the rotation `E` from
//! the parent's components to its own and the origin `r` relative to the
//! parent's, in the parent's components, both functions of the node's *own*
//! coordinates and t only. Its velocity relative to the parent, in its own
//! components, is `v_J = (ω_rel, E r')`: linear in its own velocities, with
//! the motion subspace `S = ∂v_J/∂q'_own` and `c_J = d/dt v_J` at q'' = 0.
//! Spatial vectors are (angular; linear) about the node's origin; a body's
//! inertia about its reference point is `[[I, m[c]ₓ], [−m[c]ₓ, m 1]]`, a
//! particle's `[[0, 0], [0, m 1]]`. Gravity is the base's acceleration
//! `a₀ = −g`; every other force enters as a generalized force
//! `τ = Q − ∂R/∂q' − ∂U'/∂q` (U' the potential that is not gravity's).
//!
//! A particle's parent is the earlier particle whose position, subtracted from
//! its own, leaves the fewest coordinates (a chain written with absolute angles,
//! `x_k = Σ_{j≤k} l_j sin θ_j`, gives `r_k = l_k sin θ_k`).
//!
//! The program exists only where the model is such a tree: L = T − U from
//! bodies, particles and a potential free of q', no constraints, every
//! coordinate owned by exactly one node (at most six per node). Anywhere else
//! [`program`] returns None and runs solve `M q'' = f`.

use crate::derive::Derivation;
use crate::euler::ExprMatrix;
use crate::model::frames::{mat_vec, relative_turn};
use crate::model::{Gravity, Model};
use rustc_hash::{FxHashMap, FxHashSet};
use sym::{ExprId, Node, Pool};

/// The accelerations as a program: `definitions` in order, then q''.
#[derive(Debug, Clone)]
pub(crate) struct Program {
    /// `(symbol, expr)`: each symbol stands for its expression in the later ones.
    pub definitions: Vec<(ExprId, ExprId)>,
    /// q'' per coordinate.
    pub accelerations: Vec<ExprId>,
}

/// More coordinates than this owned by one node and its joint's k×k solve
/// costs more than the tree saves.
const MAX_OWN: usize = 6;

type Vec3 = [ExprId; 3];
/// (angular; linear).
type Spatial = [ExprId; 6];
/// A symmetric 6×6 matrix, both triangles filled.
type Matrix6 = [[ExprId; 6]; 6];

/// One node of the tree (see the module text).
struct TreeNode {
    parent: Option<usize>,
    /// The coordinates it owns, in the order of the model.
    own: Vec<usize>,
    /// Parent components → own components; None for no turn.
    rotation: Option<ExprMatrix>,
    /// Its origin relative to the parent's, parent components.
    origin: Vec3,
    /// Its velocity relative to the parent, own components, in (q_own, q'_own, t).
    joint_velocity: Spatial,
    /// Mass, centre of mass (own components), inertia about the origin.
    mass: ExprId,
    center: Vec3,
    inertia: ExprMatrix,
}

/// The accelerations of `d`'s model by the articulated-body algorithm, built
/// in `pool` (a copy of the derivation's); None where the model is not a tree
/// of bodies and particles (see the module text).
pub(crate) fn program(pool: &mut Pool, d: &Derivation) -> Option<Program> {
    let model = &d.model;
    let n = d.q.len();
    if model.lagrangian.is_some()
        || model.kinetic.is_some()
        || !model.constraints.is_empty()
        || (model.bodies.is_empty() && model.particles.is_empty())
    {
        return None;
    }
    let dimension = dimension(model)?;
    let index_of: FxHashMap<ExprId, usize> = d.q.iter().enumerate().map(|(i, &s)| (s, i)).collect();
    let velocity_index: FxHashMap<ExprId, usize> = d.qd.iter().enumerate().map(|(i, &s)| (s, i)).collect();
    let coordinates_in = |pool: &Pool, es: &[ExprId]| -> Vec<usize> {
        let mut found: Vec<usize> = pool.reachable(es).iter().filter_map(|id| index_of.get(id).copied()).collect();
        found.sort_unstable();
        found
    };
    let velocities_in = |pool: &Pool, es: &[ExprId]| -> Vec<usize> {
        pool.reachable(es).iter().filter_map(|id| velocity_index.get(id).copied()).collect()
    };
    let mut seeds: FxHashMap<ExprId, ExprId> = d.q.iter().copied().zip(d.qd.iter().copied()).collect();
    seeds.insert(d.t, pool.one());

    let mut nodes: Vec<TreeNode> = Vec::new();
    let zero = pool.zero();
    for body in &model.bodies {
        let (rotation, omega) = relative_turn(pool, body, &d.q, &d.qd);
        let origin = body.position;
        let mut own = body.orientation.angles();
        own.extend(coordinates_in(pool, &origin));
        own.sort_unstable();
        own.dedup();
        let rate = pool.tangent(&origin, &seeds);
        let linear = match &rotation {
            Some(e) => mat_vec(pool, e, &[rate[0], rate[1], rate[2]]),
            None => [rate[0], rate[1], rate[2]],
        };
        nodes.push(TreeNode {
            parent: body.parent,
            own,
            rotation,
            origin,
            joint_velocity: [omega[0], omega[1], omega[2], linear[0], linear[1], linear[2]],
            mass: body.mass,
            center: body.center_of_mass,
            inertia: body.inertia,
        });
    }
    let first_particle = nodes.len();
    let positions: Vec<Vec3> = model.particles.iter().map(|p| padded(pool, &p.position)).collect();
    let position_coordinates: Vec<Vec<usize>> = positions.iter().map(|x| coordinates_in(pool, x)).collect();
    for (k, part) in model.particles.iter().enumerate() {
        // The parent: the earlier particle sharing the most coordinates whose
        // position leaves a difference free of them.
        let mut candidates: Vec<usize> = (0..k)
            .filter(|&p| {
                let (theirs, mine) = (&position_coordinates[p], &position_coordinates[k]);
                !theirs.is_empty() && theirs.len() < mine.len() && is_subset(theirs, mine)
            })
            .collect();
        candidates.sort_by_key(|&p| std::cmp::Reverse(position_coordinates[p].len()));
        let mut best: Option<(usize, Vec3, Vec<usize>)> = None;
        for p in candidates {
            let r: Vec3 = std::array::from_fn(|i| pool.sub(positions[k][i], positions[p][i]));
            let own = coordinates_in(pool, &r);
            if !own.iter().any(|c| position_coordinates[p].binary_search(c).is_ok()) {
                best = Some((p, r, own));
                break;
            }
        }
        let (parent, origin, own) = match best {
            Some((p, r, own)) => (Some(first_particle + p), r, own),
            None => (None, positions[k], position_coordinates[k].clone()),
        };
        let rate = pool.tangent(&origin, &seeds);
        nodes.push(TreeNode {
            parent,
            own,
            rotation: None,
            origin,
            joint_velocity: [zero, zero, zero, rate[0], rate[1], rate[2]],
            mass: part.mass,
            center: [zero; 3],
            inertia: [[zero; 3]; 3],
        });
    }

    // Every coordinate owned once; a node's kinematics in its own coordinates only.
    let mut owner = vec![None; n];
    for (i, node) in nodes.iter().enumerate() {
        if node.own.len() > MAX_OWN {
            return None;
        }
        for &c in &node.own {
            if owner[c].replace(i).is_some() {
                return None;
            }
        }
        let mut position_parts: Vec<ExprId> = node.origin.to_vec();
        if let Some(e) = &node.rotation {
            position_parts.extend(e.iter().flatten());
        }
        if coordinates_in(pool, &position_parts).iter().any(|c| !node.own.contains(c))
            || !velocities_in(pool, &position_parts).is_empty()
            || coordinates_in(pool, &node.joint_velocity).iter().any(|c| !node.own.contains(c))
            || velocities_in(pool, &node.joint_velocity).iter().any(|c| !node.own.contains(c))
        {
            return None;
        }
    }
    if owner.iter().any(Option::is_none) {
        return None;
    }

    let forces = generalized_forces(pool, d)?;
    let gravity = base_acceleration(pool, model.gravity.as_ref(), dimension);
    Some(Builder::new(pool).run(&nodes, &forces, gravity, &d.qd, &seeds))
}

/// The components of every position: 1 to 3 for particles, 2 or 3 for bodies
/// (which must agree); None for a mix.
fn dimension(model: &Model) -> Option<usize> {
    let mut dims = model.bodies.iter().map(|b| b.dimension).chain(model.particles.iter().map(|p| p.position.len()));
    let first = dims.next()?;
    dims.all(|d| d == first).then_some(first)
}

/// Whether the sorted `a` is part of the sorted `b`.
fn is_subset(a: &[usize], b: &[usize]) -> bool {
    let mut rest = b.iter();
    a.iter().all(|x| rest.any(|y| y == x))
}

/// A position of 1 to 3 components as three.
fn padded(pool: &Pool, x: &[ExprId]) -> Vec3 {
    std::array::from_fn(|i| x.get(i).copied().unwrap_or(pool.zero()))
}

/// τ = Q − ∂R/∂q' − ∂U'/∂q, U' the potentials that are not gravity's; None
/// when U' depends on the velocities (its d/dt ∂U'/∂q' would enter M).
fn generalized_forces(pool: &mut Pool, d: &Derivation) -> Option<Vec<ExprId>> {
    let model = &d.model;
    let mut potentials: Vec<ExprId> = model.particles.iter().filter_map(|p| p.potential).collect();
    potentials.extend(model.potential.as_ref().map(|u| u.expr));
    let u = pool.add(&potentials);
    let reach: FxHashSet<ExprId> = pool.reachable(&[u]).into_iter().collect();
    if d.qd.iter().any(|v| reach.contains(v)) {
        return None;
    }
    let du = pool.gradient(u, &d.q);
    let dr = match d.dissipation {
        Some(r) => pool.gradient(r, &d.qd),
        None => vec![pool.zero(); d.q.len()],
    };
    Some(
        (0..d.q.len())
            .map(|i| {
                let (a, b) = (pool.neg(du[i]), pool.neg(dr[i]));
                pool.add(&[d.forces[i], a, b])
            })
            .collect(),
    )
}

/// The base's spatial acceleration −g: gravity `g` pulls along the last axis
/// of the positions, a field vector along itself.
fn base_acceleration(pool: &mut Pool, gravity: Option<&Gravity>, dimension: usize) -> Spatial {
    let zero = pool.zero();
    let mut a = [zero; 6];
    match gravity {
        None => {}
        Some(Gravity::Down(g)) => a[3 + dimension - 1] = g.expr,
        Some(Gravity::Field { components, .. }) => {
            for (k, g) in components.iter().enumerate() {
                a[3 + k] = pool.neg(g.expr);
            }
        }
    }
    a
}

/// Writes the algorithm's assignments.
struct Builder<'p> {
    pool: &'p mut Pool,
    definitions: Vec<(ExprId, ExprId)>,
}

impl<'p> Builder<'p> {
    fn new(pool: &'p mut Pool) -> Builder<'p> {
        Builder { pool, definitions: Vec::new() }
    }

    /// `e` as a symbol of its own (numbers and symbols stay as they are, so
    /// that zeros fold in what uses them).
    fn def(&mut self, e: ExprId) -> ExprId {
        match self.pool.node(e) {
            Node::Num(_) | Node::Sym(_) | Node::Pi => e,
            _ => {
                // A space cannot occur in a model's names.
                let symbol = self.pool.symbol(&format!("tree {}", self.definitions.len()));
                self.definitions.push((symbol, e));
                symbol
            }
        }
    }

    fn def_all<const K: usize>(&mut self, es: [ExprId; K]) -> [ExprId; K] {
        es.map(|e| self.def(e))
    }

    fn sum(&mut self, terms: &[ExprId]) -> ExprId {
        let s = self.pool.add(terms);
        self.def(s)
    }

    fn dot(&mut self, a: &[ExprId], b: &[ExprId]) -> ExprId {
        let terms: Vec<ExprId> = a.iter().zip(b).map(|(&x, &y)| self.pool.mul2(x, y)).collect();
        self.sum(&terms)
    }

    fn cross(&mut self, a: &Vec3, b: &Vec3) -> Vec3 {
        std::array::from_fn(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let p = self.pool.mul2(a[j], b[k]);
            let m = self.pool.mul2(a[k], b[j]);
            let d = self.pool.sub(p, m);
            self.def(d)
        })
    }

    fn add3(&mut self, a: &Vec3, b: &Vec3) -> Vec3 {
        std::array::from_fn(|i| self.sum(&[a[i], b[i]]))
    }

    fn add6(&mut self, a: &Spatial, b: &Spatial) -> Spatial {
        std::array::from_fn(|i| self.sum(&[a[i], b[i]]))
    }

    /// E v.
    fn rotate(&mut self, e: Option<&ExprMatrix>, v: &Vec3) -> Vec3 {
        match e {
            None => *v,
            Some(e) => std::array::from_fn(|i| self.dot(&e[i], v)),
        }
    }

    /// Eᵀ v.
    fn rotate_back(&mut self, e: Option<&ExprMatrix>, v: &Vec3) -> Vec3 {
        match e {
            None => *v,
            Some(e) => std::array::from_fn(|i| {
                let column = [e[0][i], e[1][i], e[2][i]];
                self.dot(&column, v)
            }),
        }
    }

    /// A motion vector from the parent's frame to the node's: (E ω, E (v − r × ω)).
    fn motion_in(&mut self, node: &TreeNode, m: &Spatial) -> Spatial {
        let (w, v) = split(m);
        let r_x_w = self.cross(&node.origin, &w);
        let shifted: Vec3 = std::array::from_fn(|i| {
            let d = self.pool.sub(v[i], r_x_w[i]);
            self.def(d)
        });
        let e = node.rotation.as_ref();
        let (w, v) = (self.rotate(e, &w), self.rotate(e, &shifted));
        join(&w, &v)
    }

    /// A force vector from the node's frame to the parent's: (Eᵀn + r × Eᵀf, Eᵀf).
    fn force_out(&mut self, node: &TreeNode, f: &Spatial) -> Spatial {
        let (n, f) = split(f);
        let e = node.rotation.as_ref();
        let (n, f) = (self.rotate_back(e, &n), self.rotate_back(e, &f));
        let r_x_f = self.cross(&node.origin, &f);
        let n = self.add3(&n, &r_x_f);
        join(&n, &f)
    }

    /// v × m for motion vectors.
    fn cross_motion(&mut self, v: &Spatial, m: &Spatial) -> Spatial {
        let ((w, vl), (mw, mv)) = (split(v), split(m));
        let a = self.cross(&w, &mw);
        let b1 = self.cross(&w, &mv);
        let b2 = self.cross(&vl, &mw);
        let b = self.add3(&b1, &b2);
        join(&a, &b)
    }

    /// v ×* f for a force vector.
    fn cross_force(&mut self, v: &Spatial, f: &Spatial) -> Spatial {
        let ((w, vl), (n, ff)) = (split(v), split(f));
        let a1 = self.cross(&w, &n);
        let a2 = self.cross(&vl, &ff);
        let a = self.add3(&a1, &a2);
        let b = self.cross(&w, &ff);
        join(&a, &b)
    }

    fn mat_vec6(&mut self, a: &Matrix6, x: &Spatial) -> Spatial {
        std::array::from_fn(|i| self.dot(&a[i], x))
    }

    /// Xᵀ A X for a symmetric A in the node's frame, in the parent's.
    fn congruence(&mut self, node: &TreeNode, a: &Matrix6) -> Matrix6 {
        // B = Xᵀ A column by column, then Xᵀ Bᵀ = Xᵀ A X (A symmetric).
        let columns: Vec<Spatial> = (0..6).map(|k| self.force_out(node, &std::array::from_fn(|i| a[i][k]))).collect();
        let out: Vec<Spatial> = (0..6).map(|k| self.force_out(node, &std::array::from_fn(|i| columns[i][k]))).collect();
        std::array::from_fn(|i| std::array::from_fn(|j| if i <= j { out[j][i] } else { out[i][j] }))
    }

    /// The node's spatial inertia about its origin, its own components.
    fn inertia(&mut self, node: &TreeNode) -> Matrix6 {
        let zero = self.pool.zero();
        let mut out = [[zero; 6]; 6];
        let mc: Vec3 = std::array::from_fn(|i| self.pool.mul2(node.mass, node.center[i]));
        // m[c]ₓ: the matrix of v ↦ m c × v.
        let cx = [
            [zero, self.pool.neg(mc[2]), mc[1]],
            [mc[2], zero, self.pool.neg(mc[0])],
            [self.pool.neg(mc[1]), mc[0], zero],
        ];
        for i in 0..3 {
            for j in 0..3 {
                out[i][j] = node.inertia[i][j];
                out[i][3 + j] = cx[i][j];
                out[3 + j][i] = cx[i][j];
            }
            out[3 + i][3 + i] = node.mass;
        }
        out
    }

    /// Solves D X = B for the k×k symmetric positive definite D (Gaussian
    /// elimination without pivoting; D is a sum of inertias projected on the
    /// joint's subspace), B given by columns of k.
    fn solve(&mut self, mut dm: Vec<Vec<ExprId>>, mut b: Vec<Vec<ExprId>>) -> Vec<Vec<ExprId>> {
        let k = dm.len();
        for col in 0..k {
            let inv = {
                let one = self.pool.one();
                let r = self.pool.div(one, dm[col][col]);
                self.def(r)
            };
            for row in col + 1..k {
                let factor = {
                    let f = self.pool.mul2(dm[row][col], inv);
                    self.def(f)
                };
                for c in col + 1..k {
                    let t = self.pool.mul2(factor, dm[col][c]);
                    let d = self.pool.sub(dm[row][c], t);
                    dm[row][c] = self.def(d);
                }
                for column in b.iter_mut() {
                    let t = self.pool.mul2(factor, column[col]);
                    let d = self.pool.sub(column[row], t);
                    column[row] = self.def(d);
                }
            }
            dm[col][col] = inv;
        }
        for column in b.iter_mut() {
            for row in (0..k).rev() {
                let mut terms = vec![column[row]];
                for c in row + 1..k {
                    let t = self.pool.mul2(dm[row][c], column[c]);
                    terms.push(self.pool.neg(t));
                }
                let s = self.pool.add(&terms);
                let x = self.pool.mul2(s, dm[row][row]);
                column[row] = self.def(x);
            }
        }
        b
    }

    /// The three passes of the algorithm (RBDA Table 7.1).
    fn run(
        mut self,
        nodes: &[TreeNode],
        forces: &[ExprId],
        base: Spatial,
        qd: &[ExprId],
        seeds: &FxHashMap<ExprId, ExprId>,
    ) -> Program {
        let zero = self.pool.zero();
        let count = nodes.len();
        // Pass 1, root to leaves: velocities, bias accelerations and forces.
        let mut velocity: Vec<Spatial> = Vec::with_capacity(count);
        let mut bias: Vec<Spatial> = Vec::with_capacity(count);
        let mut inertia: Vec<Matrix6> = Vec::with_capacity(count);
        let mut force: Vec<Spatial> = Vec::with_capacity(count);
        for node in nodes {
            let v_j = self.def_all(node.joint_velocity);
            let c_j = self.pool.tangent(&node.joint_velocity, seeds);
            let c_j = self.def_all(std::array::from_fn(|i| c_j[i]));
            let v = match node.parent {
                Some(p) => {
                    let carried = self.motion_in(node, &velocity[p]);
                    self.add6(&carried, &v_j)
                }
                None => v_j,
            };
            let v_x_vj = self.cross_motion(&v, &v_j);
            bias.push(self.add6(&c_j, &v_x_vj));
            let i = self.inertia(node);
            let iv = self.mat_vec6(&i, &v);
            force.push(self.cross_force(&v, &iv));
            inertia.push(i);
            velocity.push(v);
        }
        // Pass 2, leaves to root: articulated inertias and forces.
        let mut subspace: Vec<Vec<Spatial>> = vec![Vec::new(); count];
        let mut along: Vec<Vec<ExprId>> = vec![Vec::new(); count];
        let mut across: Vec<Vec<Vec<ExprId>>> = vec![Vec::new(); count];
        for i in (0..count).rev() {
            let node = &nodes[i];
            let s: Vec<Spatial> = node
                .own
                .iter()
                .map(|&c| {
                    let col: Spatial = std::array::from_fn(|r| self.pool.diff(node.joint_velocity[r], qd[c]));
                    self.def_all(col)
                })
                .collect();
            let u: Vec<Spatial> = s.iter().map(|col| self.mat_vec6(&inertia[i], col)).collect();
            let dm: Vec<Vec<ExprId>> =
                (0..s.len()).map(|a| (0..s.len()).map(|b| self.dot(&s[a], &u[b])).collect()).collect();
            let rhs: Vec<ExprId> = node
                .own
                .iter()
                .zip(&s)
                .map(|(&c, col)| {
                    let sp = self.dot(col, &force[i]);
                    let d = self.pool.sub(forces[c], sp);
                    self.def(d)
                })
                .collect();
            // One solve for D⁻¹u and the six columns of D⁻¹Uᵀ.
            let mut columns = vec![rhs];
            for r in 0..6 {
                columns.push(u.iter().map(|col| col[r]).collect());
            }
            let solved =
                if s.is_empty() { columns.iter().map(|_| Vec::new()).collect() } else { self.solve(dm, columns) };
            if let Some(p) = node.parent {
                // Iᵃ = Iᴬ − U D⁻¹Uᵀ, pᵃ = pᴬ + Iᵃc + U D⁻¹u.
                let mut ia = inertia[i];
                for a in 0..6 {
                    for b in a..6 {
                        let mut terms = vec![ia[a][b]];
                        for (k, col) in u.iter().enumerate() {
                            let t = self.pool.mul2(col[a], solved[1 + b][k]);
                            terms.push(self.pool.neg(t));
                        }
                        let e = self.sum(&terms);
                        ia[a][b] = e;
                        ia[b][a] = e;
                    }
                }
                let ic = self.mat_vec6(&ia, &bias[i]);
                let pa: Spatial = std::array::from_fn(|r| {
                    let mut terms = vec![force[i][r], ic[r]];
                    for (k, col) in u.iter().enumerate() {
                        terms.push(self.pool.mul2(col[r], solved[0][k]));
                    }
                    self.sum(&terms)
                });
                let ia_parent = self.congruence(node, &ia);
                let pa_parent = self.force_out(node, &pa);
                for a in 0..6 {
                    for b in a..6 {
                        let e = self.sum(&[inertia[p][a][b], ia_parent[a][b]]);
                        inertia[p][a][b] = e;
                        inertia[p][b][a] = e;
                    }
                }
                force[p] = self.add6(&force[p], &pa_parent);
            }
            along[i] = solved[0].clone();
            across[i] = (0..s.len()).map(|k| (1..7).map(|r| solved[r][k]).collect()).collect();
            subspace[i] = s;
        }
        // Pass 3, root to leaves: accelerations.
        let mut accelerations = vec![zero; forces.len()];
        let mut acceleration: Vec<Spatial> = Vec::with_capacity(count);
        for (i, node) in nodes.iter().enumerate() {
            let from = match node.parent {
                Some(p) => acceleration[p],
                None => base,
            };
            let carried = self.motion_in(node, &from);
            let mut a = self.add6(&carried, &bias[i]);
            let mut terms: Vec<Vec<ExprId>> = vec![Vec::new(); 6];
            for (k, &c) in node.own.iter().enumerate() {
                // q''_k = (D⁻¹u)_k − (D⁻¹Uᵀ)_k · a.
                let wa = self.dot(&across[i][k], &a);
                let qdd = self.pool.sub(along[i][k], wa);
                let qdd = self.def(qdd);
                accelerations[c] = qdd;
                for (r, t) in terms.iter_mut().enumerate() {
                    t.push(self.pool.mul2(subspace[i][k][r], qdd));
                }
            }
            a = std::array::from_fn(|r| {
                let mut all = vec![a[r]];
                all.extend(terms[r].iter().copied());
                self.sum(&all)
            });
            acceleration.push(a);
        }
        Program { definitions: self.definitions, accelerations }
    }
}

fn split(v: &Spatial) -> (Vec3, Vec3) {
    ([v[0], v[1], v[2]], [v[3], v[4], v[5]])
}

fn join(a: &Vec3, b: &Vec3) -> Spatial {
    [a[0], a[1], a[2], b[0], b[1], b[2]]
}
