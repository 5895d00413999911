//! DOP853, Hairer's adaptive explicit Runge–Kutta method of order 8 (Dormand–Prince
//! 8(5,3)): twelve stages plus a first-same-as-last stage, an error estimate that
//! combines 5th- and 3rd-order embedded solutions, and a 7th-order dense output that
//! costs three extra stages per accepted step (so a step costs 15 evaluations; they
//! are computed on every accepted step, as `DOP853` does when dense output is asked
//! for). Enter with [`Dop853::new`].
//!
//! The coefficients are Hairer's (as tabulated in SciPy's `dop853_coefficients.py`);
//! the tests check the measured order (8) and a reference solution.
#![allow(clippy::excessive_precision)] // Coefficients are quoted as published.

use crate::adaptive::{self, first_step, step_failure, EmbeddedPair, StepControl};
use crate::error::SolveError;
use crate::method::Method;
use crate::solver::{
    check_initial, check_interpolation, check_len, Config, Solver, SolverState, Statistics, StepOutcome,
};
use crate::system::{first_non_finite, OdeSystem};

/// Nodes `c_i` of the 12 stages, the FSAL stage (`c = 1`) and the 3 dense-output stages.
const C: [f64; 16] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
    1.0,
    0.1,
    0.2,
    0.777777777777777777777777777778,
];
/// Stage coefficients `a_ij` (row `i`, nonzero entries only, as `(j, a_ij)`); row 12 holds the weights `b_j`.
const A: [&[(usize, f64)]; 16] = [
    &[],
    &[(0, 5.26001519587677318785587544488e-2)],
    &[(0, 1.97250569845378994544595329183e-2), (1, 5.91751709536136983633785987549e-2)],
    &[(0, 2.95875854768068491816892993775e-2), (2, 8.87627564304205475450678981324e-2)],
    &[
        (0, 2.41365134159266685502369798665e-1),
        (2, -8.84549479328286085344864962717e-1),
        (3, 9.24834003261792003115737966543e-1),
    ],
    &[
        (0, 3.7037037037037037037037037037e-2),
        (3, 1.70828608729473871279604482173e-1),
        (4, 1.25467687566822425016691814123e-1),
    ],
    &[
        (0, 3.7109375e-2),
        (3, 1.70252211019544039314978060272e-1),
        (4, 6.02165389804559606850219397283e-2),
        (5, -1.7578125e-2),
    ],
    &[
        (0, 3.70920001185047927108779319836e-2),
        (3, 1.70383925712239993810214054705e-1),
        (4, 1.07262030446373284651809199168e-1),
        (5, -1.53194377486244017527936158236e-2),
        (6, 8.27378916381402288758473766002e-3),
    ],
    &[
        (0, 6.24110958716075717114429577812e-1),
        (3, -3.36089262944694129406857109825),
        (4, -8.68219346841726006818189891453e-1),
        (5, 2.75920996994467083049415600797e1),
        (6, 2.01540675504778934086186788979e1),
        (7, -4.34898841810699588477366255144e1),
    ],
    &[
        (0, 4.77662536438264365890433908527e-1),
        (3, -2.48811461997166764192642586468),
        (4, -5.90290826836842996371446475743e-1),
        (5, 2.12300514481811942347288949897e1),
        (6, 1.52792336328824235832596922938e1),
        (7, -3.32882109689848629194453265587e1),
        (8, -2.03312017085086261358222928593e-2),
    ],
    &[
        (0, -9.3714243008598732571704021658e-1),
        (3, 5.18637242884406370830023853209),
        (4, 1.09143734899672957818500254654),
        (5, -8.14978701074692612513997267357),
        (6, -1.85200656599969598641566180701e1),
        (7, 2.27394870993505042818970056734e1),
        (8, 2.49360555267965238987089396762),
        (9, -3.0467644718982195003823669022),
    ],
    &[
        (0, 2.27331014751653820792359768449),
        (3, -1.05344954667372501984066689879e1),
        (4, -2.00087205822486249909675718444),
        (5, -1.79589318631187989172765950534e1),
        (6, 2.79488845294199600508499808837e1),
        (7, -2.85899827713502369474065508674),
        (8, -8.87285693353062954433549289258),
        (9, 1.23605671757943030647266201528e1),
        (10, 6.43392746015763530355970484046e-1),
    ],
    &[
        (0, 5.42937341165687622380535766363e-2),
        (5, 4.45031289275240888144113950566),
        (6, 1.89151789931450038304281599044),
        (7, -5.8012039600105847814672114227),
        (8, 3.1116436695781989440891606237e-1),
        (9, -1.52160949662516078556178806805e-1),
        (10, 2.01365400804030348374776537501e-1),
        (11, 4.47106157277725905176885569043e-2),
    ],
    &[
        (0, 5.61675022830479523392909219681e-2),
        (6, 2.53500210216624811088794765333e-1),
        (7, -2.46239037470802489917441475441e-1),
        (8, -1.24191423263816360469010140626e-1),
        (9, 1.5329179827876569731206322685e-1),
        (10, 8.20105229563468988491666602057e-3),
        (11, 7.56789766054569976138603589584e-3),
        (12, -8.298e-3),
    ],
    &[
        (0, 3.18346481635021405060768473261e-2),
        (5, 2.83009096723667755288322961402e-2),
        (6, 5.35419883074385676223797384372e-2),
        (7, -5.49237485713909884646569340306e-2),
        (10, -1.08347328697249322858509316994e-4),
        (11, 3.82571090835658412954920192323e-4),
        (12, -3.40465008687404560802977114492e-4),
        (13, 1.41312443674632500278074618366e-1),
    ],
    &[
        (0, -4.28896301583791923408573538692e-1),
        (5, -4.69762141536116384314449447206),
        (6, 7.68342119606259904184240953878),
        (7, 4.06898981839711007970213554331),
        (8, 3.56727187455281109270669543021e-1),
        (12, -1.39902416515901462129418009734e-3),
        (13, 2.9475147891527723389556272149),
        (14, -9.15095847217987001081870187138),
    ],
];
/// Weights of the 3rd-order error estimate (`b - bhh`), nonzero entries.
const E3: [(usize, f64); 8] = [
    (0, 5.42937341165687622380535766363e-2 - 0.244094488188976377952755905512),
    (5, 4.45031289275240888144113950566),
    (6, 1.89151789931450038304281599044),
    (7, -5.8012039600105847814672114227),
    (8, 3.1116436695781989440891606237e-1 - 0.733846688281611857341361741547),
    (9, -1.52160949662516078556178806805e-1),
    (10, 2.01365400804030348374776537501e-1),
    (11, 4.47106157277725905176885569043e-2 - 0.220588235294117647058823529412e-1),
];
/// Weights of the 5th-order error estimate, nonzero entries.
const E5: [(usize, f64); 8] = [
    (0, 0.1312004499419488073250102996e-1),
    (5, -0.1225156446376204440720569753e1),
    (6, -0.4957589496572501915214079952),
    (7, 0.1664377182454986536961530415e1),
    (8, -0.3503288487499736816886487290),
    (9, 0.3341791187130174790297318841),
    (10, 0.8192320648511571246570742613e-1),
    (11, -0.2235530786388629525884427845e-1),
];
/// Dense-output coefficients (rows 4..7 of the interpolant), nonzero entries.
const D: [[(usize, f64); 12]; 4] = [
    [
        (0, -0.84289382761090128651353491142e1),
        (5, 0.56671495351937776962531783590),
        (6, -0.30689499459498916912797304727e1),
        (7, 0.23846676565120698287728149680e1),
        (8, 0.21170345824450282767155149946e1),
        (9, -0.87139158377797299206789907490),
        (10, 0.22404374302607882758541771650e1),
        (11, 0.63157877876946881815570249290),
        (12, -0.88990336451333310820698117400e-1),
        (13, 0.18148505520854727256656404962e2),
        (14, -0.91946323924783554000451984436e1),
        (15, -0.44360363875948939664310572000e1),
    ],
    [
        (0, 0.10427508642579134603413151009e2),
        (5, 0.24228349177525818288430175319e3),
        (6, 0.16520045171727028198505394887e3),
        (7, -0.37454675472269020279518312152e3),
        (8, -0.22113666853125306036270938578e2),
        (9, 0.77334326684722638389603898808e1),
        (10, -0.30674084731089398182061213626e2),
        (11, -0.93321305264302278729567221706e1),
        (12, 0.15697238121770843886131091075e2),
        (13, -0.31139403219565177677282850411e2),
        (14, -0.93529243588444783865713862664e1),
        (15, 0.35816841486394083752465898540e2),
    ],
    [
        (0, 0.19985053242002433820987653617e2),
        (5, -0.38703730874935176555105901742e3),
        (6, -0.18917813819516756882830838328e3),
        (7, 0.52780815920542364900561016686e3),
        (8, -0.11573902539959630126141871134e2),
        (9, 0.68812326946963000169666922661e1),
        (10, -0.10006050966910838403183860980e1),
        (11, 0.77771377980534432092869265740),
        (12, -0.27782057523535084065932004339e1),
        (13, -0.60196695231264120758267380846e2),
        (14, 0.84320405506677161018159903784e2),
        (15, 0.11992291136182789328035130030e2),
    ],
    [
        (0, -0.25693933462703749003312586129e2),
        (5, -0.15418974869023643374053993627e3),
        (6, -0.23152937917604549567536039109e3),
        (7, 0.35763911791061412378285349910e3),
        (8, 0.93405324183624310003907691704e2),
        (9, -0.37458323136451633156875139351e2),
        (10, 0.10409964950896230045147246184e3),
        (11, 0.29840293426660503123344363579e2),
        (12, -0.43533456590011143754432175058e2),
        (13, 0.96324553959188282948394950600e2),
        (14, -0.39177261675615439165231486172e2),
        (15, -0.14972683625798562581422125276e3),
    ],
];

