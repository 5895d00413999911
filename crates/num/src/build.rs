//! The factory of solvers: [`Method::build`] and [`Method::build_separable`]
//! construct any method of the catalogue (`method.rs`) as a `Box<dyn Solver>`,
//! choosing the step of a fixed-step method first when none is given.

use crate::composition::{Composition, Scheme};
use crate::dop853::Dop853;
use crate::dopri5::Dopri5;
use crate::error::SolveError;
use crate::gauss::Gauss;
use crate::method::Method;
use crate::radau5::Radau5;
use crate::solver::{check_initial, Config, Solver};
use crate::stepsize::{guess_step, run_fixed, select_step};
use crate::system::{OdeSystem, Separable, SeparableSystem};
use crate::taylor::Taylor;

impl Method {
    /// Builds a solver for a general system from `(t0, y0)`.
    ///
    /// Fails with [`SolveError::RequiresSeparable`] for the explicit symplectic
    /// compositions. A fixed-step method without `config.dt` first picks its step with
    /// [`select_step`] (capped by `config.h_max`; set it to the length of the run).
    pub fn build<'a, S: OdeSystem + 'a>(
        self,
        mut system: S,
        t0: f64,
        y0: &[f64],
        config: &Config,
    ) -> Result<Box<dyn Solver + 'a>, SolveError> {
        config.validate()?;
        check_initial(system.dim(), t0, y0)?;
        if self.needs_separable() {
            return Err(SolveError::RequiresSeparable { method: self.name() });
        }
        let mut config = *config;
        if !self.is_adaptive() && config.dt.is_none() {
            let guess = guess_step(&mut system, self.order(), t0, y0, &config)?;
            let dt = select_step(
                |h, steps, out| {
                    let cfg = Config { dt: Some(h), ..config };
                    run_fixed(Gauss::new(&mut system, self, t0, y0, &cfg).map(Gauss::without_sub_steps), steps, out)
                },
                self.order(),
                y0,
                &config,
                guess,
            )?;
            config.dt = Some(dt);
        }
        Ok(match self {
            Method::Dopri5 => Box::new(Dopri5::new(system, t0, y0, &config)?),
            Method::Dop853 => Box::new(Dop853::new(system, t0, y0, &config)?),
            Method::Radau5 => Box::new(Radau5::new(system, t0, y0, &config)?),
            Method::Taylor => Box::new(Taylor::new(system, t0, y0, &config)?),
            _ => Box::new(Gauss::new(system, self, t0, y0, &config)?),
        })
    }

    /// Builds a solver for a separable system from `(t0, y0)`, `y0 = [q0, p0]`. Every
    /// method applies; the non-composition ones see the system through [`Separable`].
    pub fn build_separable<'a, S: SeparableSystem + 'a>(
        self,
        mut system: S,
        t0: f64,
        y0: &[f64],
        config: &Config,
    ) -> Result<Box<dyn Solver + 'a>, SolveError> {
        let Some(scheme) = Scheme::of(self) else {
            return self.build(Separable(system), t0, y0, config);
        };
        config.validate()?;
        check_initial(2 * system.n(), t0, y0)?;
        let mut config = *config;
        if config.dt.is_none() {
            let guess = guess_step(&mut Separable(&mut system), self.order(), t0, y0, &config)?;
            let dt = select_step(
                |h, steps, out| {
                    let cfg = Config { dt: Some(h), ..config };
                    run_fixed(Composition::new(&mut system, scheme, t0, y0, &cfg), steps, out)
                },
                self.order(),
                y0,
                &config,
                guess,
            )?;
            config.dt = Some(dt);
        }
        Ok(Box::new(Composition::new(system, scheme, t0, y0, &config)?))
    }
}
