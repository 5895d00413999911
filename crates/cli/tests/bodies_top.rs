//! Rigid bodies and `lagrange top` against the notes (3.2.6, 3.2.7, appendix A.5).
//!
//! Runs the real binary on `examples/tops/*.toml`:
//! - `derive` of a free asymmetric body reproduces the notes' A.5 equations of
//!   motion for α, β, γ (compared at random points), and of the heavy top the
//!   notes' T_rot and U = MgS cos β;
//! - `simulate` records ω and L; along a free asymmetric body's run Euler's
//!   equations hold (ω̇ by central differences of the recorded ω) and |L|, T stay put;
//! - the Euler angles' gimbal singularity is reported, not integrated through;
//! - `top` agrees with `simulate` of the same model: β stays in [β₁, β₂] and
//!   reaches both (at the rows where β' = 0), the mean precession rate, and the
//!   free top's α̇ = A/sin β₀ with the fixed z axis along L.

use crate::common::{is_close, json, repo_root, run as lagrange, scratch};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

/// The CSV as columns by name (event rows included, with their event text dropped).
fn read_csv(path: &Path) -> (HashMap<String, Vec<f64>>, Vec<bool>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut cols: HashMap<String, Vec<f64>> = header.iter().map(|h| (h.clone(), Vec::new())).collect();
    let mut is_event = Vec::new();
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        for (h, f) in header.iter().zip(&fields) {
            if h != "event" {
                cols.get_mut(h).unwrap().push(f.parse().unwrap());
            }
        }
        is_event
            .push(header.last().map(String::as_str) == Some("event") && fields.last().is_some_and(|f| !f.is_empty()));
    }
    (cols, is_event)
}

fn eval(pool: &mut sym::Pool, src: &str, env: &HashMap<&str, f64>) -> f64 {
    let e = pool.parse(src).unwrap_or_else(|err| panic!("cannot parse {src}: {err:?}"));
    pool.eval(e, &|n: &str| env.get(n).copied()).unwrap()
}