/// The DOP853 solver; see the module documentation.
#[derive(Clone, Debug)]
pub struct Dop853<S> {
    system: S,
    control: StepControl,
    /// Time, state, step, stop time and counters (what the accessors read).
    state: SolverState,
    /// Stages: 0..12 of the step, 12 = F(t + h, y1) (first stage of the next step),
    /// 13..16 the dense-output stages.
    k: [Vec<f64>; 16],
    y1: Vec<f64>,
    y_stage: Vec<f64>,
    /// Dense output: `y_old` and the seven interpolant coefficients.
    cont: [Vec<f64>; 8],
    /// Whether the dense output waits for [`Solver::prepare_dense`].
    lazy_dense: bool,
    /// The step size of the last step, while its dense output is pending.
    dense_pending: Option<f64>,
}

impl<S: OdeSystem> Dop853<S> {
    /// A solver for `y' = F(t, y)` from `(t0, y0)`. Uses `rtol`, `atol`, `h_init`,
    /// `h_max`, `max_steps` and `controller` of `config`.
    pub fn new(mut system: S, t0: f64, y0: &[f64], config: &Config) -> Result<Self, SolveError> {
        config.validate()?;
        let n = system.dim();
        check_initial(n, t0, y0)?;
        // Hairer's DOP853 defaults: fac1 = 0.333, fac2 = 6.
        let control = StepControl::new(config, 8, 0.333, 6.0);
        let mut k: [Vec<f64>; 16] = std::array::from_fn(|_| vec![0.0; n]);
        let mut stats = Statistics::default();
        let mut y1 = vec![0.0; n];
        let mut y_stage = vec![0.0; n];
        let h =
            first_step(&mut system, &control, 8, config.h_init, t0, y0, &mut k[0], &mut y1, &mut y_stage, &mut stats)?;
        let cont = std::array::from_fn(|i| if i == 0 { y0.to_vec() } else { vec![0.0; n] });
        Ok(Dop853 {
            system,
            control,
            state: SolverState::new(t0, y0, h, stats, config),
            k,
            y1,
            y_stage,
            cont,
            lazy_dense: false,
            dense_pending: None,
        })
    }

