//! A fixed-step Gauss run whose motion outruns its step (issue 16): the steps whose
//! stage equations do not converge are taken as sub-steps, the run reaches its end,
//! and its warnings say so, with the drift of H that shows the result is off.

use crate::common::json;
use serde_json::Value;

/// The runaway model to t = 3 under `method`: its JSON summary (exit 0).
fn runaway(method: &str) -> Value {
    let model = "crates/cli/tests/robust/cubic_runaway.toml";
    json(&["simulate", model, "--until", "3", "--method", method, "--summary", "json"])
}

#[test]
fn a_runaway_motion_is_followed_in_sub_steps_and_warned_about() {
    let summary = runaway("gauss6");
    assert_eq!(summary["t_final"].as_f64(), Some(3.0));
    let warnings: Vec<&str> = summary["warnings"].as_array().unwrap().iter().filter_map(|w| w.as_str()).collect();
    assert!(
        warnings.iter().any(|w| w.contains("did not converge")
            && w.contains("shorter sub-steps")
            && w.contains("the first at t = 2.")),
        "{warnings:?}"
    );
    // The fixed step did not resolve the end of the motion: H says so.
    assert!(warnings.iter().any(|w| w.starts_with("H is conserved, but drifted")), "{warnings:?}");
    // The same model with an adaptive method, for the answer.
    let u = runaway("dop853")["final"]["u"].as_f64().unwrap();
    assert!((u + 714.25234).abs() < 1e-6 * 714.25234, "u(3) = {u}");
}
