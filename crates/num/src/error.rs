//! Error types of the crate: what a right-hand side may report ([`RhsError`]), what
//! a solver run may fail with ([`SolveError`]), what a linear solve may fail with
//! ([`LinalgError`]), and the errors of quadrature ([`QuadratureError`]) and of
//! Newton's method ([`NewtonError`]).

/// An error a problem's right-hand side (or Jacobian) reports to the integrator.
///
/// Callers fill it in; the integrator wraps it in [`SolveError::Rhs`] with the time of
/// the failing evaluation.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RhsError {
    /// A component of the computed derivative is NaN or infinite.
    #[error("component {index} of the derivative is not finite")]
    NonFinite {
        /// Index of the first offending component.
        index: usize,
    },
    /// A matrix the right-hand side needs to solve with (e.g. a mass matrix) is singular.
    #[error("singular system: {detail}")]
    Singular {
        /// What was singular, in words.
        detail: String,
    },
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

impl From<LinalgError> for RhsError {
    fn from(err: LinalgError) -> Self {
        RhsError::Singular { detail: err.to_string() }
    }
}

/// An error of a linear solve ([`crate::LinearSolver`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LinalgError {
    /// A slice had the wrong length.
    #[error("expected a slice of length {expected}, found {found}")]
    DimensionMismatch {
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// The matrix contains NaN or an infinity at `(row, col)`.
    #[error("matrix entry ({row}, {col}) is not finite")]
    NonFinite {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// An exactly zero pivot was met in column `col`.
    #[error("matrix is singular (zero pivot in column {col})")]
    Singular {
        /// Column of the zero pivot.
        col: usize,
    },
    /// The pivots span more than the solver trusts: the smallest over the largest
    /// pivot magnitude is below the threshold, so a solution would be mostly round-off.
    #[error("matrix is ill-conditioned (pivot ratio {pivot_ratio:e} below {threshold:e})")]
    IllConditioned {
        /// min |pivot| / max |pivot|.
        pivot_ratio: f64,
        /// The threshold that was not met.
        threshold: f64,
    },
    /// `solve` was called before a successful `factor`.
    #[error("no factorization available")]
    NotFactored,
}

/// An error of a solver: invalid configuration, a failing right-hand side, or a run
/// that cannot continue.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// A configuration value is out of range (NaN, negative, zero where positive is needed).
    #[error("invalid {name} = {value}: {reason}")]
    InvalidConfig {
        /// Name of the option (`"rtol"`, `"dt"`, ...).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What was expected.
        reason: &'static str,
    },
    /// The system has zero dimension.
    #[error("the system has no state components")]
    EmptySystem,
    /// A slice had the wrong length.
    #[error("expected a state of length {expected}, found {found}")]
    DimensionMismatch {
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// The initial state or time is not finite.
    #[error("initial value component {index} is not finite")]
    NonFiniteInitial {
        /// Index of the offending component (`usize::MAX` for the time).
        index: usize,
    },
    /// The end time lies before the current time (integration runs forward only).
    #[error("end time {t_end} lies before the current time {t}")]
    EndBeforeStart {
        /// The current time.
        t: f64,
        /// The requested end time.
        t_end: f64,
    },
    /// The right-hand side reported an error.
    #[error("right-hand side failed at t = {t}: {source}")]
    Rhs {
        /// Time of the failing evaluation.
        t: f64,
        /// What the right-hand side reported.
        source: RhsError,
    },
    /// The state (or its derivative) became NaN or infinite.
    #[error("state component {index} became non-finite at t = {t}")]
    NonFiniteState {
        /// Time at which the non-finite value appeared.
        t: f64,
        /// Index of the first offending component.
        index: usize,
    },
    /// The adaptive step size fell below what the time resolution allows.
    #[error("step size {h:e} too small at t = {t}")]
    StepSizeTooSmall {
        /// Current time.
        t: f64,
        /// The step size.
        h: f64,
    },
    /// The maximal number of steps was taken.
    #[error("maximal number of steps ({max_steps}) reached at t = {t}")]
    MaxStepsExceeded {
        /// Current time.
        t: f64,
        /// The limit.
        max_steps: usize,
    },
    /// The run cannot reach its end time within the maximal number of steps, as
    /// foreseen before it took them: a fixed step that needs more, or the pace of
    /// an adaptive method (steps per unit time over its recent steps) that would
    /// need more than [`crate::FORESIGHT_MARGIN`] times as many (see [`crate::integrate`]).
    #[error("reaching t = {t_end} would take about {projected:.3e} steps, more than the maximal number ({max_steps}); stopped at t = {t} after {steps}")]
    MaxStepsForeseen {
        /// The time reached.
        t: f64,
        /// The steps taken.
        steps: usize,
        /// The end time.
        t_end: f64,
        /// The steps the whole run would take, estimated.
        projected: f64,
        /// The limit.
        max_steps: usize,
    },
    /// The stage equations of an implicit method did not converge with the fixed step.
    #[error("stage equations did not converge at t = {t} with step {h:e}; use a smaller step")]
    NoConvergence {
        /// Start of the failing step.
        t: f64,
        /// The step size.
        h: f64,
    },
    /// A step of a fixed-step implicit method whose stages did not converge even as
    /// many short sub-steps: the motion there is too fast for a fixed step.
    #[error("stage equations did not converge at t = {t}, not even with the step {h:e} cut into {sub_steps} sub-steps; the motion is too fast here for a fixed step: use an adaptive method")]
    SubStepsFailed {
        /// Start of the failing sub-step.
        t: f64,
        /// The fixed step.
        h: f64,
        /// How many sub-steps it was cut into.
        sub_steps: usize,
    },
    /// A linear solve inside the solver failed.
    #[error("linear algebra failed at t = {t}: {source}")]
    Linalg {
        /// Time of the failure.
        t: f64,
        /// The linear algebra error.
        source: LinalgError,
    },
    /// Interpolation was asked for a time outside the last step.
    #[error("cannot interpolate at t = {t}: dense output covers [{start}, {end}]")]
    InterpolationOutOfRange {
        /// Requested time.
        t: f64,
        /// Start of the last step.
        start: f64,
        /// End of the last step.
        end: f64,
    },
    /// An event function returned NaN or an infinity.
    #[error("event function {event} is not finite at t = {t}")]
    EventNonFinite {
        /// Index of the event function.
        event: usize,
        /// Time of the evaluation.
        t: f64,
    },
    /// An explicit symplectic method was requested for a system that is not separable.
    #[error("method {method} needs a separable Hamiltonian system (H = T(p) + V(q, t))")]
    RequiresSeparable {
        /// The method name.
        method: &'static str,
    },
    /// [`crate::Solver::set_state`] was called on a method that cannot restart from a
    /// replaced state (its steps carry more than the state from one to the next).
    #[error("method {method} cannot continue from a projected state; use dop853 or dopri5")]
    RestartUnsupported {
        /// The method name.
        method: &'static str,
    },
    /// [`crate::Solver::interpolate`] was called on a step whose dense output is
    /// pending ([`crate::Solver::set_lazy_dense`]) before
    /// [`crate::Solver::prepare_dense`].
    #[error("method {method}: the dense output of the last step was not prepared (call prepare_dense first)")]
    DenseOutputNotPrepared {
        /// The method name.
        method: &'static str,
    },
    /// The Taylor method was requested for a system that cannot give Taylor
    /// coefficients ([`crate::OdeSystem::taylor_series`]).
    #[error("method {method} needs the Taylor coefficients of the right-hand side, which this system cannot give")]
    RequiresTaylorSeries {
        /// The method name.
        method: &'static str,
    },
    /// The method name is unknown.
    #[error("unknown method {name:?}; known methods: {known}")]
    UnknownMethod {
        /// The name given.
        name: String,
        /// The known names, comma separated.
        known: String,
    },
}

/// An error of a quadrature ([`crate::tanh_sinh`], [`crate::gauss_legendre_rule`],
/// [`crate::gauss_kronrod`], …).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum QuadratureError {
    /// An end of the interval is not finite.
    #[error("the interval [{a}, {b}] is not finite")]
    InvalidInterval {
        /// The lower end.
        a: f64,
        /// The upper end.
        b: f64,
    },
    /// A tolerance is negative or NaN.
    #[error("the tolerance {value} must be non-negative")]
    InvalidTolerance {
        /// The tolerance given.
        value: f64,
    },
    /// No rule of this order is built.
    #[error("no Gauss–Legendre rule of order {order} (orders 1 to {max})")]
    InvalidOrder {
        /// The order asked for.
        order: usize,
        /// The largest order built.
        max: usize,
    },
    /// The integrand is NaN or infinite at a node.
    #[error("the integrand is {value} at x = {x}")]
    NotFinite {
        /// The node.
        x: f64,
        /// The integrand's value there.
        value: f64,
    },
    /// The sum of finite terms overflowed.
    #[error("the integral overflows")]
    Overflow,
}

/// Why [`crate::newton`] found no root. Each variant carries the point where it
/// stopped.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NewtonError {
    /// The residual or its Jacobian is NaN or infinite at `x`.
    #[error("the residual or its Jacobian is not finite at {x:?} (iteration {iterations})")]
    NotFinite {
        /// Where.
        x: Vec<f64>,
        /// Iterations taken before.
        iterations: usize,
    },
    /// The steps shrank to nothing while the residual stayed above its tolerance.
    #[error("Newton's method stalls at {x:?} with residual {residual}")]
    Stalled {
        /// Where.
        x: Vec<f64>,
        /// `|F(x)|` there.
        residual: f64,
    },
    /// The iterate left the region `|x − x₀| ≤ max_excursion·(1 + |x₀|)`.
    #[error("Newton's method runs away (to {x:?})")]
    RunAway {
        /// Where it went.
        x: Vec<f64>,
    },
    /// `max_iterations` iterations did not converge.
    #[error("Newton's method did not converge in {iterations} iterations (residual {residual})")]
    NoConvergence {
        /// The last iterate.
        x: Vec<f64>,
        /// The iterations taken.
        iterations: usize,
        /// `|F(x)|` there.
        residual: f64,
    },
}
