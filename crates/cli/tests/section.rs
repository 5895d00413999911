//! `lagrange simulate --section`: Poincaré sections through the real binary.
//!
//! The points are checked against closed forms where the motion has one (two
//! uncoupled oscillators, whose section at x = 0 is a sampling of y at the
//! times x passes zero upwards), and against the section's own definition
//! where it has none (Hénon–Heiles): every point on the surface to 1e-10,
//! crossing it the one way asked, on the energy surface to the run's
//! tolerance. Then the plane's axes, the figure, and bad input (exit 2).

use crate::common::{ok, run as lagrange, Csv, TempFile};
use std::f64::consts::{PI, SQRT_2};

/// x'' = −x and y'' = −2y, from x = 0, x' = 1, y = 1, y' = 0: x = sin t, y = cos(√2 t).
const OSCILLATORS: &str = r#"
name = "two oscillators"
coordinates = ["x", "y"]
kinetic = "(x'^2 + y'^2)/2"
potential = "x^2/2 + y^2"
[initial]
x = 0
"x'" = 1
y = 1
"y'" = 0
"#;

#[test]
fn the_section_of_two_oscillators_samples_y_where_x_rises_through_zero() {
    let model = TempFile::with_text("section-osc", OSCILLATORS);
    let out = TempFile::new("section-osc", "csv");
    let until = 2.0 * PI * 20.5;
    let until = until.to_string();
    let r = ok(&[
        "simulate",
        model.path(),
        "--until",
        &until,
        "--rtol",
        "1e-12",
        "--section",
        "x = 0",
        "--out",
        out.path(),
    ]);
    assert!(r.stdout.contains("20 points on the section x = 0 in the CSV"), "{}", r.describe());
    let csv = Csv::read(out.path());
    assert_eq!(csv.header, ["t", "x", "y", "x'", "y'", "H", "p_y"]);
    assert_eq!(csv.rows.len(), 20, "x rises through 0 at t = 2πk, k = 1..20 (not at the start)");
    for (k, row) in csv.rows.iter().enumerate() {
        let t = 2.0 * PI * (k + 1) as f64;
        let want = [t, 0.0, (SQRT_2 * t).cos(), 1.0, -SQRT_2 * (SQRT_2 * t).sin()];
        for (i, w) in want.iter().enumerate() {
            assert!((row[i] - w).abs() < 1e-8, "point {k}, {}: {} against {w}", csv.header[i], row[i]);
        }
        assert_eq!(row[6], row[4], "p_y = y' here");
    }
}

#[test]
fn every_henon_heiles_point_is_on_the_section_crossing_one_way_on_the_energy_surface() {
    for (energy, condition, rising) in [("0.125", "x = 0", true), ("0.0833333333333333", "x < 0", false)] {
        let out = TempFile::new("section-hh", "csv");
        let r = ok(&[
            "simulate",
            "examples/henon_heiles.toml",
            "--set",
            &format!("E={energy}"),
            "--until",
            "500",
            "--section",
            condition,
            "--out",
            out.path(),
        ]);
        let csv = Csv::read(out.path());
        assert!(csv.rows.len() > 50, "{} points: {}", csv.rows.len(), r.describe());
        let e: f64 = energy.parse().unwrap();
        for (x, (xd, h)) in csv.column("x").iter().zip(csv.column("x'").iter().zip(csv.column("H"))) {
            assert!(x.abs() < 1e-10, "{condition}: x = {x} on the section");
            assert!(if rising { *xd > 0.0 } else { *xd < 0.0 }, "{condition}: crossed the other way, x' = {xd}");
            // rtol 1e-9 (the default): a few hundred steps' errors of that size.
            assert!((h - e).abs() < 1e-8, "{condition}: H = {h} against E = {e}");
        }
    }
}

