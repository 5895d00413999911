//! The default method (issue #16): which one the derivation picks, that it
//! follows motions where a step fixed at the start failed (a runaway in a
//! cubic potential, rigid bodies tumbling near their Euler angles' gimbal
//! singularity), and that the summary says what the tolerance controlled.

use crate::common::{close, json, run, Csv, TempFile};
use serde_json::Value;

const RUNAWAY: &str = "crates/cli/tests/robust/cubic_runaway.toml";
const NEAR_GIMBAL: [(&str, f64); 2] = [
    ("crates/cli/tests/robust/tumbling_near_gimbal.toml", 0.03),
    ("crates/cli/tests/robust/tumbling_nearer_gimbal.toml", 0.004),
];

/// A model with a kink: a V-shaped potential |x|.
const V_POTENTIAL: &str = "name = \"V\"\ncoordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"abs(x)\"\n[initial]\nx = 1.0\n\"x'\" = 0.0\n";

fn summary(args: &[&str]) -> Value {
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--summary", "json"]);
    json(&all)
}

fn method_of(args: &[&str]) -> String {
    summary(args)["method"].as_str().expect("a method").to_string()
}

#[test]
fn the_default_is_taylor_where_the_equations_are_analytic_and_the_model_small_and_dop853_elsewhere() {
    for example in
        ["double_pendulum", "kepler", "chain50", "damped_oscillator", "rotating_wire_gravity", "tops/heavy_top"]
    {
        let model = format!("examples/{example}.toml");
        assert_eq!(method_of(&[&model, "--until", "1"]), "taylor", "{example}");
    }
    // Past four coordinates, with M depending on them, DOP853 is the faster
    // (a chain of 32 rods; the chain of 50 springs above keeps Taylor: M is constant).
    assert_eq!(method_of(&["examples/large/rod_chain.toml", "--until", "0.01"]), "dop853");
    // Constraints: the state is projected after every step.
    assert_eq!(method_of(&["examples/constraints/pendulum_cartesian.toml", "--until", "1"]), "dop853");
    // A kink (abs) that a Taylor series does not see coming.
    let v = TempFile::with_text("v-potential", V_POTENTIAL);
    let s = summary(&[v.path(), "--until", "4"]);
    assert_eq!(s["method"], "dop853");
    // x = 1 − t²/2 to x = 0 at t = √2, then back up the other side: x(4) = −√2·τ + τ²/2, τ = 4 − √2.
    let tau = 4.0 - 2f64.sqrt();
    close(s["final"]["x"].as_f64().unwrap(), -2f64.sqrt() * tau + tau * tau / 2.0, 1e-8);
    // Chosen by name there, the Taylor method says what it cannot see.
    let r = run(&["simulate", v.path(), "--until", "4", "--method", "taylor"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(r.stderr.contains("abs(), whose kink a Taylor series does not see"), "{}", r.describe());
}

#[test]
fn a_fixed_step_without_a_method_keeps_the_symplectic_choice() {
    let s = summary(&["examples/oscillator.toml", "--until", "10", "--dt", "0.01"]);
    assert_eq!((s["method"].as_str(), s["form"].as_str()), (Some("kahanli8"), Some("separable")));
    assert_eq!(s["tolerance_controls"], "nothing: the step was given (--dt)");
    let s = summary(&["examples/kepler.toml", "--until", "10", "--dt", "0.01"]);
    assert_eq!((s["method"].as_str(), s["form"].as_str()), (Some("gauss6"), Some("hamilton")));
}

#[test]
fn the_summary_says_what_the_tolerance_controls() {
    let taylor = summary(&["examples/pendulum.toml", "--until", "1"]);
    assert!(taylor["tolerance_controls"].as_str().unwrap().starts_with("each step's truncation error"), "{taylor}");
    let dop = summary(&["examples/pendulum.toml", "--until", "1", "--method", "dop853"]);
    assert!(dop["tolerance_controls"].as_str().unwrap().starts_with("each step's local error estimate"), "{dop}");
    let gauss = summary(&["examples/pendulum.toml", "--until", "1", "--method", "gauss6"]);
    assert!(gauss["tolerance_controls"].as_str().unwrap().contains("not the trajectory's error"), "{gauss}");
    let text = run(&["simulate", "examples/pendulum.toml", "--until", "1", "--method", "gauss6"]);
    assert!(
        text.stdout.lines().nth(2).unwrap().starts_with("tolerance controls the fixed step only"),
        "{}",
        text.describe()
    );
}

#[test]
fn the_default_follows_a_runaway_in_a_cubic_potential() {
    let s = summary(&[RUNAWAY, "--until", "3"]);
    assert_eq!(s["method"], "taylor");
    assert_eq!(s["t_final"], 3.0, "{s}");
    // SciPy's DOP853 (rtol 1e-12) gives u(3) = −714.25234, and so does a run 10⁴ times tighter.
    let u = s["final"]["u"].as_f64().unwrap();
    close(u, -714.25234, 1e-8);
    let tight = summary(&[RUNAWAY, "--until", "3", "--rtol", "1e-13"]);
    close(u, tight["final"]["u"].as_f64().unwrap(), 1e-8);
}

#[test]
fn the_default_meets_the_tolerance_near_the_gimbal_singularity() {
    for (model, closest) in NEAR_GIMBAL {
        let out = TempFile::new("near-gimbal", "csv");
        let s = summary(&[model, "--until", "5", "--rtol", "1e-10", "--out", out.path()]);
        assert_eq!((s["method"].as_str(), s["t_final"].as_f64()), (Some("taylor"), Some(5.0)), "{s}");
        // The motion comes as close to the singularity as the model says.
        let be = Csv::read(out.path()).column("be");
        assert!(be.iter().map(|b| b.sin().abs()).fold(1.0, f64::min) < closest, "{model}");
        // The final state within 100 tolerances of a run 1000 times tighter by
        // another method, and H to 1e-10.
        let reference = summary(&[model, "--until", "5", "--rtol", "1e-13", "--method", "dop853"]);
        for (name, want) in reference["final"].as_object().unwrap() {
            let (got, want) = (s["final"][name].as_f64().unwrap(), want.as_f64().unwrap());
            assert!((got - want).abs() <= 100.0 * (1e-13 + 1e-10 * want.abs()), "{model}: {name} = {got}, want {want}");
        }
        assert!(s["invariants"]["H"]["max_rel_drift"].as_f64().unwrap() < 1e-10, "{s}");
    }
}
