//! `lagrange._native`: the extension module under the `lagrange` Python package.
//!
//! This layer is thin on purpose. It turns Python values into the library's
//! inputs, runs `mech`, and hands back what the CLI would print: JSON text of
//! the output contracts, numbers as little-endian `f64` bytes that the Python
//! side views as numpy arrays without a copy, and expressions as text of the
//! expression language. The Python package (`crates/python/python/lagrange`)
//! builds the objects people use from these. Long runs release the GIL; bad
//! input becomes `lagrange.ModelError` with file, line and column; no Rust
//! panic crosses into Python (PyO3 turns one into `PanicException`, and the
//! entry points here catch them first to say what failed).

use pyo3::prelude::*;

mod analyses;
mod errors;
mod export;
mod expr;
mod model;
mod report;
mod rhs;
mod run;
mod signals;
mod sweep;

/// How the text outputs name the settings a Python user gives.
pub const TERMS: view::Terms = view::Terms {
    step: "dt",
    start_at: "at",
    full_output: "the report's fields",
    animation: "animate()",
    until: "until",
    method: "method",
};

/// Numbers as little-endian f64 bytes, which the Python side views with
/// `numpy.frombuffer` without a copy.
pub fn f64_bytes<'py>(py: Python<'py>, values: impl IntoIterator<Item = f64>) -> Bound<'py, pyo3::types::PyBytes> {
    let bytes: Vec<u8> = values.into_iter().flat_map(f64::to_le_bytes).collect();
    pyo3::types::PyBytes::new(py, &bytes)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::Derived>()?;
    m.add_class::<rhs::Rhs>()?;
    m.add_class::<rhs::Jac>()?;
    m.add_class::<run::Plot>()?;
    m.add_function(wrap_pyfunction!(model::load, m)?)?;
    m.add_function(wrap_pyfunction!(model::from_toml, m)?)?;
    m.add_function(wrap_pyfunction!(expr::tree, m)?)?;
    m.add_function(wrap_pyfunction!(expr::latex, m)?)?;
    m.add_function(wrap_pyfunction!(expr::check, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::inertia, m)?)?;
    m.add_function(wrap_pyfunction!(analyses::extremal, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::merge, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::table, m)?)?;
    m.add("METHODS", num::Method::ALL.iter().map(|m| (m.name(), m.description())).collect::<Vec<_>>())?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
