//! Constraints and their forces (`[[constraints]]`, issue #8), run through the real
//! binary on `examples/constraints/*.toml` and compared with the notes' analytic
//! results (2.2.1 (vii), 2.6.3, appendix A.3):
//!
//! - the pendulum in Cartesian coordinates: the rod's force equals the tension
//!   m g cos θ + m l θ'² along a run of about 1000 periods, and the residual of
//!   x² + y² = l² stays at round-off;
//! - the bead on a rotating wire (ph = om t, rheonomic): the multiplier is the
//!   torque N r of the wire's normal force N = 2 m om r', r = r0 cosh(om t), and H
//!   is not conserved (the constraint does work) while H − W is;
//! - the rolling disk: its two constraints are not integrable, the disk rolls
//!   without slipping to round-off, its energy is conserved, and its contact point
//!   runs on the circle of radius R ps'/ph' the notes derive;
//! - integrable velocity constraints (x' − y', y x' + x y') are recognized, with
//!   their integrals;
//! - bad input: inconsistent initial values, a nonlinear velocity constraint, a
//!   name clash, a method that cannot be projected — exit 2 with the place.

use crate::common;

use crate::common::{json, ok, run as lagrange, Csv, TempFile};
use serde_json::Value;

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn the_cartesian_pendulum_feels_the_tension_of_its_rod() {
    // m = l = 1, g = 9.81; released at θ = 1 with θ' = 0.5: the period is about
    // 2.3 s, so 2300 s are about 1000 periods.
    let csv = TempFile::new("pendulum", "csv");
    let r = ok(&[
        "simulate",
        "examples/constraints/pendulum_cartesian.toml",
        "--until",
        "2300",
        "--rtol",
        "1e-10",
        "--samples",
        "23001",
        "--out",
        csv.path(),
        "--summary",
        "json",
    ]);
    let s = r.json();
    let c = Csv::read(csv.path());
    assert_eq!(c.header, ["t", "x", "y", "x'", "y'", "H", "lambda_rod", "force_rod", "residual_rod", "residual_rod'"]);
    let (m, l, g) = (1.0, 1.0, 9.81);
    let (ix, iy, ivx, ivy, iforce, ilam) =
        (c.col("x"), c.col("y"), c.col("x'"), c.col("y'"), c.col("force_rod"), c.col("lambda_rod"));
    let (ires, ivres) = (c.col("residual_rod"), c.col("residual_rod'"));
    let mut worst_tension = 0.0f64;
    let mut worst_residual = 0.0f64;
    for row in &c.rows {
        let (x, y, vx, vy) = (row[ix], row[iy], row[ivx], row[ivy]);
        // θ from the vertical: x = l sin θ, y = −l cos θ.
        let cos_th = -y / l;
        let th_dot = (x * vy - y * vx) / (l * l);
        let tension = m * g * cos_th + m * l * th_dot * th_dot;
        worst_tension = worst_tension.max((row[iforce] - tension).abs() / tension.abs());
        // The rod pulls inward: m x'' = 2 λ x with λ = −T/(2l).
        assert!((row[ilam] + tension / (2.0 * l)).abs() < 1e-8 * tension, "λ at t = {}", row[0]);
        worst_residual = worst_residual.max(row[ires].abs()).max(row[ivres].abs());
    }
    assert!(worst_tension < 1e-8, "tension off by {worst_tension:e} (relative)");
    assert!(worst_residual < 1e-12, "residual up to {worst_residual:e}");
    let audit = &s["constraints"]["rod"];
    assert_eq!(audit["kind"], "holonomic");
    assert!(num(&audit["max_abs_residual"]) < 1e-12 && num(&audit["max_abs_velocity_residual"]) < 1e-12, "{audit}");
    // The rod does no work: H = E is conserved and audited.
    let h = &s["invariants"]["H"];
    assert_eq!(h["conserved"], true);
    assert!(num(&h["max_rel_drift"]) < 1e-7, "{h}");
    assert!(s["warnings"].as_array().unwrap().is_empty(), "{}", s["warnings"]);
}