#[test]
fn the_plane_takes_expressions_and_momenta_and_the_figure_draws_it() {
    let out = TempFile::new("section-axes", "csv");
    let svg = TempFile::new("section-axes", "svg");
    let r = ok(&[
        "simulate",
        "examples/double_pendulum.toml",
        "--until",
        "50",
        "--section",
        "a = 0",
        "--section-axes",
        "b, p_b",
        "--out",
        out.path(),
        "--plot",
        svg.path(),
        "--summary",
        "json",
    ]);
    let json = r.json();
    let csv = Csv::read(out.path());
    assert_eq!(json["section"]["points"].as_u64(), Some(csv.rows.len() as u64));
    assert_eq!(json["section"]["axes"][1], "p_b");
    assert!(csv.header.ends_with(&["p_b".to_string()]), "{:?}", csv.header);
    // p_b = ∂L/∂b' = m2 l2 (l1 a' cos(a − b) + l2 b') for the example's double pendulum (all 1): at a = 0.
    for row in &csv.rows {
        let (b, ad, bd, pb) = (row[csv.col("b")], row[csv.col("a'")], row[csv.col("b'")], row[csv.col("p_b")]);
        assert!((pb - (ad * b.cos() + bd)).abs() < 1e-9, "p_b = {pb} at b = {b}, a' = {ad}, b' = {bd}");
    }
    let figure = std::fs::read_to_string(svg.path()).unwrap();
    assert!(figure.contains("section a = 0 (increasing)") && figure.contains("\np_b\n"), "{}", &figure[..400]);
}

#[test]
fn bad_sections_are_refused_with_exit_2() {
    for (args, says) in [
        (vec!["--section", "z = 0"], "--section:1:1: in --section: unknown name 'z'"),
        (vec!["--section", "x = 0", "--section-axes", "y"], "needs two axes"),
        (vec!["--section", "x = 0", "--section-axes", "y, q_y"], "--section-axes:1:4"),
        (vec!["--section", "x = 0", "--crossing", "y = 0"], "cannot be used with"),
        (vec!["--section-axes", "y, p_y"], "--section"),
    ] {
        let mut all = vec!["simulate", "examples/henon_heiles.toml", "--until", "1"];
        all.extend(&args);
        let r = lagrange(&all);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.contains(says), "{says}: {}", r.describe());
    }
}

#[test]
fn a_sweep_of_sections_is_each_runs_simulate_section_in_grid_order() {
    // A parameter grid (the start follows from E and y0) and a grid of initial values.
    for (grid, set, one) in [
        ("y0=0.05;-0.1;0.2", "E=0.125", Some(["--set", "E=0.125", "--set", "y0=-0.1"])),
        // y' overrides the start after x' followed from E: no simulate command runs the same.
        ("y'=0:0.2:3", "E=0.0833", None),
    ] {
        let out = TempFile::new("section-sweep", "csv");
        let svg = TempFile::new("section-sweep", "svg");
        let r = ok(&[
            "sweep",
            "examples/henon_heiles.toml",
            "--until",
            "200",
            "--grid",
            grid,
            "--set",
            set,
            "--section",
            "x = 0",
            "--threads",
            "2",
            "--out",
            out.path(),
            "--plot",
            svg.path(),
        ]);
        assert!(r.stderr.contains("3 runs, 0 failed, on the section x = 0"), "{}", r.describe());
        let sweep = Csv::read(out.path());
        // A grid over a start (y') names its column apart from the point's y'.
        let name = grid.split('=').next().unwrap();
        assert_eq!(sweep.header.iter().filter(|h| h.as_str() == name).count(), 1, "{:?}", sweep.header);
        let grid_column = if name == "y'" { "grid.y'" } else { name };
        assert_eq!(sweep.header[1], grid_column, "{:?}", sweep.header);
        let runs = sweep.column("run");
        assert!(runs.windows(2).all(|w| w[0] <= w[1]), "grid order");
        assert_eq!(runs.iter().fold(0.0f64, |m, &r| m.max(r)), 2.0);
        assert!(sweep.column("x").iter().all(|x| x.abs() < 1e-10));
        let figure = std::fs::read_to_string(svg.path()).unwrap();
        assert!(figure.contains("3 runs"), "{}", &figure[..300]);
        let Some(one) = one else { continue };
        // Run 1 against simulate --section at the sweep's tolerance, digit for digit.
        let single = TempFile::new("section-sweep-one", "csv");
        let mut args = vec!["simulate", "examples/henon_heiles.toml", "--until", "200", "--rtol", "1e-10"];
        args.extend(one);
        args.extend(["--section", "x = 0", "--out", single.path()]);
        ok(&args);
        let single = Csv::read(single.path());
        let rows: Vec<&Vec<f64>> = sweep.rows.iter().filter(|row| row[0] == 1.0).collect();
        assert_eq!(rows.len(), single.rows.len());
        for (a, b) in rows.iter().zip(&single.rows) {
            assert_eq!(&a[2..], &b[..], "the sweep's point is simulate's");
        }
        assert!(figure.contains("y0 = -0.1"));
    }
}

