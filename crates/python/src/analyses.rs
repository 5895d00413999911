//! The analyses: normal modes, orbits and tops of a derived model, and the
//! two that stand beside the pipeline, inertia tensors (body files) and
//! extremals (problem files). Each returns its JSON report (the CLI's
//! `--format json`), the CLI's text, and the figure the CLI draws (`--plot`,
//! `--animate`) as SVG text where the analysis has one.

use crate::errors::{self, guarded, Place};
use crate::model::{overrides, Derived};
use mech::{ModeKind, ModesError, OrbitError, TopError};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::collections::HashMap;
use std::path::PathBuf;

/// An analysis' JSON report, its text, and its figure (SVG) where it has one.
type Analysis = (String, String, Option<String>);

fn json<T: serde::Serialize>(report: &T) -> PyResult<String> {
    serde_json::to_string(report).map_err(|e| PyRuntimeError::new_err(format!("cannot write JSON: {e}")))
}

/// The text of a file, or the text given: `(name, text)`.
fn source(py: Python<'_>, path: Option<PathBuf>, text: Option<String>, what: &str) -> PyResult<(String, String)> {
    match (path, text) {
        (Some(p), None) => {
            let name = p.display().to_string();
            let text = crate::model::read_text(&p)
                .map_err(|e| errors::plain_error(py, &name, &format!("cannot read the {what}: {e}"), None))?;
            Ok((name, text))
        }
        (None, Some(t)) => Ok(("<string>".into(), t)),
        _ => Err(errors::plain_error(py, what, &format!("give the {what} as a path or as text, not both"), None)),
    }
}

impl Derived {
    /// An analysis' error: located in the model file when it is a model error.
    fn analysis_error(&self, py: Python<'_>, model: Result<mech::ModelError, String>, help: Option<String>) -> PyErr {
        match model {
            Ok(m) => self.error(py, &m),
            Err(message) => errors::plain_error(py, &self.file, &message, help.as_deref()),
        }
    }

    fn refuse_constraints(&self, py: Python<'_>, what: &str) -> PyResult<()> {
        self.d.reject_constraints(what).map_err(|e| self.error(py, &e))
    }
}

#[pymethods]
impl Derived {
    /// Normal modes about the equilibrium nearest `[initial]` (or `at`).
    #[pyo3(signature = (at=None, allow_unstable=false))]
    fn modes(&self, py: Python<'_>, at: Option<HashMap<String, f64>>, allow_unstable: bool) -> PyResult<Analysis> {
        guarded("modes", || {
            self.refuse_constraints(py, "modes()")?;
            let config = mech::ModesConfig { at: overrides(at), keep_unstable: allow_unstable };
            let modes = py.detach(|| mech::normal_modes(&self.d, &config)).map_err(|e| {
                let help = match &e {
                    ModesError::NoEquilibrium { .. } => {
                        Some("start elsewhere with at={\"q\": v}, or check that U has a minimum".to_string())
                    }
                    other => other.help(),
                };
                let inner = match e {
                    ModesError::Model(m) => Ok(m),
                    other => Err(other.to_string()),
                };
                self.analysis_error(py, inner, help)
            })?;
            if !modes.stable && !allow_unstable {
                let unstable: Vec<String> = modes
                    .modes
                    .iter()
                    .filter(|m| m.kind == ModeKind::Unstable)
                    .map(|m| {
                        format!(
                            "Ω² = {} along {}",
                            view::human(m.omega_squared),
                            view::modes::vector(&modes.coordinates, &m.shape)
                        )
                    })
                    .collect();
                let message = format!(
                    "the equilibrium at {} is unstable ({}): a small displacement grows like exp(sqrt(-Ω²)·t) instead of oscillating",
                    view::modes::vector(&modes.coordinates, &modes.equilibrium),
                    unstable.join("; ")
                );
                let help = "start next to a stable equilibrium with at={\"q\": v}, or pass allow_unstable=True to see the growth rates";
                return Err(errors::plain_error(py, &self.file, &message, Some(help)));
            }
            let report = mech::ModesReport::new(&self.d, &modes);
            let text = view::modes::text(&self.d, &modes, &config, &crate::TERMS);
            Ok((json(&report)?, text, Some(view::modes::animation(&self.d, &modes))))
        })
    }

    /// The orbit of a model of relative motion in plane polar coordinates.
    fn orbit(&self, py: Python<'_>) -> PyResult<Analysis> {
        guarded("orbit", || {
            self.refuse_constraints(py, "orbit()")?;
            let mut orbit = mech::Orbit::new(&self.d).map_err(|e| {
                let help = e.help();
                let inner = match e {
                    OrbitError::Model(m) => Ok(m),
                    other => Err(other.to_string()),
                };
                self.analysis_error(py, inner, help)
            })?;
            let figure = view::orbit::figure(&self.d, &mut orbit).ok();
            Ok((json(&orbit.report(&self.d))?, view::orbit::text(&self.d, &orbit), figure))
        })
    }

