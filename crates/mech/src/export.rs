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

/// Writes `bytes` to a new file beside `path` and renames it to `path`: the
/// file at `path` is the old one or the whole new one, never a part (an export
/// that fails, or is stopped, leaves an earlier export as it was).
pub fn write_whole(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
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
