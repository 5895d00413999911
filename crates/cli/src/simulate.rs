//! `lagrange simulate`: integrate a model's motion, stream the trajectory to
//! CSV, draw it, and print the audit of the conserved quantities.
//!
//! The run itself is `mech::simulate`; this module parses the options, writes
//! the CSV row by row (constant memory; flushed even when the run fails, whole
//! to its last row whatever stops it: `stream.rs`), keeps a bounded, decimated
//! copy for the plot (`view::plot::PlotKeeper`), and shows progress on a
//! terminal. The summary and the figure are drawn by `view::simulate` and
//! `view::plot`. SIGINT or SIGTERM stop the run between two rows
//! (`interrupt.rs`): the summary says where, and the exit code is 130 or 143.

use crate::diagnostics::Failure;
use crate::interrupt::{self, Signal};
use crate::stream::RowWriter;
use mech::{Derivation, RunConfig, RunError, RunSettings, Section, SettingError, StopCondition};
use num::Method;
use std::io::{IsTerminal, Write};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `simulate`, as parsed by clap.
pub struct Options {
    pub model: PathBuf,
    /// `--until` (clap requires it; None is reported, not assumed).
    pub until: Option<f64>,
    pub method: Option<String>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub dt: Option<f64>,
    pub out: Option<PathBuf>,
    pub samples: Option<usize>,
    pub every_step: bool,
    pub plot: Option<PathBuf>,
    pub summary_json: bool,
    pub set: Vec<(String, f64)>,
    pub stop_when: Vec<String>,
    pub crossing: Vec<String>,
    /// `--section`: keep only this condition's one-way crossings.
    pub section: Option<String>,
    /// `--section-axes`: the plane the section is drawn in.
    pub section_axes: Option<String>,
}

/// Lists the methods, one line each.
pub fn list_methods() -> String {
    let mut s = String::new();
    for m in Method::ALL {
        s.push_str(&format!("{:<9} {}\n", m.name(), m.description()));
    }
    s
}

