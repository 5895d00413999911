//! Dormand–Prince 5(4), the adaptive explicit Runge–Kutta method of Hairer's `DOPRI5`:
//! seven stages with the last reused as the first of the next step (FSAL), a 4th-order
//! embedded error estimate, a 4th-order continuous extension for dense output, and
//! Hairer's PI step-size control. Enter with [`Dopri5::new`].

use crate::adaptive::{self, first_step, step_failure, EmbeddedPair, StepControl};
use crate::error::SolveError;
use crate::method::Method;
use crate::solver::{
    check_initial, check_interpolation, check_len, Config, Solver, SolverState, Statistics, StepOutcome,
};
use crate::system::{first_non_finite, OdeSystem};

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output (Hairer's d1..d7 of the continuous extension).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// The Dormand–Prince 5(4) solver; see the module documentation.
#[derive(Clone, Debug)]
pub struct Dopri5<S> {
    system: S,
    control: StepControl,
    /// Time, state, step, stop time and counters (what the accessors read).
    state: SolverState,
    k: [Vec<f64>; 7],
    y1: Vec<f64>,
    y_stage: Vec<f64>,
    /// Dense output coefficients of the last step (Hairer's `rcont1..5`).
    cont: [Vec<f64>; 5],
}

impl<S: OdeSystem> Dopri5<S> {
    /// A solver for `y' = F(t, y)` from `(t0, y0)`. Uses `rtol`, `atol`, `h_init`,
    /// `h_max`, `max_steps` and `controller` of `config`.
    pub fn new(mut system: S, t0: f64, y0: &[f64], config: &Config) -> Result<Self, SolveError> {
        config.validate()?;
        let n = system.dim();
        check_initial(n, t0, y0)?;
        let control = StepControl::new(config, 5, 0.2, 10.0);
        let mut k: [Vec<f64>; 7] = std::array::from_fn(|_| vec![0.0; n]);
        let mut stats = Statistics::default();
        let mut y1 = vec![0.0; n];
        let mut y_stage = vec![0.0; n];
        let h =
            first_step(&mut system, &control, 5, config.h_init, t0, y0, &mut k[0], &mut y1, &mut y_stage, &mut stats)?;
        let cont = std::array::from_fn(|i| if i == 0 { y0.to_vec() } else { vec![0.0; n] });
        let state = SolverState::new(t0, y0, h, stats, config);
        Ok(Dopri5 { system, control, state, k, y1, y_stage, cont })
    }

    /// The system, e.g. to read parameters or counters it keeps.
    pub fn system(&self) -> &S {
        &self.system
    }

    fn eval(&mut self, stage: usize, t: f64) -> Result<(), SolveError> {
        self.state.stats.rhs_evaluations += 1;
        let (y_stage, k) = if stage == 6 { (&self.y1, &mut self.k[6]) } else { (&self.y_stage, &mut self.k[stage]) };
        self.system.rhs(t, y_stage, k).map_err(|source| SolveError::Rhs { t, source })
    }

    /// One attempt with step `h`; returns the scaled error.
    fn attempt(&mut self, h: f64) -> Result<f64, SolveError> {
        let n = self.state.y.len();
        let t = self.state.t;
        macro_rules! stage {
            ($idx:expr, $c:expr, $( $a:expr => $j:expr ),+) => {{
                for i in 0..n {
                    self.y_stage[i] = self.state.y[i] + h * (0.0 $( + $a * self.k[$j][i] )+);
                }
                self.eval($idx, t + $c * h)?;
            }};
        }
        stage!(1, C2, A21 => 0);
        stage!(2, C3, A31 => 0, A32 => 1);
        stage!(3, C4, A41 => 0, A42 => 1, A43 => 2);
        stage!(4, C5, A51 => 0, A52 => 1, A53 => 2, A54 => 3);
        stage!(5, 1.0, A61 => 0, A62 => 1, A63 => 2, A64 => 3, A65 => 4);
        for i in 0..n {
            self.y1[i] = self.state.y[i]
                + h * (A71 * self.k[0][i]
                    + A73 * self.k[2][i]
                    + A74 * self.k[3][i]
                    + A75 * self.k[4][i]
                    + A76 * self.k[5][i]);
        }
        self.eval(6, t + h)?;
        let mut err = 0.0;
        for i in 0..n {
            let e = h
                * (E1 * self.k[0][i]
                    + E3 * self.k[2][i]
                    + E4 * self.k[3][i]
                    + E5 * self.k[4][i]
                    + E6 * self.k[5][i]
                    + E7 * self.k[6][i]);
            let sk = self.control.scale(self.state.y[i], self.y1[i]);
            err += (e / sk).powi(2);
        }
        let err = (err / n as f64).sqrt();
        if first_non_finite(&self.y1).is_some() {
            return Ok(f64::INFINITY);
        }
        Ok(err)
    }
}

impl<S: OdeSystem> EmbeddedPair for Dopri5<S> {
    fn state(&mut self) -> &mut SolverState {
        &mut self.state
    }

    fn control(&mut self) -> &mut StepControl {
        &mut self.control
    }

    fn attempt(&mut self, h: f64) -> Result<f64, SolveError> {
        Dopri5::attempt(self, h)
    }

    fn failure(&self, h: f64) -> SolveError {
        step_failure(self.state.t, h, &self.y1, &self.k[6])
    }

    /// Dense output of the accepted step (Hairer's continuous extension).
    fn accept(&mut self, h: f64) -> Result<(), SolveError> {
        for i in 0..self.state.y.len() {
            let ydiff = self.y1[i] - self.state.y[i];
            let bspl = h * self.k[0][i] - ydiff;
            self.cont[0][i] = self.state.y[i];
            self.cont[1][i] = ydiff;
            self.cont[2][i] = bspl;
            self.cont[3][i] = ydiff - h * self.k[6][i] - bspl;
            self.cont[4][i] = h
                * (D1 * self.k[0][i]
                    + D3 * self.k[2][i]
                    + D4 * self.k[3][i]
                    + D5 * self.k[4][i]
                    + D6 * self.k[5][i]
                    + D7 * self.k[6][i]);
        }
        std::mem::swap(&mut self.state.y, &mut self.y1);
        self.k.swap(0, 6);
        Ok(())
    }
}

impl<S: OdeSystem> Solver for Dopri5<S> {
    fn method(&self) -> Method {
        Method::Dopri5
    }
    fn solver_state(&self) -> &SolverState {
        &self.state
    }
    fn solver_state_mut(&mut self) -> &mut SolverState {
        &mut self.state
    }

    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        adaptive::step(self)
    }

    fn set_state(&mut self, y: &[f64]) -> Result<(), SolveError> {
        check_len(self.state.y.len(), y.len())?;
        self.state.y.copy_from_slice(y);
        // The first stage of the next step is F(t, y) at the new state.
        self.state.stats.rhs_evaluations += 1;
        let t = self.state.t;
        self.system.rhs(t, &self.state.y, &mut self.k[0]).map_err(|source| SolveError::Rhs { t, source })
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError> {
        check_len(self.state.y.len(), out.len())?;
        check_interpolation(t, self.state.t_old, self.state.t)?;
        let h = self.state.t - self.state.t_old;
        if h == 0.0 {
            out.copy_from_slice(&self.state.y);
            return Ok(());
        }
        let theta = (t - self.state.t_old) / h;
        let theta1 = 1.0 - theta;
        let c = &self.cont;
        for i in 0..out.len() {
            out[i] = c[0][i] + theta * (c[1][i] + theta1 * (c[2][i] + theta * (c[3][i] + theta1 * c[4][i])));
        }
        Ok(())
    }
}
