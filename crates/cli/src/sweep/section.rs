//! `lagrange sweep --section`: the Poincaré sections of many starts, one CSV
//! of their points and one figure with a colour per run, as a course shows
//! regular curves beside a chaotic sea.
//!
//! Each grid point is one `mech::simulate` run with the section's condition
//! as its crossing, so a point is located exactly as `simulate --section`
//! locates it (and equals it digit for digit). Grids over initial values
//! share the model's derivation; a grid over parameters reads the model again
//! per run with the grid's values as `--set` gives them, because initial
//! values may be expressions of the parameters (Hénon–Heiles' start follows
//! from its energy E). Runs go to worker threads; their points stream to the
//! CSV in grid order. A run that fails keeps the points it reached and its
//! message goes to stderr; the sweep then exits 1.

use crate::diagnostics::Failure;
use crate::interrupt;
use crate::stream::RowWriter;
use mech::{Derivation, Grid, RunConfig, Section, StopCondition, Target};
use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

/// What a section sweep is given beyond the model and the grid.
pub struct Options<'a> {
    pub path: &'a Path,
    pub source: &'a str,
    pub set: &'a [(String, f64)],
    pub config: RunConfig,
    pub condition: &'a str,
    pub axes: Option<&'a str>,
    pub threads: usize,
    pub out: Option<&'a Path>,
    pub plot: Option<&'a Path>,
}

/// One run's points: its CSV lines and the points in the plane.
struct Points {
    lines: String,
    plane: Vec<[f64; 2]>,
    failure: Option<String>,
}

/// Runs the sweep and writes its points and figure.
pub fn run(d: &Derivation, grid: &Grid, opts: &Options<'_>) -> Result<(), Failure> {
    let section = crate::simulate::parse_section(d, opts.condition, opts.axes)?;
    let mut row_columns = mech::row_columns(d);
    let extra: Vec<usize> = (0..2).filter(|&k| !row_columns.contains(&section.axes()[k])).collect();
    row_columns.extend(extra.iter().map(|&k| section.axes()[k].clone()));
    // A grid over a coordinate's start would name the column of that coordinate
    // at the point a second time: the grid's is `grid.NAME`.
    let mut columns = vec!["run".to_string()];
    columns.extend(grid.axes.iter().map(|a| {
        if row_columns.contains(&a.name) {
            format!("grid.{}", a.name)
        } else {
            a.name.clone()
        }
    }));
    columns.extend(row_columns);
    let header = format!("{}\n", columns.join(","));
    let write_error = |e: &std::io::Error| match opts.out {
        Some(out) => format!("cannot write {}: {e}", out.display()),
        None => format!("cannot write the output: {e}"),
    };
    let mut writer = match opts.out {
        Some(out) => {
            let _held = interrupt::gate();
            let file = crate::files::open_locked(out).map_err(|e| Failure::input(out, format!("cannot write: {e}")))?;
            RowWriter::start(file, 0, header.as_bytes()).map_err(|e| Failure::run(write_error(&e)))?
        }
        None => {
            let mut w = RowWriter::stdout();
            w.push(header.as_bytes()).and_then(|()| w.flush()).map_err(|e| Failure::run(write_error(&e)))?;
            w
        }
    };
    let parameter_grid = grid.targets.iter().any(|t| matches!(t, Target::Parameter(_)));
    let n_runs = grid.len();
    let next = AtomicUsize::new(0);
    let (send, receive) = mpsc::channel::<(usize, Points)>();
    let mut sets: Vec<view::plot::SectionSet> = Vec::new();
    let mut failures: Vec<String> = Vec::new();
    let mut failed_write: Option<std::io::Error> = None;
    let mut finished = 0usize;
    interrupt::streaming();
    std::thread::scope(|scope| {
        for _ in 0..opts.threads.min(n_runs).max(1) {
            let send = send.clone();
            let (next, section, extra) = (&next, &section, extra.as_slice());
            scope.spawn(move || loop {
                let run = next.fetch_add(1, Ordering::Relaxed);
                if run >= n_runs || interrupt::received().is_some() {
                    break;
                }
                let points = one_run(d, grid, run, section, opts, parameter_grid, extra);
                if send.send((run, points)).is_err() {
                    break;
                }
            });
        }
        drop(send);
        // Written in grid order: a run's points wait for the runs before it.
        let mut waiting: BTreeMap<usize, Points> = BTreeMap::new();
        for (run, points) in receive.iter() {
            waiting.insert(run, points);
            while let Some(points) = waiting.remove(&finished) {
                if failed_write.is_none() && !points.lines.is_empty() {
                    if let Err(e) = writer.push(points.lines.as_bytes()) {
                        failed_write = Some(e);
                        // The workers stop at their next run.
                        next.store(n_runs, Ordering::Relaxed);
                    }
                }
                let label = label(grid, finished);
                if let Some(message) = points.failure {
                    failures.push(format!("run {finished} ({label}): {message}"));
                }
                if opts.plot.is_some() {
                    sets.push(view::plot::SectionSet { label, points: points.plane });
                }
                finished += 1;
            }
        }
    });
    if let Err(e) = writer.flush() {
        failed_write.get_or_insert(e);
    }
    if let Some(e) = failed_write {
        if opts.out.is_none() && e.kind() == std::io::ErrorKind::BrokenPipe {
            return Ok(());
        }
        return Err(Failure::run(write_error(&e)));
    }
    let points: usize = sets.iter().map(|s| s.points.len()).sum();
    if let Some(svg) = opts.plot {
        let condition = section.condition();
        let subtitle = format!(
            "section {} ({}), {} runs, {points} points, rtol {}",
            condition.text,
            if condition.direction == num::Direction::Falling { "decreasing" } else { "increasing" },
            finished,
            num::Shortest(opts.config.rtol)
        );
        let figure = view::plot::section_svg(&view::plot::SectionPlot {
            title: d.model().name.clone(),
            subtitle,
            axes: section.axes().clone(),
            sets,
        });
        crate::files::write_figure(svg, "the section", figure).map_err(Failure::run)?;
    }
    for message in &failures {
        eprintln!("warning: {message}");
    }
    if let Some(signal) = interrupt::received() {
        return Err(Failure::Interrupted {
            signal,
            message: format!(
                "interrupted by {}: {finished} of {n_runs} runs finished{}",
                signal.name(),
                opts.out.map_or(String::new(), |o| format!(" ({} keeps their points, in grid order)", o.display()))
            ),
        });
    }
    eprintln!("{finished} runs, {} failed, on the section {}", failures.len(), section.condition().text);
    if !failures.is_empty() {
        let kept = opts.out.map_or(String::new(), |o| format!("; {} keeps the points they reached", o.display()));
        return Err(Failure::run(format!("{} of {n_runs} runs failed{kept}", failures.len())));
    }
    Ok(())
}

