//! `lagrange orbit`: the central-force orbit of a model's initial state — μ and
//! U(r) read from the derivation, l, E, U_eff, the turning points, the kind of
//! orbit, the period and the apsidal angle — as text that follows the notes'
//! Sec. 3.1, as JSON (`lagrange.orbit/1`), and as a figure (`--plot`): U_eff
//! with the energy line and the turning points, and the orbit in the plane.
//!
//! The computation is `mech::Orbit`, the text and the figure are `view::orbit`;
//! this module reads the options and writes the outputs.

use crate::diagnostics::Failure;
use crate::output::ReportFormat;
use mech::Orbit;
use std::path::PathBuf;

/// Options of `orbit`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML): coordinates r and an angle, L = μ/2·(r'² + r²θ'²) − U(r).
    pub model: PathBuf,
    /// Output format: text, or json (the schema `lagrange.orbit/1`).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Draw U_eff with the energy and the turning points, and the orbit, to this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Override a parameter: --set k=2 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    crate::files::refuse_overwrite(&[&args.model], &[args.plot.as_deref()]).map_err(Failure::usage)?;
    let path = &args.model;
    let (source, d) = crate::derive_file(path, &args.set, &[args.plot.as_deref()])?;
    d.reject_constraints("`lagrange orbit`").map_err(|e| Failure::model(path, &source, e))?;
    let mut orbit = Orbit::new(&d).map_err(|e| Failure::analysis(path, &source, e))?;
    if let Some(svg) = &args.plot {
        let text =
            view::orbit::figure(&d, &mut orbit).map_err(|e| Failure::run(format!("cannot draw the plot: {e}")))?;
        crate::files::write_whole(svg, text.as_bytes())
            .map_err(|e| Failure::run(format!("cannot write the plot {}: {e}", svg.display())))?;
    }
    let out = match args.format {
        ReportFormat::Json => {
            let mut s = serde_json::to_string_pretty(&orbit.report(&d))
                .map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => view::orbit::text(&d, &orbit),
    };
    crate::write_stdout(&out)
}
