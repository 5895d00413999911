//! An independent derivation to check `Derivation::new` against: L built
//! naively from the model (T = Σ ½ m |dx/dt|² by the chain rule, U summed), and
//! everything else by plain differentiation — no quadratic split, no
//! simplification, no Legendre transform. Enter with [`Oracle::new`], then
//! evaluate at a [`Point`].
//!
//! It reads the same [`Model`] as the derivation (so the text is parsed once),
//! in its own copy of the pool.

use mech::{ConstraintKind, Model};
use sym::{ExprId, Pool};

/// The independent derivation.
pub struct Oracle {
    /// Its own pool (a copy of the model's).
    pub pool: Pool,
    /// Coordinate names.
    pub names: Vec<String>,
    /// Parameter names.
    pub parameters: Vec<String>,
    /// L.
    pub lagrangian: ExprId,
    /// T + U₀ (U₀: U at zero velocities), when the model gives T and U.
    pub energy: Option<ExprId>,
    /// h − (T + U₀), when the model gives T and U.
    pub energy_gap: Option<ExprId>,
    /// ∂L/∂q'.
    pub momenta: Vec<ExprId>,
    /// ∂²L/∂q'∂q'.
    pub mass_matrix: Vec<Vec<ExprId>>,
    /// d/dt ∂L/∂q' − ∂L/∂q + ∂R/∂q' − Q, in (q, q', q'', t).
    pub residual: Vec<ExprId>,
    /// ∂L/∂q.
    pub dl_dq: Vec<ExprId>,
    /// ∂L/∂t.
    pub dl_dt: ExprId,
    /// R (zero when absent).
    pub dissipation: ExprId,
    /// Q (zero where absent).
    pub forces: Vec<ExprId>,
    /// h = Σ q' ∂L/∂q' − L.
    pub energy_function: ExprId,
    /// The true rate of change of the momenta: ∂L/∂q − ∂R/∂q' + Q.
    pub momentum_rates: Vec<ExprId>,
    /// Per constraint: its row of A (∂f/∂q, or the velocity coefficients) and its time term.
    pub constraints: Vec<(Vec<ExprId>, ExprId)>,
}

/// A point of state space and parameter values.
#[derive(Clone, Debug)]
pub struct Point {
    /// Coordinates.
    pub q: Vec<f64>,
    /// Velocities.
    pub qd: Vec<f64>,
    /// Accelerations.
    pub qdd: Vec<f64>,
    /// Momenta (set from the oracle's ∂L/∂q' at (q, q', t)).
    pub p: Vec<f64>,
    /// Time.
    pub t: f64,
    /// Parameter values, in the model's order.
    pub params: Vec<f64>,
}

impl Oracle {
    /// The oracle of a model; None for a model with rigid bodies, whose T the
    /// oracle does not build, or with loads, whose virtual work it does not.
    pub fn new(model: &Model) -> Option<Oracle> {
        if !model.bodies.is_empty() || !model.loads.is_empty() {
            return None;
        }
        Some(Oracle::build(model, model.pool.clone(), None, None))
    }

    /// The oracle of a model with rigid bodies, from the T and U the derivation
    /// built (in `pool`, its pool): what follows from them is still derived
    /// independently (momenta, M, the equations, h, H's checks, the verdicts).
    /// With loads, `forces` are the derivation's generalized forces (`[forces]`
    /// and the loads' virtual work), taken as given in the same way.
    pub fn with_energies(
        model: &Model,
        pool: Pool,
        kinetic: ExprId,
        potential: ExprId,
        forces: Option<Vec<ExprId>>,
    ) -> Oracle {
        Oracle::build(model, pool, Some((kinetic, potential)), forces)
    }

