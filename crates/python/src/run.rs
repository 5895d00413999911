//! `Model.simulate`: one run, its rows kept in memory as one table of f64
//! (the CSV's columns), with the GIL released while it integrates.
//!
//! Ctrl-C: between rows, at most every 20 ms, the run takes the GIL back for
//! a moment to let Python run its signal handlers. When one raises (a
//! KeyboardInterrupt), the run stops there and hands back the rows it has,
//! with the exception, for the Python side to raise with the partial run.

use crate::errors::{self, guarded};
use crate::model::Derived;
use crate::signals::Signals;
use mech::{
    BudgetAdvice, Derivation, RunConfig, RunError, RunSettings, Section, SettingError, StepBudget, StopCondition,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ops::ControlFlow;
use std::time::Instant;

/// The options of `simulate`, as Python passes them.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Options {
    until: f64,
    method: Option<String>,
    rtol: Option<f64>,
    atol: Option<f64>,
    dt: Option<f64>,
    samples: Option<usize>,
    every_step: bool,
    stop_when: Vec<String>,
    crossing: Vec<String>,
    section: Option<String>,
    section_axes: Option<String>,
    initial: Vec<(String, f64)>,
}

impl Derived {
    /// The run's configuration, and its Poincaré section when one is asked for
    /// (its condition is then the configuration's one crossing).
    fn config(&self, py: Python<'_>, o: &Options) -> PyResult<(RunConfig, Option<Section>)> {
        let settings = RunSettings {
            until: Some(o.until),
            method: o.method.as_deref(),
            rtol: o.rtol,
            atol: o.atol,
            dt: o.dt,
            samples: o.samples,
            every_step: o.every_step,
        };
        let base = RunConfig::from_settings(&settings).map_err(|e| setting_error(py, "simulate", e))?;
        let conditions = |texts: &[String], what: &str| -> PyResult<Vec<StopCondition>> {
            texts
                .iter()
                .map(|text| {
                    StopCondition::parse(&self.d, text, what).map_err(|e| errors::expression_error(py, what, text, &e))
                })
                .collect()
        };
        let mut config = RunConfig {
            stop_when: conditions(&o.stop_when, "stop_when")?,
            crossings: conditions(&o.crossing, "crossing")?,
            initial: o.initial.clone(),
            ..base
        };
        if o.section.is_some() && !o.crossing.is_empty() {
            let message = "section= and crossing= do not go together: a section's table holds its points only";
            return Err(errors::plain_error(py, "simulate", message, None));
        }
        let section = parse_section(py, &self.d, "simulate", o.section.as_deref(), o.section_axes.as_deref())?;
        if let Some(s) = &section {
            config.crossings.push(s.condition().clone());
        }
        config.check().map_err(|e| self.refused(py, e))?;
        Ok((config, section))
    }

    /// A run that could not start, in the Python API's terms.
    fn refused(&self, py: Python<'_>, e: RunError) -> PyErr {
        let usage =
            |message: String, help: Option<String>| errors::plain_error(py, "simulate", &message, help.as_deref());
        match e {
            RunError::Until { until } => usage(format!("until must be a positive time, not {until}"), None),
            RunError::TooManySamples { samples, max } => {
                usage(format!("samples={samples} is more rows than a run keeps ({max} at most)"), None)
            }
            RunError::TooManySteps { dt, steps, max } => usage(
                format!("dt={dt:e} would take {steps:.3e} steps to reach the end time; a run takes at most {max}"),
                None,
            ),
            RunError::StepOverSamples { dt, spacing } => usage(
                format!("dt={dt:e} is longer than the spacing of the samples, {spacing:e}"),
                Some("give a shorter dt, more samples, or every_step=True".into()),
            ),
            RunError::StepNotApplicable { method } => usage(
                format!("dt applies only to fixed-step methods, and {} chooses its own step", method.name()),
                Some("set its tolerance with rtol, or choose a fixed-step method (verlet, yoshida4, kahanli6, kahanli8, gauss2, gauss4, gauss6)".into()),
            ),
            RunError::StepBudget(b) => usage(b.what_happened(), Some(advice(&b))),
            RunError::Input(mech::ModelError { setting: Some(mech::Setting::Start { name }), message, .. }) => {
                usage(format!("initial[{name:?}]: {message}"), None)
            }
            RunError::Input(e) => self.error(py, &e),
            RunError::Failed { message, .. } => usage(message, None),
        }
    }
}

