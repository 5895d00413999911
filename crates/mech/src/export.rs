//! Code that leaves lagrange: a derivation's equations of motion written as a
//! C99 file that needs nothing beyond libm ([`to_c`]), as a Python module that
//! needs only numpy ([`to_python`]), or as an FMI 2.0 FMU for Model Exchange
//! and Co-Simulation ([`fmu`]), for controllers, optimizers and co-simulations
//! that call a right-hand side from their own code.
//!
//! Every function reads the state `[q, q']` in the model's coordinate order,
//! the parameters in the model file's `[parameters]` order and, for a model
//! with `[inputs]`, the inputs u in their file order, and computes from the same
//! expressions `lagrange derive` prints: M and f of `M q'' = f`, B = ∂f/∂u, the
//! energy function h (H written in q and q'), the energy T + U₀ where the model
//! gives T and U, and for `[[constraints]]` their residuals, Jacobian A and
//! multipliers λ of `M q'' = f + Aᵀλ`. The right-hand side solves `M q'' = f`
//! (with the constraints differentiated to acceleration level, the saddle-point
//! system `[M −Aᵀ; A 0] [q''; λ] = [f; c]`) by Gaussian elimination with
//! partial pivoting, written into the file. Each function's expressions are one
//! straight-line block over their shared subexpressions (`sym::emit`).
//!
//! What a run adds beyond the equations is not exported: the projection that
//! keeps a constrained run on its constraints (the exported right-hand side
//! drifts off them as any index-reduced system does; the residual functions
//! measure by how much), and the audit.

mod c;
pub mod fmu;
mod python;

pub use c::{to_c, SINGULAR_PIVOT_RATIO};
pub use python::to_python;

use crate::derive::Derivation;
use crate::error::ModelError;
use std::ops::Range;
use sym::{ExprId, Pool, Tape};

/// Writes `bytes` as the whole of the file at `path`.
///
/// A regular file (or none yet) is written to a new file beside it, which is then
/// renamed to it: the file is the old one or the whole new one, never a part (an
/// export that fails, or is stopped, leaves an earlier export as it was). A
/// symbolic link is followed: the file it names is replaced so, and the link stays.
/// A pipe or a device (`/dev/stdout`, a FIFO another program reads, `/dev/null`)
/// is written into, as a shell's `>` would; renaming onto it would replace the
/// node itself with a regular file. A folder is refused.
pub fn write_whole(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::{Error, ErrorKind, Write};
    // `metadata` and `open` follow links as the system does, the magic ones of
    // /proc (`/dev/stdout`) included; the rename needs the file's own path.
    let path = &match std::fs::metadata(path) {
        Ok(meta) if meta.is_dir() => {
            return Err(Error::new(ErrorKind::InvalidInput, "it is a folder; an export is written to a file"))
        }
        Ok(meta) if !meta.is_file() => {
            let mut node = std::fs::OpenOptions::new().write(true).open(path)?;
            return node.write_all(bytes).and_then(|()| node.flush());
        }
        Ok(_) => std::fs::canonicalize(path)?,
        Err(e) if e.kind() == ErrorKind::NotFound => follow_link(path)?,
        Err(e) => return Err(e),
    };
    let name = path.file_name().map_or_else(|| "export".into(), |n| n.to_string_lossy().into_owned());
    let temporary = path.with_file_name(format!(".{name}.{}.part", std::process::id()));
    let written = std::fs::File::create(&temporary).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    match written.and_then(|()| std::fs::rename(&temporary, path)) {
        Ok(()) => Ok(()),
        Err(e) => {
            let _ = std::fs::remove_file(&temporary);
            Err(e)
        }
    }
}

/// The file a path that names nothing yet stands for: the path itself, or, for
/// a symbolic link to nothing, the file at the end of its links, which the
/// export creates.
fn follow_link(path: &std::path::Path) -> std::io::Result<std::path::PathBuf> {
    let mut at = path.to_path_buf();
    // A bound on the links followed, as the system's own (ELOOP).
    for _ in 0..40 {
        match std::fs::symlink_metadata(&at) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let target = std::fs::read_link(&at)?;
                at = match at.parent() {
                    Some(folder) if target.is_relative() => folder.join(target),
                    _ => target,
                };
            }
            Ok(_) => return Ok(at),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(at),
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "too many levels of symbolic links"))
}