    fn build(model: &Model, mut pool: Pool, energies: Option<(ExprId, ExprId)>, given: Option<Vec<ExprId>>) -> Oracle {
        let pool_ref = &mut pool;
        let names: Vec<String> = model.coordinates.iter().map(|c| c.name.clone()).collect();
        let q: Vec<ExprId> = names.iter().map(|c| pool_ref.var(c, 0)).collect();
        let qd: Vec<ExprId> = names.iter().map(|c| pool_ref.var(c, 1)).collect();
        let qdd: Vec<ExprId> = names.iter().map(|c| pool_ref.var(c, 2)).collect();
        let t = pool_ref.symbol("t");
        let n = names.len();

        let (lagrangian, energy) = match (&model.lagrangian, energies) {
            (_, Some((tt, uu))) => {
                let zero = pool_ref.zero();
                let at_rest = qd.iter().map(|&v| (v, zero)).collect();
                let u0 = pool_ref.substitute(uu, &at_rest);
                let energy = pool_ref.add2(tt, u0);
                (pool_ref.sub(tt, uu), Some(energy))
            }
            (Some(l), None) => (l.expr, None),
            (None, None) => {
                let mut kinetic = Vec::new();
                let mut potential = Vec::new();
                for part in &model.particles {
                    let mut speed2 = Vec::new();
                    for &x in &part.position {
                        let mut rate: Vec<ExprId> = (0..n)
                            .map(|k| {
                                let d = pool_ref.diff(x, q[k]);
                                pool_ref.mul2(d, qd[k])
                            })
                            .collect();
                        rate.push(pool_ref.diff(x, t));
                        let rate = pool_ref.add(&rate);
                        speed2.push(pool_ref.powi(rate, 2));
                    }
                    let speed2 = pool_ref.add(&speed2);
                    let half = pool_ref.rational(1, 2);
                    kinetic.push(pool_ref.mul(&[half, part.mass, speed2]));
                    match &model.gravity {
                        Some(mech::Gravity::Down(g)) => {
                            let height = part.position[part.position.len() - 1];
                            potential.push(pool_ref.mul(&[part.mass, g.expr, height]));
                        }
                        Some(mech::Gravity::Field { components, .. }) => {
                            // U = −m g·r, every component written out.
                            for (g, &x) in components.iter().zip(&part.position) {
                                let minus = pool_ref.neg(part.mass);
                                potential.push(pool_ref.mul(&[minus, g.expr, x]));
                            }
                        }
                        None => {}
                    }
                    potential.extend(part.potential);
                }
                kinetic.extend(model.kinetic.as_ref().map(|k| k.expr));
                potential.extend(model.potential.as_ref().map(|u| u.expr));
                let tt = pool_ref.add(&kinetic);
                let uu = pool_ref.add(&potential);
                let zero = pool_ref.zero();
                let at_rest = qd.iter().map(|&v| (v, zero)).collect();
                let u0 = pool_ref.substitute(uu, &at_rest);
                let energy = pool_ref.add2(tt, u0);
                (pool_ref.sub(tt, uu), Some(energy))
            }
        };
        let dissipation = model.dissipation.as_ref().map_or(pool_ref.zero(), |r| r.expr);
        let forces: Vec<ExprId> = match given {
            Some(f) => f,
            None => model.forces.iter().map(|f| f.as_ref().map_or(pool_ref.zero(), |f| f.expr)).collect(),
        };

        let momenta: Vec<ExprId> = qd.iter().map(|&v| pool_ref.diff(lagrangian, v)).collect();
        let mass_matrix: Vec<Vec<ExprId>> =
            momenta.iter().map(|&p| qd.iter().map(|&v| pool_ref.diff(p, v)).collect()).collect();
        let dl_dq: Vec<ExprId> = q.iter().map(|&x| pool_ref.diff(lagrangian, x)).collect();
        let dl_dt = pool_ref.diff(lagrangian, t);
        let mut residual = Vec::with_capacity(n);
        let mut momentum_rates = Vec::with_capacity(n);
        for i in 0..n {
            let mut terms = Vec::new();
            for k in 0..n {
                let d = pool_ref.diff(momenta[i], q[k]);
                terms.push(pool_ref.mul2(d, qd[k]));
                terms.push(pool_ref.mul2(mass_matrix[i][k], qdd[k]));
            }
            terms.push(pool_ref.diff(momenta[i], t));
            terms.push(pool_ref.neg(dl_dq[i]));
            let dr = pool_ref.diff(dissipation, qd[i]);
            terms.push(dr);
            terms.push(pool_ref.neg(forces[i]));
            residual.push(pool_ref.add(&terms));
            let minus_dr = pool_ref.neg(dr);
            momentum_rates.push(pool_ref.add(&[dl_dq[i], minus_dr, forces[i]]));
        }
        let mut h_terms: Vec<ExprId> = (0..n).map(|i| pool_ref.mul2(qd[i], momenta[i])).collect();
        h_terms.push(pool_ref.neg(lagrangian));
        let energy_function = pool_ref.add(&h_terms);
        let energy_gap = energy.map(|e| pool_ref.sub(energy_function, e));

        let zero = pool_ref.zero();
        let at_rest = qd.iter().map(|&v| (v, zero)).collect();
        let constraints = model
            .constraints
            .iter()
            .map(|c| match c.kind {
                ConstraintKind::Holonomic => {
                    let row = q.iter().map(|&x| pool_ref.diff(c.expr.expr, x)).collect();
                    (row, pool_ref.diff(c.expr.expr, t))
                }
                ConstraintKind::Velocity => {
                    let row = qd.iter().map(|&v| pool_ref.diff(c.expr.expr, v)).collect();
                    (row, pool_ref.substitute(c.expr.expr, &at_rest))
                }
            })
            .collect();
        Oracle {
            pool,
            names,
            parameters: model.parameters.iter().map(|p| p.name.clone()).collect(),
            lagrangian,
            energy,
            energy_gap,
            momenta,
            mass_matrix,
            residual,
            dl_dq,
            dl_dt,
            dissipation,
            forces,
            energy_function,
            momentum_rates,
            constraints,
        }
    }