/// The plot of a run, as `simulate --plot` draws it: kept decimated (at most
/// a few thousand points) and drawn on demand; a section's, its points.
#[pyclass(module = "lagrange._native", frozen)]
pub struct Plot {
    figure: Figure,
}

/// What a [`Plot`] draws.
enum Figure {
    Run(view::plot::PlotData),
    Section(view::plot::SectionPlot),
}

#[pymethods]
impl Plot {
    /// The plot as SVG text.
    fn svg(&self) -> PyResult<String> {
        match &self.figure {
            Figure::Run(data) => view::plot::svg(data),
            Figure::Section(data) => view::plot::section_svg(data),
        }
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("cannot draw the plot: {e}")))
    }
}

/// What would let a run fit its step budget, naming the keyword arguments.
pub fn advice(b: &StepBudget) -> String {
    let reach = mech::approx(b.reach);
    match b.advice() {
        BudgetAdvice::ShorterRun => {
            format!("any method follows such motion step by step: give a shorter until (at most about {reach})")
        }
        BudgetAdvice::ImplicitMethod => format!(
            "a decay that much faster than the run is stiff: method=\"radau5\" (implicit) steps over it; or give a shorter until (at most about {reach})"
        ),
        BudgetAdvice::HigherOrder => format!(
            "the step is set by the tolerance on a method of order {}: one of higher order takes far fewer steps; or give a looser rtol, or a shorter until (at most about {reach})",
            b.method.order()
        ),
        BudgetAdvice::LooserTolerance => {
            format!("give a looser rtol (fewer steps for the same motion), or a shorter until (at most about {reach})")
        }
    }
}

#[pymethods]
impl Derived {
    /// Integrates the motion. Returns a dict: `columns` (names), `data`
    /// (row-major f64 bytes), `rows`, `events` (row index, condition),
    /// `summary` (the `lagrange.simulate/1` JSON text), `failure` (message or
    /// None) and `interrupt` (the exception a signal handler raised, or None).
    fn simulate<'py>(&self, py: Python<'py>, options: Options) -> PyResult<Bound<'py, PyDict>> {
        guarded("simulate", || self.simulate_inner(py, options))
    }
}

