//! `lagrange sweep`: many trajectories over a grid of initial values or
//! parameters, on all cores; one CSV row per run and a heat map.
//!
//! Two forms: `lagrange sweep MODEL --until T --grid SPEC [...]` runs a sweep (or
//! the shard `--shard i/n` of one), and `lagrange sweep --merge OUT.csv
//! SHARD.csv...` joins the shards' CSV files into the whole sweep's. Both may
//! draw `--heatmap FILE.svg`. The computation is `mech::Sweep` and the map is
//! drawn by `view::heatmap`; this module parses options, shows progress on a
//! terminal and does the IO.
//!
//! Rows stream to `--out` (or stdout) in grid order as they finish, whole
//! (`stream.rs`); the heat map and the counts are gathered as they pass. A
//! sweep stopped by SIGINT or SIGTERM (`interrupt.rs`), or by a write that
//! failed, leaves the rows of its first runs, and `--resume` continues such
//! an output (`resume.rs`): it checks that the file is this sweep's, keeps its
//! whole rows, and appends the rest.

mod resume;
mod section;

use crate::diagnostics::Failure;
use crate::interrupt;
use crate::stream::RowWriter;
use mech::{Grid, SettingError, Shard, SweepConfig, SweepError, SweepTable, TableRow};
use std::io::IsTerminal;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;
use view::heatmap::{HeatMap, HeatMapError, MAX_CELLS};

/// Options of `sweep`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML); with --merge, the shards' CSV files.
    #[arg(required = true, value_name = "MODEL | SHARD.csv")]
    pub files: Vec<PathBuf>,
    /// End time of every run (each starts at t = 0).
    #[arg(long, required_unless_present = "merge", allow_negative_numbers = true)]
    pub until: Option<f64>,
    /// The grid: NAME=START:STOP:COUNT (evenly spaced) or NAME=V1;V2;... (the values listed), comma separated (coordinates a, velocities a', parameters).
    #[arg(long, required_unless_present = "merge", allow_hyphen_values = true)]
    pub grid: Option<String>,
    /// Override a parameter for every run: --set g=1.62 (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::parse_set)]
    pub set: Vec<(String, f64)>,
    /// Integrator (see `simulate --list-methods`); default taylor (dop853 for models with rigid bodies).
    #[arg(long)]
    pub method: Option<String>,
    /// Relative tolerance (default 1e-10).
    #[arg(long, allow_negative_numbers = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (default rtol/100).
    #[arg(long, allow_negative_numbers = true)]
    pub atol: Option<f64>,
    /// Write the rows to this CSV file (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Draw a heat map of a 2-D grid to this SVG file.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// The heat map's colour: lyapunov, drift, or a final coordinate or velocity (a, a').
    #[arg(long, default_value = "lyapunov")]
    pub color: String,
    /// Run only the I-th of N slices (runs with index % N == I), for a cluster.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Skip the Lyapunov exponent's perturbed twin (halves the cost).
    #[arg(long)]
    pub no_lyapunov: bool,
    /// Continue the sweep whose partial output --out holds (from an interrupted run): keep its rows, run the rest.
    #[arg(long, requires = "out")]
    pub resume: bool,
    /// Join the shard CSV files given in place of MODEL into OUT.csv.
    #[arg(long, value_name = "OUT.csv", conflicts_with_all = ["until", "grid", "set", "method", "rtol", "atol", "out", "shard", "threads", "no_lyapunov", "resume"])]
    pub merge: Option<PathBuf>,
    /// Poincaré sections of every run on one plot: the one-way crossings of a surface, e.g. "x = 0"; the CSV
    /// holds the points (see `simulate --section`).
    #[arg(long, value_name = "CONDITION", conflicts_with_all = ["merge", "heatmap", "shard", "resume", "no_lyapunov"])]
    pub section: Option<String>,
    /// The plane the sections are drawn in: two expressions, e.g. "y, p_y" (default: the first coordinate the
    /// condition does not name, and its momentum).
    #[arg(long, value_name = "X, Y", requires = "section")]
    pub section_axes: Option<String>,
    /// Draw the sections, a colour per run, to this SVG file.
    #[arg(long, value_name = "FILE.svg", requires = "section")]
    pub plot: Option<PathBuf>,
}

/// Most worker threads a sweep starts: far above any machine's cores, far
/// below what takes the operating system seconds to refuse.
const MAX_THREADS: usize = 1024;

