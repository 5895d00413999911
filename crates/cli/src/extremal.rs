//! `lagrange extremal`: the extremal of `J[y] = ∫ f(y, y', x) dx` between two
//! fixed points (notes, Sec. 2.1 and appendix A.2) — the Euler equation,
//! Beltrami's first integral, the path solved as a boundary-value problem, its
//! value against the straight line and, with `--check-minimum`, the second
//! variation — as text that teaches, as JSON (`lagrange.extremal/1`), and as a
//! figure (`--plot`).
//!
//! The computation is `mech::extremal`, the text and the figure are
//! `view::extremal`; this module reads the options and writes the outputs.

use crate::diagnostics::Failure;
use crate::output::ReportFormat;
use mech::{ExtremalConfig, ExtremalError, Problem};
use std::path::{Path, PathBuf};

/// Options of `extremal`.
#[derive(clap::Args)]
pub struct Args {
    /// The problem file (TOML): independent, unknown, integrand, [parameters], [boundary].
    pub problem: PathBuf,
    /// Output format: text, or json (the schema `lagrange.extremal/1`).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Draw the extremal and the straight line to this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Evaluate the second variation: Legendre's condition and conjugate points (Jacobi).
    #[arg(long)]
    pub check_minimum: bool,
    /// Number of points of the reported path, both ends included.
    #[arg(long, default_value_t = 201, value_parser = clap::value_parser!(u32).range(2..=1_000_000))]
    pub points: u32,
    /// Override a parameter: --set g=1.62 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    crate::files::refuse_overwrite(&[&args.problem], &[args.plot.as_deref()]).map_err(Failure::usage)?;
    let path = &args.problem;
    let source = crate::read_source(path)?;
    let problem = Problem::parse(&source, &args.set).map_err(|e| Failure::model(path, &source, e))?;
    let config = ExtremalConfig { check_minimum: args.check_minimum, points: args.points as usize };
    let report = mech::extremal(&problem, &config).map_err(|e| failure(path, &source, e))?;
    if let Some(svg) = &args.plot {
        let text = view::extremal::figure(&report).map_err(|e| Failure::run(format!("cannot draw the plot: {e}")))?;
        crate::files::write_whole(svg, text.as_bytes())
            .map_err(|e| Failure::run(format!("cannot write the plot {}: {e}", svg.display())))?;
    }
    let out = match args.format {
        ReportFormat::Json => {
            let mut s =
                serde_json::to_string_pretty(&report).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => view::extremal::text(&report, &crate::TERMS),
    };
    crate::write_stdout(&out)
}

fn failure(path: &Path, source: &str, e: ExtremalError) -> Failure {
    match e {
        ExtremalError::Model(m) => Failure::model(path, source, m),
        ExtremalError::NoExtremal { message, help } => Failure::run(match help {
            Some(h) => format!("{}: {message}\n  help: {h}", path.display()),
            None => format!("{}: {message}", path.display()),
        }),
    }
}
