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
use pyo3::types::{PyByteArray, PyBytes, PyList};
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
        let numpy = py.import("numpy").and_then(|np| {
            let float64 = np.getattr("dtype")?.call1(("float64",))?;
            Ok((np.getattr("ndarray")?.unbind(), float64.unbind()))
        });
        Ok(Rhs { system: Mutex::new(system), dim, name: self.d.model().name.clone(), numpy: numpy.ok() })
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
            system.rhs(t, &y, &mut dy).map_err(|e| right_hand_side_error(py, t, &e))?;
        }
        PyList::new(py, dy)
    }

    /// dy/dt of `k` states given as little-endian f64 bytes, state after
    /// state (2n values each), as bytes in the same layout: the batch path of
    /// the Python wrapper, which reads and returns numpy arrays.
    fn many<'py>(&self, py: Python<'py>, t: f64, y: &[u8], k: usize) -> PyResult<Bound<'py, PyByteArray>> {
        if y.len() != 8 * k * self.dim {
            return Err(PyValueError::new_err(format!(
                "y has {} values; {} states of {} have {}",
                y.len() / 8,
                k,
                self.name,
                k * self.dim
            )));
        }
        let y: Vec<f64> = y.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        let mut dy = vec![0.0; y.len()];
        let mut all = || {
            let mut system = self.system.lock().unwrap_or_else(|e| e.into_inner());
            y.chunks_exact(self.dim).zip(dy.chunks_exact_mut(self.dim)).try_for_each(|(y, dy)| system.rhs(t, y, dy))
        };
        // Releasing the GIL costs more than one evaluation takes: only for batches.
        let result = if k >= 64 { py.detach(all) } else { all() };
        result.map_err(|e| right_hand_side_error(py, t, &e))?;
        Ok(PyByteArray::new(py, &dy.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()))
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

/// A failed evaluation as `lagrange.RunError`.
fn right_hand_side_error(py: Python<'_>, t: f64, e: &num::RhsError) -> PyErr {
    errors::raise(py, "RunError", |kw| {
        kw.set_item("message", format!("the right-hand side at t = {t}: {e}"))?;
        kw.set_item("t", t)
    })
}

/// The Jacobian of a model's right-hand side with respect to y, from the
/// symbolic derivatives (`mech::StateJacobian`).
#[pyclass(module = "lagrange._native", frozen)]
pub struct Jac {
    jacobian: Mutex<mech::StateJacobian>,
    dim: usize,
}

#[pymethods]
impl Derived {
    /// The compiled Jacobian of the right-hand side.
    fn jac(&self, py: Python<'_>) -> PyResult<Jac> {
        let jacobian = py.detach(|| mech::StateJacobian::new(&self.d)).map_err(|e| self.error(py, &e))?;
        let dim = jacobian.dim();
        Ok(Jac { jacobian: Mutex::new(jacobian), dim })
    }
}

#[pymethods]
impl Jac {
    /// ∂(dy/dt)/∂y at (t, y), y as 2n little-endian f64 bytes: (2n)² values,
    /// row by row, as bytes.
    fn eval<'py>(&self, py: Python<'py>, t: f64, y: &[u8]) -> PyResult<Bound<'py, PyByteArray>> {
        if y.len() != 8 * self.dim {
            return Err(PyValueError::new_err(format!("y has {} values, not {}", y.len() / 8, self.dim)));
        }
        let y: Vec<f64> = y.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        let mut out = vec![0.0; self.dim * self.dim];
        let mut jacobian = self.jacobian.lock().unwrap_or_else(|e| e.into_inner());
        jacobian.eval(t, &y, &mut out).map_err(|e| right_hand_side_error(py, t, &e))?;
        Ok(PyByteArray::new(py, &out.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()))
    }

    /// The length of y.
    #[getter]
    fn dim(&self) -> usize {
        self.dim
    }
}
