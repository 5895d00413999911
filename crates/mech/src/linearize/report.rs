//! A linearization as the JSON contract `lagrange.linearize/1`
//! ([`LinearizeReport`]): the operating point by name, A and B, the
//! eigenvalues with their decay rates and frequencies, and the equilibria met.

use super::{About, Linearization};
use crate::derive::Derivation;
use crate::equilibria::{EquilibriumReport, Stability};
use crate::report::Ordered;
use serde::Serialize;

/// One eigenvalue of A in the report.
#[derive(Debug, Clone, Serialize)]
pub struct Eigenvalue {
    /// Re s.
    pub re: f64,
    /// Im s.
    pub im: f64,
    /// −Re s: how fast the motion decays (negative: grows).
    pub decay_rate: f64,
    /// |Im s|: the damped angular frequency.
    pub frequency: f64,
}

/// The linearization as the JSON contract `lagrange.linearize/1`.
#[derive(Debug, Clone, Serialize)]
pub struct LinearizeReport {
    /// Always `lagrange.linearize/1`.
    pub format: &'static str,
    /// The model's name.
    pub name: String,
    /// equilibrium or steady.
    pub about: About,
    /// q at the operating point.
    pub q: Ordered<f64>,
    /// q' there.
    pub qd: Ordered<f64>,
    /// q'' there.
    pub qdd: Ordered<f64>,
    /// λ there, by constraint.
    pub multipliers: Ordered<f64>,
    /// Cyclic coordinates moving at constant rates, with the rates.
    pub moving: Ordered<f64>,
    /// Coordinates left out (no inertia).
    pub idle: Vec<String>,
    /// Coordinates eliminated by holonomic constraints.
    pub dependent_coordinates: Vec<String>,
    /// Speeds eliminated by the constraints.
    pub dependent_speeds: Vec<String>,
    /// The state x: independent coordinates, then independent speeds.
    pub state: Vec<String>,
    /// x' = A x + B u.
    #[serde(rename = "A")]
    pub a: Vec<Vec<f64>>,
    /// The inputs u, held at their values at t = 0.
    pub inputs: Vec<String>,
    /// B, one column per input (null without inputs).
    #[serde(rename = "B")]
    pub b: Option<Vec<Vec<f64>>>,
    /// The eigenvalues of A.
    pub eigenvalues: Vec<Eigenvalue>,
    /// stable (every Re < 0), marginal (none > 0, some = 0) or unstable.
    pub stability: Stability,
    /// The operating points met near the start.
    pub equilibria: Vec<EquilibriumReport>,
    /// Remarks.
    pub notes: Vec<String>,
}

impl LinearizeReport {
    /// The report of a linearization.
    pub fn new(d: &Derivation, l: &Linearization) -> LinearizeReport {
        let named = |v: &[f64]| Ordered(l.coordinates.iter().cloned().zip(v.iter().copied()).collect());
        LinearizeReport {
            format: "lagrange.linearize/1",
            name: d.model.name.clone(),
            about: l.about,
            q: named(&l.q),
            qd: named(&l.qd),
            qdd: named(&l.qdd),
            multipliers: Ordered(l.multipliers.clone()),
            moving: Ordered(l.moving.clone()),
            idle: l.idle.clone(),
            dependent_coordinates: l.dependent_coordinates.clone(),
            dependent_speeds: l.dependent_speeds.clone(),
            state: l.state.clone(),
            a: l.a.clone(),
            inputs: l.inputs.clone(),
            b: l.b.clone(),
            eigenvalues: l
                .eigenvalues
                .iter()
                .map(|&(re, im)| Eigenvalue { re, im, decay_rate: -re, frequency: im.abs() })
                .collect(),
            stability: l.stability,
            equilibria: EquilibriumReport::list(&l.unknowns, &l.equilibria, l.chosen, l.landing),
            notes: l.notes.clone(),
        }
    }
}
