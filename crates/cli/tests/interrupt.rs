//! Interrupted runs lose nothing (issue #15, cases 8 and 11): the real binary
//! is stopped by SIGINT or SIGTERM at varied moments of long `simulate` and
//! `sweep` runs, many times; each must exit 130 or 143 and leave a CSV whose
//! every line is a whole row, and a sweep resumed again and again from its
//! partial output must end as the file of an uninterrupted run, byte for byte.
//! What is asserted does not depend on when the signals land.

use crate::common::{ok, run as lagrange, scratch, start};
use std::path::Path;
use std::process::{Child, Command, Output};
use std::thread::sleep;
use std::time::{Duration, Instant};

/// Waits until the child catches SIGINT and SIGTERM (Linux shows it in
/// /proc/PID/status, line `SigCgt`): from then on a signal is the run's to
/// handle. False when the child ended first.
fn wait_for_handlers(child: &mut Child) -> bool {
    let start = Instant::now();
    let both = (1u64 << (2 - 1)) | (1u64 << (15 - 1));
    loop {
        if child.try_wait().expect("wait for lagrange").is_some() {
            return false;
        }
        let status = std::fs::read_to_string(format!("/proc/{}/status", child.id())).unwrap_or_default();
        let caught = status
            .lines()
            .find_map(|l| l.strip_prefix("SigCgt:"))
            .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
            .unwrap_or(0);
        if caught & both == both {
            return true;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "lagrange never caught SIGINT and SIGTERM");
        sleep(Duration::from_millis(1));
    }
}

/// Sends `signal` (`INT` or `TERM`) to the child.
fn signal(child: &Child, signal: &str) {
    let sent = Command::new("kill").args(["-s", signal, &child.id().to_string()]).status();
    assert!(sent.is_ok_and(|s| s.success()), "kill -s {signal}");
}

fn finish(child: Child) -> Output {
    child.wait_with_output().expect("wait for lagrange")
}

fn describe(out: &Output) -> String {
    format!(
        "exit {:?}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The kill-th signal: SIGINT and SIGTERM in turn, with the exit code each gives.
fn nth_signal(kill: usize) -> (&'static str, i32) {
    if kill.is_multiple_of(2) {
        ("INT", 130)
    } else {
        ("TERM", 143)
    }
}

/// The kill-th delay after the header: 0 to 95 ms, spread over the kills.
fn nth_delay(kill: usize) -> Duration {
    Duration::from_millis((kill as u64 * 37) % 100)
}

/// Every line of a CSV is whole: the file ends with a newline, and each row has
/// the header's number of fields, each a number. Returns the number of rows.
#[track_caller]
fn check_simulate_csv(path: &Path) -> usize {
    // A run stopped before it created its output leaves none.
    let Ok(text) = std::fs::read_to_string(path) else { return 0 };
    assert!(text.ends_with('\n'), "{} ends in the middle of a line: {:?}", path.display(), tail(&text));
    let mut lines = text.lines();
    let width = lines.next().expect("a header").split(',').count();
    let mut rows = 0;
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), width, "row {rows}: {line}");
        assert!(fields.iter().all(|f| f.parse::<f64>().is_ok()), "row {rows}: {line}");
        rows += 1;
    }
    rows
}

fn tail(text: &str) -> &str {
    &text[text.len().saturating_sub(200)..]
}

#[test]
fn a_simulation_stopped_by_a_signal_leaves_whole_rows_and_says_where() {
    let csv = scratch("interrupt", "simulate.csv");
    let csv_arg = csv.to_str().unwrap();
    // DOPRI5 has no pilot runs: rows stream from the start, and 10^5 time units (some 5·10^6
    // steps, within the step budget of 10^7) take seconds, far longer than a kill waits.
    let args = [
        "simulate",
        "examples/pendulum.toml",
        "--until",
        "1e5",
        "--method",
        "dopri5",
        "--every-step",
        "--out",
        csv_arg,
    ];
    let mut rows_seen = 0;
    for kill in 0..20 {
        let (name, code) = nth_signal(kill);
        let mut child = start(&args);
        assert!(wait_for_handlers(&mut child), "a run of 10^5 time units ended");
        sleep(nth_delay(kill));
        signal(&child, name);
        let out = finish(child);
        assert_eq!(out.status.code(), Some(code), "kill {kill} by SIG{name}: {}", describe(&out));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(&format!("interrupted by SIG{name}")), "{}", describe(&out));
        let rows = check_simulate_csv(&csv);
        if rows > 0 && String::from_utf8_lossy(&out.stdout).contains("interrupted at t = ") {
            // The summary's time is the last row's.
            let text = std::fs::read_to_string(&csv).unwrap();
            let last_t = text.lines().last().unwrap().split(',').next().unwrap();
            let t: f64 = last_t.parse().unwrap();
            assert!(stderr.contains(&format!("at t = {t}")), "last row at {t}: {}", describe(&out));
        }
        rows_seen += rows;
    }
    assert!(rows_seen > 0, "no kill landed after the first row");

    // JSON: the summary says it was interrupted, and where.
    let mut child = start(&[&args[..], &["--summary", "json"]].concat());
    assert!(wait_for_handlers(&mut child));
    sleep(Duration::from_millis(300));
    signal(&child, "TERM");
    let out = finish(child);
    assert_eq!(out.status.code(), Some(143), "{}", describe(&out));
    let rows = check_simulate_csv(&csv);
    if rows > 0 && !out.stdout.is_empty() {
        // Interrupted after the first row: the summary names the last row's time.
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(summary["interrupted"]["signal"], "SIGTERM", "{summary}");
        let text = std::fs::read_to_string(&csv).unwrap();
        let last_t: f64 = text.lines().last().unwrap().split(',').next().unwrap().parse().unwrap();
        assert_eq!(summary["interrupted"]["t"], last_t, "{summary}");
    }

    // A second signal exits at once, still between whole rows.
    for kill in 0..4 {
        let mut child = start(&args);
        assert!(wait_for_handlers(&mut child));
        sleep(nth_delay(kill));
        signal(&child, "INT");
        signal(&child, "INT");
        let out = finish(child);
        assert_eq!(out.status.code(), Some(130), "{}", describe(&out));
        check_simulate_csv(&csv);
    }
}

