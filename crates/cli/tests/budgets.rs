//! Runs that cannot reach their end time within the step budget, and stop
//! events (issue #15, cases 10, 12, 16 and 17), each a regression test: a
//! fixed step beyond the budget refused before the run (exit 2) with the
//! estimate, an adaptive run stopped by its budget diagnosed as such (exit 1,
//! not "the motion blew up"), its summary ending where the run stood, and a
//! stop event as accurate as the steps and audited like every row.

use crate::common;

use crate::common::{close, run, Csv, TempFile};
use serde_json::Value;

/// Runs the binary and expects `code`, with each of `needles` in stderr and
/// none of `absent`.
#[track_caller]
fn expect(args: &[&str], code: i32, needles: &[&str], absent: &[&str]) -> common::Run {
    let r = run(args);
    assert_eq!(r.code, Some(code), "{}", r.describe());
    for needle in needles {
        assert!(r.stderr.contains(needle), "wanted '{needle}' in:\n{}", r.describe());
    }
    for needle in absent {
        assert!(!r.stderr.contains(needle), "did not want '{needle}' in:\n{}", r.describe());
    }
    r
}

#[test]
fn a_stiff_oscillator_is_refused_before_the_run_with_the_estimate() {
    // k = m om² = 10^12: period 6.3e-6, 1.6 million of them in 10 time units.
    expect(
        &["simulate", "examples/oscillator.toml", "--until", "10", "--set", "om=1e6", "--method", "kahanli8"],
        2,
        &[
            "kahanli8 would take 3.50e7 steps of 2.86e-7",
            "more than the 10000000 steps a run may take, which reach t ≈ 2.86",
            "6.28e-6 (the period of an oscillation)",
            "give a shorter --until (at most about 2.86)",
        ],
        &["blew up"],
    );
}

#[test]
fn a_stiff_oscillator_under_an_adaptive_method_stops_on_its_budget_not_as_a_blow_up() {
    let out = TempFile::new("budget-stiff", "csv");
    let r = expect(
        &[
            "simulate",
            "examples/oscillator.toml",
            "--until",
            "100",
            "--set",
            "om=1e6",
            "--method",
            "dop853",
            "--summary",
            "json",
            "--out",
            out.path(),
        ],
        1,
        &["dop853 stopped early", "6.28e-6 (the period of an oscillation)", "--until"],
        &["blew up"],
    );
    let summary = r.json();
    let reason = &summary["failure_reason"];
    assert_eq!(reason["code"], "step_budget", "{summary}");
    assert_eq!(reason["stage"], "foreseen", "{summary}");
    assert_eq!(reason["time_scale"]["kind"], "oscillation", "{summary}");
    // The summary ends where the run stood, which the error names, and the
    // final state is that state (moving, not the initial state at rest).
    let t = summary["t_final"].as_f64().unwrap();
    assert_eq!(reason["t"].as_f64(), Some(t));
    assert!(r.stderr.contains(&format!("at t = {t} after")), "{}", r.describe());
    assert!(summary["final"]["x'"].as_f64().unwrap().abs() > 1.0, "{summary}");
    // The rows written up to there are kept.
    let csv = Csv::read(out.path());
    assert!(!csv.rows.is_empty() && csv.rows.last().unwrap()[0] <= t);
}

#[test]
fn a_low_order_method_at_a_tight_tolerance_is_refused_before_the_run() {
    // Case 17: gauss2 at rtol 1e-12 needs a step of a few 1e-7 on the double
    // pendulum, tens of millions of steps over 10 time units.
    expect(
        &["simulate", "examples/double_pendulum.toml", "--until", "10", "--method", "gauss2", "--rtol", "1e-12"],
        2,
        &["gauss2 would take", "more than the 10000000 steps", "a method of order 2", "--method gauss6", "--rtol"],
        &["stage equations"],
    );
}