#[test]
fn derive_reproduces_the_notes_a5_equations() {
    let j = json(&["derive", "examples/tops/free_asymmetric_body.toml", "--format", "json"]);
    // Notes A.5 (U = 0), q1 = α, q2 = β, q3 = γ, written with a = α, b = β, c = γ.
    let notes_al = "al''*((I1*sin(ga)^2 + I2*cos(ga)^2)*sin(be)^2 + I3*cos(be)^2) + 2*al'*be'*(I1*sin(ga)^2 + I2*cos(ga)^2 - I3)*sin(be)*cos(be) + 2*al'*ga'*(I1 - I2)*sin(be)^2*sin(ga)*cos(ga) + be''*(I1 - I2)*sin(be)*sin(ga)*cos(ga) + be'^2*(I1 - I2)*cos(be)*sin(ga)*cos(ga) + be'*ga'*((I1 - I2)*(cos(ga)^2 - sin(ga)^2) - I3)*sin(be) + ga''*I3*cos(be)";
    let notes_be = "al''*(I1 - I2)*sin(be)*sin(ga)*cos(ga) + al'^2*(I3 - I1*sin(ga)^2 - I2*cos(ga)^2)*sin(be)*cos(be) + al'*ga'*(I3 + (I1 - I2)*(cos(ga)^2 - sin(ga)^2))*sin(be) + be''*(I1*cos(ga)^2 + I2*sin(ga)^2) - 2*be'*ga'*(I1 - I2)*sin(ga)*cos(ga)";
    let notes_ga = "I3*(al''*cos(be) - al'*be'*sin(be) + ga'') - (I1 - I2)*((al'^2*sin(be)^2 - be'^2)*sin(ga)*cos(ga) + al'*be'*sin(be)*(cos(ga)^2 - sin(ga)^2))";
    let mut pool = sym::Pool::default();
    let mut seed = 0x1234_5678_9abc_def0u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.5
    };
    for _ in 0..8 {
        let names = ["al", "be", "ga", "al'", "be'", "ga'", "al''", "be''", "ga''"];
        let mut env: HashMap<&str, f64> = names.iter().map(|&n| (n, rnd())).collect();
        env.insert("I1", 1.0 + rnd().abs());
        env.insert("I2", 2.0 + rnd().abs());
        env.insert("I3", 3.5 + rnd().abs());
        env.insert("M", 1.0);
        for (q, notes) in [("al", notes_al), ("be", notes_be), ("ga", notes_ga)] {
            let ours = eval(&mut pool, j["equations"][q].as_str().unwrap(), &env);
            let theirs = eval(&mut pool, notes, &env);
            assert!(
                (ours - theirs).abs() < 1e-9 * (1.0 + theirs.abs()),
                "E_{q}: {ours} vs the notes' {theirs} at {env:?}"
            );
        }
    }
    // ω in the notes' convention, and L = Iω for a body about its centre of mass.
    assert_eq!(j["bodies"][0]["angular_velocity"][2], "ga' + al'*cos(be)");
    assert_eq!(j["bodies"][0]["angular_momentum"][2], "I3*(ga' + al'*cos(be))");

    let h = json(&["derive", "examples/tops/heavy_top.toml", "--format", "json"]);
    let t_notes = "(I*(al'^2*sin(be)^2 + be'^2) + I3*(al'*cos(be) + ga')^2)/2";
    let mut env: HashMap<&str, f64> =
        [("al", 0.3), ("be", 0.7), ("ga", -0.4), ("al'", 1.1), ("be'", -0.6), ("ga'", 9.0)].into_iter().collect();
    for (k, v) in [("M", 1.0), ("I", 1.0), ("I3", 0.5), ("S", 0.5), ("g", 9.81)] {
        env.insert(k, v);
    }
    let t = eval(&mut pool, h["kinetic"].as_str().unwrap(), &env);
    assert!((t - eval(&mut pool, t_notes, &env)).abs() < 1e-12);
    let u = eval(&mut pool, h["potential"].as_str().unwrap(), &env);
    assert!((u - 9.81 * 0.5 * 0.7f64.cos()).abs() < 1e-12);
    let cyclic: Vec<&str> = h["cyclic"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert_eq!(cyclic, ["al", "ga"]);
}