#[test]
fn the_wire_pushes_the_bead_with_the_coriolis_force() {
    // r'' = om² r from r(0) = 1, r'(0) = 0: r = cosh(om t); the wire's normal force
    // is N = 2 m om r', its torque about the axis N r is the multiplier.
    let csv = TempFile::new("wire", "csv");
    let r = ok(&[
        "simulate",
        "examples/constraints/rotating_wire.toml",
        "--until",
        "3",
        "--rtol",
        "1e-11",
        "--samples",
        "301",
        "--out",
        csv.path(),
        "--summary",
        "json",
    ]);
    let s = r.json();
    let c = Csv::read(csv.path());
    let (m, om) = (0.5, 2.0);
    let (ir, ivr, ilam, iforce, ires) =
        (c.col("r"), c.col("r'"), c.col("lambda_wire"), c.col("force_wire"), c.col("residual_wire"));
    for row in c.rows.iter().skip(1) {
        let t = row[0];
        let (rr, vr) = (row[ir], row[ivr]);
        assert!((rr - (om * t).cosh()).abs() < 1e-9 * (om * t).cosh(), "r at t = {t}");
        let normal = 2.0 * m * om * vr;
        let n_from_lambda = row[ilam] / rr;
        assert!((n_from_lambda - normal).abs() < 1e-9 * normal.abs(), "N at t = {t}: {n_from_lambda} vs {normal}");
        assert!((row[iforce] - normal * rr).abs() < 1e-9 * normal * rr);
        // Analytic N against the closed form too: 2 m om² sinh(om t).
        let closed = 2.0 * m * om * om * (om * t).sinh();
        assert!((normal - closed).abs() < 1e-8 * closed, "N vs closed form at t = {t}");
        assert!(row[ires].abs() < 1e-12 * (1.0 + om * t), "residual at t = {t}");
    }
    // A rheonomic constraint does work: H is not conserved, and the audit says so.
    let h = &s["invariants"]["H"];
    assert_eq!(h["conserved"], false);
    let e_final = 0.5 * m * ((om * (om * 3.0).sinh()).powi(2) + ((om * 3.0).cosh() * om).powi(2));
    assert!((num(&h["final"]) - e_final).abs() < 1e-8 * e_final, "{h}");
    // The work of the wire is all that changes H: H − W stays at H(0) = m om² r0²/2 = 1.
    let hw = &s["invariants"]["H-W"];
    assert_eq!(hw["conserved"], true);
    assert!(num(&hw["max_rel_drift"]) < 1e-9, "{hw}");
    let (ih, iw) = (c.col("H"), c.col("W_constraints"));
    for row in &c.rows {
        assert!((row[ih] - row[iw] - 1.0).abs() < 1e-9 * row[ih], "H - W at t = {}", row[0]);
    }
    let d = json(&["derive", "examples/constraints/rotating_wire.toml", "--format", "json"]);
    assert_eq!(d["constraints"][0]["rheonomic"], true);
    assert_eq!(d["hamiltonian_conserved"], false);
}

#[test]
fn the_rolling_disk_is_nonholonomic_and_rolls_without_slipping() {
    let d = json(&["derive", "examples/constraints/rolling_disk.toml", "--format", "json"]);
    let cs = d["constraints"].as_array().expect("constraints");
    assert_eq!(cs.len(), 2);
    for c in cs {
        assert_eq!(c["kind"], "velocity");
        assert_eq!(c["integrable"], false, "{c}");
        assert_eq!(c["rheonomic"], false);
    }
    assert_eq!(cs[0]["jacobian"], serde_json::json!(["1", "0", "0", "-R*cos(ph)"]));
    assert_eq!(cs[1]["jacobian"], serde_json::json!(["0", "1", "0", "-R*sin(ph)"]));
    assert_eq!(d["constraints_integrable"], false);
    assert_eq!(d["degrees_of_freedom"], 2);
    assert_eq!(d["multiplier_equations"]["x"], "-lambda_roll_x + m*x''");
    let text = ok(&["derive", "examples/constraints/rolling_disk.toml"]).stdout;
    assert!(text.contains("not integrable"), "{text}");
    assert!(text.contains("2 degrees of freedom"), "{text}");

    let csv = TempFile::new("disk", "csv");
    let r = ok(&[
        "simulate",
        "examples/constraints/rolling_disk.toml",
        "--until",
        "500",
        "--samples",
        "5001",
        "--out",
        csv.path(),
        "--summary",
        "json",
    ]);
    let s = r.json();
    for name in ["roll_x", "roll_y"] {
        let a = &s["constraints"][name];
        assert!(num(&a["max_abs_residual"]) <= 1e-12, "{name}: {a}");
    }
    let h = &s["invariants"]["H"];
    assert_eq!(h["conserved"], true);
    assert!(num(&h["max_rel_drift"]) < 1e-8, "{h}");
    // ph' and ps' stay constant (the constraint forces have no torque about the
    // vertical, and their torque on ps cancels), so the contact point runs on a
    // circle: x = R ps'/ph' (sin ph − sin ph0), y = −R ps'/ph' (cos ph − cos ph0).
    let c = Csv::read(csv.path());
    let (big_r, ph0, w, v) = (0.5, 0.3, 0.7, 2.0);
    let rho = big_r * v / w;
    let (ix, iy, iph, ires) = (c.col("x"), c.col("y"), c.col("ph"), c.col("residual_roll_x"));
    for row in &c.rows {
        let t = row[0];
        let ph = ph0 + w * t;
        assert!((row[iph] - ph).abs() < 1e-8 * (1.0 + t), "ph at t = {t}");
        assert!((row[ix] - rho * (ph.sin() - ph0.sin())).abs() < 1e-7, "x at t = {t}");
        assert!((row[iy] + rho * (ph.cos() - ph0.cos())).abs() < 1e-7, "y at t = {t}");
        assert!(row[ires].abs() <= 1e-12);
    }
}

