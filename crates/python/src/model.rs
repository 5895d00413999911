//! A model read and derived: `lagrange.load`, `lagrange.Model.from_toml`, and
//! the derivation's reports. [`Derived`] keeps the model's text and file name
//! so that later errors (an analysis refusing the model) point into it.

use crate::errors::{self, guarded, Place};
use mech::Derivation;
use pyo3::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A model file parsed and derived.
#[pyclass(module = "lagrange._native", frozen)]
pub struct Derived {
    /// The file's name as given (`<string>` for text).
    pub file: String,
    /// Its text.
    pub source: String,
    /// The derivation.
    pub d: Derivation,
}

impl Derived {
    /// Where errors about the model point.
    pub fn place(&self) -> Place<'_> {
        Place { file: &self.file, text: &self.source }
    }

    /// A model error as `lagrange.ModelError`.
    pub fn error(&self, py: Python<'_>, e: &mech::ModelError) -> PyErr {
        errors::model_error(py, &self.place(), e)
    }
}

/// Parameter overrides in the model's terms.
pub(crate) fn overrides(set: Option<HashMap<String, f64>>) -> Vec<(String, f64)> {
    let mut v: Vec<(String, f64)> = set.unwrap_or_default().into_iter().collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// Reads a file the model names (a body file), at most the library's file size.
pub(crate) fn read_text(path: &Path) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if meta.len() > mech::MAX_FILE_BYTES as u64 {
        return Err(format!("{}: larger than {} bytes", path.display(), mech::MAX_FILE_BYTES));
    }
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn derive(py: Python<'_>, file: String, source: String, set: &[(String, f64)], folder: &Path) -> PyResult<Derived> {
    guarded("deriving the model", || {
        let files = |name: &str| read_text(&folder.join(name));
        let place = Place { file: &file, text: &source };
        let parsed = py.detach(|| mech::Model::parse_with(&source, set, &files));
        let model = parsed.map_err(|e| errors::model_error(py, &place, &e))?;
        let d = py
            .detach(|| Derivation::new(model.with_inputs_applied()))
            .map_err(|e| errors::model_error(py, &place, &e))?;
        Ok(Derived { file: file.clone(), source: source.clone(), d })
    })
}

/// Reads and derives a model file; body files are read from its folder.
#[pyfunction]
#[pyo3(signature = (path, set=None))]
pub fn load(py: Python<'_>, path: PathBuf, set: Option<HashMap<String, f64>>) -> PyResult<Derived> {
    let file = path.display().to_string();
    let source =
        read_text(&path).map_err(|e| errors::plain_error(py, &file, &format!("cannot read the file: {e}"), None))?;
    let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
    derive(py, file, source, &overrides(set), &folder)
}

/// Derives a model given as TOML text; body files are read from `folder`.
#[pyfunction]
#[pyo3(signature = (text, name="<string>".to_string(), set=None, folder=None))]
pub fn from_toml(
    py: Python<'_>,
    text: String,
    name: String,
    set: Option<HashMap<String, f64>>,
    folder: Option<PathBuf>,
) -> PyResult<Derived> {
    if text.len() > mech::MAX_FILE_BYTES {
        let message = format!("the model text is larger than {} bytes", mech::MAX_FILE_BYTES);
        return Err(errors::plain_error(py, &name, &message, None));
    }
    derive(py, name, text, &overrides(set), &folder.unwrap_or_else(|| PathBuf::from(".")))
}

#[pymethods]
impl Derived {
    /// The file's name as given.
    #[getter]
    fn file(&self) -> &str {
        &self.file
    }

    /// The model file's text.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> String {
        self.d.model().name.clone()
    }

    /// The coordinates' names, in order.
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.d.coordinate_names().iter().map(|s| s.to_string()).collect()
    }

    /// The parameters and their values (after overrides), in the model's order.
    #[getter]
    fn parameters(&self) -> Vec<(String, f64)> {
        self.d.model().parameters.iter().map(|p| (p.name.clone(), p.value)).collect()
    }

    /// The initial state (q, q') of `[initial]`.
    fn initial(&self, py: Python<'_>) -> PyResult<(Vec<f64>, Vec<f64>)> {
        self.d.model().initial_state().map_err(|e| self.error(py, &e))
    }

    /// Whether the model has constraints.
    #[getter]
    fn constrained(&self) -> bool {
        !self.d.constraints().is_empty()
    }

    /// The `lagrange.derive/1` report as JSON text.
    fn derive_json(&self) -> PyResult<String> {
        let report = mech::DeriveReport::new(&self.d);
        serde_json::to_string(&report).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
    }

    /// The derivation as the CLI's text.
    fn text(&self) -> String {
        view::derive::text(&self.d)
    }

    /// The derivation as LaTeX, as the CLI's `--format latex`.
    fn latex(&self) -> String {
        view::derive::latex(&self.d)
    }
}
