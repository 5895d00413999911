//! `lagrange-fuzz`: long fuzz runs outside CI, and the re-check of one saved input.
//!
//! ```text
//! lagrange-fuzz expr|loader|derive|bodies|linearize|report|all [--seconds N] [--iterations N] [--seed S]
//!               [--out DIR] [--slow SECONDS] [--hang SECONDS]
//! lagrange-fuzz check TARGET FILE
//! ```
//!
//! A run prints each finding to stderr as it comes, writes its input to
//! `DIR/TARGET-N.txt` (default DIR: `fuzz-findings`), and ends with one JSON
//! line per target on stdout (iterations, seconds, findings). `all` splits
//! `--seconds` evenly over the six targets. A case running longer than
//! `--hang` seconds (default 120) is a hang: a watchdog writes its input to
//! `DIR/TARGET-hang.txt` and ends the process with exit code 3. Exit 1 when
//! anything was found, 2 for bad arguments.

use fuzz::{
    BodiesTarget, Config, Corpus, DeriveTarget, Event, ExprTarget, LinearizeTarget, LoaderTarget, ReportTarget, Stats,
    Target,
};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The targets, in the order `all` runs them.
const TARGETS: [&str; 6] = ["expr", "loader", "derive", "bodies", "linearize", "report"];

/// What the command line asks for.
struct Args {
    targets: Vec<String>,
    config: Config,
    out: PathBuf,
    hang_seconds: f64,
}

fn usage() -> ! {
    eprintln!(
        "usage: lagrange-fuzz expr|loader|derive|bodies|linearize|report|all [--seconds N] [--iterations N] [--seed S] [--out DIR] [--slow S] [--hang S]\n       lagrange-fuzz check TARGET FILE"
    );
    std::process::exit(2)
}

fn parse_args(args: &[String]) -> Args {
    let mut parsed = Args {
        targets: Vec::new(),
        config: Config::default(),
        out: PathBuf::from("fuzz-findings"),
        hang_seconds: 120.0,
    };
    let mut it = args.iter();
    match it.next().map(String::as_str) {
        Some("all") => parsed.targets = TARGETS.iter().map(|t| t.to_string()).collect(),
        Some(t) if TARGETS.contains(&t) => parsed.targets = vec![t.into()],
        _ => usage(),
    }
    while let Some(flag) = it.next() {
        let value = it.next().unwrap_or_else(|| usage());
        let number = || value.parse::<f64>().ok().filter(|v| v.is_finite() && *v >= 0.0).unwrap_or_else(|| usage());
        match flag.as_str() {
            "--seconds" => parsed.config.seconds = Some(number()),
            "--iterations" => parsed.config.iterations = Some(value.parse().unwrap_or_else(|_| usage())),
            "--seed" => parsed.config.seed = value.parse().unwrap_or_else(|_| usage()),
            "--out" => parsed.out = PathBuf::from(value),
            "--slow" => parsed.config.slow_seconds = number(),
            "--hang" => parsed.hang_seconds = number(),
            _ => usage(),
        }
    }
    if parsed.config.seconds.is_none() && parsed.config.iterations.is_none() {
        parsed.config.seconds = Some(60.0);
    }
    if let Some(s) = parsed.config.seconds {
        parsed.config.seconds = Some(s / parsed.targets.len() as f64);
    }
    parsed
}

fn make_target(name: &str, corpus: &Corpus) -> Box<dyn Target> {
    match name {
        "expr" => Box::new(ExprTarget::new(corpus)),
        "loader" => Box::new(LoaderTarget::new(corpus)),
        "bodies" => Box::new(BodiesTarget),
        "linearize" => Box::new(LinearizeTarget),
        "report" => Box::new(ReportTarget),
        _ => Box::new(DeriveTarget),
    }
}

