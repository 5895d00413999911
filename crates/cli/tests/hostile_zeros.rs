//! Zero tests that numbers once fooled (issue #15): a narrow function such as
//! `exp(-1000000*x^2)` underflows to 0 at every probe point, and a derivation
//! that took "zero at the probe points" for "zero" claimed a cyclic coordinate,
//! a conserved momentum or a central potential that is not there. A claim of
//! zero must now be proven; when it is neither proven nor refuted, nothing is
//! claimed and the output says so. True identities are still proven.

use crate::common::{json, run, TempFile};
use serde_json::Value;

/// The Lagrangian x'^2/2 - exp(-1000000*x^2): a barrier of height 1 and
/// width 1e-3 at x = 0. The start runs into it, so p_x changes by 2 (the
/// particle bounces back).
const NARROW: &str = "crates/cli/tests/undecided/narrow_barrier.toml";

/// The orbit: U = -1/r + exp(-10000*th^2)/r depends on th near th = 0
/// only; started at th = 0.5, where the true energy is 0.72 − 1 = −0.28.
const NARROW_ORBIT: &str = "crates/cli/tests/undecided/narrow_orbit.toml";

fn names(v: &Value) -> Vec<&str> {
    v.as_array().expect("an array").iter().map(|c| c["name"].as_str().expect("a name")).collect()
}

#[test]
fn a_narrow_function_is_not_taken_for_a_cyclic_coordinate() {
    let d = json(&["derive", NARROW, "--format", "json"]);
    assert_eq!(d["cyclic"], serde_json::json!([]), "x is not cyclic");
    assert_eq!(names(&d["conserved"]), ["H"], "p_x is not conserved");
    assert_eq!(d["equations"]["x"], "x'' - 2000000*x*exp(-1000000*x^2)");
    assert_eq!(d["reasons"]["cyclic"], serde_json::json!([{"code": "undecided", "coordinate": "x"}]));
    let why = d["explanations"]["cyclic"][0].as_str().expect("an explanation");
    assert!(why.starts_with("Could not decide whether ∂L/∂x is zero"), "{why}");
    // The text says so where the cyclic coordinates are listed.
    let text = run(&["derive", NARROW]);
    assert_eq!(text.code, Some(0), "{}", text.describe());
    assert!(text.stdout.contains("cyclic coordinates\n  none shown\n  Could not decide whether ∂L/∂x is zero"));
}

#[test]
fn simulate_audits_only_what_the_derivation_claims() {
    let out = TempFile::new("narrow-run", "csv");
    let r = run(&["simulate", NARROW, "--until", "0.1", "--out", out.path(), "--summary", "json"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let summary = r.json();
    let audited: Vec<&String> = summary["invariants"].as_object().expect("invariants").keys().collect();
    assert_eq!(audited, ["H"], "{}", r.describe());
    assert_eq!(summary["warnings"], serde_json::json!([]), "{}", r.describe());
    // The particle bounced off the barrier: p_x went from 1 to −1.
    assert!(summary["final"]["x'"].as_f64().unwrap() < -0.99, "{}", r.describe());
    assert!(!r.stderr.contains("p_x"), "{}", r.describe());
}

#[test]
fn orbit_refuses_a_potential_it_cannot_prove_central() {
    for format in ["text", "json"] {
        let r = run(&["orbit", NARROW_ORBIT, "--format", format]);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stdout.is_empty(), "no orbit, no energy: {}", r.describe());
        assert!(
            r.stderr.contains("cannot tell whether this is a central-force model: could not decide whether the potential U = (exp(-10000*th^2) - 1)/r depends on the angle th"),
            "{}",
            r.describe()
        );
    }
}

#[test]
fn identities_are_still_proven() {
    // U = cos(2x) + 2 sin(x)^2 is the constant 1: x is cyclic by the double-angle
    // identity, which no probe could show.
    let model = TempFile::with_text(
        "identity",
        "coordinates = [\"x\", \"y\"]\nkinetic = \"(x'^2 + y'^2)/2\"\npotential = \"cos(2*x) + 2*sin(x)^2 + y^2/2\"\n",
    );
    let d = json(&["derive", model.path(), "--format", "json"]);
    assert_eq!(d["cyclic"], serde_json::json!(["x"]));
    assert_eq!(names(&d["conserved"]), ["p_x", "H"]);
    assert_eq!(d["hamiltonian_is_energy"], true);
    assert!(d["reasons"].get("cyclic").is_none(), "nothing undecided: {d}");
    // The same identity in a central potential: U = -(cos(2*th) + 2*sin(th)^2)/r is -1/r.
    let orbit = TempFile::with_text(
        "identity-orbit",
        "coordinates = [\"r\", \"th\"]\nlagrangian = \"(r'^2 + r^2*th'^2)/2 + cos(2*th)/r + 2*sin(th)^2/r\"\n\
         [initial]\nr = 1.0\n\"r'\" = 0.0\nth = 0.5\n\"th'\" = 1.2\n",
    );
    let o = json(&["orbit", orbit.path(), "--format", "json"]);
    assert!((o["energy"].as_f64().unwrap() + 0.28).abs() < 1e-12, "{o}");
}

#[test]
fn other_claims_of_zero_are_refused_when_undecided() {
    // A velocity constraint whose nonlinearity underflows at every probe point.
    let constraint = TempFile::with_text(
        "narrow-constraint",
        "coordinates = [\"x\", \"y\"]\nkinetic = \"(x'^2 + y'^2)/2\"\n[[constraints]]\nvelocity = \"x' + exp(-1000000*x^2)*y'^2\"\n",
    );
    let r = run(&["derive", constraint.path()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("could not be shown linear in the velocities"), "{}", r.describe());
    // An inertia tensor whose symmetry cannot be shown.
    let body = TempFile::with_text(
        "narrow-inertia",
        "coordinates = [\"al\", \"be\", \"ga\"]\n[parameters]\nw = 1.0\n[[bodies]]\nmass = \"1\"\n\
         inertia = [[\"1\", \"0\", \"0\"], [\"exp(-1000000*w^2)\", \"2\", \"0\"], [\"0\", \"0\", \"3\"]]\n\
         angles = [\"al\", \"be\", \"ga\"]\n",
    );
    let r = run(&["derive", body.path()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("could not show that the inertia tensor is symmetric"), "{}", r.describe());
}

#[test]
fn h_is_not_claimed_conserved_when_dl_dt_is_undecided() {
    // A kick exp(-1000000*t^2) near t = 0, where no probe point looks.
    let model = TempFile::with_text(
        "narrow-time",
        "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"x^2/2 + exp(-1000000*t^2)*x\"\n\
         [initial]\nx = 1.0\n\"x'\" = 0.0\n",
    );
    let d = json(&["derive", model.path(), "--format", "json"]);
    assert_eq!(d["hamiltonian_conserved"], false);
    assert_eq!(d["explicit_time"], Value::Null);
    assert_eq!(names(&d["conserved"]), Vec::<&str>::new());
    assert_eq!(
        d["reasons"]["conservation"],
        serde_json::json!([{"code": "undecided", "terms": ["explicit_time"]}]),
        "{d}"
    );
    let r = run(&["modes", model.path()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("could not decide whether L depends explicitly on the time t"), "{}", r.describe());
}