/// Runs `sweep` (or `sweep --merge`).
pub fn run(args: &Args) -> Result<(), Failure> {
    if let Some(out) = &args.merge {
        return merge(args, out);
    }
    interrupt::install();
    let inputs: Vec<&Path> = args.files.iter().map(PathBuf::as_path).collect();
    crate::files::refuse_overwrite(&inputs, &[args.out.as_deref(), args.heatmap.as_deref(), args.plot.as_deref()])
        .map_err(Failure::usage)?;
    let [path] = args.files.as_slice() else {
        return Err(Failure::usage(format!(
            "sweep takes one model file, not {} files (to join shards: sweep --merge OUT.csv SHARD.csv...)",
            args.files.len()
        )));
    };
    // clap requires --until without --merge; None is reported, not assumed.
    let Some(until) = args.until else { return Err(Failure::usage("sweep needs --until T")) };
    if args.threads == Some(0) {
        return Err(Failure::usage("--threads must be at least 1"));
    }
    if let Some(threads) = args.threads.filter(|&t| t > MAX_THREADS) {
        return Err(Failure::usage(format!("--threads {threads} is more than {MAX_THREADS}, the most a sweep starts")));
    }
    let shard = match &args.shard {
        Some(text) => Shard::parse(text).map_err(usage)?,
        None => Shard::default(),
    };
    let settings = mech::SweepSettings {
        until,
        method: args.method.as_deref(),
        rtol: args.rtol,
        atol: args.atol,
        lyapunov: !args.no_lyapunov,
        shard,
        threads: args.threads,
    };
    let config = SweepConfig::from_settings(&settings).map_err(|e| match e {
        SettingError::NotPositive { setting, value } => {
            Failure::usage(format!("--{setting} must be a positive number, not {}", num::Shortest(value)))
        }
        SettingError::UnknownMethod(message) => Failure::usage(message),
        SettingError::TooFewSamples { .. } => Failure::usage("--samples needs at least 2 rows (both ends)"),
    })?;
    let (source, derivation) =
        crate::derive_file(path, &args.set, &[args.out.as_deref(), args.heatmap.as_deref(), args.plot.as_deref()])?;
    derivation.reject_constraints("`lagrange sweep`").map_err(|e| Failure::model(path, &source, e))?;
    let grid = Grid::parse(args.grid.as_deref().unwrap_or_default(), derivation.model()).map_err(usage)?;
    if let Some(condition) = &args.section {
        // Each run is simulate's, at the sweep's tolerance.
        let settings = mech::RunSettings {
            until: Some(until),
            method: args.method.as_deref(),
            rtol: Some(args.rtol.unwrap_or(mech::DEFAULT_RTOL)),
            atol: args.atol,
            dt: None,
            samples: Some(2),
            every_step: false,
        };
        let run_config = crate::simulate::run_config(path, &settings)?;
        run_config.check().map_err(|e| crate::simulate::input_failure(path, &source, e))?;
        let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let options = section::Options {
            path,
            source: &source,
            set: &args.set,
            config: run_config,
            condition,
            axes: args.section_axes.as_deref(),
            threads,
            out: args.out.as_deref(),
            plot: args.plot.as_deref(),
        };
        return section::run(&derivation, &grid, &options);
    }
    let sweep = mech::Sweep::new(&derivation, &grid, &config).map_err(|e| match e {
        SweepError::Model(e) => Failure::model(path, &source, *e),
        other => usage(other),
    })?;
    let header = sweep.header();
    let mut map = match &args.heatmap {
        Some(_) => Some(HeatMap::new(header, &args.color).map_err(heatmap_usage)?),
        None => None,
    };

    // The output, and the rows a resumed sweep already has.
    let mut tally = Tally::default();
    let write_error = |e: &std::io::Error| match &args.out {
        Some(out) => format!("cannot write {}: {e}", out.display()),
        None => format!("cannot write the output: {e}"),
    };
    let (mut writer, skip) = match &args.out {
        Some(out) if args.resume => {
            let kept = resume::open(out, header, shard, sweep.len(), |row| tally.add(row, map.as_mut()))?;
            if let Some(note) = &kept.note {
                eprintln!("{note}");
            }
            (kept.writer, kept.rows)
        }
        Some(out) => {
            let _held = interrupt::gate();
            let file = crate::files::open_locked(out).map_err(|e| Failure::input(out, format!("cannot write: {e}")))?;
            let writer =
                RowWriter::start(file, 0, header.to_csv().as_bytes()).map_err(|e| Failure::run(write_error(&e)))?;
            (writer, 0)
        }
        None => {
            let mut writer = RowWriter::stdout();
            writer
                .push(header.to_csv().as_bytes())
                .and_then(|()| writer.flush())
                .map_err(|e| Failure::run(write_error(&e)))?;
            (writer, 0)
        }
    };

    let n_runs = sweep.len();
    // Compiled before the clock starts: the summary reports it apart.
    let code = sweep.code();
    let progress = progress_bar(n_runs as u64, skip as u64);
    let start = Instant::now();
    let tick = || {
        if let Some(pb) = &progress {
            pb.inc(1);
        }
    };
    // The workers look at the signal between runs: a sweep stops between rows from its start.
    interrupt::streaming();
    let stop = || interrupt::received().is_some();
    let mut line = String::new();
    let mut failed_write: Option<std::io::Error> = None;
    let result = sweep.run(skip, &tick, &stop, |row| {
        line.clear();
        row.write_csv(&mut line);
        if let Err(e) = writer.push(line.as_bytes()) {
            failed_write = Some(e);
            return ControlFlow::Break(());
        }
        tally.add(&row, map.as_mut());
        ControlFlow::Continue(())
    });
    if let Some(pb) = &progress {
        pb.finish_and_clear();
    }
    if let Err(e) = writer.flush() {
        failed_write.get_or_insert(e);
    }
    let complete = result.map_err(usage)?;
    let seconds = start.elapsed().as_secs_f64();
    if let (Some(svg), Some(map)) = (&args.heatmap, &map) {
        crate::files::write_figure(svg, "the heat map", map.svg()).map_err(Failure::run)?;
    }
    let kept = |what: &str| match &args.out {
        Some(out) => format!(
            "{} keeps the rows of the first {} runs{what}, each whole; to run the rest:\n  {}",
            out.display(),
            tally.rows,
            resume_command()
        ),
        None => "the rows so far went to stdout (give --out FILE.csv to be able to resume)".to_string(),
    };
    if let Some(e) = failed_write {
        // A reader that went away (`| head`) wanted no more rows.
        if args.out.is_none() && e.kind() == std::io::ErrorKind::BrokenPipe {
            return Ok(());
        }
        return Err(Failure::run(format!("{}; {}", write_error(&e), kept(""))));
    }
    if !complete {
        if let Some(signal) = interrupt::received() {
            return Err(Failure::Interrupted {
                signal,
                message: format!(
                    "interrupted by {}: {} of {n_runs} runs finished; {}",
                    signal.name(),
                    tally.rows,
                    kept(" in grid order")
                ),
            });
        }
    }
    let resumed = if skip > 0 { format!(" ({skip} kept, {} run now)", n_runs - skip) } else { String::new() };
    eprintln!(
        "{n_runs} runs{}{resumed} in {seconds:.2} s on {} threads ({}, rtol {:e}); {} failed",
        if shard.is_whole() { String::new() } else { format!(" (shard {shard} of {} runs)", grid.len()) },
        args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        header.meta("method").unwrap_or("?"),
        config.rtol,
        tally.failed,
    );
    if let Some(code) = code {
        eprintln!("{code}");
    }
    tally.verdict()
}