/// The rows of a sweep's CSV: two header lines, then whole rows of runs 0, 1, 2, …
#[track_caller]
fn check_sweep_csv(path: &Path) -> usize {
    // A run stopped before it created its output leaves none.
    let text = std::fs::read_to_string(path).unwrap_or_default();
    if text.is_empty() {
        return 0;
    }
    assert!(text.ends_with('\n'), "{} ends in the middle of a line: {:?}", path.display(), tail(&text));
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("# lagrange sweep;"));
    let width = lines.next().expect("a header").split(',').count();
    let mut rows = 0;
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), width, "row {rows}: {line}");
        assert_eq!(fields[0], rows.to_string(), "rows in grid order: {line}");
        assert!(fields[1..width - 1].iter().all(|f| f.parse::<f64>().is_ok()), "row {rows}: {line}");
        rows += 1;
    }
    rows
}

#[test]
fn a_sweep_stopped_again_and_again_resumes_to_the_uninterrupted_file() {
    let whole = scratch("interrupt", "sweep-whole.csv");
    let parts = scratch("interrupt", "sweep-resumed.csv");
    let sweep = |out: &Path| {
        vec![
            "sweep".to_string(),
            "examples/double_pendulum.toml".into(),
            "--until".into(),
            "10".into(),
            "--grid".into(),
            "a=-3.1:3.1:20,b=-3.1:3.1:20".into(),
            "--no-lyapunov".into(),
            "--threads".into(),
            "2".into(),
            "--out".into(),
            out.to_str().unwrap().into(),
        ]
    };
    let args = sweep(&whole);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(check_sweep_csv(&whole), 400);

    let first = sweep(&parts);
    let mut resume = first.clone();
    resume.push("--resume".into());
    let mut done = false;
    for kills in 0..20 {
        let args = if kills == 0 { &first } else { &resume };
        let mut child = start(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let (name, code) = nth_signal(kills);
        if wait_for_handlers(&mut child) {
            sleep(nth_delay(kills));
            signal(&child, name);
        }
        let out = finish(child);
        let rows = check_sweep_csv(&parts);
        if out.status.code() == Some(0) {
            // The run finished before the signal came.
            assert_eq!(rows, 400, "{}", describe(&out));
            done = true;
            break;
        }
        assert_eq!(out.status.code(), Some(code), "kill {kills} by SIG{name}: {}", describe(&out));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(&format!("interrupted by SIG{name}")), "{}", describe(&out));
        if stderr.contains("runs finished") {
            assert!(stderr.contains(&format!("{rows} of 400 runs finished")), "{rows} rows: {}", describe(&out));
            assert!(stderr.contains("--resume"), "{}", describe(&out));
        }
    }
    if !done {
        ok(&resume.iter().map(String::as_str).collect::<Vec<_>>());
    }
    assert!(std::fs::read(&parts).unwrap() == std::fs::read(&whole).unwrap(), "the resumed file differs");
}

#[test]
fn a_resume_refuses_the_output_of_another_sweep() {
    let csv = scratch("interrupt", "other.csv");
    let out = csv.to_str().unwrap();
    let base = ["sweep", "examples/double_pendulum.toml", "--grid", "a=0:1:3", "--no-lyapunov", "--out", out];
    ok(&[&base[..], &["--until", "1"]].concat());
    let refused = lagrange(&[&base[..], &["--until", "2", "--resume"]].concat());
    assert_eq!(refused.code, Some(2), "{}", refused.describe());
    assert!(
        refused
            .stderr
            .contains("cannot resume: it is the output of another sweep: until is '1.0' there and '2.0' here"),
        "{}",
        refused.describe()
    );
    // A row out of place is refused, not skipped.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.swap(2, 3);
    std::fs::write(&csv, lines.join("\n") + "\n").unwrap();
    let refused = lagrange(&[&base[..], &["--until", "1", "--resume"]].concat());
    assert_eq!(refused.code, Some(2), "{}", refused.describe());
    assert!(refused.stderr.contains("line 3 holds run 1 where run 0 was expected"), "{}", refused.describe());
    // --resume needs the file to continue.
    let r = lagrange(&["sweep", "examples/double_pendulum.toml", "--until", "1", "--grid", "a=0:1:3", "--resume"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
}
