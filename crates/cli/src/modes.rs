//! `lagrange modes`: small oscillations about an equilibrium — the equilibrium,
//! T and U, the secular equation, the normal frequencies and mode shapes — as
//! text that follows the notes' Sec. 3.3, as JSON (`lagrange.modes/1`), and as
//! an animated SVG of every mode (`--animate`).
//!
//! The computation is `mech::normal_modes`, the text and the animation are
//! `view::modes`; this module reads the options and writes the outputs. An
//! unstable equilibrium is bad input (exit 2) unless `--allow-unstable` asks
//! to see it.

use crate::diagnostics::Failure;
use crate::output::ReportFormat;
use mech::{ModeKind, ModesConfig};
use std::path::PathBuf;
use view::human;
use view::modes::vector;

/// Options of `modes`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML).
    pub model: PathBuf,
    /// Start the search for the equilibrium here instead of at [initial]: --at a=0 b=0.
    #[arg(long = "at", value_name = "COORD=VALUE", num_args = 1.., value_parser = crate::parse_set)]
    pub at: Vec<(String, f64)>,
    /// Output format: text, or json (the schema `lagrange.modes/1`).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Draw every mode's shape, animated, to this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub animate: Option<PathBuf>,
    /// Report an unstable equilibrium (Ω² < 0) instead of rejecting it.
    #[arg(long)]
    pub allow_unstable: bool,
    /// Override a parameter: --set k=2 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    crate::files::refuse_overwrite(&[&args.model], &[args.animate.as_deref()]).map_err(Failure::usage)?;
    let path = &args.model;
    let (source, d) = crate::derive_file(path, &args.set, &[args.animate.as_deref()])?;
    d.reject_constraints("`lagrange modes`").map_err(|e| Failure::model(path, &source, e))?;
    let config = ModesConfig { at: args.at.clone(), keep_unstable: args.allow_unstable };
    let modes = mech::normal_modes(&d, &config).map_err(|e| Failure::analysis(path, &source, e))?;
    if !modes.stable && !args.allow_unstable {
        let unstable: Vec<String> = modes
            .modes
            .iter()
            .filter(|m| m.kind == ModeKind::Unstable)
            .map(|m| format!("Ω² = {} along {}", human(m.omega_squared), vector(&modes.coordinates, &m.shape)))
            .collect();
        return Err(Failure::Input {
            file: path.display().to_string(),
            message: format!(
                "the equilibrium at {} is unstable ({}): a small displacement grows like exp(sqrt(-Ω²)·t) instead of oscillating",
                vector(&modes.coordinates, &modes.equilibrium),
                unstable.join("; ")
            ),
            located: None,
            help: Some(
                "start next to a stable equilibrium with --at q=v (e.g. a pendulum's lowest position), or pass --allow-unstable to see the growth rates"
                    .into(),
            ),
        });
    }
    if let Some(svg) = &args.animate {
        crate::files::write_whole(svg, view::modes::animation(&d, &modes).as_bytes())
            .map_err(|e| Failure::run(format!("cannot write the animation {}: {e}", svg.display())))?;
    }
    let text = match args.format {
        ReportFormat::Json => {
            let report = mech::ModesReport::new(&d, &modes);
            let mut s =
                serde_json::to_string_pretty(&report).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => view::modes::text(&d, &modes, &config, &crate::TERMS),
    };
    crate::write_stdout(&text)
}
