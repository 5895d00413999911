//! `lagrange simulate` against the analytic results of the lecture notes
//! (`../shared/reference`), run through the real binary.
//!
//! Each test runs `lagrange simulate examples/X.toml ... --summary json --out
//! TMP.csv` in the repository root and compares the CSV rows and the summary
//! (`lagrange.simulate/1`) with a closed form: harmonic and damped oscillators,
//! Atwood machine, inclined plane, charged particle in a magnetic field, Kepler's
//! third law, bead on a rotating wire, beats of coupled oscillators, the
//! isochronous cycloidal pendulum, a falling stone stopped by `--stop-when`; the
//! bounded energy error of symplectic methods; every method of `--list-methods`;
//! and the failure modes (exit 2 for bad input, exit 1 for a blow-up or a
//! singular mass matrix, with the CSV kept). Broken models for `simulate` live in
//! `tests/bad_simulate/`.
//!
//! Tolerances: the runs use `--rtol 1e-10` unless said otherwise; a tolerance of
//! 1e-8 on a quantity of order one leaves a factor 100 for the accumulation of
//! local errors over the few periods integrated, and still catches any error in
//! the physics (a wrong coefficient shows at 1e-3 or worse). Each check says why
//! its own tolerance is what it is.

use crate::common::{ok, repo_root, run as lagrange, Csv, Run, TempFile};
use serde_json::Value;
use std::f64::consts::PI;

// ------------------------------------------------------------------ helpers

/// A copy of `examples/FILE` with some lines replaced, e.g. another initial
/// amplitude (initial values are not parameters, so `--set` cannot change them).
fn example_variant(file: &str, replacements: &[(&str, &str)]) -> TempFile {
    let text = std::fs::read_to_string(repo_root().join("examples").join(file))
        .unwrap_or_else(|e| panic!("cannot read examples/{file}: {e}"));
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for (old, new) in replacements {
        let i = lines
            .iter()
            .position(|l| l.trim() == *old)
            .unwrap_or_else(|| panic!("examples/{file} has no line `{old}`"));
        lines[i] = new.to_string();
    }
    let tmp = TempFile::new(file.trim_end_matches(".toml"), "toml");
    std::fs::write(&tmp.0, lines.join("\n") + "\n").expect("write the model variant");
    tmp
}

/// Runs `lagrange simulate MODEL ARGS --summary json --out TMP` and expects success.
fn simulate(model: &str, args: &[&str]) -> (Value, Csv) {
    let csv = TempFile::new("run", "csv");
    let mut all = vec!["simulate", model];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--summary", "json", "--out", csv.path()]);
    let run = ok(&all);
    let summary = run.json();
    assert_eq!(summary["format"], "lagrange.simulate/1", "{}", run.describe());
    (summary, Csv::read(csv.path()))
}

fn num(v: &Value, what: &str) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("`{what}` is not a number: {v}"))
}

/// Largest |f(row) - exact(t)| over the rows, with the time where it happens.
fn max_error(csv: &Csv, column: &str, exact: impl Fn(f64) -> f64) -> (f64, f64) {
    let t = csv.column("t");
    let v = csv.column(column);
    t.iter().zip(&v).map(|(&t, &v)| ((v - exact(t)).abs(), t)).fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
}

