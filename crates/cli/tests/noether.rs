//! Conserved quantities from symmetries of L (notes §2.4, issue #34), run
//! through the real binary: `derive` lists each with `why.code = "symmetry"`
//! and its generator, and `simulate` audits it along a run.
//!
//! - two bodies in the plane in Cartesian coordinates: P_x, P_y and L_z;
//! - the spherical pendulum in Cartesian coordinates with its constraint: L_z
//!   only (a translation would move the sphere);
//! - a charge in a uniform magnetic field in Landau gauge: a translation and a
//!   rotation that change L by dF/dt with F ≠ 0;
//! - a Lagrangian written directly in the two bodies' coordinates: shifts of
//!   two coordinates together;
//! - models without a symmetry beyond the cyclic coordinates: nothing new.

use crate::common::{json, TempFile};
use serde_json::Value;

/// The `conserved` entries whose `why.code` is `symmetry`.
fn symmetries(model: &str) -> Vec<Value> {
    let d = json(&["derive", model, "--format", "json"]);
    d["conserved"]
        .as_array()
        .expect("conserved is a list")
        .iter()
        .filter(|c| c["why"]["code"] == "symmetry")
        .cloned()
        .collect()
}

fn names(entries: &[Value]) -> Vec<&str> {
    entries.iter().map(|c| c["name"].as_str().unwrap()).collect()
}

fn named<'a>(entries: &'a [Value], name: &str) -> &'a Value {
    entries.iter().find(|c| c["name"] == name).unwrap_or_else(|| panic!("no {name} in {entries:?}"))
}

/// Every invariant's largest relative drift along a run, by name.
fn drifts(model: &str, until: &str) -> Value {
    let summary = json(&["simulate", model, "--until", until, "--rtol", "1e-10", "--summary", "json"]);
    summary["invariants"].clone()
}

#[track_caller]
fn audited(invariants: &Value, name: &str, bound: f64) {
    let v = &invariants[name];
    let drift = v["max_abs_drift"].as_f64().unwrap_or_else(|| panic!("{name} is not audited: {invariants}"));
    assert!(drift < bound, "{name} drifts by {drift}: {v}");
}

#[test]
fn two_bodies_in_cartesian_coordinates_conserve_momentum_and_angular_momentum() {
    let model = "examples/two_body_cartesian.toml";
    let found = symmetries(model);
    assert_eq!(names(&found), ["P_x", "P_y", "L_z"], "{found:?}");
    assert_eq!(named(&found, "P_x")["expr"], "m1*x1' + m2*x2'");
    let l_z = named(&found, "L_z");
    let generator = &l_z["why"]["generator"];
    assert_eq!(generator["kind"], "rotation");
    assert_eq!(generator["axis"], "z");
    assert_eq!(generator["xi"], serde_json::json!({"x1": "-y1", "y1": "x1", "x2": "-y2", "y2": "x2"}));
    assert!(l_z["why"].get("F").is_none(), "L is unchanged: no F");
    assert!(l_z["reason"].as_str().unwrap().contains("rotating every particle about z"), "{l_z}");
    let run = drifts(model, "20");
    for name in ["P_x", "P_y", "L_z"] {
        audited(&run, name, 1e-8);
    }
    // The initial values are the sums of the two bodies' own.
    let p_x = run["P_x"]["initial"].as_f64().unwrap();
    assert!((p_x - 3.0 * 0.1).abs() < 1e-12, "P_x(0) = {p_x}");
    let l = run["L_z"]["initial"].as_f64().unwrap();
    let want = 3.0 * (0.25 * 0.375) + 1.0 * (-0.75 * -1.125);
    assert!((l - want).abs() < 1e-12, "L_z(0) = {l}, want {want}");
}

#[test]
fn the_spherical_pendulum_in_cartesian_coordinates_conserves_only_l_z() {
    let model = "examples/spherical_pendulum_cartesian.toml";
    let found = symmetries(model);
    assert_eq!(names(&found), ["L_z"], "{found:?}");
    assert_eq!(named(&found, "L_z")["expr"], "-m*x'*y + m*x*y'");
    let run = drifts(model, "10");
    audited(&run, "L_z", 1e-7);
    // The cyclic x and y are not claimed: the rod's force acts on them.
    assert!(run.get("p_x").is_none() && run.get("P_x").is_none(), "{run}");
}

#[test]
fn a_charge_in_a_magnetic_field_conserves_quantities_with_a_gauge_term() {
    let model = "examples/charged_particle_landau.toml";
    let found = symmetries(model);
    assert_eq!(names(&found), ["P_y", "L_z"], "{found:?}");
    let p_y = named(&found, "P_y");
    assert_eq!(p_y["expr"], "B*Q*x + m*y'");
    assert_eq!(p_y["why"]["F"], "-B*Q*x");
    assert_eq!(p_y["why"]["generator"]["kind"], "translation");
    let l_z = named(&found, "L_z");
    assert!(l_z["why"]["F"].is_string(), "{l_z}");
    let run = drifts(model, "10");
    audited(&run, "P_y", 1e-9);
    audited(&run, "L_z", 1e-8);
    // x' = 1, y' = 0.5 at the origin: P_y(0) = m y' = 0.5.
    assert_eq!(run["P_y"]["initial"].as_f64(), Some(0.5));
}