#[test]
fn integrable_velocity_constraints_are_holonomic_in_disguise() {
    let d = json(&["derive", "examples/constraints/hyperbola.toml", "--format", "json"]);
    assert_eq!(d["constraints"][0]["integrable"], true);
    assert_eq!(d["constraints"][0]["integral"], "x*y");
    let model = TempFile::with_text(
        "diff",
        "coordinates = [\"x\", \"y\"]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nname = \"same\"\nvelocity = \"x' - y'\"\n",
    );
    let d = json(&["derive", model.path(), "--format", "json"]);
    assert_eq!(d["constraints"][0]["integrable"], true);
    assert_eq!(d["constraints"][0]["integral"], "x - y");
    let text = ok(&["derive", model.path()]).stdout;
    assert!(text.contains("x - y = const in disguise"), "{text}");
    // The particle on the hyperbola keeps x y = 2 to round-off.
    let csv = TempFile::new("hyperbola", "csv");
    ok(&["simulate", "examples/constraints/hyperbola.toml", "--until", "50", "--out", csv.path()]);
    let c = Csv::read(csv.path());
    let (ix, iy) = (c.col("x"), c.col("y"));
    for row in &c.rows {
        assert!((row[ix] * row[iy] - 2.0).abs() < 1e-13, "x y at t = {}", row[0]);
    }
}

const PENDULUM: &str = r#"coordinates = ["x", "y"]
gravity = "g"
[parameters]
l = 1.0
g = 9.81
[[particles]]
mass = 1
position = ["x", "y"]
[[constraints]]
holonomic = "x^2 + y^2 - l^2"
[initial]
x = 0.6
y = -0.8
"x'" = 0.8
"y'" = 0.6
"#;

#[track_caller]
fn bad(args: &[&str], expect: &[&str]) {
    let r = lagrange(args);
    assert_eq!(r.code, Some(2), "lagrange {args:?}\n{}\n{}", r.stdout, r.stderr);
    for e in expect {
        assert!(r.stderr.contains(e), "expected `{e}` in:\n{}", r.stderr);
    }
}

