//! Rigid bodies along a run: the columns of their ω and L, the recorder that
//! evaluates them row by row, and the guards that stop a run before a body's
//! Euler angles reach their gimbal singularity.

use crate::derive::BodyMotion;
use num::{Direction, Event};
use sym::ExprId;

/// The CSV column names of the bodies' ω and L: `omega1..3`, `L1..3`, prefixed
/// with `NAME_` when the model has more than one body
/// ([`crate::model::columns::body_columns`]).
pub fn column_names(bodies: &[BodyMotion]) -> Vec<String> {
    let names: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
    crate::model::columns::body_columns(&names)
}

/// The smallest |sin β| a run accepts for an Euler-angle body at relative
/// tolerance `rtol`. Solving for the accelerations divides by the angles' mass
/// matrix, whose determinant is ∝ sin²β; round-off in the accelerations grows
/// like ε/sin²β (ε the machine epsilon), so below sqrt(ε/rtol) it exceeds the
/// tolerance asked for. Clamped to [1e-6, 1e-3].
pub fn gimbal_threshold(rtol: f64) -> f64 {
    (f64::EPSILON / rtol.max(1e-300)).sqrt().clamp(1e-6, 1e-3)
}

/// A condition a run stops on, as a failure, before a body's Euler angles
/// reach their gimbal singularity.
#[derive(Debug, Clone)]
pub struct GimbalGuard {
    /// The index of β among the coordinates.
    pub beta: usize,
    /// s, from [`gimbal_threshold`].
    pub threshold: f64,
    /// The body's name.
    pub body: String,
    /// β's name.
    pub beta_name: String,
    /// The body's sequence of turns: proper Euler angles are singular at
    /// sin β = 0, Tait–Bryan angles at cos β = 0.
    pub sequence: crate::euler::Sequence,
}

impl GimbalGuard {
    /// Whether the state is past the guard.
    pub fn violated(&self, q: &[f64]) -> bool {
        let s = self.gauge(q[self.beta]).abs();
        s.is_nan() || s < self.threshold
    }

    /// sin β for proper Euler angles, cos β for Tait–Bryan ones: zero at the
    /// singularity.
    fn gauge(&self, beta: f64) -> f64 {
        gauge(self.sequence.proper(), beta)
    }

    /// What happened at time t, in the user's terms.
    pub fn message(&self, t: f64) -> String {
        let t = num::Shortest(t);
        if !self.sequence.proper() {
            return format!(
                "body '{}' reached the gimbal singularity of its {} angles at t = {t}: |cos {b}| fell below {:.1e} ({b} near ±π/2), where the first and last turns are about the same axis and the angles' mass matrix (determinant ∝ cos²{b}) is singular, so the accelerations cannot be trusted. {}",
                self.body,
                self.sequence.name(),
                self.threshold,
                self.advice(),
                b = self.beta_name
            );
        }
        format!(
            "body '{}' reached the gimbal singularity of its Euler angles at t = {t}: |sin {b}| fell below {:.1e} ({b} near 0 or π), where α and γ turn about the same axis and the angles' mass matrix (determinant ∝ sin²{b}) is singular, so the accelerations cannot be trusted. {}",
            self.body,
            self.threshold,
            self.advice(),
            b = self.beta_name
        )
    }

    /// What happened at time t, as data.
    pub fn failure(&self, t: f64) -> crate::run::RunFailure {
        crate::run::RunFailure::Gimbal { body: self.body.clone(), t }
    }

    /// What to do about it.
    pub fn advice(&self) -> String {
        if self.sequence != crate::euler::Sequence::NOTES {
            let at = if self.sequence.proper() { "0 or π" } else { "±π/2" };
            return format!(
                "{} angles cannot follow a motion through {b} = {at}: choose another sequence (`sequence` of the body) or tilt the fixed frame for this motion, or end the run earlier (a shorter end time, or a stop condition)",
                self.sequence.name(),
                b = self.beta_name
            );
        }
        format!(
            "Euler angles cannot follow a motion through {b} = 0 or π: tilt the fixed frame so that the body's 3-axis stays away from the fixed z axis, or end the run earlier (a shorter end time, or a stop condition)",
            b = self.beta_name
        )
    }
}

