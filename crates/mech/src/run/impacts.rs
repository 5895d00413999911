//! Impacts in a run: each `[[impacts]]` surface φ(q, t) ≥ 0 is a terminal
//! event where φ falls through 0, located on the method's own states like a
//! stop condition; there the velocities jump by Newton's law
//! ([`crate::ImpactLaw`]), solved with M's numbers at the impact, and the run
//! goes on from a solver started afresh at the state after it.
//!
//! A jump can bring the motion onto another surface it is moving into (the
//! balls of Newton's cradle touch): the impacts at one instant are taken one
//! after another until no surface in contact is approached. Bounces that die
//! out (a ball coming to rest, Zeno's accumulation of impacts before a finite
//! time) end the run as a failure that says so, since the resting contact that
//! follows is not modelled; so does a surface found crossed between events.

use super::dynamics::{Dynamics, Form, System};
use super::report::{ImpactTally, RunFailure};
use crate::derive::{Derivation, Layout};
use crate::error::ModelError;
use num::{Direction, Event};
use sym::Tape;

/// A surface is in contact where |φ| is at most this (in φ's units): the
/// event's root is located to round-off in t, so φ there is round-off too, and
/// the surfaces of bodies placed touching are 0 to round-off.
const CONTACT_GAP: f64 = 1e-9;

/// After the impacts of an instant every surface in contact is lifted to
/// φ = LIFT (in φ's units), q moved along M⁻¹∇φ: at the event φ is 0 to
/// round-off and may be −1e-16, and a fall through 0 counts only from φ > 0,
/// so the next impact is found however short the bounce. The motion is moved
/// by 1e-12, far below any tolerance a run is given.
const LIFT: f64 = 1e-12;

/// Bounces end as Zeno's (or as a body come to rest) when the normal speed
/// after an impact is below this fraction of the fastest impact on that
/// surface: a bounce's height goes as its speed squared, so at 1e-4 it is
/// 1e-8 of the first, the order of the integrator's tolerance, below which
/// the bounces cannot be told apart from a body resting on the surface.
const ZENO_SPEED_RATIO: f64 = 1e-4;

/// Most impacts taken at one instant (a chain of touching bodies, each
/// passing its momentum on): more is taken for an accumulation.
const MAX_IMPACTS_AT_ONCE: usize = 1000;

/// A surface crossed by more than this between events (an impact the events
/// missed: two crossings within one probe interval) fails the run.
const CROSSED_BY: f64 = 1e-6;

/// The impacts of a run: their surfaces and laws compiled, and what they did.
pub(crate) struct Impacts {
    n: usize,
    /// Per impact: φ, v_n, ∇φ (n entries), ∂φ/∂t, e.
    tape: Tape,
    /// φ alone, per impact, for the events.
    surfaces: Vec<Tape>,
    values: Vec<f64>,
    out: Vec<f64>,
    /// M at the impacts (the Lagrange form of the run's dynamics).
    system: System,
    /// "impact NAME before" and "impact NAME after", the rows' event labels.
    pub(crate) labels: Vec<[String; 2]>,
    /// The impacts' names, in the order of their events.
    pub(crate) names: Vec<String>,
    pub(crate) tallies: Vec<ImpactTally>,
}

/// The state of a run at an impact, before the jump.
#[derive(Debug, Clone)]
pub(crate) struct StateAt {
    pub(crate) t: f64,
    pub(crate) q: Vec<f64>,
    pub(crate) qd: Vec<f64>,
    /// The invariants there, from which the audit measures the jump.
    pub(crate) invariants: Vec<f64>,
}

/// The impacts of one instant: the surfaces struck, in order, and why the run
/// ends after them, if it does (the bounces have died out).
pub(crate) struct Struck {
    pub(crate) surfaces: Vec<usize>,
    pub(crate) ends: Option<(RunFailure, String)>,
}