impl Derived {
    fn simulate_inner<'py>(&self, py: Python<'py>, options: Options) -> PyResult<Bound<'py, PyDict>> {
        let started = Instant::now();
        let (config, mut section) = self.config(py, &options)?;
        let d = &self.d;
        let names: Vec<String> = d.coordinate_names().iter().map(|s| s.to_string()).collect();
        let inv_names: Vec<String> = mech::invariants_of(d).into_iter().map(|i| i.name).collect();
        let mut bodies = mech::BodyRecorder::new(d);
        let mut columns = mech::row_columns(d);
        // A section's table: its points' rows, then the plane's axes that are not columns already.
        let mut section_columns: Vec<usize> = Vec::new();
        if let Some(s) = &section {
            section_columns = (0..2).filter(|&k| !columns.contains(&s.axes()[k])).collect();
            columns.extend(section_columns.iter().map(|&k| s.axes()[k].clone()));
        }
        let mut section_points: Vec<[f64; 2]> = Vec::new();
        let width = columns.len();
        let mut body_values = vec![0.0; bodies.as_ref().map_or(0, |b| b.columns().len())];

        let mut data: Vec<f64> = Vec::new();
        let mut events: Vec<(usize, String)> = Vec::new();
        let mut interrupt: Option<PyErr> = None;
        let mut first_row: Option<f64> = None;
        let mut plot = view::plot::PlotKeeper::of(d);
        let result = py.detach(|| {
            let mut signals = Signals::new();
            mech::simulate(d, &config, |row| {
                first_row.get_or_insert_with(|| started.elapsed().as_secs_f64());
                if let Err(e) = signals.check() {
                    interrupt = Some(e);
                    return ControlFlow::Break(());
                }
                let point = match section.as_mut() {
                    Some(s) if s.takes(row) => Some(s.point(row.t, row.q, row.qd)),
                    Some(_) => return ControlFlow::Continue(()),
                    None => None,
                };
                if let (Some(label), None) = (row.event, point) {
                    events.push((data.len() / width, label.to_string()));
                }
                // Impact rows are drawn (the kink of a bounce); crossings are not samples.
                if row.event.is_none_or(|e| e.starts_with("impact ")) {
                    plot.push(row.t, row.q, row.qd, &row.invariants_less_jumps());
                }
                data.push(row.t);
                if let Some(b) = bodies.as_mut() {
                    b.eval(row.t, row.q, row.qd, &mut body_values);
                }
                data.extend(
                    row.q.iter().chain(row.qd).chain(row.invariants).chain(&body_values).chain(row.constraints),
                );
                if let Some(point) = point {
                    data.extend(section_columns.iter().map(|&k| point[k]));
                    section_points.push(point);
                }
                ControlFlow::Continue(())
            })
        });
        let (report, failure) = match result {
            Ok(r) => (r, None),
            Err(RunError::Failed { message, mut report }) => {
                if let Some(mech::RunFailure::StepBudget(b)) = &report.failure_reason {
                    report.failure = Some(format!("{}; {}", b.what_happened(), advice(b)));
                }
                let message = report.failure.clone().unwrap_or(message);
                (*report, Some(message))
            }
            Err(e) => return Err(self.refused(py, e)),
        };
        let interrupted = interrupt.as_ref().map(|_| view::simulate::Interrupted {
            signal: "SIGINT".into(),
            t: (data.len() >= width).then(|| data[data.len() - width]),
        });
        // The model was derived when it was loaded, not as part of this call.
        let timing = view::simulate::Timing { derive_seconds: 0.0, setup_seconds: first_row };
        let mut summary = view::simulate::summary_json(&report, &names, &timing, interrupted.as_ref(), &crate::TERMS);
        let mut text = view::simulate::summary_text(&report, &names, d, interrupted.as_ref(), &crate::TERMS);
        let figure = match &section {
            Some(s) => {
                let points = section_points.len();
                summary["section"] = view::simulate::section_json(s, points);
                text.push_str(&format!(
                    "{points} point{} on the section {}\n",
                    if points == 1 { "" } else { "s" },
                    s.condition().text
                ));
                Figure::Section(view::plot::SectionPlot {
                    title: d.model().name.clone(),
                    subtitle: view::plot::section_subtitle(s, points, &report),
                    axes: s.axes().clone(),
                    sets: vec![view::plot::SectionSet { label: String::new(), points: section_points }],
                })
            }
            None => Figure::Run(plot.into_plot(&d.model().name, &report, &names, &inv_names)),
        };
        let plot = Plot { figure };

        let out = PyDict::new(py);
        out.set_item("columns", columns)?;
        out.set_item("rows", data.len() / width)?;
        out.set_item("data", crate::f64_bytes(py, data))?;
        out.set_item("events", events)?;
        out.set_item("summary", summary.to_string())?;
        out.set_item("summary_text", text)?;
        out.set_item("failure", failure)?;
        let warnings: Vec<String> = report.warnings.iter().map(|w| view::simulate::warning(w, &crate::TERMS)).collect();
        out.set_item("warnings", warnings)?;
        out.set_item("interrupt", interrupt.map(|e| e.into_value(py)))?;
        out.set_item("plot", Bound::new(py, plot)?)?;
        Ok(out)
    }
}

/// The Poincaré section of `section=` drawn in the plane of `section_axes=`
/// (None without `section=`), refused as `lagrange.ModelError` naming the
/// argument at fault; `what` is the method that took them.
pub(crate) fn parse_section(
    py: Python<'_>,
    d: &Derivation,
    what: &str,
    section: Option<&str>,
    axes: Option<&str>,
) -> PyResult<Option<Section>> {
    let Some(text) = section else {
        return match axes {
            Some(_) => Err(errors::plain_error(py, what, "section_axes= needs section=", None)),
            None => Ok(None),
        };
    };
    let condition =
        StopCondition::parse(d, text, "section").map_err(|e| errors::expression_error(py, "section", text, &e))?;
    let s = Section::new(d, condition, axes)
        .map_err(|e| errors::expression_error(py, "section_axes", axes.unwrap_or_default(), &e))?;
    Ok(Some(s))
}

/// A run's setting that cannot be used, as `lagrange.ModelError` naming the
/// option (`what` is the method that took it).
pub(crate) fn setting_error(py: Python<'_>, what: &str, e: SettingError) -> PyErr {
    let message = match e {
        SettingError::UnknownMethod(message) => format!("method: {message}"),
        SettingError::NotPositive { setting, value } => format!("{setting} must be a positive number, not {value}"),
        SettingError::TooFewSamples { .. } => "samples needs at least 2 rows (both ends)".into(),
    };
    errors::plain_error(py, what, &message, None)
}
