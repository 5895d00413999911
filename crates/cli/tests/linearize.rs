//! `lagrange linearize` through the real binary against results derived by
//! hand: the damped oscillator's A, the spinning hoop's stable angle and
//! frequency, the sleeping top's bound I3²ω3² > 4 I M g S and its two
//! frequencies, the heavy top's steady precession against the notes'
//! effective potential, the leaning rolling disc's critical spin g/(3r) (as in
//! SymPy's test_linearize), and a holonomic constraint eliminated; `modes`
//! leaves the hoop's unstable top for its stable angle; bad flags exit 2.

use serde_json::Value;

use crate::common;
use crate::common::{close, json, run, Run};

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().expect("an array").iter().map(|x| x.as_f64().expect("a number")).collect()
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().expect("rows").iter().map(floats).collect()
}

/// (re, im) of every eigenvalue.
fn eigenvalues(v: &Value) -> Vec<(f64, f64)> {
    v["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e["re"].as_f64().unwrap(), e["im"].as_f64().unwrap()))
        .collect()
}

/// The eigenvalues with Im > 0 or Re ≠ 0 (the zeros of cyclic coordinates left out), checked against `want`.
#[track_caller]
fn check_nonzero(v: &Value, want: &[(f64, f64)], tol: f64) {
    let got: Vec<(f64, f64)> = eigenvalues(v).into_iter().filter(|e| e.0 != 0.0 || e.1 != 0.0).collect();
    assert_eq!(got.len(), want.len(), "{got:?} against {want:?}");
    for w in want {
        assert!(
            got.iter()
                .any(|g| (g.0 - w.0).abs() <= tol * (1.0 + w.0.abs()) && (g.1 - w.1).abs() <= tol * (1.0 + w.1.abs())),
            "{w:?} is not among {got:?}"
        );
    }
}

#[test]
fn damped_oscillator_gives_the_textbook_matrix() {
    // m x'' + be x' + m om² x = 0: A = [[0, 1], [−om², −be/m]] with m = om = 1, be = 0.3.
    let v = json(&["linearize", "examples/damped_oscillator.toml", "--set", "be=0.3", "--format", "json"]);
    assert_eq!(v["format"], "lagrange.linearize/1");
    assert_eq!(matrix(&v["A"]), vec![vec![0.0, 1.0], vec![-1.0, -0.3]]);
    assert_eq!(v["state"], serde_json::json!(["x", "x'"]));
    assert_eq!(v["inputs"], serde_json::json!([]));
    assert!(v["B"].is_null());
    assert_eq!(v["stability"], "stable");
    check_nonzero(&v, &[(-0.15, (1.0f64 - 0.0225).sqrt()), (-0.15, -(1.0f64 - 0.0225).sqrt())], 1e-12);
}

#[test]
fn spinning_hoop_leaves_its_unstable_top_for_the_stable_angle() {
    let (g, w) = (9.81f64, 5.0f64);
    let th0 = (g / (w * w)).acos();
    let v = json(&["linearize", "examples/bead_on_hoop.toml", "--format", "json"]);
    close(v["q"]["th"].as_f64().unwrap(), th0, 1e-10);
    // U_eff'' = m R² w² sin²th0, so A = [[0, 1], [−w² sin²th0, 0]].
    let a = matrix(&v["A"]);
    close(a[1][0], -(w * th0.sin()).powi(2), 1e-9);
    check_nonzero(&v, &[(0.0, w * th0.sin()), (0.0, -w * th0.sin())], 1e-9);
    let eq = v["equilibria"].as_array().unwrap();
    let top = eq.iter().find(|e| e["landing"] == true).expect("Newton's landing point is listed");
    assert_eq!(top["at"]["th"], 0.0);
    assert_eq!(top["stability"], "unstable");
    // modes does the same, and says U is effective: U(q0) = −(w²/2) sin²th0 − g cos th0.
    let m = json(&["modes", "examples/bead_on_hoop.toml", "--format", "json"]);
    close(m["equilibrium"]["th"].as_f64().unwrap(), th0, 1e-10);
    close(m["frequencies"][0].as_f64().unwrap(), w * th0.sin(), 1e-9);
    close(m["potential"].as_f64().unwrap(), -(w * w / 2.0) * th0.sin().powi(2) - g * th0.cos(), 1e-12);
    assert!(m["effective_potential"].is_string());
    let Run { code, stdout, .. } = run(&["modes", "examples/bead_on_hoop.toml"]);
    assert_eq!(code, Some(0));
    assert!(stdout.contains("th = 0: unstable  (reached from the start)"), "{stdout}");
    assert!(stdout.contains("not derive's U"), "{stdout}");
    // --allow-unstable keeps the landing point.
    let v = json(&["linearize", "examples/bead_on_hoop.toml", "--allow-unstable", "--format", "json"]);
    assert_eq!(v["q"]["th"], 0.0);
    assert_eq!(v["stability"], "unstable");
    check_nonzero(&v, &[((w * w - g).sqrt(), 0.0), (-(w * w - g).sqrt(), 0.0)], 1e-9);
}

/// Upright with spin ω3: λ = ±i (I3ω3 ± sqrt(I3²ω3² − 4 I M g S)) / 2I.
#[test]
fn sleeping_top_is_stable_above_the_bound_and_unstable_below() {
    let (m, i1, i3, s, g) = (1.0f64, 1.0f64, 0.5f64, 0.5f64, 9.81f64);
    let bound = (4.0 * i1 * m * g * s).sqrt() / i3;
    for w3 in [12.0f64, 6.0] {
        let rate = format!("c={w3}");
        let v = json(&[
            "linearize",
            "examples/tops/sleeping_top.toml",
            "--about",
            "steady",
            "--rate",
            &rate,
            "--format",
            "json",
        ]);
        let disc = (i3 * w3).powi(2) - 4.0 * i1 * m * g * s;
        if w3 > bound {
            let (a, b) = ((i3 * w3 + disc.sqrt()) / (2.0 * i1), (i3 * w3 - disc.sqrt()) / (2.0 * i1));
            check_nonzero(&v, &[(0.0, a), (0.0, -a), (0.0, b), (0.0, -b)], 1e-9);
            assert_eq!(v["stability"], "marginal");
        } else {
            let (re, im) = ((-disc).sqrt() / (2.0 * i1), i3 * w3 / (2.0 * i1));
            check_nonzero(&v, &[(re, im), (re, -im), (-re, im), (-re, -im)], 1e-9);
            assert_eq!(v["stability"], "unstable");
        }
        assert_eq!(v["moving"]["c"], w3);
    }
}

/// The heavy top precessing steadily at al' = 0.85 with ga' = 12: β₀ from
/// I al'² cos β − I3 ω3 al' + M g S = 0, and the nutation frequency from the
/// notes' U_eff(β) = (p_al − p_ga cos β)²/(2 I sin²β) + M g S cos β: Ω² = U_eff''(β₀)/I.
#[test]
fn heavy_top_steady_precession_against_the_effective_potential() {
    let (m, i1, i3, s, g) = (1.0f64, 1.0f64, 0.5f64, 0.5f64, 9.81f64);
    let (al, ga) = (0.85f64, 12.0f64);
    let v = json(&[
        "linearize",
        "examples/tops/heavy_top.toml",
        "--about",
        "steady",
        "--rate",
        "al=0.85",
        "--format",
        "json",
    ]);
    let be = v["q"]["be"].as_f64().unwrap();
    // ω3 = al' cos β + ga': I al'² cos β − I3 (al' cos β + ga') al' + M g S = 0.
    let cos_be = (i3 * ga * al - m * g * s) / ((i1 - i3) * al * al);
    close(be, cos_be.acos(), 1e-9);
    let p_ga = i3 * (al * be.cos() + ga);
    let p_al = i1 * al * be.sin().powi(2) + p_ga * be.cos();
    let u = |b: f64| (p_al - p_ga * b.cos()).powi(2) / (2.0 * i1 * b.sin().powi(2)) + m * g * s * b.cos();
    let h = 1e-4;
    let u2 = (u(be + h) - 2.0 * u(be) + u(be - h)) / (h * h);
    let omega = (u2 / i1).sqrt();
    check_nonzero(&v, &[(0.0, omega), (0.0, -omega)], 1e-6);
    assert_eq!(v["stability"], "marginal");
}

/// Upright rolling at spin W: lean and heading obey (I + m r²) θ'' = m g r θ − (J + m r²) W ψ',
/// I ψ'' = J W θ', so λ² = (m g r − (J + m r²) J W²/I)/(I + m r²) = (4/5)(g/r − 3W²) for a thin disc:
/// stable above W² = g/(3r) (SymPy's test_linearize_rolling_disc_kane: all eigenvalues zero at 1/√3 with g = r = 1).
#[test]
fn leaning_disk_rolls_upright_above_the_critical_spin() {
    let (g, r) = (9.81f64, 0.5f64);
    for w in [5.0f64, 2.0] {
        let rate = format!("ph={w}");
        let v = json(&[
            "linearize",
            "examples/constraints/leaning_disk.toml",
            "--about",
            "steady",
            "--rate",
            &rate,
            "--format",
            "json",
        ]);
        assert_eq!(v["state"].as_array().unwrap().len(), 8, "5 coordinates and 3 independent speeds");
        let mut dep: Vec<String> =
            v["dependent_speeds"].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect();
        dep.sort();
        assert_eq!(dep, ["x'", "y'"]);
        let l2 = 0.8 * (g / r - 3.0 * w * w);
        if l2 < 0.0 {
            check_nonzero(&v, &[(0.0, (-l2).sqrt()), (0.0, -(-l2).sqrt())], 1e-9);
            assert_eq!(v["stability"], "marginal");
        } else {
            check_nonzero(&v, &[(l2.sqrt(), 0.0), (-l2.sqrt(), 0.0)], 1e-9);
            assert_eq!(v["stability"], "unstable");
        }
        close(v["qd"]["x"].as_f64().unwrap(), r * w, 1e-12);
    }
}

/// x² + y² = l²: hanging at (0, −l), y is dependent, x' = x'' with A = [[0, 1], [−g/l, 0]]
/// (SymPy's test_linearize_pendulum_lagrange_nonminimal); the tension λ = −m g/(2l) from the force λ ∇f.
#[test]
fn a_holonomic_constraint_is_eliminated() {
    let v = json(&["linearize", "examples/constraints/pendulum_cartesian.toml", "--set", "l=2", "--format", "json"]);
    let (g, l) = (9.81f64, 2.0f64);
    close(v["q"]["y"].as_f64().unwrap(), -l, 1e-12);
    assert_eq!(v["dependent_coordinates"], serde_json::json!(["y"]));
    assert_eq!(v["state"], serde_json::json!(["x", "x'"]));
    let a = matrix(&v["A"]);
    close(a[0][1], 1.0, 1e-12);
    close(a[1][0], -g / l, 1e-9);
    assert!(a[0][0].abs() < 1e-12 && a[1][1].abs() < 1e-12);
    close(v["multipliers"]["rod"].as_f64().unwrap(), -g / (2.0 * l), 1e-9);
}

#[test]
fn bad_flags_name_the_flag_and_exit_2() {
    let Run { code, stderr, .. } = run(&["linearize", "examples/bead_on_hoop.toml", "--rate", "th=1"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("--rate th:"), "{stderr}");
    let Run { code, stderr, .. } =
        run(&["linearize", "examples/tops/sleeping_top.toml", "--about", "steady", "--rate", "a=1"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("--rate a:") && stderr.contains("not cyclic"), "{stderr}");
    let Run { code, stderr, .. } = run(&["linearize", "examples/bead_on_hoop.toml", "--at", "zz=1"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("--at zz:"), "{stderr}");
    // A time-dependent force is refused at its [forces] entry.
    let Run { code, stderr, .. } = run(&["linearize", "examples/driven_oscillator.toml"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("examples/driven_oscillator.toml:") && stderr.contains("time t"), "{stderr}");
}

/// A model of one coordinate x with kinetic energy x'²/2 and this potential.
fn one_coordinate(tag: &str, potential: &str, damping: &str) -> std::path::PathBuf {
    let path = common::scratch("linearize-issue29", &format!("{tag}.toml"));
    let text = format!(
        "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"{potential}\"\ndissipation = \"{damping}\"\n[initial]\nx = -0.5\n\"x'\" = 0\n"
    );
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn every_example_linearizes_or_says_why() {
    let root = common::repo_root();
    for dir in ["examples", "examples/constraints", "examples/tops", "examples/bicycle"] {
        for entry in std::fs::read_dir(root.join(dir)).unwrap() {
            let path = entry.unwrap().path();
            let text = std::fs::read_to_string(&path).unwrap_or_default();
            if path.extension().is_none_or(|e| e != "toml") || !text.lines().any(|l| l.starts_with("coordinates")) {
                continue;
            }
            let r = run(&["linearize", path.to_str().unwrap()]);
            assert!(r.code == Some(0) || (r.code == Some(2) && r.stderr.contains("error:")), "{}", r.describe());
        }
    }
}

#[test]
fn nilpotent_degenerate_and_widely_spread_spectra_are_found() {
    // Free particle and U = x³ from x = −0.5 (Newton to the double root 0):
    // A = [[0, 1], [0, 0]], s = 0 twice, marginal.
    for (tag, potential) in [("free", "0"), ("cubic", "x^3")] {
        let v = json(&["linearize", one_coordinate(tag, potential, "0").to_str().unwrap(), "--format", "json"]);
        assert_eq!(eigenvalues(&v), vec![(0.0, 0.0), (0.0, 0.0)], "{tag}");
        assert_eq!(v["stability"], "marginal", "{tag}");
    }
    // Overdamped, m = k = 1, b = 1e4: s = (−b ± √(b² − 4))/2.
    let v = json(&["linearize", one_coordinate("over", "x^2/2", "1e4*x'^2/2").to_str().unwrap(), "--format", "json"]);
    // The slow root as 2c/(−b − √(b² − 4c)), free of cancellation.
    let b: f64 = 1e4;
    let slow = -2.0 / (b + (b * b - 4.0).sqrt());
    let got = eigenvalues(&v);
    assert_eq!(got.len(), 2, "{got:?}");
    assert!((got[0].0 - slow).abs() <= 1e-9 * slow.abs() && got[0].1 == 0.0, "{got:?}");
    assert!((got[1].0 - (-b - slow)).abs() <= 1e-9 * b && got[1].1 == 0.0, "{got:?}");
    assert_eq!(v["stability"], "stable");
    // No equilibrium: U = exp(x), and a constant force of 1 or of 1e-13.
    for (tag, potential) in [("exp", "exp(x)"), ("one", "x"), ("tiny", "1e-13*x")] {
        let r = run(&["linearize", one_coordinate(tag, potential, "0").to_str().unwrap()]);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.contains("no equilibrium"), "{}", r.describe());
    }
}

#[test]
fn a_coordinate_given_twice_is_refused() {
    let r = run(&["linearize", "examples/pendulum.toml", "--at", "ph=1", "--at", "ph=2"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("--at ph: given twice"), "{}", r.describe());
}
