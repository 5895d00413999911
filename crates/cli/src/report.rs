//! `lagrange report`: run a model and write one self-contained HTML page that
//! typesets its derivation, animates the mechanism, plots the run and shows
//! the audit and the analyses that apply. The page is `view::report`'s; this
//! module runs the model, keeps its rows and writes the file.

use crate::diagnostics::Failure;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `report`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML).
    pub model: PathBuf,
    /// End time of the run shown.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub until: f64,
    /// The HTML file to write.
    #[arg(short = 'o', long = "out", value_name = "FILE.html", default_value = "report.html")]
    pub out: PathBuf,
    /// Rows of the run (evenly spaced, both ends included); long runs are decimated for display.
    #[arg(long, default_value_t = 2001)]
    pub samples: usize,
    /// The integrator (see `lagrange simulate --list-methods`); default: chosen for the model.
    #[arg(long)]
    pub method: Option<String>,
    /// Relative tolerance.
    #[arg(long, allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// A Poincaré section drawn among the analyses: the one-way crossings of a surface, e.g. "x = 0".
    #[arg(long, value_name = "CONDITION")]
    pub section: Option<String>,
    /// The plane the section is drawn in: two expressions, e.g. "y, p_y".
    #[arg(long, value_name = "X, Y", requires = "section")]
    pub section_axes: Option<String>,
    /// Override a parameter: --set g=1.62 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    crate::files::refuse_overwrite(&[&args.model], &[Some(args.out.as_path())]).map_err(Failure::usage)?;
    let started = Instant::now();
    let path = &args.model;
    let (source, d) = crate::derive_file(path, &args.set, &[Some(args.out.as_path())])?;
    let derived = started.elapsed().as_secs_f64();
    let settings = mech::RunSettings {
        until: Some(args.until),
        method: args.method.as_deref(),
        rtol: args.rtol,
        atol: None,
        dt: None,
        samples: Some(args.samples),
        every_step: false,
    };
    let mut config = crate::simulate::run_config(path, &settings)?;
    let mut section = match &args.section {
        Some(text) => {
            let s = crate::simulate::parse_section(&d, text, args.section_axes.as_deref())?;
            config.crossings.push(s.condition().clone());
            Some(s)
        }
        None => None,
    };
    config.check().map_err(|e| crate::simulate::input_failure(path, &source, e))?;

    let page = view::report::run_page(&d, &config, args.until, started, derived, &crate::TERMS, section.as_mut())
        .map_err(|e| crate::simulate::input_failure(path, &source, e))?;
    crate::files::write_whole(&args.out, page.html.as_bytes())
        .map_err(|e| Failure::run(format!("cannot write the report {}: {e}", args.out.display())))?;
    crate::write_stdout(&format!(
        "{}: {} of {} rows shown, {:.0} kB\n",
        args.out.display(),
        page.shown,
        page.rows,
        page.html.len() as f64 / 1000.0
    ))?;
    match page.failure {
        // The page shows the rows up to the failure; the failure is the exit code's.
        Some(message) => Err(Failure::run(format!("{message} ({} shows the rows up to there)", args.out.display()))),
        None => Ok(()),
    }
}
