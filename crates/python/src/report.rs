//! `Model.report(...)`: the one-page HTML report `lagrange report` writes (the
//! derivation typeset, the mechanism animated, the run plotted, the audit and
//! the analyses), as text for a file or a notebook's `_repr_html_`.

use crate::errors::{self, guarded};
use crate::model::Derived;
use mech::{RunConfig, RunError, RunSettings};
use pyo3::prelude::*;
use std::time::Instant;

#[pymethods]
impl Derived {
    /// The page and, where the run failed midway, why (the page shows the
    /// rows up to there).
    #[pyo3(signature = (until, samples=2001, method=None, rtol=None, section=None, section_axes=None))]
    #[allow(clippy::too_many_arguments)]
    fn report(
        &self,
        py: Python<'_>,
        until: f64,
        samples: usize,
        method: Option<String>,
        rtol: Option<f64>,
        section: Option<String>,
        section_axes: Option<String>,
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
            let mut config =
                RunConfig::from_settings(&settings).map_err(|e| crate::run::setting_error(py, "report", e))?;
            let d = &self.d;
            let mut section = crate::run::parse_section(py, d, "report", section.as_deref(), section_axes.as_deref())?;
            if let Some(s) = &section {
                config.crossings.push(s.condition().clone());
            }
            config.check().map_err(|e| usage(e.to_string()))?;
            let page =
                py.detach(|| view::report::run_page(d, &config, until, started, 0.0, &crate::TERMS, section.as_mut()));
            match page {
                Ok(page) => Ok((page.html, page.failure)),
                Err(RunError::Input(e)) => Err(self.error(py, &e)),
                Err(e) => Err(usage(e.to_string())),
            }
        })
    }
}
