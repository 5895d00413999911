//! `lagrange export`: a model's equations of motion as code for another
//! program (`--to c`: one C99 file, `mech::export::to_c`; `--to python`: a
//! numpy module, `mech::export::to_python`; `--to fmu`: an FMI 2.0 FMU,
//! `mech::export::fmu`, its binary built by the system's C compiler). The file is written
//! beside its destination and moved into place whole, so an existing output is
//! never replaced by a half-written one.

use crate::diagnostics::Failure;
use std::path::PathBuf;

/// The language written (`--to`).
#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
pub enum To {
    /// One C99 file needing only libm: lagrange_rhs, the mass matrix, the forcing, h and the energy.
    C,
    /// A Python module needing only numpy: rhs and jac for scipy's solve_ivp, M, f, h and the energy.
    Python,
    /// An FMI 2.0 FMU for Model Exchange and Co-Simulation, its binary built by the system's C compiler.
    Fmu,
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
    let version = env!("CARGO_PKG_VERSION");
    let bytes = match args.to {
        To::C => mech::export::to_c(&d, version).map(String::into_bytes),
        To::Python => mech::export::to_python(&d, version).map(String::into_bytes),
        To::Fmu => return fmu(&d, args, &source),
    }
    .map_err(|e| Failure::model(path, &source, e))?;
    mech::export::write_whole(&args.out, &bytes)
        .map_err(|e| Failure::run(format!("cannot write {}: {e}", args.out.display())))
}

/// `--to fmu`: the sources, the binary from the system's C compiler (exit 2
/// naming how to choose one where there is none), the archive.
fn fmu(d: &mech::Derivation, args: &Args, source: &str) -> Result<(), Failure> {
    use mech::export::fmu;
    let stem = args.out.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    let sources = fmu::sources(d, env!("CARGO_PKG_VERSION"), &fmu::identifier(&stem))
        .map_err(|e| Failure::model(&args.model, source, e))?;
    let compiler = sym::c_compiler().map_err(|e| {
        Failure::usage(format!(
            "the FMU's binary is compiled at export time and needs a C compiler: {e}; install one (cc, gcc or clang), or name it with CC=/path/to/cc"
        ))
    })?;
    let bytes = fmu::package(&sources, &compiler).map_err(|e| Failure::run(format!("cannot build the FMU: {e}")))?;
    mech::export::write_whole(&args.out, &bytes)
        .map_err(|e| Failure::run(format!("cannot write {}: {e}", args.out.display())))
}