#[test]
fn a_run_that_cannot_start_fails_the_sweep_and_the_others_are_kept() {
    let out = TempFile::new("section-sweep-fail", "csv");
    // At E = 1/8 the start y0 = 0.8 has no real x' (2E − y0² + 2y0³/3 < 0).
    let r = lagrange(&[
        "sweep",
        "examples/henon_heiles.toml",
        "--until",
        "100",
        "--grid",
        "y0=0.1;0.8",
        "--set",
        "E=0.125",
        "--section",
        "x = 0",
        "--out",
        out.path(),
    ]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(r.stderr.contains("run 1 (y0 = 0.8)") && r.stderr.contains("1 of 2 runs failed"), "{}", r.describe());
    let csv = Csv::read(out.path());
    assert!(!csv.rows.is_empty() && csv.rows.iter().all(|row| row[0] == 0.0));
}

#[test]
fn sweep_section_options_that_do_not_go_together_exit_2() {
    for extra in [["--heatmap", "h.svg"], ["--shard", "0/2"], ["--plot", "p.svg"]] {
        let mut args = vec!["sweep", "examples/henon_heiles.toml", "--until", "1", "--grid", "y0=0.1;0.2"];
        if extra[0] != "--plot" {
            args.extend(["--section", "x = 0"]);
        }
        args.extend(extra);
        let r = lagrange(&args);
        assert_eq!(r.code, Some(2), "{}", r.describe());
    }
}

/// A section condition without a value where the motion goes (sqrt(x) at
/// x < 0) ends the run naming the condition, the time and the state, where
/// it once said "event function 0 is not finite".
#[test]
fn a_condition_without_a_value_is_named_with_the_state() {
    let model = TempFile::with_text("section-undefined", OSCILLATORS);
    let r = lagrange(&["simulate", model.path(), "--until", "10", "--section", "sqrt(x) = 0.5", "--summary", "json"]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(r.stderr.contains("the condition `sqrt(x) = 0.5` has no value at t = "), "{}", r.describe());
    assert!(r.stderr.contains("(x = -"), "the state is named: {}", r.describe());
    assert!(!r.stderr.contains("event function"), "{}", r.describe());
    let summary = r.json();
    assert_eq!(summary["failure_reason"]["code"], "undefined_condition", "{}", r.describe());
    assert_eq!(summary["failure_reason"]["condition"], "sqrt(x) = 0.5", "{}", r.describe());
    let t = summary["failure_reason"]["t"].as_f64().unwrap();
    // x = sin t turns negative at t = π; the condition is evaluated at the steps'
    // ends, the first of them past π.
    assert!(t > PI && t < 2.0 * PI, "t = {t}");
    let x: f64 = r.stderr.split("(x = ").nth(1).and_then(|s| s.split(',').next()).unwrap().parse().unwrap();
    assert!(x < 0.0 && (x - t.sin()).abs() < 1e-4, "the state at t = {t} is x = sin t, not {x}");
}
