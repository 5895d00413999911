//! `lagrange extremal` run through the real binary: the JSON contract
//! (`lagrange.extremal/1`), the notes' classic extremals against their closed
//! forms (straight line, brachistochrone cycloid, catenary, the oscillator's
//! action and its conjugate point at π/ω), Goldschmidt's case (exit 1), the
//! figure, and bad problem files (exit 2 with file:line:col).

use serde_json::Value;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use crate::common::{close, json, repo_root, run, scratch, Run};

/// `lagrange extremal ARGS --format json`, which must succeed.
#[track_caller]
fn extremal(args: &[&str]) -> Value {
    let mut all = vec!["extremal"];
    all.extend_from_slice(args);
    all.extend(["--format", "json"]);
    json(&all)
}

fn path(v: &Value) -> Vec<[f64; 2]> {
    v["path"]
        .as_array()
        .expect("a path")
        .iter()
        .map(|p| [p[0].as_f64().expect("x"), p[1].as_f64().expect("y")])
        .collect()
}

fn temp(name: &str, text: &str) -> PathBuf {
    let file = scratch("extremal", name);
    std::fs::write(&file, text).expect("write the problem");
    file
}

/// Bisection for a root of an increasing or decreasing `f` on [lo, hi].
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let up = f(hi) > f(lo);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (f(mid) > 0.0) == up {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn shortest_path_is_the_straight_line() {
    let v = extremal(&["examples/extremal/shortest_path.toml"]);
    assert_eq!(v["format"], "lagrange.extremal/1");
    for key in ["euler_equation", "first_integral", "value", "straight_line_value", "path"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    close(v["value"].as_f64().unwrap(), 5.0, 1e-12);
    close(v["straight_line_value"].as_f64().unwrap(), 5.0, 1e-12);
    let p = path(&v);
    assert_eq!(p.len(), 201);
    assert_eq!(p[0], [0.0, 0.0]);
    for [x, y] in &p {
        assert!((y - 4.0 / 3.0 * x).abs() < 1e-12, "({x}, {y}) is off the line");
    }
    close(p[200][0], 3.0, 1e-12);
    close(p[200][1], 4.0, 1e-12);
    // The Euler equation of the arc length is y'' = 0; Beltrami: -1/sqrt(1 + y'^2) = -3/5.
    assert_eq!(v["acceleration"], "0");
    close(v["first_integral_constant"].as_f64().unwrap(), -0.6, 1e-12);
}

/// The cycloid x = a(θ − sin θ), y = a(1 − cos θ) from the origin through (x1, y1): (a, θ1).
fn cycloid(x1: f64, y1: f64) -> (f64, f64) {
    let theta = bisect(|t| (t - t.sin()) / (1.0 - t.cos()) - x1 / y1, 1e-6, 2.0 * PI - 1e-9);
    (y1 / (1.0 - theta.cos()), theta)
}

#[track_caller]
fn check_brachistochrone(file: &Path, x1: f64, y1: f64, g: f64) {
    let v = extremal(&[file.to_str().unwrap(), "--check-minimum"]);
    let (a, theta1) = cycloid(x1, y1);
    let time = (a / g).sqrt() * theta1;
    close(v["value"].as_f64().unwrap(), time, 1e-8);
    assert_eq!(v["endpoints"], "singular_start");
    assert_eq!(v["minimum"], true);
    assert!(v["straight_line_value"].as_f64().unwrap() > time);
    assert_eq!(path(&v).len(), 201);
    close(v["departure"][0].as_f64().unwrap(), PI / 2.0, 1e-12);
    // The Euler equation solved for y'' reads as the notes write it.
    assert_eq!(v["acceleration"], "-(y'^2 + 1)/(2*y)");
    // Every point lies on the cycloid: θ from x (monotone), then y.
    for [x, y] in path(&v) {
        let theta = bisect(|t| a * (t - t.sin()) - x, 0.0, theta1 + 1e-6);
        assert!((a * (1.0 - theta.cos()) - y).abs() < 1e-8 * y1, "({x}, {y}) is off the cycloid");
    }
}

#[test]
fn brachistochrone_is_the_cycloid() {
    check_brachistochrone(&repo_root().join("examples/extremal/brachistochrone.toml"), 1.0, 0.8, 9.81);
}

#[test]
fn brachistochrone_dips_below_a_low_end() {
    // x1/y1 = 5 > π/2: the cycloid passes its lowest point (θ1 > π) and climbs to the end.
    let text = "name = \"low end\"\nindependent = \"x\"\nunknown = \"y\"\nintegrand = \"sqrt((1 + y'^2)/(2*g*y))\"\n\
                [parameters]\ng = 1.62\n[boundary]\nstart = [0, 0]\nend = [2.0, 0.4]\n";
    let file = temp("low.toml", text);
    let (_, theta1) = cycloid(2.0, 0.4);
    assert!(theta1 > PI);
    check_brachistochrone(&file, 2.0, 0.4, 1.62);
    // Close to the next cusp (θ1 ≈ 5.47), where neighbouring members end in the cusp
    // before reaching x1, and a steep one (θ1 ≈ 0.15) that stays nearly vertical.
    for (name, x1, y1) in [("cusp.toml", 1.0, 0.05), ("steep.toml", 0.1, 2.0)] {
        let file = temp(name, &text.replace("end = [2.0, 0.4]", &format!("end = [{x1}, {y1}]")));
        check_brachistochrone(&file, x1, y1, 1.62);
    }
}

#[test]
fn brachistochrone_ending_on_the_singular_line_is_solved_from_the_end() {
    // The mirror image of the default example: from (0, 0.8) down to the cusp at (1, 0).
    let text = "independent = \"x\"\nunknown = \"y\"\nintegrand = \"sqrt((1 + y'^2)/(2*g*y))\"\n\
                [parameters]\ng = 9.81\n[boundary]\nstart = [0, 0.8]\nend = [1, 0]\n";
    let file = temp("mirror.toml", text);
    let v = extremal(&[file.to_str().unwrap(), "--check-minimum", "--points", "51"]);
    let (a, theta1) = cycloid(1.0, 0.8);
    close(v["value"].as_f64().unwrap(), (a / 9.81).sqrt() * theta1, 1e-8);
    assert_eq!(v["endpoints"], "singular_end");
    assert_eq!(v["minimum"], true);
    let p = path(&v);
    assert_eq!(p.len(), 51);
    assert_eq!(p[50], [1.0, 0.0]);
    for [x, y] in p {
        let theta = bisect(|t| a * (t - t.sin()) - (1.0 - x), 0.0, theta1 + 1e-6);
        assert!((a * (1.0 - theta.cos()) - y).abs() < 1e-8, "({x}, {y}) is off the cycloid");
    }
}

#[test]
fn catenary_two_extremals_and_the_lower_one() {
    let v = extremal(&["examples/extremal/catenary.toml", "--check-minimum"]);
    // a·cosh(h/a) = R with R = 1, h = 0.5: the shallow and the deep catenary.
    let (r, h) = (1.0, 0.5);
    let shallow = bisect(|a: f64| a * (h / a).cosh() - r, 0.5516, 1.0);
    let deep = bisect(|a: f64| a * (h / a).cosh() - r, 0.05, 0.5516);
    let area = |a: f64| a * (h + 0.5 * a * (2.0 * h / a).sinh());
    let ext = v["extremals"].as_array().unwrap();
    assert_eq!(ext.len(), 2, "{ext:?}");
    assert_eq!(v["acceleration"], "(y'^2 + 1)/y");
    close(ext[0]["value"].as_f64().unwrap(), area(shallow), 1e-9);
    close(ext[1]["value"].as_f64().unwrap(), area(deep), 1e-9);
    close(v["value"].as_f64().unwrap(), area(shallow), 1e-9);
    for [x, y] in path(&v) {
        assert!((y - shallow * (x / shallow).cosh()).abs() < 1e-8, "({x}, {y}) is off the catenary");
    }
    // The shallow one is a minimum; the deep one has a conjugate point inside.
    assert_eq!(v["minimum"], true);
    assert!(v["conjugate_point"].is_null());
    // The conjugate point is where neighbouring catenaries through the start meet the
    // deep one again: y(x; a) = a·cosh((x − b)/a) with b = x0 + a·acosh(y0/a), ∂y/∂a = 0.
    let c = ext[1]["conjugate_point"].as_f64().expect("the deep catenary has a conjugate point");
    let y = |x: f64, a: f64| a * ((x + h - a * (r / a).acosh()) / a).cosh();
    let dy_da = |x: f64| (y(x, deep * (1.0 + 1e-6)) - y(x, deep * (1.0 - 1e-6))) / (2e-6 * deep);
    let want = bisect(dy_da, -h + 1e-3, h);
    close(c, want, 1e-6);
}

#[test]
fn goldschmidt_rings_too_far_apart_have_no_extremal() {
    let Run { code, stdout, stderr, .. } = run(&["extremal", "examples/extremal/catenary.toml", "--set", "h=0.7"]);
    assert_eq!(code, Some(1), "{stdout}{stderr}");
    assert!(stderr.contains("no extremal"), "{stderr}");
    assert!(stderr.contains("Goldschmidt"), "{stderr}");
}

#[test]
fn oscillator_action_stops_being_a_minimum_after_half_a_period() {
    // ω = sqrt(k/m) = 2: the conjugate point of t = 0 is π/ω = π/2.
    let (m, k): (f64, f64) = (1.0, 4.0);
    let omega: f64 = (k / m).sqrt();
    for t_end in [1.0, 1.5, 2.0, 3.0] {
        let set = format!("T={t_end}");
        let v =
            extremal(&["examples/extremal/oscillator_action.toml", "--check-minimum", "--set", "k=4", "--set", &set]);
        // q = sin(ωt)/sin(ωT): S = (mω/2)·cot(ωT).
        close(v["value"].as_f64().unwrap(), 0.5 * m * omega / (omega * t_end).tan(), 1e-9);
        let before = t_end < PI / omega;
        assert_eq!(v["minimum"], before, "T = {t_end}");
        if before {
            assert!(v["conjugate_point"].is_null());
        } else {
            close(v["conjugate_point"].as_f64().unwrap(), PI / omega, 1e-8);
        }
        assert_eq!(v["second_variation"]["legendre"], true);
    }
}

#[test]
fn text_teaches_and_the_figure_is_drawn() {
    let svg = std::env::temp_dir().join(format!("lagrange-extremal-{}.svg", std::process::id()));
    let Run { code, stdout, stderr, .. } =
        run(&["extremal", "examples/extremal/catenary.toml", "--check-minimum", "--plot", svg.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stderr}");
    for needle in ["Euler equation", "Beltrami", "straight line", "Legendre", "Jacobi", "conjugate", "minimum"] {
        assert!(stdout.contains(needle), "missing {needle}:\n{stdout}");
    }
    let drawn = std::fs::read_to_string(&svg).expect("the SVG is written");
    assert!(drawn.starts_with("<svg") && drawn.contains("<polyline"), "{}", &drawn[..200.min(drawn.len())]);
    let _ = std::fs::remove_file(svg);
}

#[track_caller]
fn check_bad(name: &str, text: &str, location: &str, needle: &str) {
    let file = temp(name, text);
    let Run { code, stdout, stderr, .. } = run(&["extremal", file.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{stdout}{stderr}");
    assert!(stderr.contains(&format!("{name}:{location}")), "expected {name}:{location} in\n{stderr}");
    assert!(stderr.contains(needle), "expected '{needle}' in\n{stderr}");
}

#[test]
fn bad_problems_exit_2_with_a_location() {
    let head = "independent = \"x\"\nunknown = \"y\"\n";
    let tail = "[boundary]\nstart = [0, 0]\nend = [1, 1]\n";
    check_bad("accel.toml", &format!("{head}integrand = \"sqrt(1 + y''^2)\"\n{tail}"), "3:23", "not allowed");
    check_bad("unknown.toml", &format!("{head}integrand = \"k*y'^2\"\n{tail}"), "3:14", "'k'");
    check_bad(
        "order.toml",
        &format!("{head}integrand = \"y'^2\"\n[boundary]\nstart = [1, 0]\nend = [0.5, 1]\n"),
        "6:7",
        "must be greater",
    );
    check_bad("missing.toml", &format!("{head}{tail}"), "1:1", "integrand");
    check_bad("linear.toml", &format!("{head}integrand = \"y*y' + y^2\"\n{tail}"), "3:13", "linear");
    check_bad(
        "boundary.toml",
        &format!("{head}integrand = \"y'^2\"\n[boundary]\nstart = [0, \"w\"]\nend = [1, 1]\n"),
        "5:14",
        "'w'",
    );
}
