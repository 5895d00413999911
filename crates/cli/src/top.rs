//! `lagrange top`: a symmetric top's precession and nutation from a model's
//! initial state, as text that follows the notes' Sec. 3.2.7, as JSON
//! (`lagrange.top/1`), and as a figure (`--plot`): U_eff(β) with E' and the
//! turning angles, and the path of the symmetry axis on the unit sphere seen
//! from above, from a short simulation of the same model.
//!
//! The computation is `mech::Top`, the text and the figure are `view::top`;
//! this module reads the options and writes the outputs.

use crate::diagnostics::Failure;
use crate::output::ReportFormat;
use mech::Top;
use std::path::PathBuf;

/// Options of `top`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML): one [[bodies]] table with inertia = ["I", "I", "I3"].
    pub model: PathBuf,
    /// Output format: text, or json (the schema `lagrange.top/1`).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Draw U_eff(β) with E' and the turning angles, and the path of the symmetry axis, to this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Override a parameter: --set I3=0.8 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    crate::files::refuse_overwrite(&[&args.model], &[args.plot.as_deref()]).map_err(Failure::usage)?;
    let path = &args.model;
    let (source, d) = crate::derive_file(path, &args.set, &[args.plot.as_deref()])?;
    let top = Top::new(&d).map_err(|e| Failure::analysis(path, &source, e))?;
    if let Some(svg) = &args.plot {
        let text = view::top::figure(&d, &top).map_err(|e| Failure::run(format!("cannot draw the plot: {e}")))?;
        crate::files::write_whole(svg, text.as_bytes())
            .map_err(|e| Failure::run(format!("cannot write the plot {}: {e}", svg.display())))?;
    }
    let out = match args.format {
        ReportFormat::Json => {
            let mut s = serde_json::to_string_pretty(&top.report())
                .map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => view::top::text(&d, &top),
    };
    crate::write_stdout(&out)
}
