//! `lagrange.sweep`: a grid of runs on the cores of this machine, one shard
//! of it (the CLI's `--shard i/n`), and the merge of shards computed
//! elsewhere (the Dask workers of `lagrange.sweep(client=...)`).
//!
//! Tables cross the boundary as the CLI's sweep CSV (numbers in the shortest
//! form that reads back exactly, so a merged table equals a one-process
//! sweep's bit for bit) and are read into columns by [`table`].

use crate::errors::{self, guarded};
use crate::model::Derived;
use crate::signals::Signals;
use mech::{Grid, SettingError, Shard, Sweep, SweepConfig, SweepError, SweepTable};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ops::ControlFlow;

/// The options of a sweep, as Python passes them.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Options {
    grid: String,
    until: f64,
    method: Option<String>,
    rtol: Option<f64>,
    atol: Option<f64>,
    lyapunov: bool,
    shard: Option<(usize, usize)>,
    threads: Option<usize>,
}

fn sweep_error(py: Python<'_>, what: &str, e: SweepError) -> PyErr {
    errors::plain_error(py, what, &e.to_string(), None)
}

#[pymethods]
impl Derived {
    /// Runs the sweep (or one shard of it). Returns a dict: `csv` (the table
    /// as the CLI writes it, rows in run order) and `interrupt` (the exception
    /// a signal handler raised, or None; the table then holds a prefix).
    fn sweep<'py>(&self, py: Python<'py>, options: Options) -> PyResult<Bound<'py, PyDict>> {
        guarded("sweep", || {
            let grid = Grid::parse(&options.grid, self.d.model()).map_err(|e| sweep_error(py, "grid", e))?;
            if !(options.until.is_finite() && options.until > 0.0) {
                let message = format!("until must be a positive time, not {}", options.until);
                return Err(errors::plain_error(py, "until", &message, None));
            }
            let shard = match options.shard {
                None => Shard::default(),
                Some((index, count)) if count >= 1 && index < count => Shard { index, count },
                Some((index, count)) => {
                    let message = format!("shard ({index}, {count}) is not a part: give (i, n) with 0 <= i < n");
                    return Err(errors::plain_error(py, "shard", &message, None));
                }
            };
            let settings = mech::SweepSettings {
                until: options.until,
                method: options.method.as_deref(),
                rtol: options.rtol,
                atol: options.atol,
                lyapunov: options.lyapunov,
                shard,
                threads: options.threads,
            };
            let config = SweepConfig::from_settings(&settings).map_err(|e| match e {
                SettingError::UnknownMethod(message) => errors::plain_error(py, "method", &message, None),
                SettingError::NotPositive { setting, value } => {
                    errors::plain_error(py, setting, &format!("{setting} must be a positive number, not {value}"), None)
                }
                SettingError::TooFewSamples { .. } => {
                    errors::plain_error(py, "samples", "samples needs at least 2 rows (both ends)", None)
                }
            })?;
            let sweep = Sweep::new(&self.d, &grid, &config).map_err(|e| match e {
                SweepError::Model(m) => self.error(py, &m),
                other => sweep_error(py, "sweep", other),
            })?;
            let mut csv = sweep.header().to_csv();
            let mut interrupt: Option<PyErr> = None;
            let result = py.detach(|| {
                let mut signals = Signals::new();
                sweep.run(0, &|| {}, &|| false, |row| {
                    row.write_csv(&mut csv);
                    if let Err(e) = signals.check() {
                        interrupt = Some(e);
                        return ControlFlow::Break(());
                    }
                    ControlFlow::Continue(())
                })
            });
            result.map_err(|e| sweep_error(py, "sweep", e))?;
            let out = PyDict::new(py);
            out.set_item("csv", csv)?;
            out.set_item("interrupt", interrupt.map(|e| e.into_value(py)))?;
            Ok(out)
        })
    }
}

/// Merges shard tables (`(name, csv)` pairs) into the whole sweep's CSV.
#[pyfunction]
pub fn merge(py: Python<'_>, shards: Vec<(String, String)>) -> PyResult<String> {
    guarded("merge", || {
        let mut tables = Vec::with_capacity(shards.len());
        for (name, text) in &shards {
            let table = SweepTable::parse(text, name).map_err(|e| sweep_error(py, name, e))?;
            tables.push((name.clone(), table));
        }
        let merged = mech::merge(&tables).map_err(|e| sweep_error(py, "merge", e))?;
        Ok(merged.to_csv())
    })
}

/// Reads a sweep CSV into columns: a dict with `meta` (provenance pairs),
/// `columns` (the numeric columns' names), `runs` (the run indices),
/// `data` (row-major f64 bytes) and `failures` (one string per row).
#[pyfunction]
pub fn table<'py>(py: Python<'py>, csv: &str, name: &str) -> PyResult<Bound<'py, PyDict>> {
    guarded("table", || {
        let table = SweepTable::parse(csv, name).map_err(|e| sweep_error(py, name, e))?;
        let columns = &table.header.columns;
        let out = PyDict::new(py);
        out.set_item("meta", table.header.meta.clone())?;
        out.set_item("columns", columns[1..columns.len() - 1].to_vec())?;
        out.set_item("runs", table.rows.iter().map(|r| r.run).collect::<Vec<_>>())?;
        out.set_item("data", crate::f64_bytes(py, table.rows.iter().flat_map(|r| r.values.iter().copied())))?;
        out.set_item("failures", table.rows.iter().map(|r| r.failure.clone()).collect::<Vec<_>>())?;
        Ok(out)
    })
}