    /// The system, e.g. to read parameters or counters it keeps.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// Evaluates stage `s` (`1..12` or `13..16`) at `t + c_s h`.
    fn stage(&mut self, s: usize, h: f64) -> Result<(), SolveError> {
        let n = self.state.y.len();
        for i in 0..n {
            let mut acc = 0.0;
            for &(j, a) in A[s] {
                acc += a * self.k[j][i];
            }
            self.y_stage[i] = self.state.y[i] + h * acc;
        }
        let t = self.state.t + C[s] * h;
        self.state.stats.rhs_evaluations += 1;
        self.system.rhs(t, &self.y_stage, &mut self.k[s]).map_err(|source| SolveError::Rhs { t, source })
    }

    /// One attempt with step `h`; returns the scaled error.
    fn attempt(&mut self, h: f64) -> Result<f64, SolveError> {
        let n = self.state.y.len();
        for s in 1..12 {
            self.stage(s, h)?;
        }
        for i in 0..n {
            let mut acc = 0.0;
            for &(j, b) in A[12] {
                acc += b * self.k[j][i];
            }
            self.y1[i] = self.state.y[i] + h * acc;
        }
        let t1 = self.state.t + h;
        self.state.stats.rhs_evaluations += 1;
        self.system.rhs(t1, &self.y1, &mut self.k[12]).map_err(|source| SolveError::Rhs { t: t1, source })?;
        let mut err5 = 0.0;
        let mut err3 = 0.0;
        for i in 0..n {
            let sk = self.control.scale(self.state.y[i], self.y1[i]);
            let mut e5 = 0.0;
            for &(j, e) in &E5 {
                e5 += e * self.k[j][i];
            }
            let mut e3 = 0.0;
            for &(j, e) in &E3 {
                e3 += e * self.k[j][i];
            }
            err5 += (e5 / sk).powi(2);
            err3 += (e3 / sk).powi(2);
        }
        if first_non_finite(&self.y1).is_some() || first_non_finite(&self.k[12]).is_some() {
            return Ok(f64::INFINITY);
        }
        if err5 == 0.0 && err3 == 0.0 {
            return Ok(0.0);
        }
        let denom = err5 + 0.01 * err3;
        Ok(h.abs() * err5 / (denom * n as f64).sqrt())
    }

