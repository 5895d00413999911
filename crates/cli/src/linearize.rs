//! `lagrange linearize`: the state-space matrix A of the small motion about an
//! equilibrium or a steady motion, its eigenvalues and the verdict on
//! stability, as text or as JSON (`lagrange.linearize/1`).
//!
//! The computation is `mech::linearize`, the text `view::linearize`; this
//! module reads the options and writes the output. An unstable operating
//! point is reported (exit 0): its growth rates are the answer.

use crate::diagnostics::Failure;
use crate::output::ReportFormat;
use mech::{About, LinearizeConfig};
use std::path::PathBuf;

/// What to linearize about (`--about`).
#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
pub enum AboutArg {
    /// Rest: every q' = 0, nothing accelerates.
    Equilibrium,
    /// Cyclic coordinates at constant rates (from [initial] or --rate), the others still.
    Steady,
}

/// Options of `linearize`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML).
    pub model: PathBuf,
    /// Linearize about an equilibrium or a steady motion.
    #[arg(long, value_enum, default_value_t = AboutArg::Equilibrium)]
    pub about: AboutArg,
    /// Start the search for the operating point here instead of at [initial]: --at th=1.
    #[arg(long = "at", value_name = "COORD=VALUE", num_args = 1.., value_parser = crate::parse_set)]
    pub at: Vec<(String, f64)>,
    /// The rate of a cyclic coordinate in a steady motion: --rate c=12 (else its [initial] q').
    #[arg(long = "rate", value_name = "COORD=VALUE", num_args = 1.., value_parser = crate::parse_set)]
    pub rate: Vec<(String, f64)>,
    /// Keep the point Newton's method reaches from the start even when it is unstable.
    #[arg(long)]
    pub allow_unstable: bool,
    /// Output format: text, or json (the schema `lagrange.linearize/1`).
    #[arg(long, value_enum, default_value_t = ReportFormat::Text)]
    pub format: ReportFormat,
    /// Override a parameter: --set k=2 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let path = &args.model;
    // A coordinate named twice would silently keep its last value.
    for (flag, pairs) in [("--at", &args.at), ("--rate", &args.rate)] {
        for (k, (name, value)) in pairs.iter().enumerate() {
            if let Some((_, first)) = pairs[..k].iter().find(|(other, _)| other == name) {
                return Err(Failure::usage(format!(
                    "{flag} {name}: given twice ({name}={first}, then {name}={value}); give each coordinate once"
                )));
            }
        }
    }
    // The inputs stay symbols: B is the response to them.
    let source = crate::read_source(path)?;
    let model = crate::parse_model(path, &source, &args.set)?;
    let d = mech::Derivation::new(model).map_err(|e| Failure::model(path, &source, e))?;
    let about = match args.about {
        AboutArg::Equilibrium => About::Equilibrium,
        AboutArg::Steady => About::Steady,
    };
    if about == About::Equilibrium {
        if let Some((name, _)) = args.rate.first() {
            return Err(Failure::usage(format!(
                "--rate {name}: a rate applies to a steady motion (--about steady); at an equilibrium every speed is zero"
            )));
        }
    }
    let config =
        LinearizeConfig { about, at: args.at.clone(), rates: args.rate.clone(), keep_unstable: args.allow_unstable };
    let lin = match mech::linearize(&d, &config) {
        Ok(l) => l,
        Err(mech::LinearizeError::Rate { name, message }) => {
            return Err(Failure::usage(format!("--rate {name}: {message}")))
        }
        Err(e) => return Err(Failure::analysis(path, &source, e)),
    };
    let text = match args.format {
        ReportFormat::Json => {
            let report = mech::LinearizeReport::new(&d, &lin);
            let mut s =
                serde_json::to_string_pretty(&report).map_err(|e| Failure::run(format!("cannot write JSON: {e}")))?;
            s.push('\n');
            s
        }
        ReportFormat::Text => view::linearize::text(&d, &lin, &config, &crate::TERMS),
    };
    crate::write_stdout(&text)
}
