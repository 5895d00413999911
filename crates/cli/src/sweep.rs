//! `lagrange sweep`: many trajectories over a grid of initial values or
//! parameters, on all cores; one CSV row per run and a heat map.
//!
//! Two forms: `lagrange sweep MODEL --until T --grid SPEC [...]` runs a sweep (or
//! the shard `--shard i/n` of one), and `lagrange sweep --merge OUT.csv
//! SHARD.csv...` joins the shards' CSV files into the whole sweep's. Both may
//! draw `--heatmap FILE.svg`. The computation is `mech::sweep`; this module
//! parses options, shows progress on a terminal and does the IO.

mod heatmap;

use crate::diagnostics::Failure;
use mech::{Grid, Shard, SweepConfig, SweepError, SweepTable};
use num::Method;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `sweep`.
#[derive(clap::Args)]
pub struct Args {
    /// The model file (TOML); with --merge, the shards' CSV files.
    #[arg(required = true, value_name = "MODEL | SHARD.csv")]
    pub files: Vec<PathBuf>,
    /// End time of every run (each starts at t = 0).
    #[arg(long, required_unless_present = "merge", allow_negative_numbers = true)]
    pub until: Option<f64>,
    /// The grid: NAME=START:STOP:COUNT, comma separated (coordinates a, velocities a', parameters).
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
    /// Join the shard CSV files given in place of MODEL into OUT.csv.
    #[arg(long, value_name = "OUT.csv", conflicts_with_all = ["until", "grid", "set", "method", "rtol", "atol", "out", "shard", "threads", "no_lyapunov"])]
    pub merge: Option<PathBuf>,
}

/// Most worker threads a sweep starts: far above any machine's cores, far
/// below what takes the operating system seconds to refuse.
const MAX_THREADS: usize = 1024;

/// Runs `sweep` (or `sweep --merge`).
pub fn run(args: &Args) -> Result<(), Failure> {
    if let Some(out) = &args.merge {
        return merge(args, out);
    }
    let inputs: Vec<&Path> = args.files.iter().map(PathBuf::as_path).collect();
    crate::files::refuse_overwrite(&inputs, &[args.out.as_deref(), args.heatmap.as_deref()]).map_err(Failure::usage)?;
    let [path] = args.files.as_slice() else {
        return Err(Failure::usage(format!(
            "sweep takes one model file, not {} files (to join shards: sweep --merge OUT.csv SHARD.csv...)",
            args.files.len()
        )));
    };
    // clap requires --until without --merge; None is reported, not assumed.
    let Some(until) = args.until else { return Err(Failure::usage("sweep needs --until T")) };
    for (name, v) in [("--rtol", args.rtol), ("--atol", args.atol)] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(Failure::usage(format!("{name} must be a positive number, not {v}")));
            }
        }
    }
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
    let method = match &args.method {
        Some(name) => Some(name.parse::<Method>().map_err(|e| Failure::usage(e.to_string()))?),
        None => None,
    };
    let (source, derivation) = crate::derive_file(path, &args.set)?;
    derivation.reject_constraints("`lagrange sweep`").map_err(|e| Failure::model(path, &source, e))?;
    let grid = Grid::parse(args.grid.as_deref().unwrap_or_default(), derivation.model()).map_err(usage)?;
    if args.heatmap.is_some() {
        let mut columns: Vec<String> = vec!["t_final".into(), "energy_drift".into()];
        if !args.no_lyapunov {
            columns.push("lyapunov".into());
        }
        for c in derivation.coordinate_names() {
            columns.extend([format!("final_{c}"), format!("final_{c}'")]);
        }
        heatmap::check_request(grid.axes.len(), &args.color, &columns).map_err(Failure::usage)?;
    }
    let rtol = args.rtol.unwrap_or(mech::DEFAULT_RTOL);
    let config = SweepConfig {
        until,
        method,
        rtol,
        atol: args.atol.unwrap_or(rtol * 1e-2),
        lyapunov: !args.no_lyapunov,
        shard,
        threads: args.threads,
    };

    let n_runs = shard.runs(grid.len()).count();
    let progress = progress_bar(n_runs as u64);
    let start = Instant::now();
    let tick = || {
        if let Some(pb) = &progress {
            pb.inc(1);
        }
    };
    let result = mech::sweep(&derivation, &grid, &config, &tick);
    if let Some(pb) = &progress {
        pb.finish_and_clear();
    }
    let table = result.map_err(|e| match e {
        SweepError::Model(e) => Failure::model(path, &source, e),
        other => usage(other),
    })?;
    let seconds = start.elapsed().as_secs_f64();
    write_csv(&table, args.out.as_deref())?;
    if let Some(svg) = &args.heatmap {
        heatmap::write_svg(svg, &table, &args.color).map_err(Failure::run)?;
    }
    let failed = table.rows.iter().filter(|r| !r.failure.is_empty()).count();
    eprintln!(
        "{n_runs} runs{} in {seconds:.2} s on {} threads ({}, rtol {:e}); {failed} failed",
        if shard.is_whole() { String::new() } else { format!(" (shard {shard} of {} runs)", grid.len()) },
        args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        table.meta("method").unwrap_or("?"),
        config.rtol,
    );
    Ok(())
}

/// A sweep's error in the CLI's terms: its settings named by their flags.
fn usage(e: SweepError) -> Failure {
    match e {
        SweepError::ShardSyntax { text } => {
            Failure::usage(format!("--shard must be I/N with 0 <= I < N (the I-th of N slices), not '{text}'"))
        }
        SweepError::Until { until } => Failure::usage(format!("--until must be a positive time, not {until}")),
        other => Failure::usage(other.to_string()),
    }
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
    if args.heatmap.is_some() {
        let n_axes = table.axes().map_or(0, |a| a.len());
        heatmap::check_request(n_axes, &args.color, &table.columns).map_err(Failure::usage)?;
    }
    write_csv(&table, Some(out))?;
    if let Some(svg) = &args.heatmap {
        heatmap::write_svg(svg, &table, &args.color).map_err(Failure::run)?;
    }
    eprintln!("merged {} shards: {} runs into {}", shards.len(), table.rows.len(), out.display());
    Ok(())
}

fn write_csv(table: &SweepTable, out: Option<&Path>) -> Result<(), Failure> {
    let text = table.to_csv();
    match out {
        Some(p) => {
            let mut file =
                crate::files::create_locked(p).map_err(|e| Failure::input(p, format!("cannot write: {e}")))?;
            std::io::Write::write_all(&mut file, text.as_bytes())
                .map_err(|e| Failure::run(format!("cannot write {}: {e}", p.display())))
        }
        None => crate::write_stdout(&text),
    }
}

fn progress_bar(len: u64) -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(len);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {elapsed} (eta {eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Some(pb)
}
