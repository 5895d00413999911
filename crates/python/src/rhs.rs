//! `Model.rhs()`: the compiled right-hand side `f(t, y) -> dy/dt` with
//! `y = [q, q']`, for people's own integrators (`scipy.integrate.solve_ivp`).
//!
//! It is the same compiled code `simulate` runs (the Lagrange form of
//! `mech::System`, native once Cranelift has compiled it), called once per
//! evaluation. A model with constraints has no such function without its
//! multipliers, and is refused.
//!
//! `solve_ivp` passes y as a float64 numpy array. Read element by element
//! through the sequence protocol, each component becomes a numpy scalar
//! first, which costs more than the compiled function itself; such an array
//! is read from its bytes in one copy instead (anything else, a list, a
//! tuple, another dtype, goes the general way).

use crate::errors;
use crate::model::Derived;
use mech::{Form, System};
use num::OdeSystem;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};
use std::sync::Mutex;

/// The right-hand side of a model's equations of motion as a Python callable.
#[pyclass(module = "lagrange._native", frozen)]
pub struct Rhs {
    system: Mutex<System>,
    dim: usize,
    /// The model's name, for messages.
    name: String,
    /// numpy's array type and its native float64 dtype, for the fast read of y
    /// (None if numpy cannot be imported: then every y goes the general way).
    numpy: Option<(Py<PyAny>, Py<PyAny>)>,
    /// The Python model it was made from, which it pickles as (None: made
    /// without one, and not picklable).
    owner: Option<Py<PyAny>>,
}

#[pymethods]
impl Derived {
    /// The compiled right-hand side (see the module documentation).
    #[pyo3(signature = (owner=None))]
    fn rhs(&self, py: Python<'_>, owner: Option<Py<PyAny>>) -> PyResult<Rhs> {
        if !self.d.constraints().is_empty() {
            let message = "rhs() needs a model without constraints: the constraint forces depend on the multipliers, which simulate() solves for at every step";
            return Err(errors::plain_error(py, &self.file, message, None));
        }
        let system = py.detach(|| mech::Dynamics::new(&self.d).system(Form::Lagrange));
        let dim = 2 * self.d.coordinate_names().len();
        let numpy = py.import("numpy").and_then(|np| {
            let float64 = np.getattr("dtype")?.call1(("float64",))?;
            Ok((np.getattr("ndarray")?.unbind(), float64.unbind()))
        });
        Ok(Rhs { system: Mutex::new(system), dim, name: self.d.model().name.clone(), numpy: numpy.ok(), owner })
    }
}

#[pymethods]
impl Rhs {
    /// `f(t, y)`: dy/dt as a list, y = [q..., q'...] in the model's order.
    fn __call__<'py>(&self, py: Python<'py>, t: f64, y: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyList>> {
        let y = self.state(y)?;
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

    /// Pickles as `model.rhs()`: the model travels as its text and the
    /// right-hand side is compiled again where it is unpickled.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (Py<PyAny>,))> {
        let Some(owner) = &self.owner else {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "this right-hand side was made without its lagrange.Model and cannot be pickled; pickle the model, or take model.rhs()",
            ));
        };
        let call = py.import("operator")?.getattr("methodcaller")?.call1(("rhs",))?;
        Ok((call, (owner.clone_ref(py),)))
    }
}

impl Rhs {
    /// y as floats: a one-dimensional float64 numpy array from its bytes,
    /// anything else through the sequence protocol.
    fn state(&self, y: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let py = y.py();
        if let Some((ndarray, float64)) = &self.numpy {
            if y.get_type().is(ndarray.bind(py))
                && y.getattr(intern!(py, "dtype"))?.is(float64.bind(py))
                && y.getattr(intern!(py, "ndim"))?.extract::<usize>()? == 1
            {
                let bytes = y.call_method0(intern!(py, "tobytes"))?;
                let bytes = bytes.cast::<PyBytes>()?.as_bytes();
                return Ok(bytes
                    .chunks_exact(8)
                    .map(|c| {
                        let mut word = [0u8; 8];
                        word.copy_from_slice(c);
                        f64::from_ne_bytes(word)
                    })
                    .collect());
            }
        }
        y.extract().map_err(|e: PyErr| {
            PyTypeError::new_err(format!("y must be a sequence of floats ([q, q']): {}", e.value(py)))
        })
    }
}
