//! What a run hands back: each output row ([`Row`]), the audit of its
//! invariants, its report ([`RunReport`]), and how it failed ([`RunError`],
//! [`RunFailure`]), keeping the report of what it did before.

use crate::error::ModelError;
use crate::model::ConstraintKind;
use num::Method;

use super::budget::StepBudget;
use super::dynamics::Form;

/// Something a run noticed that did not stop it. Data, not text: a front
/// end words it with its own names for the settings (`view::simulate::warning`).
#[derive(Debug, Clone, PartialEq)]
pub enum RunWarning {
    /// A conserved invariant drifted by more than the method's tolerance
    /// explains (`explained`, relative).
    Drift {
        /// The invariant's name.
        invariant: String,
        /// Its largest relative drift.
        drift: f64,
        /// The drift the tolerance accounts for.
        explained: f64,
    },
    /// H drifted past the bound the pilot runs chose the fixed step for
    /// (though within what the tolerance explains): the motion after the
    /// pilots needed a shorter step.
    PilotOutgrown {
        /// H's largest relative drift.
        drift: f64,
        /// The bound the step was chosen for.
        bound: f64,
    },
    /// A constraint violated beyond 1e-9 despite the projection.
    ConstraintViolated {
        /// The constraint's name.
        constraint: String,
        /// The largest residual, of position or velocity.
        residual: f64,
    },
    /// The Taylor method ran on equations with abs(), whose kink its series
    /// does not see.
    TaylorAcrossKink,
    /// A fixed step whose stage equations did not converge was taken as
    /// shorter sub-steps.
    Subdivided(num::Subdivisions),
}

/// One output row.
#[derive(Debug)]
pub struct Row<'a> {
    /// Time.
    pub t: f64,
    /// Coordinates.
    pub q: &'a [f64],
    /// Velocities.
    pub qd: &'a [f64],
    /// Invariants, in the order of [`RunReport::invariants`].
    pub invariants: &'a [f64],
    /// Whether this row is a stop event or a crossing.
    pub is_event: bool,
    /// The condition of a stop or crossing row, as the user wrote it.
    pub event: Option<&'a str>,
    /// With constraints: λ, |Aᵀλ| and the residuals, in the order of
    /// [`crate::constraint_columns`] (empty otherwise).
    pub constraints: &'a [f64],
    /// With impacts: the sum of each invariant's jumps at the impacts so far
    /// (in the order of `invariants`; empty without impacts).
    pub jumps: &'a [f64],
}

impl<'a> Row<'a> {
    /// The invariants less their jumps at impacts so far: what drifts only by
    /// the integrator's error, for plots of the drift (the rows and the CSV
    /// keep the invariants themselves).
    pub fn invariants_less_jumps(&self) -> std::borrow::Cow<'a, [f64]> {
        if self.jumps.is_empty() {
            return std::borrow::Cow::Borrowed(self.invariants);
        }
        std::borrow::Cow::Owned(self.invariants.iter().zip(self.jumps).map(|(i, j)| i - j).collect())
    }
}

/// The audit of one invariant.
#[derive(Debug, Clone)]
pub struct Audit {
    /// Its name (`H`, `E`, `p_th`).
    pub name: String,
    /// Whether the derivation says it is conserved.
    pub conserved: bool,
    /// Value at the start.
    pub initial: f64,
    /// Value at the last row.
    pub final_value: f64,
    /// Largest |I(t) − I(0)| over the rows (the jumps at impacts left out).
    pub max_abs_drift: f64,
    /// Largest |I(t) − I(0)| / |I(0)| (or the absolute drift where I(0) = 0),
    /// the jumps at impacts left out.
    pub max_rel_drift: f64,
    /// The sum of its jumps at impacts (0 without impacts): the drifts measure
    /// I(t) − I(0) less the jumps before t.
    pub impact_change: f64,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// The method used.
    pub method: Method,
    /// The state variables integrated.
    pub form: Form,
    /// How the accelerations were computed: `"articulated-body"` (the model's
    /// tree, O(n), [`dynamics`]) or `"mass-matrix"` (M and f, solved).
    pub right_hand_side: &'static str,
    /// The fixed step used, for fixed-step methods.
    pub dt: Option<f64>,
    /// Whether that step was given (`RunConfig::dt`) rather than chosen from the tolerance.
    pub step_given: bool,
    /// Tolerances.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Right-hand-side evaluations of the Taylor method's look-ahead.
    pub look_ahead_evaluations: usize,
    /// Time reached.
    pub t_final: f64,
    /// Coordinates at the end.
    pub final_q: Vec<f64>,
    /// Velocities at the end.
    pub final_qd: Vec<f64>,
    /// Invariant audits.
    pub invariants: Vec<Audit>,
    /// Why the run ended (`finished`, or the stop condition's text).
    pub stopped_by: Option<String>,
    /// What the run noticed that did not stop it (an invariant drifting
    /// beyond what the tolerance explains, …); a front end words them.
    pub warnings: Vec<RunWarning>,
    /// Why the run failed midway, if it did.
    pub failure: Option<String>,
    /// The same as data: what failed, when and where.
    pub failure_reason: Option<RunFailure>,
    /// Right-hand-side evaluations of the pilot runs that chose a fixed step.
    pub pilot_rhs_evaluations: usize,
    /// Wall-clock seconds of the integration (compilation included).
    pub wall_seconds: f64,
    /// With constraints: the audit of each constraint (empty otherwise).
    pub constraints: Vec<ConstraintAudit>,
    /// With `[[impacts]]`: what happened at each surface (empty otherwise).
    pub impacts: Vec<ImpactTally>,
}