pub fn run(opts: &Options) -> Result<(), Failure> {
    interrupt::install();
    crate::files::refuse_overwrite(&[&opts.model], &[opts.out.as_deref(), opts.plot.as_deref()])
        .map_err(Failure::usage)?;
    // Setup is timed from here (reading the model file) to the first row, which
    // the integration hands over before its first step: parse, derive, compile
    // and, for fixed-step methods, the pilot runs that choose the step.
    let started = Instant::now();
    let path = &opts.model;
    let (source, derivation) = crate::derive_file(path, &opts.set, &[opts.out.as_deref(), opts.plot.as_deref()])?;
    let derived = started.elapsed().as_secs_f64();
    let mut first_row: Option<f64> = None;

    let Some(until) = opts.until else { return Err(Failure::usage("simulate needs --until T")) };
    let settings = RunSettings {
        until: Some(until),
        method: opts.method.as_deref(),
        rtol: opts.rtol,
        atol: opts.atol,
        dt: opts.dt,
        samples: opts.samples,
        every_step: opts.every_step,
    };
    let mut config = run_config(path, &settings)?;
    for text in &opts.stop_when {
        config.stop_when.push(parse_stop(&derivation, text, "--stop-when")?);
    }
    for text in &opts.crossing {
        config.crossings.push(parse_stop(&derivation, text, "--crossing")?);
    }
    let mut section = match &opts.section {
        Some(text) => {
            let s = parse_section(&derivation, text, opts.section_axes.as_deref())?;
            config.crossings.push(s.condition().clone());
            Some(s)
        }
        None => None,
    };

    // Bad settings are reported before any file is created.
    config.check().map_err(|e| input_failure(path, &source, e))?;

    // Columns: t, coordinates, velocities, invariants.
    let names: Vec<String> = derivation.coordinate_names().iter().map(|s| s.to_string()).collect();
    // Crossings and impacts mark their rows in an `event` column (a section's
    // rows are all its crossings, and no impact row is one of its points).
    let with_events = !opts.crossing.is_empty() || (!derivation.impacts().is_empty() && section.is_none());
    // A section's CSV: its points' rows, then the plane's axes where they are not columns already.
    let mut section_columns: Vec<usize> = Vec::new();
    let inv_names: Vec<String> = mech::invariants_of(&derivation).into_iter().map(|i| i.name).collect();
    let mut fields = RowFields::new(&derivation);
    // The file is opened and locked before the run (one that cannot be written
    // is bad input). A new file gets its header at once, so that a run stopped
    // before its first row, even by SIGKILL, leaves a CSV that reads as one
    // without rows. An existing file is cut and given its header only at the
    // first row, or at the end of a run that had none: a run refused before it
    // starts (exit 2) leaves it as it was, and removes a file it created.
    let mut pending: Option<PendingCsv> = None;
    let mut csv: Option<RowWriter> = None;
    let mut created: Option<&Path> = None;
    if let Some(p) = &opts.out {
        let mut cols = mech::row_columns(&derivation);
        if let Some(s) = &section {
            section_columns = (0..2).filter(|&k| !cols.contains(&s.axes()[k])).collect();
            cols.extend(section_columns.iter().map(|&k| s.axes()[k].clone()));
        }
        if with_events {
            cols.push("event".into());
        }
        let header = format!("{}\n", cols.join(","));
        let new = !p.exists();
        // A signal finds a new file absent or with its header whole.
        let _held = interrupt::gate();
        let file =
            crate::files::open_locked(p).map_err(|e| Failure::input(p, format!("cannot create the CSV file: {e}")))?;
        if new {
            created = Some(p);
            let writer = RowWriter::start(file, 0, header.as_bytes());
            csv = Some(writer.map_err(|e| Failure::run(format!("cannot write {}: {e}", p.display())))?);
        } else {
            pending = Some(PendingCsv { file, header });
        }
    }
    let mut line: Vec<u8> = Vec::with_capacity(256);
    let mut crossings_seen = 0usize;
    // The section's points, for the plot (16 bytes each: a run of 10⁷ steps crosses fewer times).
    let mut section_points: Vec<[f64; 2]> = Vec::new();
    let mut csv_error: Option<std::io::Error> = None;
    let mut plot_data = opts.plot.is_some().then(|| view::plot::PlotKeeper::of(&derivation));
    let progress = progress_bar(until);
    // The time of the last row handed over (written, with --out), and the
    // signal that stopped the run before the next one.
    let mut last_row: Option<f64> = None;
    let mut stopped_by: Option<Signal> = None;

    let result = mech::simulate(&derivation, &config, |row| {
        first_row.get_or_insert_with(|| {
            interrupt::streaming();
            started.elapsed().as_secs_f64()
        });
        if let Some(signal) = interrupt::received() {
            stopped_by = Some(signal);
            return ControlFlow::Break(());
        }
        if let Some(p) = pending.take() {
            match p.start() {
                Ok(w) => csv = Some(w),
                Err(e) => {
                    csv_error = Some(e);
                    return ControlFlow::Break(());
                }
            }
        }
        let point = match section.as_mut() {
            Some(s) if s.takes(row) => Some(s.point(row.t, row.q, row.qd)),
            Some(_) => {
                // Not a point of the section: not written, not drawn.
                last_row = Some(row.t);
                if let Some(pb) = &progress {
                    pb.set_position((row.t / until * 1000.0) as u64);
                }
                return ControlFlow::Continue(());
            }
            None => None,
        };
        if let Some(w) = csv.as_mut() {
            let r = (|| -> std::io::Result<()> {
                line.clear();
                fields.push(&mut line, row, point.as_ref(), &section_columns);
                if with_events {
                    // Conditions are quoted: they may contain commas (atan2(y, x) < 0).
                    write!(
                        line,
                        ",{}",
                        row.event.map_or(String::new(), |e| format!("\"{}\"", e.replace('"', "\"\"")))
                    )?;
                }
                line.push(b'\n');
                w.push(&line)
            })();
            if let Err(e) = r {
                csv_error = Some(e);
                return ControlFlow::Break(());
            }
        }
        last_row = Some(row.t);
        if row.event.is_some() {
            crossings_seen += 1;
        }
        if let Some(point) = point {
            if opts.plot.is_some() {
                section_points.push(point);
            }
        }
        // Impact rows are drawn (the kink of a bounce); crossings are not samples.
        let drawn = row.event.is_none_or(|e| e.starts_with("impact "));
        if let Some(keeper) = plot_data.as_mut().filter(|_| drawn) {
            keeper.push(row.t, row.q, row.qd, &row.invariants_less_jumps());
        }
        if let Some(pb) = &progress {
            pb.set_position((row.t / until * 1000.0) as u64);
        }
        ControlFlow::Continue(())
    });
    if let Some(pb) = &progress {
        pb.finish_and_clear();
    }
    if matches!(&result, Err(e) if !matches!(e, RunError::Failed { .. })) {
        // Refused before it started: the file as it was, or none.
        drop(pending.take());
        if let Some(path) = created {
            drop(csv.take());
            let _ = std::fs::remove_file(path);
        }
    } else if let Some(p) = pending.take() {
        match p.start() {
            Ok(w) => csv = Some(w),
            Err(e) => csv_error = Some(e),
        }
    }
    if let Some(mut w) = csv {
        if let Err(e) = w.flush() {
            csv_error.get_or_insert(e);
        }
    }
    if let Some(e) = csv_error {
        let p = opts.out.as_deref().unwrap_or(Path::new("-"));
        return Err(Failure::run(format!("cannot write {}: {e}", p.display())));
    }
    let (report, failure) = match result {
        Ok(r) => (r, None),
        Err(RunError::Failed { message, mut report }) => {
            // The budget's advice names the flags that follow it.
            if let Some(mech::RunFailure::StepBudget(b)) = &report.failure_reason {
                report.failure = Some(crate::budget::ran_out(b));
            }
            let message = report.failure.clone().unwrap_or(message);
            (*report, Some(message))
        }
        Err(e) => return Err(input_failure(path, &source, e)),
    };
    let interrupted =
        stopped_by.map(|signal| view::simulate::Interrupted { signal: signal.name().into(), t: last_row });

    if let (Some(plot_path), Some(keeper)) = (&opts.plot, plot_data) {
        let figure = match &section {
            Some(s) => {
                let subtitle = view::plot::section_subtitle(s, crossings_seen, &report);
                view::plot::section_svg(&view::plot::SectionPlot {
                    title: derivation.model().name.clone(),
                    subtitle,
                    axes: s.axes().clone(),
                    sets: vec![view::plot::SectionSet { label: String::new(), points: section_points }],
                })
            }
            None => view::plot::svg(&keeper.into_plot(&derivation.model().name, &report, &names, &inv_names)),
        };
        crate::files::write_figure(plot_path, "the plot", figure).map_err(Failure::run)?;
    }
    let mut text = if opts.summary_json {
        let timing = view::simulate::Timing { derive_seconds: derived, setup_seconds: first_row };
        let mut value = view::simulate::summary_json(&report, &names, &timing, interrupted.as_ref(), &crate::TERMS);
        if let Some(s) = &section {
            value["section"] = view::simulate::section_json(s, crossings_seen);
        }
        let mut s = serde_json::to_string_pretty(&value).unwrap_or_default();
        s.push('\n');
        s
    } else {
        view::simulate::summary_text(&report, &names, &derivation, interrupted.as_ref(), &crate::TERMS)
    };
    if let (false, Some(s)) = (opts.summary_json, &section) {
        text.push_str(&format!(
            "{crossings_seen} point{} on the section {}{}\n",
            if crossings_seen == 1 { "" } else { "s" },
            s.condition().text,
            if opts.out.is_some() { " in the CSV" } else { " (give --out to keep them)" }
        ));
    }
    if !opts.summary_json && !opts.crossing.is_empty() {
        text.push_str(&format!(
            "{crossings_seen} crossing{} recorded{}\n",
            if crossings_seen == 1 { "" } else { "s" },
            if opts.out.is_some() { " in the CSV (column event)" } else { " (give --out to keep them)" }
        ));
    }
    crate::write_stdout(&text)?;
    for w in &report.warnings {
        eprintln!("warning: {}", view::simulate::warning(w, &crate::TERMS));
    }
    let keeps = |what: &str| opts.out.as_ref().map_or(String::new(), |p| format!(" ({} keeps {what})", p.display()));
    if let Some(signal) = stopped_by {
        let at = last_row.map_or("before the first row".to_string(), |t| format!("at t = {}", num::Shortest(t)));
        return Err(Failure::Interrupted {
            signal,
            message: format!("interrupted by {} {at}{}", signal.name(), keeps("every row up to there, each whole")),
        });
    }
    match failure {
        Some(message) => Err(Failure::run(format!("{message}{}", keeps("the rows up to there")))),
        None => Ok(()),
    }
}

