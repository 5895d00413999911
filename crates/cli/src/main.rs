//! The `lagrange` command-line program: argument parsing, reading files,
//! rendering diagnostics and writing results. Everything it prints is computed
//! by the `mech` library and worded or drawn by `view`; this crate only does IO.
//!
//! Exit codes: 0 done; 2 bad input (file, expression, model, arguments), with a
//! message naming file, line and column; 1 a run that failed midway; 130 and
//! 143 a run stopped by SIGINT and SIGTERM (`simulate`, `sweep`).

mod budget;
mod decimal;
mod diagnostics;
mod export;
mod extremal;
mod files;
mod import;
mod inertia;
mod interrupt;
mod linearize;
mod modes;
mod orbit;
mod output;
mod report;
mod simulate;
mod stream;
mod sweep;
mod top;

use clap::{Parser, Subcommand, ValueEnum};
use diagnostics::Failure;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Analytical mechanics from a model file: equations of motion, Hamiltonian, conserved quantities.
#[derive(Parser)]
#[command(
    name = "lagrange",
    version,
    about = "Analytical mechanics from a model file: equations of motion, Hamiltonian, conserved quantities, motion",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Derive momenta, Euler–Lagrange equations, M q'' = f, cyclic coordinates, H and Hamilton's equations.
    Derive {
        /// The model file (TOML).
        model: PathBuf,
        /// Output format.
        #[arg(long, value_enum, default_value_t = Format::Text)]
        format: Format,
        /// Override a parameter: --set g=1.62 (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
        set: Vec<(String, f64)>,
    },
    /// Integrate the motion from [initial], stream it to CSV, plot it and audit the conserved quantities.
    Simulate {
        /// The model file (TOML).
        #[arg(required_unless_present = "list_methods")]
        model: Option<PathBuf>,
        /// End time (the run starts at t = 0).
        #[arg(long, required_unless_present = "list_methods", allow_negative_numbers = true)]
        until: Option<f64>,
        /// Integrator (see --list-methods); default: chosen from the derivation.
        #[arg(long)]
        method: Option<String>,
        /// Relative tolerance (default 1e-9); fixed-step methods pick their step from it.
        #[arg(long, allow_negative_numbers = true)]
        rtol: Option<f64>,
        /// Absolute tolerance (default 1e-12, or rtol/1000 when --rtol is given).
        #[arg(long, allow_negative_numbers = true)]
        atol: Option<f64>,
        /// Fixed step for fixed-step methods.
        #[arg(long, allow_negative_numbers = true)]
        dt: Option<f64>,
        /// Write the trajectory to this CSV file.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Number of evenly spaced rows (both ends included; default 1001).
        #[arg(long, conflicts_with = "every_step")]
        samples: Option<usize>,
        /// One row per integrator step instead of evenly spaced samples.
        #[arg(long)]
        every_step: bool,
        /// Draw coordinates, a phase portrait and the invariants' drift to this SVG file.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Summary format on stdout.
        #[arg(long, value_enum, default_value_t = SummaryFormat::Text)]
        summary: SummaryFormat,
        /// Override a parameter: --set g=1.62 (repeatable).
        #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
        set: Vec<(String, f64)>,
        /// Stop when a condition becomes true, e.g. "y < 0" or "th' > 0" (repeatable).
        #[arg(long = "stop-when", value_name = "CONDITION")]
        stop_when: Vec<String>,
        /// Record the crossings of a condition as extra CSV rows without stopping, e.g. "th = 0" or "x' > 0" (repeatable).
        #[arg(long = "crossing", value_name = "CONDITION")]
        crossing: Vec<String>,
        /// A Poincaré section: keep only the one-way crossings of a surface, e.g. "x = 0" (x increasing)
        /// or "th < 0" (decreasing); --out writes them, --plot draws them.
        #[arg(long, value_name = "CONDITION", conflicts_with = "crossing")]
        section: Option<String>,
        /// The plane the section is drawn in: two expressions, e.g. "y, p_y" (default: the first coordinate
        /// the section's condition does not name, and its momentum).
        #[arg(long, value_name = "X, Y", requires = "section")]
        section_axes: Option<String>,
        /// List the integrators and exit.
        #[arg(long)]
        list_methods: bool,
    },
    /// Run many trajectories over a grid of initial values or parameters, on all cores.
    Sweep(sweep::Args),
    /// Small oscillations about an equilibrium: normal frequencies and mode shapes.
    Modes(modes::Args),
    /// The state-space matrix A about an equilibrium or a steady motion, its eigenvalues and the stability.
    Linearize(linearize::Args),
    /// A central-force orbit from the initial state: turning points, kind, period, apsidal angle.
    Orbit(orbit::Args),
    /// The inertia tensor of a body file: mass, centre of mass, tensor about a point, principal axes.
    Inertia(inertia::Args),
    /// A symmetric top from the initial state: precession, nutation bounds, steady precession, sleeping top.
    Top(top::Args),
    /// The extremal of a functional ∫ f(y, y', x) dx between fixed ends: Euler equation, path, value, second variation.
    Extremal(extremal::Args),
    /// One HTML page that opens offline: the derivation typeset, the mechanism animated, plots, the audit and the analyses.
    Report(report::Args),
    /// A URDF robot as a model file: a body per moving joint, fixed joints merged, limits and meshes left out.
    Import(import::Args),
    /// The equations of motion as code for another program: a C99 file, a numpy module (rhs, jac) or an FMI 2.0 FMU.
    Export(export::Args),
}