    /// Dense-output coefficients of the accepted step `[t, t + h]` (before the swap).
    fn build_dense(&mut self, h: f64) -> Result<(), SolveError> {
        for s in 13..16 {
            self.stage(s, h)?;
        }
        let n = self.state.y.len();
        for i in 0..n {
            let dy = self.y1[i] - self.state.y[i];
            let bspl = h * self.k[0][i] - dy;
            self.cont[0][i] = self.state.y[i];
            self.cont[1][i] = dy;
            self.cont[2][i] = bspl;
            self.cont[3][i] = dy - h * self.k[12][i] - bspl;
            for (r, row) in D.iter().enumerate() {
                let mut acc = 0.0;
                for &(j, d) in row {
                    acc += d * self.k[j][i];
                }
                self.cont[4 + r][i] = h * acc;
            }
        }
        Ok(())
    }
}

impl<S: OdeSystem> EmbeddedPair for Dop853<S> {
    fn state(&mut self) -> &mut SolverState {
        &mut self.state
    }

    fn control(&mut self) -> &mut StepControl {
        &mut self.control
    }

    fn attempt(&mut self, h: f64) -> Result<f64, SolveError> {
        Dop853::attempt(self, h)
    }

    fn failure(&self, h: f64) -> SolveError {
        step_failure(self.state.t, h, &self.y1, &self.k[12])
    }

    fn accept(&mut self, h: f64) -> Result<(), SolveError> {
        if self.lazy_dense {
            self.dense_pending = Some(h);
        } else {
            self.build_dense(h)?;
        }
        std::mem::swap(&mut self.state.y, &mut self.y1);
        self.k.swap(0, 12);
        Ok(())
    }
}

impl<S: OdeSystem> Solver for Dop853<S> {
    fn method(&self) -> Method {
        Method::Dop853
    }
    fn solver_state(&self) -> &SolverState {
        &self.state
    }
    fn solver_state_mut(&mut self) -> &mut SolverState {
        &mut self.state
    }

    fn step(&mut self) -> Result<StepOutcome, SolveError> {
        // This step overwrites the stages a pending dense output would need.
        self.dense_pending = None;
        adaptive::step(self)
    }

    fn set_lazy_dense(&mut self, lazy: bool) {
        self.lazy_dense = lazy;
    }

    fn prepare_dense(&mut self) -> Result<(), SolveError> {
        let Some(h) = self.dense_pending.take() else { return Ok(()) };
        // The stages of the last step are still there, with the step's two ends
        // swapped (y ↔ y1, k[0] ↔ k[12]) and t moved on: put them back as
        // `build_dense` expects them (before the swap), build, and swap again.
        std::mem::swap(&mut self.state.y, &mut self.y1);
        self.k.swap(0, 12);
        let t_end = self.state.t;
        self.state.t = self.state.t_old;
        let built = self.build_dense(h);
        self.state.t = t_end;
        std::mem::swap(&mut self.state.y, &mut self.y1);
        self.k.swap(0, 12);
        built
    }

    fn set_state(&mut self, y: &[f64]) -> Result<(), SolveError> {
        check_len(self.state.y.len(), y.len())?;
        // The last step's dense output is kept: build it before the state changes.
        self.prepare_dense()?;
        self.state.y.copy_from_slice(y);
        // The first stage of the next step is F(t, y) at the new state.
        self.state.stats.rhs_evaluations += 1;
        let t = self.state.t;
        self.system.rhs(t, &self.state.y, &mut self.k[0]).map_err(|source| SolveError::Rhs { t, source })
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) -> Result<(), SolveError> {
        check_len(self.state.y.len(), out.len())?;
        check_interpolation(t, self.state.t_old, self.state.t)?;
        if self.dense_pending.is_some() {
            return Err(SolveError::DenseOutputNotPrepared { method: "dop853" });
        }
        let h = self.state.t - self.state.t_old;
        if h == 0.0 {
            out.copy_from_slice(&self.state.y);
            return Ok(());
        }
        let s = (t - self.state.t_old) / h;
        let s1 = 1.0 - s;
        let c = &self.cont;
        for i in 0..out.len() {
            out[i] = c[0][i]
                + s * (c[1][i]
                    + s1 * (c[2][i] + s * (c[3][i] + s1 * (c[4][i] + s * (c[5][i] + s1 * (c[6][i] + s * c[7][i]))))));
        }
        Ok(())
    }
}