/// The CSV fields of a run's rows, as `simulate --out` writes them and
/// `sweep --section` after each row's run and grid values.
pub(crate) struct RowFields {
    /// Rigid bodies' ω and L, six columns per body (None without bodies).
    bodies: Option<mech::BodyRecorder>,
    body_values: Vec<f64>,
}

impl RowFields {
    pub(crate) fn new(d: &Derivation) -> RowFields {
        let bodies = mech::BodyRecorder::new(d);
        let body_values = vec![0.0; bodies.as_ref().map_or(0, |b| b.columns().len())];
        RowFields { bodies, body_values }
    }

    /// Appends the fields of `row` to `line`, comma separated, in the order of
    /// `mech::row_columns`: t, the coordinates, the velocities, the invariants,
    /// the bodies' ω and L, the constraints' columns; then, for a section's
    /// `point`, its axes `extra` (those that are not columns already).
    pub(crate) fn push(&mut self, line: &mut Vec<u8>, row: &mech::Row<'_>, point: Option<&[f64; 2]>, extra: &[usize]) {
        crate::decimal::push_f64(line, row.t);
        if let Some(b) = self.bodies.as_mut() {
            b.eval(row.t, row.q, row.qd, &mut self.body_values);
        }
        let state = row.q.iter().chain(row.qd).chain(row.invariants).chain(&self.body_values).chain(row.constraints);
        let axes = point.into_iter().flat_map(|p| extra.iter().map(move |&k| &p[k]));
        for &v in state.chain(axes) {
            line.push(b',');
            crate::decimal::push_f64(line, v);
        }
    }
}