/// Summary formats of `simulate`.
#[derive(Clone, Copy, ValueEnum, PartialEq)]
enum SummaryFormat {
    /// A table for people.
    Text,
    /// JSON (`lagrange.simulate/1`).
    Json,
}

/// Output formats of `derive`.
#[derive(Clone, Copy, ValueEnum)]
enum Format {
    /// Text that reads like the lecture notes.
    Text,
    /// LaTeX equations.
    Latex,
    /// JSON (`lagrange.derive/1`).
    Json,
}

/// How the text outputs name this program's flags.
pub(crate) const TERMS: view::Terms = view::Terms {
    step: "--dt",
    start_at: "--at",
    full_output: "--format json",
    animation: "--animate",
    until: "--until",
    method: "--method",
};

fn parse_set(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("expected NAME=VALUE, found '{s}'"))?;
    let value: f64 = value
        .trim()
        .parse()
        .map_err(|_| format!("the value of '{}' must be a number, found '{}'", name.trim(), value.trim()))?;
    if !value.is_finite() {
        return Err(format!("the value of '{}' must be finite", name.trim()));
    }
    Ok((name.trim().to_string(), value))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Derive { model, format, set } => derive(&model, format, &set),
        Command::Sweep(args) => sweep::run(&args),
        Command::Modes(args) => modes::run(&args),
        Command::Linearize(args) => linearize::run(&args),
        Command::Orbit(args) => orbit::run(&args),
        Command::Inertia(args) => inertia::run(&args),
        Command::Top(args) => top::run(&args),
        Command::Extremal(args) => extremal::run(&args),
        Command::Report(args) => report::run(&args),
        Command::Import(args) => import::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Simulate { list_methods: true, .. } => write_stdout(&simulate::list_methods()),
        Command::Simulate {
            model,
            until,
            method,
            rtol,
            atol,
            dt,
            out,
            samples,
            every_step,
            plot,
            summary,
            set,
            stop_when,
            crossing,
            section,
            section_axes,
            list_methods: false,
        } => simulate::run(&simulate::Options {
            model: model.unwrap_or_default(),
            until,
            method,
            rtol,
            atol,
            dt,
            out,
            samples,
            every_step,
            plot,
            summary_json: summary == SummaryFormat::Json,
            set,
            stop_when,
            crossing,
            section,
            section_axes,
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            let _ = std::io::stdout().flush();
            eprint!("{}", failure.render());
            ExitCode::from(failure.exit_code())
        }
    }
}

/// Reads a model file, or explains why it cannot.
pub(crate) fn read_source(path: &Path) -> Result<String, Failure> {
    files::read_text(path, mech::MAX_FILE_BYTES as u64)
        .map_err(|e| Failure::input(path, e.message("cannot read the file")))
}

/// Parses a model file's text; the files it names (body files of `[[bodies]]`)
/// are read relative to the model file's folder.
pub(crate) fn parse_model(path: &Path, source: &str, set: &[(String, f64)]) -> Result<mech::Model, Failure> {
    let folder = path.parent().unwrap_or(Path::new("."));
    let files = |name: &str| -> Result<String, String> {
        let file = folder.join(name);
        files::read_text(&file, mech::MAX_FILE_BYTES as u64).map_err(|e| format!("{}: {e}", file.display()))
    };
    mech::Model::parse_with(source, set, &files).map_err(|e| Failure::model(path, source, e))
}

/// Reads, parses and derives a model file; its text comes back too, for the
/// diagnostics of what the command does next.
/// The model's inputs take their values (runs need numbers; `derive` keeps them
/// as symbols). Once the model is read, the command's `outputs` are checked
/// again, now against the files it names too (a body file), before the
/// derivation: none may be one of them.
pub(crate) fn derive_file(
    path: &Path,
    set: &[(String, f64)],
    outputs: &[Option<&Path>],
) -> Result<(String, mech::Derivation), Failure> {
    let source = read_source(path)?;
    let model = parse_model(path, &source, set)?.with_inputs_applied();
    files::refuse_overwrite(&[path], outputs).map_err(Failure::usage)?;
    let derivation = mech::Derivation::new(model).map_err(|e| Failure::model(path, &source, e))?;
    Ok((source, derivation))
}

fn derive(path: &Path, format: Format, set: &[(String, f64)]) -> Result<(), Failure> {
    let source = read_source(path)?;
    let start = std::time::Instant::now();
    let model = parse_model(path, &source, set)?;
    let parse_seconds = start.elapsed().as_secs_f64();
    let derivation = mech::Derivation::new(model).map_err(|e| Failure::model(path, &source, e))?;
    let derive_seconds = start.elapsed().as_secs_f64();
    let text = match format {
        Format::Json => {
            let report = mech::DeriveReport::new(&derivation);
            let mut value =
                serde_json::to_value(&report).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            // Extra field: parse + the whole derivation in this process (no start-up,
            // no printing).
            if let serde_json::Value::Object(map) = &mut value {
                map.insert("derive_seconds".into(), serde_json::json!(derive_seconds));
                // Extra field: parse + L, M and f only, the steps a CAS such as
                // SymEngine's benchmark script performs.
                let equations = parse_seconds + derivation.equations_seconds();
                map.insert("equations_seconds".into(), serde_json::json!(equations));
            }
            let mut s =
                serde_json::to_string_pretty(&value).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        Format::Text => view::derive::text(&derivation),
        Format::Latex => view::derive::latex(&derivation),
    };
    write_stdout(&text)
}

/// Writes to stdout; a closed pipe is not an error worth a message.
pub(crate) fn write_stdout(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Failure::run(format!("cannot write the output: {e}"))),
    }
}
