//! `Model.export(to, path)`: the model's equations as a C99 file, a numpy
//! module or an FMI 2.0 FMU, as `lagrange export --to` writes them
//! (`mech::export`), written whole or not at all.

use crate::errors::{self, guarded};
use crate::model::Derived;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;

#[pymethods]
impl Derived {
    /// Writes the export `to` ("c", "python" or "fmu") to `path`.
    fn export(&self, py: Python<'_>, to: &str, path: PathBuf) -> PyResult<()> {
        guarded("exporting the model", || {
            // The derivation with the inputs as symbols: the export takes them as arguments.
            let d = self.shown();
            let version = env!("CARGO_PKG_VERSION");
            let bytes = match to {
                "c" => py.detach(|| mech::export::to_c(d, version)).map(String::into_bytes),
                "python" => py.detach(|| mech::export::to_python(d, version)).map(String::into_bytes),
                "fmu" => return self.fmu(py, &path),
                other => {
                    return Err(PyValueError::new_err(format!(
                        "cannot export to {other:?}: the targets are \"c\", \"python\" and \"fmu\""
                    )))
                }
            }
            .map_err(|e| self.error(py, &e))?;
            write(&path, &bytes)
        })
    }
}

impl Derived {
    /// The FMU: its sources, the binary from the system's C compiler, the archive.
    fn fmu(&self, py: Python<'_>, path: &std::path::Path) -> PyResult<()> {
        use mech::export::fmu;
        let stem = path.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
        let sources = py
            .detach(|| fmu::sources(self.shown(), env!("CARGO_PKG_VERSION"), &fmu::identifier(&stem)))
            .map_err(|e| self.error(py, &e))?;
        let compiler = sym::c_compiler().map_err(|e| {
            errors::lagrange_error(
                py,
                &format!(
                    "the FMU's binary is compiled at export time and needs a C compiler: {e}; install one (cc, gcc or clang), or name it with the CC environment variable"
                ),
            )
        })?;
        let bytes = py
            .detach(|| fmu::package(&sources, &compiler))
            .map_err(|e| errors::lagrange_error(py, &format!("cannot build the FMU: {e}")))?;
        write(path, &bytes)
    }
}

/// Writes the file whole (`mech::export::write_whole`), an I/O failure as `OSError`.
fn write(path: &std::path::Path, bytes: &[u8]) -> PyResult<()> {
    mech::export::write_whole(path, bytes)
        .map_err(|e| PyOSError::new_err(format!("cannot write {}: {e}", path.display())))
}