/// The grid point of a run as a label: `y0 = 0.1, py0 = 0`.
fn label(grid: &Grid, run: usize) -> String {
    let values = grid.point(run);
    let parts: Vec<String> =
        grid.axes.iter().zip(&values).map(|(a, v)| format!("{} = {}", a.name, num::Shortest(*v))).collect();
    parts.join(", ")
}

/// The points of run `run`: from the shared derivation with the grid's start
/// values, or, on a parameter grid, from the model read again with its values.
fn one_run(
    d: &Derivation,
    grid: &Grid,
    run: usize,
    section: &Section,
    opts: &Options<'_>,
    parameter_grid: bool,
    extra: &[usize],
) -> Points {
    let values = grid.point(run);
    let mut config = opts.config.clone();
    let mut set = opts.set.to_vec();
    for ((axis, target), value) in grid.axes.iter().zip(&grid.targets).zip(&values) {
        match target {
            Target::Parameter(_) => set.push((axis.name.clone(), *value)),
            Target::Coordinate(_) | Target::Velocity(_) => config.initial.push((axis.name.clone(), *value)),
        }
    }
    let own;
    let (d, mut section) = if parameter_grid {
        match rederive(opts, &set, section) {
            Ok((derivation, section)) => {
                own = derivation;
                (&own, section)
            }
            Err(message) => return Points { lines: String::new(), plane: Vec::new(), failure: Some(message) },
        }
    } else {
        (d, section.clone())
    };
    config.crossings = vec![section.condition().clone()];
    let mut lines = String::new();
    let mut plane = Vec::new();
    let mut fields = crate::simulate::RowFields::new(d);
    let mut line: Vec<u8> = Vec::with_capacity(256);
    let result = mech::simulate(d, &config, |row| {
        if interrupt::received().is_some() {
            return ControlFlow::Break(());
        }
        if !section.takes(row) {
            return ControlFlow::Continue(());
        }
        let point = section.point(row.t, row.q, row.qd);
        line.clear();
        line.extend_from_slice(run.to_string().as_bytes());
        for v in &values {
            line.push(b',');
            crate::decimal::push_f64(&mut line, *v);
        }
        line.push(b',');
        fields.push(&mut line, row, Some(&point), extra);
        line.push(b'\n');
        lines.push_str(&String::from_utf8_lossy(&line));
        plane.push(point);
        ControlFlow::Continue(())
    });
    let failure = match result {
        Ok(_) => None,
        Err(mech::RunError::Failed { message, report }) => Some(report.failure.unwrap_or(message)),
        Err(e) => Some(e.to_string()),
    };
    Points { lines, plane, failure }
}

/// The model read again with `set` (the command's and the grid's parameter
/// values) and derived, and the section made anew over it.
fn rederive(opts: &Options<'_>, set: &[(String, f64)], section: &Section) -> Result<(Derivation, Section), String> {
    let folder = opts.path.parent().unwrap_or(Path::new("."));
    let files = |name: &str| -> Result<String, String> {
        let file = folder.join(name);
        crate::files::read_text(&file, mech::MAX_FILE_BYTES as u64).map_err(|e| format!("{}: {e}", file.display()))
    };
    let model = mech::Model::parse_with(opts.source, set, &files).map_err(|e| e.message)?.with_inputs_applied();
    let d = Derivation::new(model).map_err(|e| e.message)?;
    let condition = StopCondition::parse(&d, &section.condition().text, "--section").map_err(|e| e.message)?;
    let section = Section::new(&d, condition, opts.axes).map_err(|e| e.message)?;
    Ok((d, section))
}