/// Refuses a model with `[[impacts]]`: exported code is a right-hand side with
/// no events, and would carry the motion through each surface as if it were not
/// there (an exported bouncing ball falls through its floor). Refused rather than
/// exported without a word; the smooth motion between impacts is the export of
/// the model without its `[[impacts]]` tables.
fn refuse_impacts(d: &Derivation) -> Result<(), ModelError> {
    let Some(first) = d.model().impacts.first() else { return Ok(()) };
    Err(ModelError::at(
        first.name_span.clone(),
        format!(
            "impact '{}' cannot be exported: exported code has no events, so its motion would pass through the surface {} = 0 as if it were not there",
            first.name,
            d.pool().display(first.surface.expr)
        ),
    )
    .with_help(
        "to export the smooth motion between impacts, export a copy of the model without its [[impacts]] tables, and apply the restitution law where the calling program finds φ = 0 (derive prints the law, ∇φ and the normal velocity)",
    ))
}

/// The symbols exported code reads, in the order of a tape's inputs: the
/// derivation's layout `[q, q', t, parameters]`, then the inputs u, then what a
/// function adds of its own (q'' and λ in Python's Jacobian).
struct Reads {
    symbols: Vec<ExprId>,
    t: usize,
    parameters: Range<usize>,
    inputs: Range<usize>,
}

impl Reads {
    /// The layout and the inputs, then `extra`.
    fn new(d: &Derivation, extra: &[ExprId]) -> Reads {
        let layout = d.layout();
        let mut symbols = layout.symbols().to_vec();
        let start = symbols.len();
        symbols.extend(d.inputs());
        let inputs = start..symbols.len();
        symbols.extend(extra);
        Reads { symbols, t: layout.t(), parameters: layout.parameters(), inputs }
    }

    /// Where input k of a tape compiled over these symbols sits.
    fn which(&self, k: usize) -> Read {
        if k < self.t {
            Read::State(k)
        } else if k == self.t {
            Read::Time
        } else if self.parameters.contains(&k) {
            Read::Parameter(k - self.parameters.start)
        } else if self.inputs.contains(&k) {
            Read::Input(k - self.inputs.start)
        } else {
            Read::Extra(k - self.inputs.end)
        }
    }

    /// The expressions as a tape over these symbols.
    fn compile(&self, pool: &Pool, exprs: &[ExprId]) -> Result<Tape, ModelError> {
        compile(pool, exprs, &self.symbols)
    }
}

/// One input of a tape, as [`Reads::which`] names it.
enum Read {
    State(usize),
    Time,
    Parameter(usize),
    Input(usize),
    Extra(usize),
}

/// The expressions as a tape over `symbols`.
fn compile(pool: &Pool, exprs: &[ExprId], symbols: &[ExprId]) -> Result<Tape, ModelError> {
    Tape::compile(pool, exprs, symbols)
        .map_err(|e| ModelError::whole(format!("the equations cannot be written as code: {e}")))
}

/// h, as the energy T + U₀ where the derivation proves them equal (the shorter
/// expression on the shared path: the same rule as a run's audit of H).
fn hamiltonian(d: &Derivation) -> ExprId {
    match (d.energy, d.hamiltonian_is_energy) {
        (Some(e), Some(true)) => e,
        _ => d.energy_function,
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::write_whole;
    use std::os::unix::fs::FileTypeExt;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lagrange-write-whole-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A pipe is written into and stays a pipe: renaming onto it would have put
    /// a regular file in its place (as root, `-o /dev/null` replaced /dev/null).
    #[test]
    fn a_pipe_is_written_into_not_replaced() {
        let dir = scratch("fifo");
        let fifo = dir.join("out.c");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
        assert!(made.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).expect("the pipe reads"))
        };
        write_whole(&fifo, b"int main;\n").expect("written into the pipe");
        assert_eq!(reader.join().unwrap(), b"int main;\n");
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "the pipe is still a pipe");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A link is followed: the file it names gets the export, the link stays a
    /// link, also when it names a file not made yet.
    #[test]
    fn a_link_is_followed_and_kept() {
        let dir = scratch("link");
        let target = dir.join("model.c");
        std::fs::write(&target, "old").unwrap();
        let link = dir.join("link.c");
        std::os::unix::fs::symlink("model.c", &link).unwrap();
        write_whole(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        let dangling = dir.join("later.c");
        std::os::unix::fs::symlink(dir.join("made_now.c"), &dangling).unwrap();
        write_whole(&dangling, b"made").unwrap();
        assert!(std::fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(dir.join("made_now.c")).unwrap(), b"made");
        let folder = dir.join("folder");
        std::fs::create_dir(&folder).unwrap();
        let err = write_whole(&folder, b"x").unwrap_err();
        assert!(err.to_string().contains("folder"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