#[test]
fn bad_constraints_exit_2_with_the_place() {
    // Consistent initial values run (0.6, −0.8) on the unit circle, (0.8, 0.6) tangent.
    let good = TempFile::with_text("good", PENDULUM);
    ok(&["simulate", good.path(), "--until", "1"]);
    // Off the circle by 0.01 in x: f = 0.6^2 − 0.36 ... residual 2·0.6·0.01 + 1e-4.
    let off = TempFile::with_text("off", &PENDULUM.replace("x = 0.6", "x = 0.61"));
    bad(&["simulate", off.path(), "--until", "1"], &["violate the constraint 'c1'", "1.210e-2", ":10:13"]);
    // A velocity not tangent to the circle.
    let fast = TempFile::with_text("fast", &PENDULUM.replace("\"y'\" = 0.6", "\"y'\" = 0.7"));
    bad(&["simulate", fast.path(), "--until", "1"], &["at velocity level", "-1.600e-1"]);
    let nonlinear = TempFile::with_text(
        "nonlinear",
        "coordinates = [\"x\", \"y\"]\nkinetic = \"x'^2/2 + y'^2/2\"\n[[constraints]]\nvelocity = \"x'*y'\"\n",
    );
    bad(&["derive", nonlinear.path()], &["not linear in the velocities", ":4:12"]);
    let with_velocity = TempFile::with_text("holvel", &PENDULUM.replace("x^2 + y^2 - l^2", "x'^2 + y^2 - l^2"));
    bad(&["derive", with_velocity.path()], &["'x'' is not allowed here", "coordinates and the time t"]);
    let clash = TempFile::with_text("clash", &PENDULUM.replace("[[constraints]]\n", "[[constraints]]\nname = \"l\"\n"));
    bad(&["derive", clash.path()], &["constraint 'l' has the name of a coordinate or parameter"]);
    let both =
        TempFile::with_text("both", &PENDULUM.replace("[[constraints]]\n", "[[constraints]]\nvelocity = \"x'\"\n"));
    bad(&["derive", both.path()], &["either `holonomic` or `velocity`"]);
    bad(&["simulate", good.path(), "--until", "1", "--method", "gauss6"], &["cannot run a model with constraints"]);
}

/// A wheel lying flat has no lowest rim point, where the contact divides by
/// √(1 − e_z²): refused at the rolling contact, saying whether its axle is
/// vertical whatever the coordinates (when read) or at the start (when a run
/// starts; the model itself derives).
#[test]
fn a_wheel_lying_flat_is_refused_at_its_rolling_contact() {
    let dir = common::repo_root().join("crates/cli/tests/bad_bodies");
    let flat = dir.join("flat_wheel.toml");
    bad(&["derive", flat.to_str().unwrap()], &["lies flat whatever the coordinates", "flat_wheel.toml:20:11:"]);
    let at_start = dir.join("coin_flat_at_start.toml");
    ok(&["derive", at_start.to_str().unwrap()]);
    bad(
        &["simulate", at_start.to_str().unwrap(), "--until", "1"],
        &["lies flat at the start", "coin_flat_at_start.toml:23:11:"],
    );
    // Tilted by 0.3 about y and at rest on its rim, the same model runs.
    let text = std::fs::read_to_string(&at_start).unwrap();
    let tilted = text.replacen("th = 0\n", "th = 0.3\n", 1).replacen("z = 0\n", "z = \"R*sin(0.3)\"\n", 1);
    let tilted = TempFile::with_text("tilted", &tilted.replacen("\"ps'\" = 1", "\"ps'\" = 0", 1));
    ok(&["simulate", tilted.path(), "--until", "0.1"]);
}

/// A disc rolling along y about its axle along x never slips along x: the
/// contact's x component is identically 0 and is left out (not a constraint
/// the derivation would refuse), and the disc rolls, y' = −R th'.
#[test]
fn a_rolling_component_that_is_identically_zero_is_left_out() {
    let model = TempFile::with_text(
        "roll-along-y",
        "coordinates = [\"y\", \"th\"]\n[parameters]\nm = 1.0\nR = 0.5\n\
         [[bodies]]\nname = \"w\"\nmass = \"m\"\ninertia = [\"m*R^2/2\", \"m*R^2/4\", \"m*R^2/4\"]\n\
         angle = \"th\"\naxis = \"x\"\nposition = [\"0\", \"y\", \"R\"]\n\
         [[constraints]]\nname = \"roll\"\nrolling = \"w\"\nradius = \"R\"\n\
         [initial]\ny = 0\nth = 0\n\"y'\" = 1\n\"th'\" = -2\n",
    );
    let csv = TempFile::new("roll-along-y", "csv");
    ok(&["simulate", model.path(), "--until", "2", "--out", csv.path()]);
    let table = Csv::read(csv.path());
    assert!(table.header.iter().any(|c| c == "lambda_roll_y"), "{:?}", table.header);
    assert!(!table.header.iter().any(|c| c.contains("roll_x")), "{:?}", table.header);
    let (y, th) = (table.column("y"), table.column("th"));
    for (y, th) in y.iter().zip(&th) {
        assert!((y + 0.5 * th).abs() < 1e-9, "y = {y}, th = {th}");
    }
    assert!(y.last().unwrap().abs() > 1.0, "the disc rolls: {y:?}");
}
