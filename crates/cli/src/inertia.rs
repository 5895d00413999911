//! `lagrange inertia`: the inertia tensor of a body file — its parts, the total
//! mass and centre of mass, the tensor about the centre of mass and about a
//! chosen point (Steiner's parallel-axis step), exact and numeric, the
//! principal moments and axes and the symmetry they show — as text that
//! follows the notes' Sec. 3.2.3, or as JSON (`lagrange.inertia/1`).
//!
//! The computation is `mech::inertia`, the text is `view::inertia`; this
//! module reads the options and writes the output.

use crate::diagnostics::Failure;
use crate::output::ReportFormat;
use mech::inertia::BodyFile;
use std::path::PathBuf;

/// Options of `inertia`.
#[derive(clap::Args)]
pub struct Args {
    /// The body file (TOML): [[parts]] with shape, mass, size, center, orientation, a density over a region, or a given inertia tensor.
    pub body: PathBuf,
    /// The reference point: `com` (the centre of mass) or x,y,z (numbers or expressions in the parameters).
    #[arg(long, default_value = "com", allow_hyphen_values = true, value_name = "com|x,y,z")]
    pub about: String,
    /// Output format: text, or json (the schema `lagrange.inertia/1`).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Override a parameter: --set a=2 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let path = &args.body;
    let source = crate::read_source(path)?;
    let body = BodyFile::parse(&source, &args.set).map_err(|e| Failure::model(path, &source, e))?;
    let mut props = body.mass_properties().map_err(|e| Failure::model(path, &source, e))?;
    let point = props.parse_about(&args.about).map_err(|e| Failure::expression("--about", &args.about, e, 0))?;
    let report = props.report(point);
    let out = match args.format {
        ReportFormat::Json => {
            let mut s =
                serde_json::to_string_pretty(&report).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => view::inertia::text(&body, &props, point, &report),
    };
    crate::write_stdout(&out)
}