    /// The state-space matrices A (and B, with inputs) of the small motion about
    /// an equilibrium or a steady motion, their eigenvalues and the verdict.
    #[pyo3(signature = (about="equilibrium", at=None, rates=None, allow_unstable=false))]
    fn linearize(
        &self,
        py: Python<'_>,
        about: &str,
        at: Option<HashMap<String, f64>>,
        rates: Option<HashMap<String, f64>>,
        allow_unstable: bool,
    ) -> PyResult<Analysis> {
        guarded("linearize", || {
            let about = match about {
                "equilibrium" => mech::About::Equilibrium,
                "steady" => mech::About::Steady,
                other => {
                    let message = format!("about must be \"equilibrium\" or \"steady\", not {other:?}");
                    return Err(errors::plain_error(py, "linearize", &message, None));
                }
            };
            let rates = overrides(rates);
            if let (mech::About::Equilibrium, Some((name, _))) = (about, rates.first()) {
                let message = format!(
                    "rates[{name:?}]: a rate applies to a steady motion (about=\"steady\"); at an equilibrium every speed is zero"
                );
                return Err(errors::plain_error(py, "linearize", &message, None));
            }
            let config = mech::LinearizeConfig { about, at: overrides(at), rates, keep_unstable: allow_unstable };
            // The inputs stay symbols: B is the response to them.
            let d = self.shown();
            let lin = py.detach(|| mech::linearize(d, &config)).map_err(|e| {
                let help = match &e {
                    mech::LinearizeError::NoPoint { .. } => Some(
                        "start elsewhere with at={\"q\": v}, or change the rates with rates={\"q\": v}".to_string(),
                    ),
                    other => other.help(),
                };
                let inner = match e {
                    mech::LinearizeError::Model(m) => Ok(m),
                    mech::LinearizeError::Rate { name, message } => Err(format!("rates[{name:?}]: {message}")),
                    other => Err(other.to_string()),
                };
                self.analysis_error(py, inner, help)
            })?;
            let report = mech::LinearizeReport::new(d, &lin);
            Ok((json(&report)?, view::linearize::text(d, &lin, &config, &crate::TERMS), None))
        })
    }

    /// The symmetric top's constants of the motion, nutation and precession.
    fn top(&self, py: Python<'_>) -> PyResult<Analysis> {
        guarded("top", || {
            let top = mech::Top::new(&self.d).map_err(|e| match e {
                TopError::Model(m) => self.error(py, &m),
            })?;
            let figure = view::top::figure(&self.d, &top).ok();
            Ok((json(&top.report())?, view::top::text(&self.d, &top), figure))
        })
    }
}

/// The mass properties of a body file about a point (default its centre of mass).
#[pyfunction]
#[pyo3(signature = (path=None, text=None, set=None, about="com".to_string()))]
pub fn inertia(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    set: Option<HashMap<String, f64>>,
    about: String,
) -> PyResult<Analysis> {
    guarded("inertia", || {
        let (name, source) = source(py, path, text, "body file")?;
        let place = Place { file: &name, text: &source };
        let body = mech::inertia::BodyFile::parse(&source, &overrides(set))
            .map_err(|e| errors::model_error(py, &place, &e))?;
        let mut props = body.mass_properties().map_err(|e| errors::model_error(py, &place, &e))?;
        let point = props.parse_about(&about).map_err(|e| errors::expression_error(py, "about", &about, &e))?;
        let report = props.report(point);
        Ok((json(&report)?, view::inertia::text(&body, &props, point, &report), None))
    })
}

/// The extremal of a variational problem file.
#[pyfunction]
#[pyo3(signature = (path=None, text=None, set=None, check_minimum=false, points=201))]
pub fn extremal(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    set: Option<HashMap<String, f64>>,
    check_minimum: bool,
    points: usize,
) -> PyResult<Analysis> {
    guarded("extremal", || {
        let (name, source) = source(py, path, text, "problem file")?;
        let place = Place { file: &name, text: &source };
        if !(2..=1_000_000).contains(&points) {
            return Err(errors::plain_error(
                py,
                "points",
                &format!("points must be from 2 to 1000000, not {points}"),
                None,
            ));
        }
        let problem =
            mech::Problem::parse(&source, &overrides(set)).map_err(|e| errors::model_error(py, &place, &e))?;
        let config = mech::ExtremalConfig { check_minimum, points };
        let report = py.detach(|| mech::extremal(&problem, &config)).map_err(|e| match e {
            mech::ExtremalError::Model(m) => errors::model_error(py, &place, &m),
            mech::ExtremalError::NoExtremal { message, help } => errors::raise(py, "RunError", |kw| {
                kw.set_item(
                    "message",
                    match help {
                        Some(h) => format!("{name}: {message}\n  help: {h}"),
                        None => format!("{name}: {message}"),
                    },
                )
            }),
        })?;
        let figure = view::extremal::figure(&report).ok();
        Ok((json(&report)?, view::extremal::text(&report, &crate::TERMS), figure))
    })
}