/// The CSV file of a run before its first row: opened and locked, not yet cut.
struct PendingCsv {
    file: std::fs::File,
    header: String,
}

impl PendingCsv {
    /// Cuts the file and writes the header, under the interrupt gate, so that
    /// a signal finds the file as it was or with its header whole.
    fn start(self) -> std::io::Result<RowWriter> {
        let _held = interrupt::gate();
        RowWriter::start(self.file, 0, self.header.as_bytes())
    }
}

/// The settings checked and made a run's configuration (no stop conditions),
/// by `mech`'s one rule, its refusals in the command line's words.
pub(crate) fn run_config(path: &Path, s: &RunSettings<'_>) -> Result<RunConfig, Failure> {
    RunConfig::from_settings(s).map_err(|e| match e {
        SettingError::UnknownMethod(message) => Failure::input(path, message),
        SettingError::NotPositive { setting, value } => {
            Failure::usage(format!("--{setting} must be a positive number, not {}", num::Shortest(value)))
        }
        SettingError::TooFewSamples { .. } => Failure::usage("--samples needs at least 2 rows (both ends)"),
    })
}

/// A run that could not start, in the CLI's terms (exit 2).
pub(crate) fn input_failure(path: &Path, source: &str, e: RunError) -> Failure {
    match e {
        RunError::Until { until } => Failure::usage(format!("--until must be a positive time, not {}", num::Shortest(until))),
        RunError::TooManySamples { samples, max } => {
            Failure::usage(format!("--samples {samples} is more rows than a run writes ({max} at most)"))
        }
        RunError::TooManySteps { dt, steps, max } => Failure::usage(format!(
            "--dt {dt:e} would take {steps:.3e} steps to reach the end time; a run takes at most {max}"
        )),
        RunError::StepOverSamples { dt, spacing } => Failure::usage(format!(
            "--dt {dt:e} is longer than the spacing of the samples, {spacing:e} (--until over --samples − 1): give a shorter --dt, more --samples, or --every-step"
        )),
        RunError::StepNotApplicable { method } => Failure::usage(format!(
            "--dt applies only to fixed-step methods, and {} chooses its own step: set its tolerance with --rtol, or choose a fixed-step method (verlet, yoshida4, kahanli6, kahanli8, gauss2, gauss4, gauss6)",
            method.name()
        )),
        RunError::StepBudget(b) => crate::budget::refused(&b),
        RunError::Input(e) => Failure::model(path, source, e),
        RunError::Failed { message, .. } => Failure::run(message),
    }
}

/// `EXPR < RHS`, `EXPR > RHS` or `EXPR` (any crossing of zero), for the option `option`.
fn parse_stop(d: &Derivation, text: &str, option: &str) -> Result<StopCondition, Failure> {
    StopCondition::parse(d, text, option).map_err(|e| Failure::expression(option, text, e, 0))
}

/// The Poincaré section of `--section TEXT` drawn in the plane of
/// `--section-axes AXES` (by default the first coordinate the condition does
/// not name, and its momentum), refused as bad input naming the option at fault.
pub(crate) fn parse_section(d: &Derivation, text: &str, axes: Option<&str>) -> Result<Section, Failure> {
    let condition = parse_stop(d, text, "--section")?;
    Section::new(d, condition, axes).map_err(|e| Failure::expression("--section-axes", axes.unwrap_or_default(), e, 0))
}

fn progress_bar(until: f64) -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(1000);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {percent:>3}% t of {msg}  {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    pb.set_message(num::Shortest(until).to_string());
    Some(pb)
}
