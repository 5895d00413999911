//! `Model.export(to, path)`: the model's equations as a C99 file, a numpy
//! module or an FMI 2.0 FMU, as `lagrange export --to` writes them
//! (`mech::export`), written whole or not at all, and never over the model's
//! own file.

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
            self.refuse_own_file(&path)?;
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
    /// Refuses `path` where it is the model's own file, by any name (a link,
    /// another spelling): the export would replace the model, which the CLI
    /// refuses too. Only a file that exists can be the model.
    fn refuse_own_file(&self, path: &std::path::Path) -> PyResult<()> {
        let (Ok(model), Ok(out)) = (std::fs::metadata(&self.file), std::fs::metadata(path)) else { return Ok(()) };
        #[cfg(unix)]
        let same = {
            use std::os::unix::fs::MetadataExt;
            model.dev() == out.dev() && model.ino() == out.ino()
        };
        #[cfg(not(unix))]
        let same = {
            let _ = (model, out);
            std::fs::canonicalize(&self.file).ok() == std::fs::canonicalize(path).ok()
        };
        if same {
            return Err(PyValueError::new_err(format!(
                "{} is the model's own file {}: the export would replace it; choose another path",
                path.display(),
                self.file
            )));
        }
        Ok(())
    }

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