#[test]
fn a_run_far_beyond_the_budget_is_refused_or_stopped_at_once() {
    // Case 10: a fixed step is refused before the run; an adaptive method (the
    // default's, or DOP853) stops at its first checkpoint, a 128th of the budget.
    expect(
        &["simulate", "examples/pendulum.toml", "--until", "1e12", "--method", "kahanli8"],
        2,
        &["kahanli8 would take", "to reach t = 1000000000000", "--until"],
        &[],
    );
    let default = expect(
        &["simulate", "examples/pendulum.toml", "--until", "1e12", "--summary", "json"],
        1,
        &["taylor stopped early", "(the period of an oscillation)"],
        &["blew up"],
    );
    assert_eq!(default.json()["steps"], 10_000_000 / 128);
    let r = expect(
        &["simulate", "examples/pendulum.toml", "--until", "1e12", "--method", "dop853", "--summary", "json"],
        1,
        &["dop853 stopped early", "(the period of an oscillation)"],
        &["blew up"],
    );
    let summary = r.json();
    assert_eq!(summary["steps"], 10_000_000 / 128);
    let t = summary["t_final"].as_f64().unwrap();
    assert!(t > 1000.0, "{summary}");
    // The final state is the one reached, audited: H has its drift there.
    let h = &summary["invariants"]["H"];
    let (initial, last) = (h["initial"].as_f64().unwrap(), h["final"].as_f64().unwrap());
    assert_ne!(summary["final"]["ph"].as_f64(), Some(1.0), "{summary}");
    assert!(h["max_abs_drift"].as_f64().unwrap() >= (last - initial).abs(), "{summary}");
}

/// The summary of the pendulum stopped at the bottom of its swing.
fn stopped_at_the_bottom(extra: &[&str]) -> Value {
    let mut args = vec!["simulate", "examples/pendulum.toml", "--until", "10", "--stop-when", "ph < 0"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--summary", "json"]);
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    r.json()
}

#[test]
fn a_stop_event_meets_the_tolerance_and_is_audited_like_every_row() {
    // Case 16: released at ph = 1 from rest, the pendulum (g = 9.81, l = 1)
    // passes the bottom with ph'² = 2 g/l (1 − cos 1).
    // The default method, and a fixed-step one whose event falls between steps.
    for method in ["taylor", "kahanli8"] {
        let out = TempFile::new("budget-event", "csv");
        let extra: &[&str] = if method == "taylor" { &[] } else { &["--method", method] };
        let summary = stopped_at_the_bottom(&[extra, &["--out", out.path()]].concat());
        assert_eq!(summary["method"], method);
        stop_event_is_accurate(&summary, &out);
    }
}

/// The pendulum's stop at the bottom of its swing: as accurate as the tolerance,
/// audited, the CSV's last row.
#[track_caller]
fn stop_event_is_accurate(summary: &Value, out: &TempFile) {
    let speed = -(2.0 * 9.81 * (1.0 - 1f64.cos())).sqrt();
    close(summary["final"]["ph'"].as_f64().unwrap(), speed, 1e-9);
    assert!(summary["final"]["ph"].as_f64().unwrap().abs() < 1e-12, "{summary}");
    let h = &summary["invariants"]["H"];
    let (initial, last) = (h["initial"].as_f64().unwrap(), h["final"].as_f64().unwrap());
    assert!((last - initial).abs() < 1e-9 * initial.abs(), "{summary}");
    assert!(h["max_abs_drift"].as_f64().unwrap() >= (last - initial).abs(), "{summary}");
    // The event row is the CSV's last, the state of the summary.
    let csv = Csv::read(out.path());
    let row = csv.rows.last().unwrap();
    assert_eq!(row[csv.col("t")], summary["t_final"].as_f64().unwrap());
    assert_eq!(row[csv.col("ph'")], summary["final"]["ph'"].as_f64().unwrap());
    // The time agrees with a run at a far tighter tolerance.
    let reference = stopped_at_the_bottom(&["--method", "dop853", "--rtol", "1e-13"]);
    close(summary["t_final"].as_f64().unwrap(), reference["t_final"].as_f64().unwrap(), 1e-10);
}

#[test]
fn a_run_refused_before_it_starts_leaves_its_output_as_it_was() {
    // Exit 2 means nothing was computed: an existing --out keeps its content,
    // and no file is left where there was none.
    let refused = ["simulate", "examples/pendulum.toml", "--until", "1e12", "--method", "kahanli8", "--out"];
    let kept = TempFile::new("refused-kept", "csv");
    std::fs::write(kept.path(), "an earlier run's rows\n").unwrap();
    expect(&[&refused[..], &[kept.path()]].concat(), 2, &["kahanli8 would take"], &[]);
    assert_eq!(std::fs::read_to_string(kept.path()).unwrap(), "an earlier run's rows\n");
    let fresh = TempFile::new("refused-fresh", "csv");
    expect(&[&refused[..], &[fresh.path()]].concat(), 2, &["kahanli8 would take"], &[]);
    assert!(!std::path::Path::new(fresh.path()).exists(), "no file where there was none");
}