/// Re-runs the check of `target` on the input in `file`.
fn check(target: &str, file: &Path, corpus: &Corpus) -> i32 {
    let input = match std::fs::read_to_string(file) {
        Ok(text) => text,
        Err(err) => {
            eprintln!("cannot read {}: {err}", file.display());
            return 2;
        }
    };
    let check = || match target {
        "expr" => fuzz::check_expression(&input),
        "loader" => fuzz::check_file(&input, &corpus.body_files()),
        "derive" => fuzz::check_derivation(&input),
        "bodies" => fuzz::check_bodies(&input),
        "linearize" => fuzz::check_linearization(&input),
        "report" => fuzz::check_report(&input),
        _ => usage(),
    };
    // A panic is a finding like any other (the hook has printed where it was).
    let outcome = std::panic::catch_unwind(check).unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic".into());
        fuzz::Outcome::problem(fuzz::FindingKind::Panic, message)
    });
    match outcome.problem {
        Some((kind, message)) => {
            println!("{kind:?}: {message}");
            1
        }
        None => {
            println!("fine: {}", outcome.signature);
            0
        }
    }
}

/// The watchdog: ends the process when one case runs past `hang` seconds.
fn watchdog(current: Arc<Mutex<Option<(Instant, String, String)>>>, hang: f64, out: PathBuf) {
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(500));
        let guard = current.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((started, target, input)) = guard.as_ref() {
            if started.elapsed().as_secs_f64() > hang {
                let path = out.join(format!("{target}-hang.txt"));
                let _ = std::fs::create_dir_all(&out);
                let _ = std::fs::write(&path, input);
                eprintln!("hang: one {target} case ran past {hang} s; its input is in {}", path.display());
                std::process::exit(3);
            }
        }
    });
}

fn summary(stats: &Stats, files: &[String]) -> String {
    let findings: Vec<serde_json::Value> = stats
        .findings
        .iter()
        .zip(files)
        .map(|(f, file)| serde_json::json!({"kind": format!("{:?}", f.kind), "message": f.message, "file": file, "iteration": f.iteration}))
        .collect();
    serde_json::json!({
        "target": stats.target,
        "iterations": stats.iterations,
        "seconds": (stats.seconds * 10.0).round() / 10.0,
        "signatures": stats.signatures,
        "corpus": stats.corpus,
        "slowest_seconds": (stats.slowest_seconds * 1000.0).round() / 1000.0,
        "findings": findings,
    })
    .to_string()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let corpus = match Corpus::load(&Corpus::repo_root()) {
        Ok(corpus) => corpus,
        Err(err) => {
            eprintln!("cannot read the seed corpus: {err}");
            std::process::exit(2)
        }
    };
    if args.first().map(String::as_str) == Some("check") {
        let (Some(target), Some(file)) = (args.get(1), args.get(2)) else { usage() };
        std::process::exit(check(target, Path::new(file), &corpus));
    }
    let args = parse_args(&args);
    let current = Arc::new(Mutex::new(None));
    watchdog(current.clone(), args.hang_seconds, args.out.clone());
    let mut found = false;
    for name in &args.targets {
        let mut target = make_target(name, &corpus);
        let mut files = Vec::new();
        let stats = fuzz::run(target.as_mut(), &args.config, &mut |event| match event {
            Event::Start(input) => {
                *current.lock().unwrap_or_else(|e| e.into_inner()) =
                    Some((Instant::now(), name.clone(), input.to_string()));
            }
            Event::Found(f) => {
                let path = args.out.join(format!("{name}-{}.txt", files.len() + 1));
                let _ = std::fs::create_dir_all(&args.out);
                let written = std::fs::write(&path, &f.input).is_ok();
                eprintln!(
                    "{name}: {:?} at iteration {}: {}{}",
                    f.kind,
                    f.iteration,
                    f.message,
                    if written { format!(" (input in {})", path.display()) } else { String::new() }
                );
                files.push(path.display().to_string());
            }
        });
        *current.lock().unwrap_or_else(|e| e.into_inner()) = None;
        found |= !stats.findings.is_empty();
        println!("{}", summary(&stats, &files));
    }
    std::process::exit(i32::from(found));
}