impl Impacts {
    /// The impacts of `d`, compiled; None when the model has none.
    pub(crate) fn new(d: &Derivation, dynamics: &Dynamics) -> Result<Option<Impacts>, ModelError> {
        let laws = d.impacts();
        if laws.is_empty() {
            return Ok(None);
        }
        let mut outputs = Vec::new();
        for law in laws {
            outputs.push(law.surface);
            outputs.push(law.normal_velocity);
            outputs.extend(&law.gradient);
            outputs.push(law.rate);
            outputs.push(law.restitution);
        }
        let compile = |outputs: &[sym::ExprId]| {
            Tape::compile(&d.model.pool, outputs, d.layout.symbols())
                .map_err(|e| ModelError::whole(format!("the impact laws cannot be evaluated: {e}")))
        };
        let tape = compile(&outputs)?;
        let surfaces = laws.iter().map(|l| compile(&[l.surface])).collect::<Result<Vec<_>, _>>()?;
        let n = d.q.len();
        let mut values = d.layout.values();
        let parameters = d.layout.parameters();
        for (slot, p) in values[parameters].iter_mut().zip(&d.model.parameters) {
            *slot = p.value;
        }
        Ok(Some(Impacts {
            n,
            out: vec![0.0; outputs.len()],
            tape,
            surfaces,
            values,
            system: dynamics.system(Form::Lagrange),
            labels: laws
                .iter()
                .map(|l| [format!("impact {} before", l.name), format!("impact {} after", l.name)])
                .collect(),
            names: laws.iter().map(|l| l.name.clone()).collect(),
            tallies: laws
                .iter()
                .map(|l| ImpactTally { name: l.name.clone(), count: 0, energy_lost: 0.0, fastest: 0.0 })
                .collect(),
        }))
    }

    /// How many surfaces there are.
    pub(crate) fn len(&self) -> usize {
        self.labels.len()
    }

