//! Stop events (issue #15, case 16), a regression test: a stop event as
//! accurate as the steps and audited like every row.

mod common;

use common::{close, run, Csv, TempFile};
use serde_json::Value;

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
    let out = TempFile::new("budget-event", "csv");
    let summary = stopped_at_the_bottom(&["--out", out.path()]);
    assert_eq!(summary["method"], "kahanli8");
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
