//! Expressions of the expression language from Python: their tree (for
//! `.to_sympy()`), their LaTeX, and their values over numpy arrays.
//!
//! Expressions cross the boundary as text, which the language guarantees to
//! parse back to the same expression; each call parses it in a fresh pool.

use crate::errors;
use crate::model::Derived;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use sym::{Func, Node, Number, Pool};

fn parse(py: Python<'_>, pool: &mut Pool, text: &str) -> PyResult<sym::ExprId> {
    pool.parse(text).map_err(|e| {
        let m = mech::ModelError::at(e.span.start as usize..e.span.end as usize, e.to_string());
        errors::expression_error(py, "expression", text, &m)
    })
}

/// Checks that `text` parses; raises `ModelError` at the place it does not.
#[pyfunction]
pub fn check(py: Python<'_>, text: &str) -> PyResult<String> {
    let mut pool = Pool::default();
    let e = parse(py, &mut pool, text)?;
    Ok(pool.display(e).to_string())
}

/// The expression as LaTeX (dots for velocities, Greek letters for their names).
#[pyfunction]
pub fn latex(py: Python<'_>, text: &str) -> PyResult<String> {
    let mut pool = Pool::default();
    let e = parse(py, &mut pool, text)?;
    Ok(pool.latex(e).to_string())
}

/// The expression as nested tuples: `("num", "1/2")`, `("pi",)`,
/// `("sym", name, order)`, `("add", [..])`, `("mul", [..])`, `("pow", a, b)`,
/// `("call", "sin", a)`, `("atan2", y, x)`. Numbers come as exact text
/// (`"1/2"`, `"0.1"`), so SymPy can keep rationals exact.
#[pyfunction]
pub fn tree<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    let mut pool = Pool::default();
    let e = parse(py, &mut pool, text)?;
    node(py, &pool, e)
}

fn node<'py>(py: Python<'py>, pool: &Pool, e: sym::ExprId) -> PyResult<Bound<'py, PyAny>> {
    let list = |ids: &[sym::ExprId]| -> PyResult<Vec<Bound<'py, PyAny>>> {
        ids.iter().map(|&id| node(py, pool, id)).collect()
    };
    let t = match pool.node(e) {
        Node::Num(n) => {
            PyTuple::new(py, ["num".into_pyobject(py)?.into_any(), number(n).into_pyobject(py)?.into_any()])?
        }
        Node::Pi => PyTuple::new(py, ["pi"])?,
        Node::Sym(s) => ("sym", pool.name_str(s.name).to_string(), s.order).into_pyobject(py)?,
        Node::Add(xs) => ("add", list(xs)?).into_pyobject(py)?,
        Node::Mul(xs) => ("mul", list(xs)?).into_pyobject(py)?,
        Node::Pow(a, b) => ("pow", node(py, pool, *a)?, node(py, pool, *b)?).into_pyobject(py)?,
        Node::Func(f, a) => ("call", func_name(*f), node(py, pool, *a)?).into_pyobject(py)?,
        Node::Atan2(y, x) => ("atan2", node(py, pool, *y)?, node(py, pool, *x)?).into_pyobject(py)?,
    };
    Ok(t.into_any())
}

fn func_name(f: Func) -> &'static str {
    f.name()
}

/// A number as exact text: `p/q` for a rational, the shortest round-trip
/// decimal for a float.
fn number(n: &Number) -> String {
    match n {
        Number::Rational(r) => r.to_string(),
        Number::Float(x) => format!("{x:?}"),
    }
}

#[pymethods]
impl Derived {
    /// Evaluates `text` at the given values: `names[k]` takes the `count`
    /// values in `columns[k]` (little-endian f64 bytes, all of one length).
    /// Parameters not given take the model's values. Returns `count` values
    /// as bytes.
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        text: &str,
        names: Vec<String>,
        columns: Vec<Vec<u8>>,
        count: usize,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let mut pool = Pool::default();
        let e = parse(py, &mut pool, text)?;
        let used: Vec<String> = pool.symbols(e).into_iter().map(|s| pool.symbol_text(s)).collect();
        refuse_unknown(&self.d, &names, &used)?;
        let mut inputs = Vec::new();
        let mut values: Vec<Vec<f64>> = Vec::new();
        for s in pool.symbols(e) {
            let name = pool.symbol_text(s);
            let given = names.iter().position(|n| *n == name);
            let column = match given {
                Some(k) => {
                    let bytes = &columns[k];
                    if bytes.len() != 8 * count {
                        return Err(PyValueError::new_err(format!(
                            "{name}: {} values, expected {count}",
                            bytes.len() / 8
                        )));
                    }
                    bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect()
                }
                None if s.order == 0 => match self.d.model().parameter(&name) {
                    Some(v) => vec![v; count],
                    None => return Err(PyValueError::new_err(format!("no value for {name} (give it as {name}=...)"))),
                },
                None => {
                    return Err(PyValueError::new_err(format!("no value for {name} (give it as {{\"{name}\": ...}})")))
                }
            };
            let id = pool.sym(s);
            inputs.push(id);
            values.push(column);
        }
        let mut tape =
            sym::Tape::compile(&pool, &[e], &inputs).map_err(|err| PyValueError::new_err(err.to_string()))?;
        let mut out = vec![0.0; count];
        let mut row = vec![0.0; inputs.len()];
        let mut one = [0.0];
        for i in 0..count {
            for (slot, column) in row.iter_mut().zip(&values) {
                *slot = column[i];
            }
            tape.eval(&row, &mut one);
            out[i] = one[0];
        }
        Ok(crate::f64_bytes(py, out))
    }
}

/// Refuses a given name that is neither in the expression nor a name of the
/// model (a misspelt `gg=1.0` would otherwise be ignored), naming the closest.
fn refuse_unknown(d: &mech::Derivation, given: &[String], used: &[String]) -> PyResult<()> {
    let model = d.model();
    let mut known: Vec<String> = vec!["t".into()];
    for c in d.coordinate_names() {
        known.extend([c.to_string(), format!("{c}'"), format!("{c}''"), format!("p_{c}")]);
    }
    known.extend(model.parameters.iter().map(|p| p.name.clone()));
    known.extend(model.inputs.iter().map(|u| u.name.clone()));
    known.extend(d.constraints().list.iter().map(|c| format!("lambda_{}", c.name)));
    for name in given {
        if used.contains(name) || known.contains(name) {
            continue;
        }
        let closest = known
            .iter()
            .map(|k| (strsim::damerau_levenshtein(name, k), k))
            .min_by_key(|(distance, _)| *distance)
            .filter(|(distance, _)| *distance <= name.chars().count().max(2))
            .map(|(_, k)| format!(" (did you mean {k:?}?)"))
            .unwrap_or_default();
        let mut list = known.iter().take(20).map(String::as_str).collect::<Vec<_>>().join(", ");
        if known.len() > 20 {
            list.push_str(", …");
        }
        return Err(PyValueError::new_err(format!(
            "{name:?} is not a name of this model{closest}: the names are the coordinates, their velocities and momenta, the parameters and t ({list})"
        )));
    }
    Ok(())
}