    /// One terminal event per surface, φ falling through 0, on solver states
    /// (whose first n entries are q in every form).
    pub(crate) fn events<'a>(&self, d: &'a Derivation) -> Vec<Event<'a>> {
        let layout: &'a Layout = &d.layout;
        (0..self.len())
            .map(|k| {
                let mut tape = self.surfaces[k].clone();
                let mut values = self.values.clone();
                let zero = vec![0.0; self.n];
                let n = self.n;
                Event::new(move |t, y| {
                    layout.set_state(&mut values, t, &y[..n], &zero);
                    let mut out = [0.0];
                    tape.eval(&values, &mut out);
                    out[0]
                })
                .with_direction(Direction::Falling)
                .with_terminal(true)
            })
            .collect()
    }

    /// Evaluates every law at (t, q, q').
    fn eval(&mut self, t: f64, q: &[f64], qd: &[f64], layout: &Layout) {
        layout.set_state(&mut self.values, t, q, qd);
        self.tape.eval(&self.values, &mut self.out);
    }

    /// The outputs of impact `k`: φ, v_n, ∇φ, ∂φ/∂t, e.
    fn of(&self, k: usize) -> (f64, f64, &[f64], f64) {
        let w = self.n + 4;
        let o = &self.out[k * w..(k + 1) * w];
        (o[0], o[1], &o[2..2 + self.n], o[w - 1])
    }

    /// Which surfaces the state (t, q, q') rests on: in contact (|φ| within
    /// [`CONTACT_GAP`]) and not moving off (v_n ≤ 0). A surface crossed later
    /// without an impact was then a resting contact, which runs do not model,
    /// not a bounce the events missed.
    pub(crate) fn resting(&mut self, t: f64, q: &[f64], qd: &[f64], layout: &Layout) -> Vec<bool> {
        self.eval(t, q, qd, layout);
        (0..self.len())
            .map(|k| {
                let (phi, v_n, _, _) = self.of(k);
                phi.abs() <= CONTACT_GAP && v_n <= 0.0
            })
            .collect()
    }

    /// The surface a row has crossed by more than [`CROSSED_BY`] (an impact
    /// the events did not see), with φ there.
    pub(crate) fn crossed(&mut self, t: f64, q: &[f64], qd: &[f64], layout: &Layout) -> Option<(usize, f64)> {
        self.eval(t, q, qd, layout);
        (0..self.len()).map(|k| (k, self.of(k).0)).find(|&(_, phi)| phi < -CROSSED_BY)
    }

    /// The jumps at time t, starting with surface `first` (the event's): q'
    /// is replaced by the velocities after every impact the instant holds,
    /// and q lifted off the surfaces in contact ([`LIFT`]). Returns the
    /// surfaces struck, in order, or why the run cannot go on.
    pub(crate) fn strike(
        &mut self,
        first: usize,
        t: f64,
        q: &mut [f64],
        qd: &mut [f64],
        layout: &Layout,
    ) -> Result<Struck, (RunFailure, String)> {
        let n = self.n;
        let mut y = vec![0.0; 2 * n];
        y[..n].copy_from_slice(q);
        let m = self.system.mass_matrix_at(t, &y);
        let mass = nalgebra::DMatrix::from_row_slice(n, n, &m);
        let singular = || {
            (
                RunFailure::Singular { t },
                format!(
                    "the mass matrix is singular at the impact at t = {}: the jump is undetermined",
                    num::Shortest(t)
                ),
            )
        };
        let lu = mass.clone().lu();
        let kinetic = |v: &[f64]| {
            let v = nalgebra::DVector::from_column_slice(v);
            0.5 * v.dot(&(&mass * &v))
        };
        let mut struck = Vec::new();
        let mut ends = None;
        let mut next = Some(first);
        while let Some(k) = next {
            if struck.len() == MAX_IMPACTS_AT_ONCE {
                let name = &self.tallies[k].name;
                return Err((
                    RunFailure::Zeno { t, impact: name.clone(), impacts: self.total() },
                    format!(
                        "{MAX_IMPACTS_AT_ONCE} impacts at one instant, t = {}, without the motion leaving the surfaces (last '{name}'): the contacts do not resolve",
                        num::Shortest(t)
                    ),
                ));
            }
            self.eval(t, q, qd, layout);
            let (_, v_before, gradient, e) = self.of(k);
            let gradient = nalgebra::DVector::from_column_slice(gradient);
            let x = lu.solve(&gradient).ok_or_else(singular)?;
            let reach = gradient.dot(&x);
            if !(reach > 0.0 && reach.is_finite()) {
                return Err((
                    RunFailure::Singular { t },
                    format!(
                        "the surface of impact '{}' has no normal at t = {} (∇φ = 0 there): the jump is undetermined",
                        self.tallies[k].name,
                        num::Shortest(t)
                    ),
                ));
            }
            let before = kinetic(qd);
            let scale = (1.0 + e) * v_before / reach;
            for (v, dx) in qd.iter_mut().zip(x.iter()) {
                *v -= scale * dx;
            }
            let after = kinetic(qd);
            let tally = &mut self.tallies[k];
            tally.count += 1;
            tally.energy_lost += before - after;
            tally.fastest = tally.fastest.max(v_before.abs());
            let v_after = -e * v_before;
            struck.push(k);
            if v_after.abs() < ZENO_SPEED_RATIO * tally.fastest && ends.is_none() {
                let name = tally.name.clone();
                let why = if e == 0.0 {
                    format!("the impact on '{name}' is plastic (e = 0): the motion stays on the surface")
                } else {
                    format!(
                        "the impacts on '{name}' accumulate (Zeno): after {} of them the normal speed has fallen to {:.3e}, below {ZENO_SPEED_RATIO:e} of the fastest ({:.3e})",
                        tally.count,
                        v_after.abs(),
                        tally.fastest
                    )
                };
                ends = Some((
                    RunFailure::Zeno { t, impact: name, impacts: self.total() },
                    format!(
                        "{why}, at t = {}; a resting contact is not modelled, so the run ends here",
                        num::Shortest(t)
                    ),
                ));
            }
            // The next surface in contact that the new velocities move into.
            // (A speed within round-off of the fastest impact's is no approach.)
            self.eval(t, q, qd, layout);
            let round_off = 1e-12 * self.tallies.iter().fold(0.0f64, |a, t| a.max(t.fastest));
            next = (0..self.len()).find(|&j| {
                let (phi, v, _, _) = self.of(j);
                phi.abs() <= CONTACT_GAP && v < -round_off
            });
        }
        // Off the surfaces in contact, a Newton step each along M⁻¹∇φ (φ is
        // linear at this scale), twice over for surfaces that share coordinates.
        for _ in 0..2 {
            for j in 0..self.len() {
                self.eval(t, q, qd, layout);
                let (phi, _, gradient, _) = self.of(j);
                if !(phi.abs() <= CONTACT_GAP && phi < LIFT) {
                    continue;
                }
                let gradient = nalgebra::DVector::from_column_slice(gradient);
                let Some(x) = lu.solve(&gradient) else { continue };
                let reach = gradient.dot(&x);
                if reach > 0.0 && reach.is_finite() {
                    for (qi, dx) in q.iter_mut().zip(x.iter()) {
                        *qi += (LIFT - phi) / reach * dx;
                    }
                }
            }
        }
        Ok(Struck { surfaces: struck, ends })
    }

    /// Impacts so far, on every surface.
    pub(crate) fn total(&self) -> usize {
        self.tallies.iter().map(|t| t.count).sum()
    }
}
