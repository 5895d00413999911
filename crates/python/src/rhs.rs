//! `Model.rhs()`: the compiled right-hand side `f(t, y) -> dy/dt` with
//! `y = [q, q']`, for people's own integrators (`scipy.integrate.solve_ivp`).
//!
//! It is the same compiled code `simulate` runs (the Lagrange form of
//! `mech::System`, native once Cranelift has compiled it), called once per
//! evaluation. A model with constraints has no such function without its
//! multipliers, and is refused.

use crate::errors;
use crate::model::Derived;
use mech::{Form, System};
use num::OdeSystem;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::sync::Mutex;

/// The right-hand side of a model's equations of motion as a Python callable.
#[pyclass(module = "lagrange._native", frozen)]
pub struct Rhs {
    system: Mutex<System>,
    dim: usize,
    /// The model's name, for messages.
    name: String,
}

#[pymethods]
impl Derived {
    /// The compiled right-hand side (see the module documentation).
    fn rhs(&self, py: Python<'_>) -> PyResult<Rhs> {
        if !self.d.constraints().is_empty() {
            let message = "rhs() needs a model without constraints: the constraint forces depend on the multipliers, which simulate() solves for at every step";
            return Err(errors::plain_error(py, &self.file, message, None));
        }
        let system = py.detach(|| mech::Dynamics::new(&self.d).system(Form::Lagrange));
        let dim = 2 * self.d.coordinate_names().len();
        Ok(Rhs { system: Mutex::new(system), dim, name: self.d.model().name.clone() })
    }
}

#[pymethods]
impl Rhs {
    /// `f(t, y)`: dy/dt as a list, y = [q..., q'...] in the model's order.
    fn __call__<'py>(&self, py: Python<'py>, t: f64, y: Vec<f64>) -> PyResult<Bound<'py, PyList>> {
        if y.len() != self.dim {
            return Err(PyValueError::new_err(format!(
                "y has {} components; {} has {} ([q, q'])",
                y.len(),
                self.name,
                self.dim
            )));
        }
        let mut dy = vec![0.0; self.dim];
        {
            let mut system = self.system.lock().unwrap_or_else(|e| e.into_inner());
            system.rhs(t, &y, &mut dy).map_err(|e| {
                errors::raise(py, "RunError", |kw| {
                    kw.set_item("message", format!("the right-hand side at t = {t}: {e}"))?;
                    kw.set_item("t", t)
                })
            })?;
        }
        PyList::new(py, dy)
    }

    /// The length of y.
    #[getter]
    fn dim(&self) -> usize {
        self.dim
    }

    fn __repr__(&self) -> String {
        format!("<compiled right-hand side of {}: y = [q, q'], {} components>", self.name, self.dim)
    }
}