/// The rows written so far, how many of them failed, and the first that did.
#[derive(Default)]
struct Tally {
    rows: usize,
    failed: usize,
    first_failure: Option<(usize, String)>,
}

impl Tally {
    /// Counts a row, and draws it into the heat map if there is one.
    fn add(&mut self, row: &TableRow, map: Option<&mut HeatMap>) {
        self.rows += 1;
        if !row.failure.is_empty() {
            self.failed += 1;
            self.first_failure.get_or_insert_with(|| (row.run, row.failure.clone()));
        }
        if let Some(map) = map {
            map.add(row);
        }
    }

    /// The exit of a sweep with these rows, run or merged alike: some rows
    /// failing is what a sweep finds out (exit 0); all of them, that it found
    /// nothing (exit 1, with the first run's reason).
    fn verdict(&self) -> Result<(), Failure> {
        match &self.first_failure {
            Some((run, reason)) if self.failed == self.rows => {
                Err(Failure::run(format!("every run failed ({}); the first, run {run}: {reason}", self.rows)))
            }
            _ => Ok(()),
        }
    }
}

/// This command line with `--resume` (once), quoted for a POSIX shell.
fn resume_command() -> String {
    let mut words: Vec<String> = std::env::args().collect();
    if let Some(first) = words.first_mut() {
        *first = "lagrange".into();
    }
    if !words.iter().any(|w| w == "--resume") {
        words.push("--resume".into());
    }
    words.iter().map(|w| shell_quoted(w)).collect::<Vec<_>>().join(" ")
}