/// The terminal events of the guards, two per body in the guards' order: |sin β|
/// falling to the threshold, and sin β changing sign (β passing 0 or π within
/// one step, between two step ends that are both clear of the threshold). The
/// guard of event `k` is `guards[k / 2]`.
pub(crate) fn guard_events(guards: &[GimbalGuard]) -> Vec<Event<'static>> {
    let mut events = Vec::with_capacity(2 * guards.len());
    for g in guards {
        let (beta, s2, proper) = (g.beta, g.threshold * g.threshold, g.sequence.proper());
        events.push(
            Event::new(move |_t, y| gauge(proper, y[beta]).powi(2) - s2)
                .with_direction(Direction::Falling)
                .with_terminal(true),
        );
        events.push(Event::new(move |_t, y| gauge(proper, y[beta])).with_terminal(true));
    }
    events
}

/// sin β (proper Euler angles) or cos β (Tait–Bryan): zero at the singularity.
fn gauge(proper: bool, beta: f64) -> f64 {
    if proper {
        beta.sin()
    } else {
        beta.cos()
    }
}

/// One [`GimbalGuard`] per body that turns in Euler angles, for a run at relative tolerance `rtol`.
pub fn gimbal_guards(d: &crate::Derivation, rtol: f64) -> Vec<GimbalGuard> {
    let s = gimbal_threshold(rtol);
    d.model
        .bodies
        .iter()
        .filter_map(|b| {
            let (angles, sequence) = b.orientation.euler()?;
            let beta = angles[1];
            Some(GimbalGuard {
                beta,
                threshold: s,
                body: b.name.clone(),
                beta_name: d.model.coordinates[beta].name.clone(),
                sequence,
            })
        })
        .collect()
}

/// Evaluates the bodies' ω and L along a run: one tape over `[q, q', t, parameters]`.
#[derive(Debug, Clone)]
pub struct BodyRecorder {
    tape: sym::Tape,
    inputs: Vec<f64>,
    layout: crate::derive::Layout,
    columns: Vec<String>,
}

impl BodyRecorder {
    /// None when the derivation has no bodies.
    pub fn new(d: &crate::Derivation) -> Option<BodyRecorder> {
        if d.bodies.is_empty() {
            return None;
        }
        let exprs: Vec<ExprId> =
            d.bodies.iter().flat_map(|b| b.omega.iter().chain(&b.angular_momentum).copied()).collect();
        let tape = sym::Tape::compile(d.pool(), &exprs, d.layout.symbols()).ok()?;
        Some(BodyRecorder {
            tape,
            inputs: d.layout.values(),
            layout: d.layout.clone(),
            columns: column_names(&d.bodies),
        })
    }

    /// The column names, six per body.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// ω and L of every body at (t, q, q'), into `out` (length `columns().len()`).
    pub fn eval(&mut self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) {
        self.layout.set_state(&mut self.inputs, t, q, qd);
        self.tape.eval(&self.inputs, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Derivation, Model};

    #[test]
    fn several_bodies_get_prefixed_columns_and_their_own_angles() {
        let body = |name: &str, a: &str| {
            format!("[[bodies]]\nname = \"{name}\"\nmass = 1\ninertia = [1, 2, 3]\nangles = [\"{a}1\", \"{a}2\", \"{a}3\"]\n")
        };
        let text = format!(
            "coordinates = [\"a1\", \"a2\", \"a3\", \"b1\", \"b2\", \"b3\"]\n{}{}",
            body("left", "a"),
            body("right", "b")
        );
        let d = Derivation::new(Model::parse(&text, &[]).unwrap()).unwrap();
        let cols = column_names(&d.bodies);
        assert_eq!(cols[0], "left_omega1");
        assert_eq!(cols[11], "right_L3");
        let shared = text.replace("[\"b1\", \"b2\", \"b3\"]", "[\"b1\", \"a2\", \"b3\"]");
        let e = Model::parse(&shared, &[]).unwrap_err();
        assert!(e.message.contains("already an angle of body 'left'"), "{}", e.message);
        let single = column_names(&d.bodies[..1]);
        assert_eq!(single, ["omega1", "omega2", "omega3", "L1", "L2", "L3"]);
    }

    #[test]
    fn gimbal_threshold_follows_the_tolerance() {
        assert!((gimbal_threshold(1e-9) - (f64::EPSILON / 1e-9).sqrt()).abs() < 1e-15);
        assert_eq!(gimbal_threshold(1e-3), 1e-6);
        assert_eq!(gimbal_threshold(1e-16), 1e-3);
    }
}