#[test]
fn fields_in_the_symmetric_gauge_give_shifts_with_time_in_f() {
    // U = −Q E0 x − Q B0 (x y' − y x')/2: shifting x changes L by Q E0 + Q B0 y'/2,
    // the rate of F = Q E0 t + Q B0 y/2, so m x' − Q B0 y − Q E0 t is conserved.
    let found = symmetries("examples/charged_particle.toml");
    assert_eq!(names(&found), ["N_x", "N_y"], "combinations of the two are not listed again: {found:?}");
    assert_eq!(named(&found, "N_x")["expr"], "-E0*Q*t + m*x' - B0*Q*y");
    assert_eq!(named(&found, "N_x")["why"]["F"], "E0*Q*t + B0*Q*y/2");
    let run = drifts("examples/charged_particle.toml", "10");
    audited(&run, "N_x", 1e-9);
    audited(&run, "N_y", 1e-9);
}

#[test]
fn a_lagrangian_in_the_bodies_own_coordinates_is_searched_by_shifts() {
    let model = TempFile::with_text(
        "noether-two-body",
        r#"
coordinates = ["x1", "x2"]
lagrangian = "m1*x1'^2/2 + m2*x2'^2/2 - k*(x1 - x2)^2/2"
[parameters]
m1 = 1.0
m2 = 2.0
k = 3.0
[initial]
x1 = 0.5
x2 = 0.0
"x1'" = 0.0
"x2'" = 0.0
"#,
    );
    let found = symmetries(model.path());
    assert_eq!(names(&found), ["N_x1_plus_x2"], "{found:?}");
    assert_eq!(found[0]["expr"], "m1*x1' + m2*x2'");
    assert_eq!(found[0]["why"]["generator"]["coordinates"], serde_json::json!(["x1", "x2"]));
}

#[test]
fn models_without_a_further_symmetry_get_nothing_new() {
    for model in [
        "examples/double_pendulum.toml",
        "examples/pendulum.toml",
        "examples/two_body.toml",
        "examples/central_force.toml",
        "examples/kepler.toml",
        "examples/damped_oscillator.toml",
        "examples/spherical_pendulum.toml",
        "examples/constraints/pendulum_cartesian.toml",
    ] {
        let found = symmetries(model);
        assert!(found.is_empty(), "{model}: {found:?}");
    }
}

#[test]
fn a_free_rigid_body_conserves_its_angular_momentum_in_space() {
    // Euler angles al, be, ga (zxz): L_z is p_al (al is cyclic), and rotations
    // about x and y give the other two components.
    let model = "examples/tops/free_asymmetric_body.toml";
    let found = symmetries(model);
    assert_eq!(names(&found), ["L_x", "L_y"], "{found:?}");
    let generator = &named(&found, "L_x")["why"]["generator"];
    assert_eq!(generator["kind"], "rotation");
    assert!(generator["xi"].get("be").is_some(), "{generator}");
    assert!(named(&found, "L_x")["reason"].as_str().unwrap().contains("rotating the body about x"));
    let run = drifts(model, "20");
    for name in ["L_x", "L_y", "p_al"] {
        audited(&run, name, 1e-8);
    }
    // |L| is the same whichever way it is computed: L_x² + L_y² + p_al² at the
    // start equals the body-frame (I1 ω1)² + (I2 ω2)² + (I3 ω3)².
    // ω in the body frame does not depend on al.
    let (be, ga) = (1.1f64, 0.2f64);
    let (ald, bed, gad) = (0.5f64, 0.4f64, 1.5f64);
    let w1 = ald * be.sin() * ga.sin() + bed * ga.cos();
    let w2 = ald * be.sin() * ga.cos() - bed * ga.sin();
    let w3 = ald * be.cos() + gad;
    let body = (1.0 * w1).powi(2) + (2.0 * w2).powi(2) + (3.0 * w3).powi(2);
    let initial = |name: &str| run[name]["initial"].as_f64().unwrap();
    let space = initial("L_x").powi(2) + initial("L_y").powi(2) + initial("p_al").powi(2);
    assert!((space - body).abs() < 1e-9 * body, "|L|² in space {space}, in the body {body}");
}

#[test]
fn a_torque_fixed_in_space_leaves_the_components_across_it() {
    // The torque is along y: L_x (p_ph, ph turning about x) and L_z stay, L_y does not.
    let found = symmetries("examples/tops/torqued_body.toml");
    assert_eq!(names(&found), ["L_z"], "{found:?}");
}