/// `word` as a shell reads it back: as it is when it is plain, otherwise in single quotes.
fn shell_quoted(word: &str) -> String {
    let plain = !word.is_empty() && word.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', "'\\''"))
    }
}

/// A sweep's error in the CLI's terms: its settings named by their flags.
fn usage(e: SweepError) -> Failure {
    match e {
        SweepError::ShardSyntax { text } => {
            Failure::usage(format!("--shard must be I/N with 0 <= I < N (the I-th of N slices), not '{text}'"))
        }
        SweepError::Until { until } => {
            Failure::usage(format!("--until must be a positive time, not {}", num::Shortest(until)))
        }
        other => Failure::usage(other.to_string()),
    }
}

/// A heat map that cannot be drawn, in the CLI's terms (exit 2).
fn heatmap_usage(e: HeatMapError) -> Failure {
    Failure::usage(match e {
        HeatMapError::NotTwoDimensional { axes } => format!(
            "--heatmap needs a 2-D grid (two axes, as in --grid \"a=-3:3:100,b=-3:3:100\"); this one has {axes}; the CSV has every run"
        ),
        HeatMapError::UnevenAxis { name } => format!(
            "--heatmap draws evenly spaced axes, and the values of '{name}' are not (give it as START:STOP:COUNT); the CSV has every run"
        ),
        HeatMapError::TooManyCells { first, second } => format!(
            "--heatmap draws at most {MAX_CELLS} cells, and this grid has {first} × {second} = {}; the CSV has every run (draw a coarser grid, or plot the CSV)",
            first * second
        ),
        HeatMapError::UnknownColor { color, known } => {
            format!("--color '{color}' is not available; choose one of {}", known.join(", "))
        }
    })
}

/// `sweep --merge OUT.csv SHARD.csv...`.
fn merge(args: &Args, out: &Path) -> Result<(), Failure> {
    let shards: Vec<&Path> = args.files.iter().map(PathBuf::as_path).collect();
    crate::files::refuse_overwrite(&shards, &[Some(out), args.heatmap.as_deref()]).map_err(Failure::usage)?;
    let mut shards = Vec::with_capacity(args.files.len());
    for path in &args.files {
        let text = crate::files::read_text(path, crate::files::MAX_CSV_BYTES)
            .map_err(|e| Failure::input(path, e.to_string()))?;
        let name = path.display().to_string();
        let table = SweepTable::parse(&text, &name).map_err(|e| Failure::input(path, e.to_string()))?;
        shards.push((name, table));
    }
    let table = mech::merge(&shards).map_err(|e| Failure::usage(e.to_string()))?;
    let mut map = match &args.heatmap {
        Some(_) => Some(HeatMap::new(&table.header, &args.color).map_err(heatmap_usage)?),
        None => None,
    };
    let mut tally = Tally::default();
    table.rows.iter().for_each(|row| tally.add(row, map.as_mut()));
    write_csv(&table, out)?;
    if let (Some(svg), Some(map)) = (&args.heatmap, &map) {
        crate::files::write_figure(svg, "the heat map", map.svg()).map_err(Failure::run)?;
    }
    eprintln!(
        "merged {} shards: {} runs into {}; {} failed",
        shards.len(),
        table.rows.len(),
        out.display(),
        tally.failed
    );
    tally.verdict()
}

/// Writes a merged table to `out`.
fn write_csv(table: &SweepTable, out: &Path) -> Result<(), Failure> {
    let mut file = crate::files::create_locked(out).map_err(|e| Failure::input(out, format!("cannot write: {e}")))?;
    std::io::Write::write_all(&mut file, table.to_csv().as_bytes())
        .map_err(|e| Failure::run(format!("cannot write {}: {e}", out.display())))
}

fn progress_bar(len: u64, done: u64) -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(len);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {elapsed} (eta {eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    pb.set_position(done);
    Some(pb)
}