/// What happened at one surface along a run.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactTally {
    /// The impact's name.
    pub name: String,
    /// How many impacts there were.
    pub count: usize,
    /// The kinetic energy they took, Σ ½(q'⁻ᵀMq'⁻ − q'⁺ᵀMq'⁺) (0 for e = 1).
    pub energy_lost: f64,
    /// The fastest normal speed |v_n| of an impact.
    pub fastest: f64,
}

/// Why a run failed midway, as data beside the message: what happened, at
/// which time, to which component (`x`, `x'` or `p_x`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum RunFailure {
    /// A rigid body reached the gimbal singularity of its Euler angles.
    Gimbal {
        /// The body.
        body: String,
        /// When.
        t: f64,
    },
    /// A component of the state grew without bound or stopped being finite.
    BlowUp {
        /// When.
        t: f64,
        /// Which component.
        component: String,
    },
    /// The equations gave a non-finite rate of change.
    NonFiniteRate {
        /// When.
        t: f64,
        /// Of which component.
        component: String,
    },
    /// The mass matrix (with constraints: the system with the multipliers)
    /// became singular: the accelerations are undetermined.
    Singular {
        /// When.
        t: f64,
    },
    /// The integrator could not take a step (too small, or implicit stages that
    /// do not converge) for no reason that could be told.
    Step {
        /// The last time reached.
        t: f64,
    },
    /// A row could not be evaluated (an invariant, a constraint column).
    Row {
        /// When.
        t: f64,
    },
    /// The run could not reach its end time within its step budget: it spent
    /// the budget, or its pace was foreseen far beyond it.
    StepBudget(StepBudget),
    /// Impacts accumulated (Zeno) or left the motion resting on a surface,
    /// a contact the run does not model; or a surface was found crossed.
    Zeno {
        /// When.
        t: f64,
        /// The impact's name.
        impact: String,
        /// Impacts so far, on every surface.
        impacts: usize,
    },
    /// A condition the run watches (a stop condition, a section, an impact's
    /// surface) has no value at the state reached (`sqrt(x) = 0.5` at x < 0).
    UndefinedCondition {
        /// When.
        t: f64,
        /// The condition as written, or the impact's name.
        condition: String,
    },
    /// A row was found past an impact surface that no event saw crossed.
    SurfaceCrossed {
        /// When.
        t: f64,
        /// The impact's name.
        impact: String,
    },
}

impl RunFailure {
    /// The failure's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            RunFailure::Gimbal { .. } => "gimbal",
            RunFailure::BlowUp { .. } => "blow_up",
            RunFailure::NonFiniteRate { .. } => "non_finite_rate",
            RunFailure::Singular { .. } => "singular",
            RunFailure::Step { .. } => "step",
            RunFailure::Row { .. } => "row",
            RunFailure::StepBudget(_) => "step_budget",
            RunFailure::Zeno { .. } => "zeno",
            RunFailure::UndefinedCondition { .. } => "undefined_condition",
            RunFailure::SurfaceCrossed { .. } => "surface_crossed",
        }
    }
}

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The end time is not a positive, finite number.
    #[error("the end time must be positive and finite, not {}", num::Shortest(*.until))]
    Until {
        /// The end time asked for.
        until: f64,
    },
    /// More output samples than [`MAX_SAMPLES`].
    #[error("{samples} samples are more than a run writes ({max} at most)")]
    TooManySamples {
        /// The samples asked for.
        samples: usize,
        /// [`MAX_SAMPLES`].
        max: usize,
    },
    /// A fixed step that would take more steps than a solver may to reach the end.
    #[error("the step {dt} would take {steps:.3e} steps; a run takes at most {max}")]
    TooManySteps {
        /// The step.
        dt: f64,
        /// The steps it would take.
        steps: f64,
        /// The solvers' budget.
        max: usize,
    },
    /// A fixed step longer than the spacing of the samples, which would be
    /// shortened to that spacing rather than taken as given.
    #[error("the step {dt} is longer than the spacing of the samples ({spacing})")]
    StepOverSamples {
        /// The step.
        dt: f64,
        /// The spacing of the samples.
        spacing: f64,
    },
    /// A fixed step, chosen from the tolerance, that would take more steps than
    /// the run's budget to reach the end time (refused before the run).
    #[error("{0}")]
    StepBudget(Box<StepBudget>),
    /// A fixed step given for an adaptive method, which chooses its own.
    #[error("a fixed step applies only to fixed-step methods, and {} chooses its own", .method.name())]
    StepNotApplicable {
        /// The method.
        method: Method,
    },
    /// Bad input: an impossible method, a missing initial value (exit 2).
    #[error("{0}")]
    Input(ModelError),
    /// The run failed midway (exit 1); the report covers what was done.
    #[error("{message}")]
    Failed {
        /// What happened, naming the time and the coordinate.
        message: String,
        /// The run up to the failure.
        report: Box<RunReport>,
    },
}

/// The audit of one constraint along a run.
#[derive(Debug, Clone)]
pub struct ConstraintAudit {
    /// Its name.
    pub name: String,
    /// Holonomic or velocity.
    pub kind: ConstraintKind,
    /// Largest |f(q, t)| (holonomic) or |A q' + a_t| (velocity) over the rows.
    pub max_abs_residual: f64,
    /// Largest |A q' + a_t| over the rows (for a holonomic constraint, df/dt).
    pub max_abs_velocity_residual: f64,
    /// The multiplier λ at the last row.
    pub final_lambda: f64,
    /// Largest |Aᵀλ| over the rows.
    pub max_force: f64,
}
