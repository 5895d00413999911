//! `lagrange export`: a model's equations of motion as code for another
//! program (`--to c`: one C99 file, `mech::export::to_c`; `--to python`: a
//! numpy module, `mech::export::to_python`). The file is written
//! beside its destination and moved into place whole, so an existing output is
//! never replaced by a half-written one.

use crate::diagnostics::Failure;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The language written (`--to`).
#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
pub enum To {
    /// One C99 file needing only libm: lagrange_rhs, the mass matrix, the forcing, h and the energy.
    C,
    /// A Python module needing only numpy: rhs and jac for scipy's solve_ivp, M, f, h and the energy.
    Python,
}

/// Options of `export`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML).
    pub model: PathBuf,
    /// The language to write.
    #[arg(long, value_enum)]
    pub to: To,
    /// The file to write.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    pub out: PathBuf,
    /// Override a parameter's default: --set g=1.62 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let path = &args.model;
    crate::files::refuse_overwrite(&[path], &[Some(&args.out)]).map_err(Failure::usage)?;
    let source = crate::read_source(path)?;
    let model = crate::parse_model(path, &source, &args.set)?;
    let d = mech::Derivation::new(model).map_err(|e| Failure::model(path, &source, e))?;
    let text = match args.to {
        To::C => mech::export::to_c(&d, env!("CARGO_PKG_VERSION")),
        To::Python => mech::export::to_python(&d, env!("CARGO_PKG_VERSION")),
    }
    .map_err(|e| Failure::model(path, &source, e))?;
    replace_whole(&args.out, text.as_bytes())
        .map_err(|e| Failure::run(format!("cannot write {}: {e}", args.out.display())))
}

/// Writes `bytes` to a new file beside `path` and renames it to `path`: the
/// file at `path` is the old one or the whole new one, never a part.
fn replace_whole(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
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