#[test]
fn euler_equations_hold_along_a_free_asymmetric_body() {
    let csv = scratch("bodies", "asym.csv");
    let r = lagrange(&[
        "simulate",
        "examples/tops/free_asymmetric_body.toml",
        "--until",
        "4",
        "--samples",
        "4001",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let (c, _) = read_csv(&csv);
    let (i1, i2, i3) = (1.0, 2.0, 3.0);
    let (w1, w2, w3) = (&c["omega1"], &c["omega2"], &c["omega3"]);
    let dt = c["t"][1] - c["t"][0];
    let mut worst = 0.0f64;
    for k in 1..w1.len() - 1 {
        let d = |w: &Vec<f64>| (w[k + 1] - w[k - 1]) / (2.0 * dt);
        let e1 = i1 * d(w1) - (i2 - i3) * w2[k] * w3[k];
        let e2 = i2 * d(w2) - (i3 - i1) * w3[k] * w1[k];
        let e3 = i3 * d(w3) - (i1 - i2) * w1[k] * w2[k];
        worst = worst.max(e1.abs()).max(e2.abs()).max(e3.abs());
    }
    // Central differences at dt = 1e-3 are good to ~dt²·|ω'''| ≈ 1e-6.
    assert!(worst < 1e-4, "Euler's equations (N = 0) residual {worst}");
    // L = Iω in body components; |L| and T = ½ω·L are conserved.
    let l0 = (c["L1"][0].powi(2) + c["L2"][0].powi(2) + c["L3"][0].powi(2)).sqrt();
    let t0 = 0.5 * (i1 * w1[0] * w1[0] + i2 * w2[0] * w2[0] + i3 * w3[0] * w3[0]);
    for k in 0..w1.len() {
        assert!((c["L1"][k] - i1 * w1[k]).abs() < 1e-12);
        let l = (c["L1"][k].powi(2) + c["L2"][k].powi(2) + c["L3"][k].powi(2)).sqrt();
        let t = 0.5 * (i1 * w1[k] * w1[k] + i2 * w2[k] * w2[k] + i3 * w3[k] * w3[k]);
        assert!((l - l0).abs() < 1e-8 * l0, "|L| drifted: {l} vs {l0}");
        assert!((t - t0).abs() < 1e-8 * t0, "T drifted: {t} vs {t0}");
        assert!((c["H"][k] - t0).abs() < 1e-8 * t0, "H is T for a free body");
    }
}

#[test]
fn the_gimbal_singularity_is_reported() {
    // Started at β = 1e-12: bad input, located at the initial value.
    let start = scratch("bodies", "start.toml");
    let text = std::fs::read_to_string(repo_root().join("examples/tops/heavy_top.toml")).unwrap();
    std::fs::write(&start, text.replace("be = 0.6", "be = 1e-12")).unwrap();
    let r = lagrange(&["simulate", start.to_str().unwrap(), "--until", "1"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("gimbal singularity") && r.stderr.contains(":25:6"), "{}", r.stderr);

    // Driven through β = 0 (a spherical body turning about a horizontal axis):
    // exit 1, the time, the explanation, and the rows up to there kept.
    let through = scratch("bodies", "through.toml");
    std::fs::write(
        &through,
        "coordinates = [\"al\", \"be\", \"ga\"]\n[[bodies]]\nmass = 1\ninertia = [1, 1, 1]\nangles = [\"al\", \"be\", \"ga\"]\n[initial]\nal = 0\n\"al'\" = 0\nbe = 0.5\n\"be'\" = -1\nga = 0\n\"ga'\" = 0\n",
    )
    .unwrap();
    let csv = scratch("bodies", "through.csv");
    let r = lagrange(&["simulate", through.to_str().unwrap(), "--until", "2", "--out", csv.to_str().unwrap()]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(r.stderr.contains("gimbal singularity") && r.stderr.contains("at t = 0.49"), "{}", r.stderr);
    let (c, _) = read_csv(&csv);
    let last = *c["t"].last().unwrap();
    assert!(last > 0.49 && last < 0.5, "rows up to the singularity are kept: last t = {last}");
    assert!(c["be"].iter().all(|b| b.sin().abs() > 1e-4 * 0.999), "no row past the threshold");
}

#[test]
fn heavy_top_nutation_agrees_with_simulate() {
    for (set, kind) in [(vec![], "cusps"), (vec!["--set", "S=0.3"], "cusps")] {
        let mut args = vec!["top", "examples/tops/heavy_top.toml", "--format", "json"];
        args.extend(&set);
        let top = json(&args);
        assert_eq!(top["format"], "lagrange.top/1");
        assert_eq!(top["kind"], "heavy");
        assert_eq!(top["nutation"]["kind"], kind);
        check_nutation(&top, &set, &[]);
    }
    // With precession (al' > 0 at the start): loops or a monotonic wave.
    for kind in ["loops", "monotonic"] {
        let file = scratch("bodies", &format!("heavy_{kind}.toml"));
        let text = std::fs::read_to_string(repo_root().join("examples/tops/heavy_top.toml")).unwrap();
        let al = if kind == "loops" { "-0.5" } else { "0.9" };
        std::fs::write(&file, text.replace("\"al'\" = 0.0", &format!("\"al'\" = {al}"))).unwrap();
        let top = json(&["top", file.to_str().unwrap(), "--format", "json"]);
        assert_eq!(top["nutation"]["kind"], kind, "{top}");
        check_nutation(&top, &[], &[file.to_str().unwrap()]);
    }
}

#[test]
fn nutation_with_an_initial_beta_rate_and_a_hanging_top() {
    // β' ≠ 0 at the start: neither turning angle is the initial β. S < 0: the
    // centre of mass below the pivot (U_eff's cubic has a negative leading term).
    let text = std::fs::read_to_string(repo_root().join("examples/tops/heavy_top.toml")).unwrap();
    for (s, name) in [("0.5", "rate"), ("-0.5", "hanging")] {
        let file = scratch("bodies", &format!("heavy_{name}.toml"));
        let t = text.replace("\"be'\" = 0.0", "\"be'\" = 0.7").replace("S = 0.5 ", &format!("S = {s} "));
        std::fs::write(&file, t).unwrap();
        let top = json(&["top", file.to_str().unwrap(), "--format", "json"]);
        let (b1, b2) = (top["nutation"]["beta_min"].as_f64().unwrap(), top["nutation"]["beta_max"].as_f64().unwrap());
        assert!(b1 < 0.6 - 1e-3 && b2 > 0.6 + 1e-3, "{name}: [{b1}, {b2}] strictly around β₀ = 0.6");
        check_nutation(&top, &[], &[file.to_str().unwrap()]);
    }
}

/// β within [β₁, β₂], both reached at the rows where β' = 0, and the mean α̇.
fn check_nutation(top: &Value, set: &[&str], file: &[&str]) {
    let (b1, b2) = (top["nutation"]["beta_min"].as_f64().unwrap(), top["nutation"]["beta_max"].as_f64().unwrap());
    let period = top["nutation"]["period"].as_f64().unwrap();
    let mean = top["mean_precession_rate"].as_f64().unwrap();
    let csv = scratch("bodies", &format!("heavy_{}.csv", b2.to_bits()));
    let until = format!("{}", 6.2 * period);
    let model = file.first().copied().unwrap_or("examples/tops/heavy_top.toml");
    let mut args = vec![
        "simulate",
        model,
        "--until",
        &until,
        "--crossing",
        "be' = 0",
        "--rtol",
        "1e-11",
        "--out",
        csv.to_str().unwrap(),
    ];
    args.extend(set);
    let r = lagrange(&args);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let (c, ev) = read_csv(&csv);
    for &b in &c["be"] {
        assert!(b >= b1 - 1e-6 && b <= b2 + 1e-6, "β = {b} outside [{b1}, {b2}]");
    }
    let turns: Vec<usize> = (0..ev.len()).filter(|&k| ev[k]).collect();
    assert!(turns.len() >= 10, "{} turning rows", turns.len());
    let (mut lo, mut hi) = (0, 0);
    for &k in &turns {
        let b = c["be"][k];
        if (b - b1).abs() < 1e-6 {
            lo += 1;
        } else if (b - b2).abs() < 1e-6 {
            hi += 1;
        } else {
            panic!("β' = 0 at β = {b}, which is neither β₁ = {b1} nor β₂ = {b2}");
        }
    }
    assert!(lo >= 3 && hi >= 3, "β₁ reached {lo} times, β₂ {hi} times");
    // Between two turning rows of the same kind lies a whole number of nutations.
    let same: Vec<usize> =
        turns.iter().copied().filter(|&k| (c["be"][k] - c["be"][turns[turns.len() - 1]]).abs() < 1e-5).collect();
    let (k0, k1) = (same[0], *same.last().unwrap());
    let sim_mean = (c["al"][k1] - c["al"][k0]) / (c["t"][k1] - c["t"][k0]);
    assert!((sim_mean - mean).abs() < 1e-6 * (1.0 + mean.abs()), "mean precession {sim_mean} vs top's {mean}");
    let n_periods = ((c["t"][k1] - c["t"][k0]) / period).round();
    assert!(((c["t"][k1] - c["t"][k0]) - n_periods * period).abs() < 1e-6, "nutation period");
}

#[test]
fn free_top_precesses_about_l_at_a_over_sin_beta0() {
    let top = json(&["top", "examples/tops/free_symmetric_top.toml", "--format", "json"]);
    assert_eq!(top["kind"], "free");
    let (i, i3, w, b0) = (1.0f64, 1.6f64, 2.0f64, 0.4f64);
    let w3 = w * b0.cos() * i / i3;
    let a = w * b0.sin();
    let omega_body = (i3 - i) / i * w3;
    assert!((top["omega3"].as_f64().unwrap() - w3).abs() < 1e-12);
    assert!((top["body_precession_rate"].as_f64().unwrap() - omega_body).abs() < 1e-12);
    assert!((top["inclination"].as_f64().unwrap() - (i * a / (i3 * w3)).atan()).abs() < 1e-12);
    let rate = top["space_precession_rate"].as_f64().unwrap();
    assert!((rate - a / b0.sin()).abs() < 1e-12, "α̇ = A/sin β₀");

    let csv = scratch("bodies", "free.csv");
    let r = lagrange(&[
        "simulate",
        "examples/tops/free_symmetric_top.toml",
        "--until",
        "10",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let (c, _) = read_csv(&csv);
    for k in 0..c["t"].len() {
        assert!((c["al'"][k] - rate).abs() < 1e-7, "α̇ = {} vs {rate}", c["al'"][k]);
        assert!((c["be"][k] - b0).abs() < 1e-7, "β stays β₀");
        // ω₁ + iω₂ turns at Ω in the body: ω₁ = A cos(Ωt), ω₂ = A sin(Ωt) (γ₀ = π/2).
        let t = c["t"][k];
        assert!((c["omega1"][k] - a * (omega_body * t).cos()).abs() < 1e-6);
        assert!((c["omega2"][k] - a * (omega_body * t).sin()).abs() < 1e-6);
    }
}

#[test]
fn moving_reference_point_conserves_the_right_things() {
    // The pendulum on a sliding pivot: p_x and H conserved, the CM's horizontal motion uniform.
    let j = json(&["derive", "examples/tops/physical_pendulum.toml", "--format", "json"]);
    let names: Vec<&str> = j["conserved"].as_array().unwrap().iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert!(names.contains(&"p_x") && names.contains(&"H"), "{names:?}");
    let csv = scratch("bodies", "pend.csv");
    let r =
        lagrange(&["simulate", "examples/tops/physical_pendulum.toml", "--until", "5", "--out", csv.to_str().unwrap()]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let (c, _) = read_csv(&csv);
    // x_cm = x + a·(Dᵀe₁)_x = x + a(cos γ cos α − sin γ cos β sin α) moves
    // uniformly (no horizontal force) at p_x/M.
    let xcm = |k: usize| {
        let (al, be, ga) = (c["al"][k], c["be"][k], c["ga"][k]);
        c["x"][k] + 0.5 * (ga.cos() * al.cos() - ga.sin() * be.cos() * al.sin())
    };
    let v = c["p_x"][0];
    assert!(v.abs() > 1e-3, "the example moves the centre of mass");
    for k in 0..c["t"].len() {
        let off = xcm(k) - xcm(0) - v * c["t"][k];
        assert!(off.abs() < 1e-8, "x_cm off uniform motion by {off} at t = {}", c["t"][k]);
    }
}

#[test]
fn bad_bodies_exit_2_with_a_location() {
    let asym = lagrange(&["top", "examples/tops/free_asymmetric_body.toml"]);
    assert_eq!(asym.code, Some(2));
    assert!(asym.stderr.contains("I1 = I2") && asym.stderr.contains(":15:11"), "{}", asym.stderr);
    let none = lagrange(&["top", "examples/pendulum.toml"]);
    assert_eq!(none.code, Some(2));
    assert!(none.stderr.contains("exactly one rigid body"), "{}", none.stderr);
    let text = std::fs::read_to_string(repo_root().join("examples/tops/heavy_top.toml")).unwrap();
    for (from, to, what) in [
        ("angles = [\"al\", \"be\", \"ga\"]", "angles = [\"al\", \"be\", \"al\"]", "listed twice"),
        ("angles = [\"al\", \"be\", \"ga\"]", "angles = [\"al\", \"be\"]", "three Euler angles"),
        (
            "inertia = [\"I\", \"I\", \"I3\"]",
            "inertia = [[\"I\", 0, 1], [0, \"I\", 0], [0, 0, \"I3\"]]",
            "not symmetric",
        ),
        ("inertia = [\"I\", \"I\", \"I3\"]", "inertia = \"top_body.toml\"", "cannot read the body file"),
        ("inertia = [\"I\", \"I\", \"I3\"]", "inertia = [\"I\", \"-I\", \"I3\"]", "a principal moment is negative"),
        ("inertia = [\"I\", \"I\", \"I3\"]", "inertia = [\"I\", \"I\", \"3*I\"]", "exceeds the sum of the other two"),
        ("inertia = [\"I\", \"I\", \"I3\"]", "inertia = [\"I\", \"I\", \"J3\"]", "J3"),
        ("position = [\"0\", \"0\", \"0\"]", "position = [\"0\", \"0\"]", "not 3 (x, y, z)"),
        ("center_of_mass = [\"0\", \"0\", \"S\"]", "center_of_mass = [\"0\", \"0\", \"be\"]", "be"),
        ("[[bodies]]", "[[particles]]\nmass = 1\nposition = [\"0\", \"1\"]\n[[bodies]]", "3-D"),
        ("angles = [\"al\", \"be\", \"ga\"]", "angles = [\"al\", \"be\", \"th\"]", "not a coordinate"),
        ("mass = \"M\"", "mass = \"-M\"", "positive"),
    ] {
        let file = scratch("bodies", "bad.toml");
        std::fs::write(&file, text.replace(from, to)).unwrap();
        let r = lagrange(&["derive", file.to_str().unwrap()]);
        assert_eq!(r.code, Some(2), "{to}: {}", r.stderr);
        assert!(r.stderr.contains(what), "{to}: {}", r.stderr);
        let at = r.stderr.find("bad.toml:").map(|i| &r.stderr[i + 9..]).unwrap_or("");
        assert!(at.starts_with(|c: char| c.is_ascii_digit()), "{to}: located: {}", r.stderr);
    }
}

#[test]
fn top_plot_is_an_svg_with_both_panels() {
    for model in ["examples/tops/heavy_top.toml", "examples/tops/free_symmetric_top.toml"] {
        let svg = scratch("bodies", &format!("{}.svg", model.len()));
        let r = lagrange(&["top", model, "--plot", svg.to_str().unwrap()]);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") || text.contains("<svg"), "{model}: not an SVG");
        assert!(text.contains("effective potential") && text.contains("symmetry axis on the unit sphere"));
        // The axis path is drawn: many points, not an empty panel.
        assert!(text.matches("<circle").count() > 1000, "{model}: the axis path has too few points");
    }
}

#[test]
fn euler_equations_with_the_gravity_torque_along_a_heavy_top() {
    // N = r_cm × F in body components: S e₃ × (−Mg D e_z) = MgS sin β (cos γ, −sin γ, 0),
    // the notes' N₁, N₂ with U = MgS cos β (N₃ = −∂U/∂γ = 0).
    let csv = scratch("bodies", "heavy_euler.csv");
    let r = lagrange(&[
        "simulate",
        "examples/tops/heavy_top.toml",
        "--set",
        "I3=0.4",
        "--until",
        "3",
        "--samples",
        "6001",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let (c, _) = read_csv(&csv);
    let (i, i3, mgs) = (1.0, 0.4, 9.81 * 0.5);
    let (w1, w2, w3) = (&c["omega1"], &c["omega2"], &c["omega3"]);
    let dt = c["t"][1] - c["t"][0];
    let mut worst = 0.0f64;
    for k in 1..w1.len() - 1 {
        let d = |w: &Vec<f64>| (w[k + 1] - w[k - 1]) / (2.0 * dt);
        let (be, ga) = (c["be"][k], c["ga"][k]);
        let n = [mgs * be.sin() * ga.cos(), -mgs * be.sin() * ga.sin(), 0.0];
        let e1 = i * d(w1) - (i - i3) * w2[k] * w3[k] - n[0];
        let e2 = i * d(w2) - (i3 - i) * w3[k] * w1[k] - n[1];
        let e3 = i3 * d(w3) - n[2];
        worst = worst.max(e1.abs()).max(e2.abs()).max(e3.abs());
    }
    assert!(worst < 1e-3, "Euler's equations with torque: residual {worst}");
}

/// A body whose inertia is a body file (`lagrange inertia`): the solid cone on
/// its apex gets I = 3/20 M R² + 3/5 M h², I3 = 3/10 M R² about the pivot and
/// S = 3h/4 from the file, and `top` reads them back.
#[test]
fn a_body_file_gives_mass_centre_and_inertia() {
    let (m, r, h, g) = (1.0, 0.5, 1.0, 9.81);
    let i1 = 3.0 / 20.0 * m * r * r + 3.0 / 5.0 * m * h * h;
    let i3 = 3.0 / 10.0 * m * r * r;
    let s = 0.75 * h;
    let d = json(&["derive", "examples/tops/cone_top.toml", "--format", "json"]);
    let mut pool = sym::Pool::default();
    let env: HashMap<&str, f64> = [("be", 0.7), ("g", g)].into_iter().collect();
    let mm = &d["mass_matrix"];
    let close = |a: f64, b: f64| is_close(a, b, 1e-12, 1.0);
    assert!(close(eval(&mut pool, mm[1][1].as_str().unwrap(), &env), i1));
    assert!(close(eval(&mut pool, mm[2][2].as_str().unwrap(), &env), i3));
    // M_αα = I sin²β + I3 cos²β, U = M g S cos β.
    let want = i1 * 0.7f64.sin().powi(2) + i3 * 0.7f64.cos().powi(2);
    assert!(close(eval(&mut pool, mm[0][0].as_str().unwrap(), &env), want));
    assert!(close(eval(&mut pool, d["potential"].as_str().unwrap(), &env), m * g * s * 0.7f64.cos()));
    let top = json(&["top", "examples/tops/cone_top.toml", "--format", "json"]);
    assert_eq!(top["kind"], "heavy");
    assert!(close(top["p_gamma"].as_f64().unwrap(), i3 * 40.0));

    // A mass that contradicts the file, and a file that is not there: exit 2 at the place.
    let text = std::fs::read_to_string(repo_root().join("examples/tops/cone_top.toml")).unwrap();
    let dir = repo_root().join("examples/tops");
    let bad = text.replace("name = \"cone\"\n", "name = \"cone\"\nmass = 2.0\n");
    let path = dir.join(format!("bad-mass-{}.toml", std::process::id()));
    std::fs::write(&path, bad).unwrap();
    let run = lagrange(&["derive", path.to_str().unwrap()]);
    std::fs::remove_file(&path).unwrap();
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    assert!(run.stderr.contains("mass is 2 here but 1 in its body file"), "{}", run.stderr);
    assert!(run.stderr.contains(":13:"), "{}", run.stderr);
    let missing = text.replace("cone_top_body.toml", "no_such_body.toml");
    let path = scratch("bodies", "missing-body.toml");
    std::fs::write(&path, missing).unwrap();
    let run = lagrange(&["derive", path.to_str().unwrap()]);
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    assert!(run.stderr.contains("cannot read the body file 'no_such_body.toml'"), "{}", run.stderr);
}

/// An error inside a body file is reported at its line and column in that file,
/// and the model's `inertia` value is underlined.
#[test]
fn an_error_in_a_body_file_names_its_line_and_column() {
    let body = scratch("bodyfile", "broken_body.toml");
    std::fs::write(
        &body,
        "name = \"broken\"\n[[parts]]\nshape = \"sphere\"\nmass = \"1\"\nsize = [\"R\"]\ncenter = [0, 0, 0]\n",
    )
    .unwrap();
    let model = body.with_file_name("top.toml");
    std::fs::write(
        &model,
        "coordinates = [\"al\", \"be\", \"ga\"]\n[[bodies]]\ninertia = \"broken_body.toml\"\nangles = [\"al\", \"be\", \"ga\"]\n",
    )
    .unwrap();
    let r = lagrange(&["derive", model.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    let first = r.stderr.lines().next().unwrap_or_default();
    assert!(first.contains(":3:11: in the body file broken_body.toml:5:"), "{}", r.describe());
    assert!(first.contains("unknown name 'R'"), "{}", r.describe());
}

/// A body in roll, pitch and yaw (`sequence = "xyz"`): with no torque its
/// angular momentum in space, Dᵀ·L with D = R_z(ps)·R_y(th)·R_x(ph) written out
/// here, stays where it starts; and a run that pitches through ±π/2 stops at
/// the Tait–Bryan gimbal singularity, |cos th| → 0, with its reason.
#[test]
fn a_body_in_tait_bryan_angles_keeps_its_angular_momentum_in_space() {
    let out = scratch("bodies", "xyz.csv");
    let r = lagrange(&[
        "simulate",
        "examples/tops/free_body_xyz.toml",
        "--until",
        "10",
        "--rtol",
        "1e-11",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ph, th, ps) = (col("ph"), col("th"), col("ps"));
    let l_body = [col("L1"), col("L2"), col("L3")];
    let mut first: Option<[f64; 3]> = None;
    let mut rows = 0;
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let (c1, s1) = (v[ph].cos(), v[ph].sin());
        let (c2, s2) = (v[th].cos(), v[th].sin());
        let (c3, s3) = (v[ps].cos(), v[ps].sin());
        // D = R_z(ps) R_y(th) R_x(ph), each the turn of the frame (passive).
        let rx = [[1.0, 0.0, 0.0], [0.0, c1, s1], [0.0, -s1, c1]];
        let ry = [[c2, 0.0, -s2], [0.0, 1.0, 0.0], [s2, 0.0, c2]];
        let rz = [[c3, s3, 0.0], [-s3, c3, 0.0], [0.0, 0.0, 1.0]];
        let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| -> [[f64; 3]; 3] {
            std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
        };
        let d = mul(rz, mul(ry, rx));
        let lb = l_body.map(|c| v[c]);
        let space: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| d[k][i] * lb[k]).sum());
        let first = *first.get_or_insert(space);
        for k in 0..3 {
            assert!((space[k] - first[k]).abs() < 1e-8, "L{} in space moved to {} from {}", k + 1, space[k], first[k]);
        }
        rows += 1;
    }
    assert!(rows > 100, "{rows} rows");

    let model = std::fs::read_to_string(repo_root().join("examples/tops/free_body_xyz.toml")).unwrap();
    let file = scratch("bodies", "xyz_gimbal.toml");
    // A pure turn about the body's y axis: th runs through π/2.
    let pitching = model
        .replace("ph = 0.3", "ph = 0")
        .replace("th = 0.2", "th = 1.4")
        .replace("ps = -0.4", "ps = 0")
        .replace("\"ph'\" = 0.5", "\"ph'\" = 0")
        .replace("\"th'\" = 1.0", "\"th'\" = 3.0")
        .replace("\"ps'\" = -0.7", "\"ps'\" = 0");
    std::fs::write(&file, pitching).unwrap();
    let r = lagrange(&["simulate", file.to_str().unwrap(), "--until", "2", "--out", "gimbal.csv"]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(r.stderr.contains("|cos th| fell below") && r.stderr.contains("xyz angles"), "{}", r.stderr);

    // `top` reads the notes' angles only, and says so at the body.
    let r = lagrange(&["top", "examples/tops/free_body_xyz.toml"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("free_body_xyz.toml:11:1") && r.stderr.contains("z-x-z"), "{}", r.stderr);
    // A sequence that is not one is refused where it is written.
    let bad = scratch("bodies", "bad_sequence.toml");
    std::fs::write(&bad, model.replace("sequence = \"xyz\"", "sequence = \"xxz\"")).unwrap();
    let r = lagrange(&["derive", bad.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("'xxz' is not a sequence of three turns") && r.stderr.contains(":15:12"), "{}", r.stderr);
}