    /// The value of a symbol at `point`: a coordinate, velocity, acceleration,
    /// momentum `p_q`, `t`, or a parameter.
    pub fn value(&self, point: &Point, name: &str) -> Option<f64> {
        if name == "t" {
            return Some(point.t);
        }
        if let Some(i) = self.parameters.iter().position(|p| p == name) {
            return Some(point.params[i]);
        }
        if let Some(q) = name.strip_prefix("p_") {
            return self.names.iter().position(|c| c == q).map(|i| point.p[i]);
        }
        let base = name.trim_end_matches('\'');
        let i = self.names.iter().position(|c| c == base)?;
        match name.len() - base.len() {
            0 => Some(point.q[i]),
            1 => Some(point.qd[i]),
            2 => Some(point.qdd[i]),
            _ => None,
        }
    }

    /// Evaluates an expression of `pool` (the oracle's or the derivation's) at `point`.
    pub fn eval(&self, pool: &Pool, e: ExprId, point: &Point) -> Result<f64, String> {
        pool.eval(e, &|name| self.value(point, name)).map_err(|err| err.to_string())
    }

    /// A random point for comparing values: q in ±1.2, q' and q'' in ±1, t in
    /// [0, 1.5], parameters in [0.5, 2] (every result is symbolic in them, and
    /// the model's own values may be extreme), with the oracle's momenta there;
    /// None where they are not finite.
    pub fn point(&self, rng: &mut crate::rng::Rng) -> Option<Point> {
        let n = self.names.len();
        let q = (0..n).map(|_| rng.range(-1.2, 1.2)).collect();
        let qd = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        self.complete(rng, q, qd)
    }

    /// A random point for deciding whether something vanishes identically: q in
    /// ±1.5 and velocities of magnitude 0.5 to 1.5, so that a high power of a
    /// velocity (q'^65) is not negligible at every point.
    pub fn probe_point(&self, rng: &mut crate::rng::Rng) -> Option<Point> {
        let n = self.names.len();
        let q = (0..n).map(|_| rng.range(-1.5, 1.5)).collect();
        let qd = (0..n).map(|_| rng.range(0.5, 1.5) * if rng.chance(0.5) { -1.0 } else { 1.0 }).collect();
        self.complete(rng, q, qd)
    }

    fn complete(&self, rng: &mut crate::rng::Rng, q: Vec<f64>, qd: Vec<f64>) -> Option<Point> {
        let n = self.names.len();
        let mut point = Point {
            q,
            qd,
            qdd: (0..n).map(|_| rng.range(-1.0, 1.0)).collect(),
            p: vec![0.0; n],
            t: rng.range(0.0, 1.5),
            params: self.parameters.iter().map(|_| rng.range(0.5, 2.0)).collect(),
        };
        for i in 0..n {
            point.p[i] = self.eval(&self.pool, self.momenta[i], &point).ok().filter(|v| v.is_finite())?;
        }
        Some(point)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pendulum_from_a_particle_has_the_textbook_residual() {
        let text = "coordinates = [\"th\"]\ngravity = \"g\"\n[parameters]\nm = 2.0\nl = 1.5\ng = 9.81\n\
                    [[particles]]\nmass = \"m\"\nposition = [\"l*sin(th)\", \"-l*cos(th)\"]\n";
        let model = Model::parse(text, &[]).expect("a valid model");
        let o = Oracle::new(&model).expect("no bodies");
        let point =
            Point { q: vec![0.3], qd: vec![0.7], qdd: vec![-0.2], p: vec![0.0], t: 0.0, params: vec![2.0, 1.5, 9.81] };
        let residual = o.eval(&o.pool, o.residual[0], &point).expect("every symbol has a value");
        // m l² θ'' + m g l sin θ.
        let want = 2.0 * 1.5f64.powi(2) * -0.2 + 2.0 * 9.81 * 1.5 * 0.3f64.sin();
        assert!((residual - want).abs() < 1e-12, "{residual} vs {want}");
        let h = o.eval(&o.pool, o.energy_function, &point).unwrap();
        let e = o.eval(&o.pool, o.energy.unwrap(), &point).unwrap();
        assert!((h - e).abs() < 1e-12);
    }
}
