//! `lagrange modes` and `lagrange orbit` run through the real binary on the
//! examples: the JSON contracts (`lagrange.modes/1`, `lagrange.orbit/1`), the
//! notes' results (coupled oscillators, triatomic molecule, double pendulum,
//! the 50-mass chain, Kepler orbits, the reduced mass), the figures, and the
//! failures that are bad input (exit 2).

use serde_json::Value;
use std::f64::consts::PI;

use crate::common;
use crate::common::{close, json, run, scratch, Run, TempFile};

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().expect("an array").iter().map(|x| x.as_f64().expect("a number")).collect()
}

#[test]
fn coupled_oscillators_follow_the_contract() {
    let v = json(&["modes", "examples/coupled_oscillators.toml", "--format", "json"]);
    assert_eq!(v["format"], "lagrange.modes/1");
    for key in ["equilibrium", "T", "U", "frequencies", "modes", "stable"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    let f = floats(&v["frequencies"]);
    close(f[0], 1.0, 1e-12);
    close(f[1], 1.5, 1e-12);
    assert_eq!(v["stable"], true);
    assert_eq!(v["equilibrium"]["q1"], 0.0);
    assert_eq!(floats(&v["U"][0]), vec![1.625, -0.625]);
    assert!(v["secular_equation"].as_str().unwrap().ends_with("= 0"));
}

#[test]
fn triatomic_molecule_frequencies_and_free_translation() {
    let v = json(&["modes", "examples/triatomic.toml", "--format", "json"]);
    let (m, big, k) = (16.0f64, 12.0f64, 1.0f64);
    let f = floats(&v["frequencies"]);
    close(f[0] + 1.0, 1.0, 1e-12);
    close(f[1], (k / m).sqrt(), 1e-12);
    close(f[2], (k / m * (1.0 + 2.0 * m / big)).sqrt(), 1e-12);
    assert_eq!(v["kinds"][0], "free");
    let exact: Vec<&str> = v["exact_frequencies"].as_array().unwrap().iter().map(|x| x.as_str().unwrap()).collect();
    assert_eq!(exact[1], "sqrt(k/m)");
    let Run { stdout: text, .. } = run(&["modes", "examples/triatomic.toml"]);
    assert!(text.contains("free motion"), "{text}");
}

#[test]
fn chain_of_fifty_masses_has_the_textbook_frequencies() {
    let v = json(&["modes", "examples/chain50.toml", "--format", "json"]);
    let f = floats(&v["frequencies"]);
    assert_eq!(f.len(), 50);
    for (j, w) in f.iter().enumerate() {
        let want = 2.0 * ((j + 1) as f64 * PI / (2.0 * 51.0)).sin();
        close(*w, want, 1e-10);
    }
}

#[test]
fn double_pendulum_upside_down_is_rejected_and_its_lowest_position_is_not() {
    let Run { code, stderr, .. } = run(&["modes", "examples/double_pendulum.toml"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("unstable") && stderr.contains("--at"), "{stderr}");

    let v = json(&["modes", "examples/double_pendulum.toml", "--at", "a=0", "b=0", "--format", "json"]);
    let f = floats(&v["frequencies"]);
    let g = 9.81f64;
    close(f[0], ((2.0 - 2f64.sqrt()) * g).sqrt(), 1e-12);
    close(f[1], ((2.0 + 2f64.sqrt()) * g).sqrt(), 1e-12);

    let v = json(&["modes", "examples/double_pendulum.toml", "--allow-unstable", "--format", "json"]);
    assert_eq!(v["stable"], false);
    assert!(v["frequencies"][0].is_null());
}

#[test]
fn modes_bad_input_exits_2() {
    let Run { code, stderr, .. } = run(&["modes", "examples/kepler.toml"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("no equilibrium"), "{stderr}");
    let Run { code, stderr, .. } = run(&["modes", "examples/coupled_oscillators.toml", "--at", "zz=1"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("no coordinate 'zz'"), "{stderr}");
}

/// A generalized force keeps small oscillations out: the refusal names the
/// `[forces]` entry's value by file:line:col (here line 7, after `y = `).
#[test]
fn modes_refuses_a_generalized_force_at_its_entry() {
    let text = "coordinates = [\"x\", \"y\"]\n\
                kinetic = \"(x'^2 + y'^2)/2\"\n\
                potential = \"(x^2 + y^2)/2\"\n\
                \n\
                [forces]\n\
                x = \"0\"\n\
                y = \"-y'\"\n\
                \n\
                [initial]\n\
                x = 0.1\n\
                y = 0.0\n\
                \"x'\" = 0.0\n\
                \"y'\" = 0.0\n";
    assert_eq!(text.lines().nth(6), Some("y = \"-y'\""));
    let model = TempFile::with_text("modes-force", text);
    let Run { code, stderr, .. } = run(&["modes", model.path()]);
    assert_eq!(code, Some(2), "{stderr}");
    let first = stderr.lines().next().unwrap_or("");
    assert!(first.starts_with(&format!("error: {}:7:5: ", model.path())), "{stderr}");
    assert!(first.contains("generalized forces [forces], which are not derived from a potential"), "{stderr}");

    // The same for the example with a driving force (its only [forces] entry).
    let example = std::fs::read_to_string(common::repo_root().join("examples/driven_oscillator.toml")).unwrap();
    let (line, entry) = example.lines().enumerate().find(|(_, l)| l.starts_with("x = \"F0")).expect("the force");
    let col = entry.find('"').unwrap() + 1;
    let Run { code, stderr, .. } = run(&["modes", "examples/driven_oscillator.toml"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.starts_with(&format!("error: examples/driven_oscillator.toml:{}:{col}: ", line + 1)), "{stderr}");
}

#[test]
fn modes_animation_is_an_svg() {
    let path = scratch("modes-orbit", "triatomic.svg");
    let Run { code, stderr, .. } = run(&["modes", "examples/triatomic.toml", "--animate", path.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stderr}");
    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("<animate") && svg.trim_end().ends_with("</svg>"));
}

#[test]
fn kepler_orbit_follows_the_contract_and_the_closed_forms() {
    let v = json(&["orbit", "examples/kepler.toml", "--format", "json"]);
    assert_eq!(v["format"], "lagrange.orbit/1");
    for key in [
        "energy",
        "angular_momentum",
        "reduced_mass",
        "kind",
        "eccentricity",
        "semi_latus_rectum",
        "periapsis",
        "apoapsis",
        "period",
        "apsidal_angle",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    // mu = k = 1, r = 1, th' = 1.2 at rest radially: l = 1.2, E = 0.72 - 1.
    let (l, e) = (1.2f64, 0.72 - 1.0);
    let alpha = l * l;
    let eps = (1.0 + 2.0 * e * l * l).sqrt();
    assert_eq!(v["kind"], "ellipse");
    close(v["eccentricity"].as_f64().unwrap(), eps, 1e-13);
    close(v["semi_latus_rectum"].as_f64().unwrap(), alpha, 1e-13);
    close(v["periapsis"].as_f64().unwrap(), alpha / (1.0 + eps), 1e-13);
    close(v["apoapsis"].as_f64().unwrap(), alpha / (1.0 - eps), 1e-13);
    let a = alpha / (1.0 - eps * eps);
    close(v["period"].as_f64().unwrap(), 2.0 * PI * a.powf(1.5), 1e-13);
    close(v["apsidal_angle"].as_f64().unwrap(), PI, 1e-15);
}

#[test]
fn two_bodies_orbit_with_the_reduced_mass() {
    let v = json(&["orbit", "examples/two_body.toml", "--format", "json"]);
    close(v["reduced_mass"].as_f64().unwrap(), 3.0 * 1.0 / (3.0 + 1.0), 1e-14);
    assert_eq!(v["reduced_mass_expr"], "m1*m2/(m1 + m2)");
    assert_eq!(v["kind"], "ellipse");
    // k = G m1 m2 = 3, mu = 3/4, r = 1, th' = 1.5: l = 9/8, E = mu/2*(9/4) - 3.
    let (mu, k, l) = (0.75f64, 3.0f64, 1.125f64);
    let e = 0.5 * mu * 2.25 - k;
    close(v["energy"].as_f64().unwrap(), e, 1e-14);
    close(v["eccentricity"].as_f64().unwrap(), (1.0 + 2.0 * e * l * l / (mu * k * k)).sqrt(), 1e-13);
}

#[test]
fn screened_potential_precesses_and_plots() {
    let path = scratch("modes-orbit", "central.svg");
    let v = json(&["orbit", "examples/central_force.toml", "--format", "json", "--plot", path.to_str().unwrap()]);
    assert_eq!(v["kind"], "bounded");
    assert!(v["eccentricity"].is_null());
    let apsidal = v["apsidal_angle"].as_f64().unwrap();
    assert!(apsidal > PI && apsidal < 1.1 * PI, "{apsidal}");
    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.contains("<svg") && svg.contains("effective potential"));
}

/// The Laplace–Runge–Lenz vector `orbit` reports stays constant along a `simulate` run.
#[test]
fn runge_lenz_vector_is_conserved_in_simulation() {
    let v = json(&["orbit", "examples/kepler.toml", "--format", "json"]);
    let a0 = floats(&v["runge_lenz"]);
    let csv = scratch("modes-orbit", "kepler.csv");
    let Run { code, stderr, .. } =
        run(&["simulate", "examples/kepler.toml", "--until", "45", "--rtol", "1e-11", "--out", csv.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ir, ith, ird, ithd) = (col("r"), col("th"), col("r'"), col("th'"));
    let (mu, k) = (1.0, 1.0);
    for line in lines {
        let x: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
        let (r, th, rd, thd) = (x[ir], x[ith], x[ird], x[ithd]);
        let l = mu * r * r * thd;
        let (c, s) = (th.cos(), th.sin());
        let (vx, vy) = (rd * c - r * thd * s, rd * s + r * thd * c);
        let a = [mu * l * vy - mu * k * c, -mu * l * vx - mu * k * s];
        assert!((a[0] - a0[0]).abs() < 1e-7 && (a[1] - a0[1]).abs() < 1e-7, "A = {a:?}, reported {a0:?}");
    }
}

#[test]
fn orbit_rejects_other_models() {
    let Run { code, stderr, .. } = run(&["orbit", "examples/coupled_oscillators.toml"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("not a central-force model"), "{stderr}");
    let Run { code, stderr, .. } = run(&["orbit", "examples/chain50.toml"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("exactly two"), "{stderr}");
}

/// With dissipation the damped motion's roots come too: m x'' + β x' + k x = 0
/// has s = −β/2m ± i√(k/m − β²/4m²) (underdamped) and two real roots
/// (−β ± √(β² − 4mk))/2m (overdamped), in `lagrange.modes/1` as `C` and `damped`.
#[test]
fn a_damped_oscillator_has_the_roots_of_its_characteristic_equation() {
    for (be, om) in [(0.1, 1.0), (0.3, 2.0), (3.0, 1.0)] {
        let r = run(&[
            "modes",
            "examples/damped_oscillator.toml",
            "--set",
            &format!("be={be}"),
            "--set",
            &format!("om={om}"),
            "--format",
            "json",
        ]);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        assert_eq!(v["C"][0][0].as_f64(), Some(be));
        let roots = v["damped"].as_array().unwrap();
        assert_eq!(roots.len(), 2);
        let (m, k) = (1.0f64, om * om);
        let disc = be * be - 4.0 * m * k;
        let want: Vec<(f64, f64)> = if disc < 0.0 {
            let w = (-disc).sqrt() / (2.0 * m);
            vec![(-be / (2.0 * m), w), (-be / (2.0 * m), -w)]
        } else {
            vec![((-be + disc.sqrt()) / (2.0 * m), 0.0), ((-be - disc.sqrt()) / (2.0 * m), 0.0)]
        };
        for (root, (re, im)) in roots.iter().zip(want) {
            let (got_re, got_im) = (root["re"].as_f64().unwrap(), root["im"].as_f64().unwrap());
            assert!((got_re - re).abs() < 1e-12 && (got_im - im).abs() < 1e-12, "be = {be}: {root} vs {re} {im}");
            assert!((root["decay_rate"].as_f64().unwrap() + re).abs() < 1e-12);
            assert!((root["frequency"].as_f64().unwrap() - im.abs()).abs() < 1e-12);
        }
    }
    // Without dissipation there is no damped motion to report.
    let r = run(&["modes", "examples/oscillator.toml", "--format", "json"]);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert!(v["damped"].is_null() && v["C"].is_null(), "{}", r.stdout);
}
