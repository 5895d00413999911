//! `Model.report(...)`: the one-page HTML report `lagrange report` writes (the
//! derivation typeset, the mechanism animated, the run plotted, the audit and
//! the analyses), as text for a file or a notebook's `_repr_html_`.

use crate::errors::{self, guarded};
use crate::model::Derived;
use mech::{RunConfig, RunError, RunSettings};
use pyo3::prelude::*;
use std::ops::ControlFlow;
use std::time::Instant;

#[pymethods]
impl Derived {
    /// The page and, where the run failed midway, why (the page shows the
    /// rows up to there).
    #[pyo3(signature = (until, samples=2001, method=None, rtol=None))]
    fn report(
        &self,
        py: Python<'_>,
        until: f64,
        samples: usize,
        method: Option<String>,
        rtol: Option<f64>,
    ) -> PyResult<(String, Option<String>)> {
        guarded("report", || {
            let started = Instant::now();
            let settings = RunSettings {
                until: Some(until),
                method: method.as_deref(),
                rtol,
                atol: None,
                dt: None,
                samples: Some(samples),
                every_step: false,
            };
            let usage = |message: String| errors::plain_error(py, "report", &message, None);
            let config = RunConfig::from_settings(&settings).map_err(|e| crate::run::setting_error(py, "report", e))?;
            config.check().map_err(|e| usage(e.to_string()))?;
            let d = &self.d;
            let mut rows = view::report::Recorder::new();
            let mut first_row = None;
            let result = py.detach(|| {
                mech::simulate(d, &config, |row| {
                    first_row.get_or_insert_with(|| started.elapsed().as_secs_f64());
                    rows.push(row);
                    ControlFlow::Continue(())
                })
            });
            let (report, failure) = match result {
                Ok(r) => (r, None),
                Err(RunError::Failed { message, report }) => {
                    let message = report.failure.clone().unwrap_or(message);
                    (*report, Some(message))
                }
                Err(RunError::Input(e)) => return Err(self.error(py, &e)),
                Err(e) => return Err(usage(e.to_string())),
            };
            let names: Vec<String> = d.coordinate_names().iter().map(|s| s.to_string()).collect();
            let timing = view::simulate::Timing { derive_seconds: 0.0, setup_seconds: first_row };
            let summary = view::simulate::summary_json(&report, &names, &timing, None, &crate::TERMS);
            let data = rows.data(d, until, summary);
            Ok((view::report::page(&data), failure))
        })
    }
}