fn assert_close_rows(csv: &Csv, column: &str, tol: f64, exact: impl Fn(f64) -> f64) {
    let (err, at) = max_error(csv, column, exact);
    assert!(err <= tol, "{column}: error {err:.3e} at t = {at} exceeds {tol:.1e}");
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// A float as text that parses back to the same f64.
fn exact_text(x: f64) -> String {
    format!("{x:?}")
}

// ------------------------------------------------------------------ oscillators

/// Notes ch. 2, Sec. 2.5 (ii): x'' = -om^2 x, x(0) = A, x'(0) = v0 gives
/// x = A cos(om t) + (v0/om) sin(om t).
#[test]
fn harmonic_oscillator_follows_the_cosine() {
    let model = example_variant("oscillator.toml", &[("\"x'\" = 0.0", "\"x'\" = 0.6")]);
    let om = 2.0;
    let (a, v0) = (1.0, 0.6);
    let (summary, csv) = simulate(model.path(), &["--until", "20", "--rtol", "1e-10", "--set", "om=2", "--set", "m=3"]);
    assert_eq!(csv.header, ["t", "x", "x'", "H"]);
    assert_eq!(csv.rows.len(), 1001, "default: 1001 evenly spaced rows");
    // 1e-8: amplitude ~1.2, ~6 periods at rtol 1e-10 (the default method is
    // the adaptive Taylor method).
    assert_close_rows(&csv, "x", 1e-8, |t| a * (om * t).cos() + v0 / om * (om * t).sin());
    assert_close_rows(&csv, "x'", 2e-8, |t| -a * om * (om * t).sin() + v0 * (om * t).cos());
    // H = m/2 (x'^2 + om^2 x^2) = 3/2 (0.36 + 4) in every row (8 digits of rtol 1e-10).
    assert_close_rows(&csv, "H", 1e-8, |_| 1.5 * (v0 * v0 + om * om * a * a));
    assert_eq!(summary["method"], "taylor", "unconstrained and analytic: the Taylor method");
    assert!(num(&summary["t_final"], "t_final") == 20.0);
}

/// Notes ch. 2, Sec. 2.6.2 (Rayleigh dissipation): m x'' + be x' + m om^2 x = 0,
/// underdamped: x = e^{-g t} (cos(w t) + g/w sin(w t)), g = be/(2m), w = sqrt(om^2 - g^2).
#[test]
fn damped_oscillator_is_underdamped_closed_form() {
    let (summary, csv) = simulate("examples/damped_oscillator.toml", &["--until", "30", "--rtol", "1e-10"]);
    let g: f64 = 0.1 / 2.0;
    let w = (1.0 - g * g).sqrt();
    // 1e-8 absolute: x decays from 1 to ~0.2 over ~5 periods; the Taylor method at rtol 1e-10.
    assert_close_rows(&csv, "x", 1e-8, |t| (-g * t).exp() * ((w * t).cos() + g / w * (w * t).sin()));
    assert_close_rows(&csv, "x'", 1e-8, |t| -(-g * t).exp() * (1.0 + g * g / (w * w)) * w * (w * t).sin());
    assert_eq!(summary["method"], "taylor", "dissipation is analytic: the Taylor method");
    // H = T + U decays monotonically (dH/dt = -be x'^2 <= 0), and the audit says it is not conserved.
    let h = csv.column("H");
    assert!(h.windows(2).all(|w| w[1] <= w[0] + 1e-12), "H increases somewhere");
    assert_eq!(summary["invariants"]["H"]["conserved"], false);
    assert_eq!(summary["warnings"].as_array().map(Vec::len), Some(0), "no drift warning for a non-conserved H");
}

/// Atwood machine (examples/atwood.toml): x'' = (m1 - m2) g/(m1 + m2), constant.
#[test]
fn atwood_machine_accelerates_uniformly() {
    let (m1, m2, g) = (2.0, 1.0, 9.81);
    let acc = (m1 - m2) * g / (m1 + m2);
    let (summary, csv) = simulate("examples/atwood.toml", &["--until", "1", "--rtol", "1e-10"]);
    // x = x0 + a t^2/2 is a polynomial the 8th-order method integrates to round-off:
    // 1e-12 relative leaves room for the sum of 100 steps.
    let x = csv.column("x");
    let xd = csv.column("x'");
    for (i, &t) in csv.column("t").iter().enumerate() {
        assert!(rel(x[i], 2.0 + acc * t * t / 2.0) < 1e-12, "x({t}) = {}, expected {}", x[i], 2.0 + acc * t * t / 2.0);
        assert!((xd[i] - acc * t).abs() < 1e-11, "x'({t}) = {}, expected {}", xd[i], acc * t);
    }
    let xf = num(&summary["final"]["x"], "final.x");
    assert!(rel(xf, 2.0 + acc / 2.0) < 1e-12, "final x = {xf}");
    // Reversing the masses reverses the acceleration.
    let (summary, _) = simulate("examples/atwood.toml", &["--until", "1", "--set", "m1=1", "--set", "m2=2"]);
    let xf = num(&summary["final"]["x"], "final.x");
    assert!(rel(xf, 2.0 - acc / 2.0) < 1e-12, "final x with m1 < m2 = {xf}");
}

/// Notes ch. 2, Sec. 2.2.1 b) example (i): x'' = g sin(al) cos(al).
#[test]
fn inclined_plane_acceleration_is_g_sin_cos() {
    let (g, al): (f64, f64) = (9.81, 0.5);
    let acc = g * al.sin() * al.cos();
    let (_, csv) = simulate("examples/inclined_plane.toml", &["--until", "2", "--rtol", "1e-10"]);
    // Uniform acceleration: exact to round-off (see the Atwood machine); 1e-11 absolute on x <= 8.3.
    assert_close_rows(&csv, "x", 1e-11, |t| acc * t * t / 2.0);
    assert_close_rows(&csv, "x'", 1e-11, |t| acc * t);
    // Another angle, through --set.
    let al2: f64 = 1.1;
    let (_, csv) = simulate("examples/inclined_plane.toml", &["--until", "1", "--set", "al=1.1"]);
    assert_close_rows(&csv, "x", 1e-11, |t| g * al2.sin() * al2.cos() * t * t / 2.0);
}

// ------------------------------------------------------------------ charged particle

/// Notes ch. 2, Sec. 2.6.1 b) with E0 = 0: a helix around z with radius
/// m v_perp/(Q B) and period 2 pi m/(Q B), drifting with v_z.
#[test]
fn charged_particle_gyrates_with_the_cyclotron_period() {
    let (m, q, b) = (3.0, 1.0, 2.0);
    let (vperp, vz) = (1.0, 0.1);
    let radius = m * vperp / (q * b);
    let period = 2.0 * PI * m / (q * b);
    let until = exact_text(2.0 * period);
    let (summary, csv) = simulate(
        "examples/charged_particle.toml",
        &["--set", "E0=0", "--set", "m=3", "--set", "B0=2", "--until", &until, "--rtol", "1e-10", "--samples", "801"],
    );
    // Start at the origin moving along +y; the force Q v x B points along +x,
    // so the centre of the circle is (radius, 0).
    let (x, y, z, t) = (csv.column("x"), csv.column("y"), csv.column("z"), csv.column("t"));
    for i in 0..t.len() {
        let r = ((x[i] - radius).powi(2) + y[i].powi(2)).sqrt();
        // 1e-8 relative on the radius: two turns at rtol 1e-10.
        assert!(rel(r, radius) < 1e-8, "distance from the centre {r} at t = {}, expected {radius}", t[i]);
        assert!((z[i] - vz * t[i]).abs() < 1e-10, "z = {} at t = {}", z[i], t[i]);
        // Phase: x = R (1 - cos(w t)), y = R sin(w t), w = 2 pi / period; the
        // period itself is checked here to 1e-8 (radius-sized position error).
        let w = 2.0 * PI / period;
        assert!((x[i] - radius * (1.0 - (w * t[i]).cos())).abs() < 1e-8, "x = {} at t = {}", x[i], t[i]);
        assert!((y[i] - radius * (w * t[i]).sin()).abs() < 1e-8, "y = {} at t = {}", y[i], t[i]);
    }
    // After two periods the particle is back above the origin.
    let fin = &summary["final"];
    assert!(num(&fin["x"], "x").abs() < 1e-8 && num(&fin["y"], "y").abs() < 1e-8, "final {fin}");
    assert!((num(&fin["y'"], "y'") - vperp).abs() < 1e-8, "final {fin}");
    // H = m v^2/2 (the magnetic field does no work) and p_z = m v_z are audited as conserved.
    for name in ["H", "p_z"] {
        let inv = &summary["invariants"][name];
        assert_eq!(inv["conserved"], true, "{name}: {inv}");
        assert!(num(&inv["max_rel_drift"], name) < 1e-9, "{name}: {inv}");
    }
}

// ------------------------------------------------------------------ Kepler

/// Notes ch. 3, Sec. 3.1.3: the bounded orbit of L = mu/2 (r'^2 + r^2 th'^2) + k/r
/// has period T = 2 pi sqrt(mu a^3/k) with a = -k/(2E) (Kepler's third law).
fn kepler_period() -> f64 {
    let (mu, k) = (1.0f64, 1.0f64);
    let (r0, thd0) = (1.0f64, 1.2f64);
    let energy = mu * (r0 * thd0).powi(2) / 2.0 - k / r0; // r'(0) = 0: E = -0.28
    let a = -k / (2.0 * energy);
    2.0 * PI * (mu * a.powi(3) / k).sqrt()
}

#[test]
fn kepler_orbit_closes_after_the_third_law_period() {
    let period = kepler_period();
    let until = exact_text(3.0 * period);
    let (summary, csv) = simulate("examples/kepler.toml", &["--until", &until, "--rtol", "1e-10", "--samples", "301"]);
    let fin = &summary["final"];
    // After three periods r and r' are back and th advanced by 6 pi; 1e-8 on
    // quantities of order one (three orbits at rtol 1e-10).
    assert!((num(&fin["r"], "r") - 1.0).abs() < 1e-8, "final {fin}");
    assert!(num(&fin["r'"], "r'").abs() < 1e-8, "final {fin}");
    assert!((num(&fin["th"], "th") - 6.0 * PI).abs() < 1e-8, "final {fin}");
    // Rows 100 and 200 are one and two periods.
    let (t, r, th) = (csv.column("t"), csv.column("r"), csv.column("th"));
    for (row, turns) in [(100, 1.0), (200, 2.0)] {
        assert!(rel(t[row], turns * period) < 1e-14, "row {row} is at t = {}", t[row]);
        assert!((r[row] - 1.0).abs() < 1e-8, "r = {} after {turns} periods", r[row]);
        assert!((th[row] - 2.0 * PI * turns).abs() < 1e-8, "th = {} after {turns} periods", th[row]);
    }
    // In between, r stays within the apsides a (1 -+ e), e = 0.44.
    let a = 1.0 / 0.56;
    let e = 1.0 - 1.0 / a; // r(0) = 1 is the periapsis
    let (rmin, rmax) = r.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(rmin >= a * (1.0 - e) - 1e-9 && rmax <= a * (1.0 + e) + 1e-9, "r in [{rmin}, {rmax}]");
}

/// The same period measured by `--stop-when`: th crosses 2 pi after T.
#[test]
fn kepler_period_by_stop_condition() {
    let period = kepler_period();
    let (summary, _) =
        simulate("examples/kepler.toml", &["--until", "20", "--rtol", "1e-10", "--stop-when", "th > 2*pi"]);
    assert_eq!(summary["stopped_by"], "th > 2*pi");
    let t = num(&summary["t_final"], "t_final");
    // 1e-9 relative: the event is located on the integrator's interpolant to
    // far better than rtol; one orbit.
    assert!(rel(t, period) < 1e-9, "t_final = {t}, third law: {period}");
    assert!((num(&summary["final"]["r"], "r") - 1.0).abs() < 1e-8, "{}", summary["final"]);
}

/// The conservation audit: H and the cyclic coordinate's momentum p_th.
#[test]
fn kepler_conservation_audit() {
    let (summary, csv) = simulate("examples/kepler.toml", &["--until", "100"]);
    assert_eq!(csv.header, ["t", "r", "th", "r'", "th'", "H", "p_th"]);
    let inv = &summary["invariants"];
    for (name, initial) in [("H", -0.28), ("p_th", 1.2)] {
        let a = &inv[name];
        assert_eq!(a["conserved"], true, "{name}: {a}");
        assert!((num(&a["initial"], "initial") - initial).abs() < 1e-15, "{name}: {a}");
        // Default rtol 1e-9: the Taylor method keeps both to ~1e-10 over ~6
        // periods (Gauss–Legendre would keep p_th, linear in p, to round-off).
        let limit = 1e-8;
        assert!(num(&a["max_rel_drift"], "max_rel_drift") < limit, "{name}: {a}");
        assert!(num(&a["max_abs_drift"], "max_abs_drift") < limit, "{name}: {a}");
    }
    for key in ["method", "steps", "rhs_evaluations", "t_final", "final", "wall_seconds"] {
        assert!(!summary[key].is_null(), "the summary has no `{key}`");
    }
    // Setup: reading + parsing + deriving, then up to the first row (compiling
    // and gauss6's pilot runs), which the integration's own time includes too.
    let derive = num(&summary["derive_seconds"], "derive_seconds");
    let setup = num(&summary["setup_seconds"], "setup_seconds");
    let wall = num(&summary["wall_seconds"], "wall_seconds");
    assert!(derive > 0.0 && setup >= derive && setup < derive + wall, "{derive} {setup} {wall}");
    // The audit agrees with the CSV columns.
    let h = csv.column("H");
    let drift = h.iter().map(|v| (v - h[0]).abs()).fold(0.0, f64::max);
    assert!((drift - num(&inv["H"]["max_abs_drift"], "H drift")).abs() <= 1e-15, "CSV drift {drift}");
}

// ------------------------------------------------------------------ rotating wire

/// Notes ch. 2, Sec. 2.2.1 a) (v) / 2.4.2 d) (iv): r'' = om^2 r, so
/// r = r0 cosh(om t) + (r0'/om) sinh(om t); H = m/2 (r'^2 - om^2 r^2) is
/// conserved, E = m/2 (r'^2 + om^2 r^2) is not, and both are columns.
#[test]
fn bead_on_rotating_wire_follows_cosh() {
    let model = example_variant("rotating_wire.toml", &[("\"r'\" = 0.0", "\"r'\" = 0.5")]);
    let om = 2.0;
    let (r0, v0) = (1.0, 0.5);
    let (summary, csv) = simulate(model.path(), &["--until", "3", "--rtol", "1e-10", "--set", "om=2"]);
    assert_eq!(csv.header, ["t", "r", "r'", "H", "E"]);
    let exact = |t: f64| r0 * (om * t).cosh() + v0 / om * (om * t).sinh();
    let exact_d = |t: f64| r0 * om * (om * t).sinh() + v0 * (om * t).cosh();
    let (t, r, rd, e) = (csv.column("t"), csv.column("r"), csv.column("r'"), csv.column("E"));
    for i in 0..t.len() {
        // Relative 1e-8: r grows to ~250, errors grow with it (exponential instability).
        assert!(rel(r[i], exact(t[i])) < 1e-8, "r({}) = {}, expected {}", t[i], r[i], exact(t[i]));
        assert!(rel(rd[i], exact_d(t[i])) < 1e-8, "r'({}) = {}, expected {}", t[i], rd[i], exact_d(t[i]));
        let e_exact = (exact_d(t[i]).powi(2) + (om * exact(t[i])).powi(2)) / 2.0;
        assert!(rel(e[i], e_exact) < 2e-8, "E({}) = {}, expected {e_exact}", t[i], e[i]);
    }
    let h = &summary["invariants"]["H"];
    assert_eq!(h["conserved"], true);
    assert!((num(&h["initial"], "H") - (v0 * v0 - om * om * r0 * r0) / 2.0).abs() < 1e-15, "{h}");
    assert_eq!(summary["invariants"]["E"]["conserved"], false, "E is not conserved");
}

// ------------------------------------------------------------------ coupled oscillators

/// Notes ch. 3, Sec. 3.3.1 (vi): q1 = A/2 (cos W1 t + cos W2 t),
/// q2 = A/2 (cos W1 t - cos W2 t), W1 = 1, W2 = 1.5: the energy goes over to the
/// second mass and back with period 2 pi/(W2 - W1) = 4 pi.
#[test]
fn coupled_oscillators_beat() {
    let (w1, w2) = (1.0, 1.5);
    let exchange = 2.0 * PI / (w2 - w1);
    let until = exact_text(2.0 * exchange);
    let (_, csv) =
        simulate("examples/coupled_oscillators.toml", &["--until", &until, "--rtol", "1e-10", "--samples", "801"]);
    // 1e-8 absolute on amplitudes of order 1 over ~6 slow periods.
    assert_close_rows(&csv, "q1", 1e-8, |t| ((w1 * t).cos() + (w2 * t).cos()) / 2.0);
    assert_close_rows(&csv, "q2", 1e-8, |t| ((w1 * t).cos() - (w2 * t).cos()) / 2.0);
    // Energy of each mass alone (its kinetic energy and its own spring k = 1):
    // all on mass 1 at t = 0, all on mass 2 at half the exchange period
    // (row 200), back on mass 1 after one exchange period (row 400).
    let (t, q1, q2, v1, v2) =
        (csv.column("t"), csv.column("q1"), csv.column("q2"), csv.column("q1'"), csv.column("q2'"));
    let e1 = |i: usize| (v1[i] * v1[i] + q1[i] * q1[i]) / 2.0;
    let e2 = |i: usize| (v2[i] * v2[i] + q2[i] * q2[i]) / 2.0;
    assert!((t[200] - exchange / 2.0).abs() < 1e-12 && (t[400] - exchange).abs() < 1e-12);
    assert!(e1(200) < 1e-15 && (e2(200) - 0.5).abs() < 1e-8, "t = {}: e1 = {}, e2 = {}", t[200], e1(200), e2(200));
    assert!((e1(400) - 0.5).abs() < 1e-8 && e2(400) < 1e-15, "t = {}: e1 = {}, e2 = {}", t[400], e1(400), e2(400));
}

// ------------------------------------------------------------------ cycloidal pendulum

/// Notes ch. 2, Sec. 2.2.1 b): u = -cos(al/2) oscillates harmonically with
/// omega = sqrt(g/(4R)) whatever the amplitude. Released at rest, al' first
/// turns negative after half a period.
#[test]
fn cycloidal_pendulum_is_isochronous() {
    let half_period = PI * (4.0 * 1.0 / 9.81f64).sqrt();
    let mut halves = Vec::new();
    for (amplitude, method) in
        [("0.5", None), ("2.0", None), ("2.8", None), ("0.5", Some("dop853")), ("2.8", Some("dop853"))]
    {
        let line = format!("al = {amplitude}");
        let model = example_variant("cycloidal_pendulum.toml", &[("al = 2.0", &line)]);
        let mut args = vec!["--until", "10", "--rtol", "1e-10", "--stop-when", "al' < 0"];
        if let Some(m) = method {
            args.extend_from_slice(&["--method", m]);
        }
        let (summary, _) = simulate(model.path(), &args);
        assert_eq!(summary["stopped_by"], "al' < 0", "al0 = {amplitude}");
        let t = num(&summary["t_final"], "t_final");
        // 1e-9 relative against pi sqrt(4R/g): one half-period at rtol 1e-10,
        // the crossing located by root finding on the interpolant.
        assert!(rel(t, half_period) < 1e-9, "al0 = {amplitude} ({method:?}): half period {t}, expected {half_period}");
        // The turning point mirrors the start about the bottom al = pi.
        let al = num(&summary["final"]["al"], "al");
        let al0: f64 = amplitude.parse().unwrap();
        assert!((al - (2.0 * PI - al0)).abs() < 1e-7, "al0 = {amplitude}: turning point {al}");
        halves.push(t);
    }
    // Independent of the amplitude (the brief's 1e-6; it holds far tighter).
    for t in &halves {
        assert!(rel(*t, halves[0]) < 1e-9, "half periods differ: {halves:?}");
    }
}

// ------------------------------------------------------------------ stop condition

/// A stone released at height h falls for sqrt(2h/g): `--stop-when "y < 0"`.
#[test]
fn falling_stone_stops_at_the_ground() {
    let (h, g, v0) = (10.0f64, 9.81f64, 1.0f64);
    for extra in [&[][..], &["--method", "dop853"][..], &["--set", "h=2.5", "--set", "g=1.62"][..]] {
        let mut args = vec!["--until", "10", "--rtol", "1e-10", "--stop-when", "y < 0"];
        args.extend_from_slice(extra);
        let (summary, csv) = simulate("examples/free_fall.toml", &args);
        let (h, g) = if extra.contains(&"h=2.5") { (2.5, 1.62) } else { (h, g) };
        let expected = (2.0 * h / g).sqrt();
        let t = num(&summary["t_final"], "t_final");
        // 1e-8 relative (the brief); the crossing of a parabola is located to round-off.
        assert!(rel(t, expected) < 1e-8, "{extra:?}: stopped at {t}, expected {expected}");
        assert_eq!(summary["stopped_by"], "y < 0", "{extra:?}");
        assert!(num(&summary["final"]["y"], "y").abs() < 1e-8, "{extra:?}: {}", summary["final"]);
        assert!(rel(num(&summary["final"]["x"], "x"), v0 * expected) < 1e-8, "{extra:?}: {}", summary["final"]);
        // The CSV ends at the event row.
        let last = csv.rows.last().expect("rows");
        assert!(rel(last[csv.col("t")], t) < 1e-15, "{extra:?}: last CSV row at {}", last[0]);
        assert!(
            csv.column("y").iter().rev().skip(1).all(|&y| y > 0.0),
            "{extra:?}: rows below ground before the event"
        );
    }
}

// ------------------------------------------------------------------ symplectic methods

/// Störmer–Verlet keeps the pendulum's energy error bounded: 10^6 steps, and the
/// largest |H - H0| in the last tenth of the run is no larger than in the first
/// tenth (a non-symplectic method's error grows linearly instead).
#[test]
fn verlet_energy_error_is_bounded_over_a_million_steps() {
    let (summary, csv) = simulate(
        "examples/pendulum.toml",
        &["--method", "verlet", "--dt", "0.01", "--until", "10000", "--samples", "100001"],
    );
    assert_eq!(summary["method"], "verlet");
    assert_eq!(num(&summary["steps"], "steps"), 1e6, "10^6 steps of 0.01");
    let h = csv.column("H");
    assert_eq!(h.len(), 100_001);
    let tenth = h.len() / 10;
    let max_dev = |rows: &[f64]| rows.iter().map(|v| (v - h[0]).abs()).fold(0.0, f64::max);
    let first = max_dev(&h[..tenth]);
    let last = max_dev(&h[h.len() - tenth..]);
    // Bounded oscillation: ratio ~1 (the brief allows 2); with dt = 0.01 and
    // order 2 the error is ~dt^2 g/l ~ 1e-3 relative, never growing.
    assert!(last / first < 2.0, "|H - H0| grows: first tenth {first:.3e}, last tenth {last:.3e}");
    assert!(first / h[0].abs() < 1e-3, "energy error {first:.3e} is not O(dt^2)");

    // The control: a non-symplectic method's energy error grows linearly, so the
    // same measure gives ~10 (first tenth vs last tenth) -- the check above
    // does tell the two kinds apart.
    let (_, csv) = simulate(
        "examples/pendulum.toml",
        &["--method", "dopri5", "--rtol", "1e-6", "--until", "10000", "--samples", "100001"],
    );
    let h = csv.column("H");
    let max_dev = |rows: &[f64]| rows.iter().map(|v| (v - h[0]).abs()).fold(0.0, f64::max);
    let (first, last) = (max_dev(&h[..tenth]), max_dev(&h[h.len() - tenth..]));
    assert!(last / first > 5.0, "dopri5: first tenth {first:.3e}, last tenth {last:.3e}: no secular growth?");
}

/// Every method of `--list-methods` runs the oscillator and the pendulum and meets its tolerance.
#[test]
fn every_method_integrates_oscillator_and_pendulum() {
    let list = lagrange(&["simulate", "--list-methods"]);
    assert_eq!(list.code, Some(0), "{}", list.describe());
    let methods: Vec<&str> = list.stdout.lines().filter_map(|l| l.split_whitespace().next()).collect();
    for expected in
        ["dopri5", "dop853", "verlet", "yoshida4", "kahanli6", "kahanli8", "gauss2", "gauss4", "gauss6", "radau5"]
    {
        assert!(methods.contains(&expected), "--list-methods lacks {expected}: {methods:?}");
    }
    // The pendulum has no elementary closed form: its reference is dop853 at rtol 1e-13.
    let (reference, _) =
        simulate("examples/pendulum.toml", &["--method", "dop853", "--until", "10", "--rtol", "1e-13"]);
    let pendulum_final = num(&reference["final"]["ph"], "ph");
    let cases = [
        ("examples/oscillator.toml", "x", (20.0f64).cos(), &["--set", "om=2"][..]),
        ("examples/pendulum.toml", "ph", pendulum_final, &[][..]),
    ];
    let mut failures = Vec::new();
    for method in &methods {
        // Both models are separable, so verlet, yoshida4 and kahanli6/8 apply.
        for (model, coordinate, exact_final, extra) in cases {
            let mut args = vec!["--method", method, "--until", "10", "--rtol", "1e-8"];
            args.extend_from_slice(extra);
            let (summary, _) = simulate(model, &args);
            assert_eq!(summary["method"], *method);
            let x = num(&summary["final"][coordinate], coordinate);
            let drift = num(&summary["invariants"]["H"]["max_rel_drift"], "drift");
            // rtol 1e-8: H and the final coordinate (order 1, after ~2-3
            // periods) to 100 rtol. Fixed-step methods pick the step from the
            // energy error (10 rtol) and the phase error of a symplectic method
            // grows linearly (gauss2: 4.5e-7 on the pendulum); the adaptive ones
            // control the local error only (radau5 drifts ~13 rtol).
            if (x - exact_final).abs() > 1e-6 || drift > 1e-6 {
                failures.push(format!(
                    "{method} on {model}: final {coordinate} error {:.3e}, H drift {drift:.3e}",
                    (x - exact_final).abs()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "methods out of tolerance:\n  {}", failures.join("\n  "));
}

/// A separable-only method on a non-separable model is bad input (exit 2).
#[test]
fn separable_method_on_non_separable_model_exits_2() {
    let run = lagrange(&["simulate", "examples/cycloidal_pendulum.toml", "--until", "1", "--method", "verlet"]);
    assert_eq!(run.code, Some(2), "{}", run.describe());
    assert!(run.stderr.contains("separable"), "{}", run.describe());
}

// ------------------------------------------------------------------ bad input: exit 2

#[test]
fn until_must_be_positive() {
    for until in ["0", "-1"] {
        let run = lagrange(&["simulate", "examples/oscillator.toml", "--until", until]);
        assert_eq!(run.code, Some(2), "{}", run.describe());
        assert!(run.stderr.contains("--until"), "{}", run.describe());
    }
}

#[test]
fn unknown_method_lists_the_methods() {
    let run = lagrange(&["simulate", "examples/oscillator.toml", "--until", "1", "--method", "nosuch"]);
    assert_eq!(run.code, Some(2), "{}", run.describe());
    assert!(run.stderr.contains("nosuch"), "{}", run.describe());
    for m in ["dopri5", "dop853", "verlet", "kahanli8", "gauss6", "radau5"] {
        assert!(run.stderr.contains(m), "the message does not list {m}\n{}", run.describe());
    }
}

#[test]
fn missing_initial_value_exits_2() {
    let run = lagrange(&["simulate", "crates/cli/tests/bad_simulate/missing_initial_velocity.toml", "--until", "1"]);
    assert_eq!(run.code, Some(2), "{}", run.describe());
    assert!(run.stderr.contains("missing_initial_velocity.toml"), "names the file\n{}", run.describe());
    assert!(run.stderr.contains("x'"), "names the missing value\n{}", run.describe());
}

// ------------------------------------------------------------------ failed runs: exit 1

/// The first number after `t = ` in a message.
fn time_in(message: &str) -> Option<f64> {
    let rest = &message[message.find("t = ")? + 4..];
    let end = rest.find(|c: char| !(c.is_ascii_digit() || ".eE-+".contains(c))).unwrap_or(rest.len());
    rest[..end].trim_end_matches('.').parse().ok()
}

/// Runs a model expected to fail mid-run: exit 1, the CSV kept with a header and
/// finite rows before `t_limit`. Returns the run and the CSV.
fn failing_run(model: &str, extra: &[&str]) -> (Run, Csv) {
    let csv = TempFile::new("failing", "csv");
    let mut args = vec!["simulate", model, "--until", "5", "--out", csv.path()];
    args.extend_from_slice(extra);
    let run = lagrange(&args);
    assert_eq!(run.code, Some(1), "expected exit 1 (a failed run)\n{}", run.describe());
    assert!(csv.0.exists(), "the CSV is gone\n{}", run.describe());
    let table = Csv::read(csv.path());
    (run, table)
}

/// x'' = x^3 from x = 1, x' = 1 blows up at t* = 1.3110287771 (the integral in
/// `bad_simulate/blow_up.toml`): exit 1, rows kept, the message names the time and
/// the coordinate.
fn blow_up_is_reported(extra: &[&str]) {
    let t_star = 1.311_028_777_146;
    let (run, csv) = failing_run("crates/cli/tests/bad_simulate/blow_up.toml", extra);
    assert_eq!(csv.header, ["t", "x", "x'", "H"], "{extra:?}");
    assert!(csv.rows.len() > 100, "{extra:?}: only {} rows kept", csv.rows.len());
    let last = csv.rows.last().unwrap();
    assert!(last.iter().all(|v| v.is_finite()), "{extra:?}: last row not finite: {last:?}");
    assert!(last[0] < t_star && last[0] > 1.2, "{extra:?}: last row at t = {}", last[0]);
    // The rows before the blow-up are sane: x increases, H = 1/4 early on.
    assert!(csv.column("x").windows(2).all(|w| w[1] > w[0]), "{extra:?}: x not increasing");
    assert!((csv.rows[1][csv.col("H")] - 0.25).abs() < 1e-8, "{extra:?}");
    // stderr names the time (within 2% of t*) and the coordinate.
    let t = time_in(&run.stderr).unwrap_or_else(|| panic!("no `t = ` in the message\n{}", run.describe()));
    assert!(rel(t, t_star) < 0.02, "{extra:?}: the message says t = {t}, the blow-up is at {t_star}\n{}", run.stderr);
    assert!(
        ["'x'", "'x''", "'p_x'"].iter().any(|name| run.stderr.contains(name)),
        "{extra:?}: the message does not name the coordinate that blows up\n{}",
        run.describe()
    );
    assert!(
        run.stderr.contains("keeps the rows"),
        "{extra:?}: the message does not mention the kept CSV\n{}",
        run.stderr
    );
}

#[test]
fn blow_up_exits_1_default_method() {
    blow_up_is_reported(&[]);
}

#[test]
fn blow_up_exits_1_dop853() {
    blow_up_is_reported(&["--method", "dop853"]);
}

/// M = x^2 reaches 0 at t = 1/2: exit 1 with a message about the singular mass
/// matrix near t = 0.5, rows kept.
fn singular_mass_matrix_is_reported(model: &str, extra: &[&str]) {
    let (run, csv) = failing_run(model, extra);
    let last = csv.rows.last().expect("rows before the singularity");
    assert!(last.iter().all(|v| v.is_finite()) && last[0] <= 0.5 + 1e-9, "last row {last:?}");
    assert!(last[0] > 0.45, "rows stop early, at t = {}", last[0]);
    let stderr = run.stderr.to_lowercase();
    assert!(
        stderr.contains("singular") && stderr.contains("mass matrix"),
        "{extra:?}: the message does not say that the mass matrix became singular\n{}",
        run.describe()
    );
    let t = time_in(&run.stderr).unwrap_or_else(|| panic!("no `t = ` in the message\n{}", run.describe()));
    assert!((t - 0.5).abs() < 0.01, "{extra:?}: the message says t = {t}, M = x^2 vanishes at t = 0.5");
}

#[test]
fn singular_mass_matrix_midrun_1d_default_method() {
    singular_mass_matrix_is_reported("crates/cli/tests/bad_simulate/singular_midrun.toml", &[]);
}

#[test]
fn singular_mass_matrix_midrun_1d_dop853() {
    singular_mass_matrix_is_reported("crates/cli/tests/bad_simulate/singular_midrun.toml", &["--method", "dop853"]);
}

#[test]
fn singular_mass_matrix_midrun_2d_default_method() {
    singular_mass_matrix_is_reported("crates/cli/tests/bad_simulate/singular_midrun_2d.toml", &[]);
}

#[test]
fn singular_mass_matrix_midrun_2d_dop853() {
    singular_mass_matrix_is_reported("crates/cli/tests/bad_simulate/singular_midrun_2d.toml", &["--method", "dop853"]);
}

/// Gauss–Legendre, chosen by name, keeps Kepler's p_th (linear in p, so a
/// quadratic invariant of the method) to round-off, and H to its tolerance.
#[test]
fn kepler_under_gauss_legendre_keeps_p_th_to_round_off() {
    let (summary, _) = simulate("examples/kepler.toml", &["--until", "100", "--method", "gauss6"]);
    assert_eq!(summary["method"], "gauss6");
    assert_eq!(summary["form"], "hamilton");
    assert!(num(&summary["invariants"]["p_th"]["max_rel_drift"], "p_th drift") < 1e-13, "{summary}");
    assert!(num(&summary["invariants"]["H"]["max_rel_drift"], "H drift") < 1e-8, "{summary}");
}
