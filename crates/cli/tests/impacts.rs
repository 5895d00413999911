//! `[[impacts]]` through the real binary: unilateral contacts and Newton's
//! impact law q'⁺ = q'⁻ − (1 + e) M⁻¹∇φ v_n⁻/(∇φᵀM⁻¹∇φ).
//!
//! Checked against closed forms: the bouncing ball (impact times and speeds,
//! the Zeno end at t∞ with all of m g h₀ lost), Newton's cradle (the momentum
//! passed along, kept with the energy at e = 1), a rod falling on one end
//! (the angular momentum about the struck end kept through the impact, and
//! the energy lost, (1 − e²)/2 · m v²/(1 + 3 cos²θ)), a pendulum against a
//! wall, and a floor that moves (the law on the relative velocity). Then the
//! reports and bad input (exit 2).

use crate::common::{repo_root, run as lagrange, TempFile};
use serde_json::Value;

/// A CSV whose last column is `event` (quoted text, or empty).
struct Rows {
    header: Vec<String>,
    rows: Vec<(Vec<f64>, String)>,
}

impl Rows {
    fn read(path: &str) -> Rows {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read {path}: {e}"));
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().expect("a header").split(',').map(str::to_string).collect();
        assert_eq!(header.last().map(String::as_str), Some("event"), "{header:?}");
        let rows = lines
            .map(|l| {
                let (values, event) = l.rsplit_once(',').expect("an event column");
                let values: Vec<f64> = values.split(',').map(|v| v.parse().expect("a number")).collect();
                assert_eq!(values.len() + 1, header.len(), "row `{l}`");
                (values, event.trim_matches('"').to_string())
            })
            .collect();
        Rows { header, rows }
    }

    fn col(&self, name: &str) -> usize {
        self.header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }

    /// How many impact instants began (an instant the run ended at has no row after).
    fn instants(&self) -> usize {
        self.rows.iter().filter(|(_, e)| e.ends_with(" before")).count()
    }

    /// The (before, after) rows of every impact instant, in order.
    fn impacts(&self) -> Vec<(&[f64], &[f64], &str)> {
        let mut out = Vec::new();
        for pair in self.rows.windows(2) {
            let ((a, ea), (b, eb)) = (&pair[0], &pair[1]);
            if ea.ends_with(" before") && eb.ends_with(" after") {
                out.push((a.as_slice(), b.as_slice(), eb.as_str()));
            }
        }
        out
    }
}

fn example(name: &str) -> String {
    repo_root().join("examples/impacts").join(name).to_str().unwrap().to_string()
}

/// `simulate` with `args`; the exit code, the CSV and the summary JSON.
fn simulate(model: &str, args: &[&str]) -> (Option<i32>, Rows, Value) {
    let out = TempFile::new("impacts", "csv");
    let mut all = vec!["simulate", model, "--out", out.path(), "--summary", "json"];
    all.extend_from_slice(args);
    let r = lagrange(&all);
    assert!(r.code == Some(0) || r.code == Some(1), "{}", r.describe());
    (r.code, Rows::read(out.path()), r.json())
}

const G: f64 = 9.81;

/// Ball dropped from h0 = 1 with e = 0.9: impact k (from 1) at
/// t_k = T (1 + 2e + … + 2e^{k−1}), T = √(2h0/g), meeting the floor at
/// v_k = e^{k−1} √(2 g h0) and leaving at e times that.
#[test]
fn the_bouncing_ball_meets_the_closed_form_with_every_method() {
    let (e, h0) = (0.9f64, 1.0f64);
    let fall = (2.0 * h0 / G).sqrt();
    let v0 = (2.0 * G * h0).sqrt();
    for method in ["taylor", "dop853", "gauss6", "kahanli8", "verlet"] {
        let (code, rows, _) =
            simulate(&example("bouncing_ball.toml"), &["--until", "6", "--method", method, "--rtol", "1e-12"]);
        assert_eq!(code, Some(0), "{method}");
        let impacts = rows.impacts();
        // t_k < 6 for k ≤ 11 (t_11 = 5.93).
        assert_eq!(impacts.len(), 11, "{method}");
        let (t, y, yd) = (rows.col("t"), rows.col("y"), rows.col("y'"));
        let mut t_k = fall;
        for (k, (before, after, label)) in impacts.iter().enumerate() {
            assert_eq!(*label, "impact floor after");
            let v_k = e.powi(k as i32) * v0;
            let tol = if method == "verlet" { 1e-6 } else { 1e-8 };
            assert!((before[t] - t_k).abs() < tol, "{method} impact {k}: t = {} against {t_k}", before[t]);
            assert!(before[y].abs() < 1e-9 && after[y].abs() < 1e-9, "{method}: on the floor");
            assert!((before[yd] + v_k).abs() < tol * 10.0, "{method} impact {k}: {} against {}", before[yd], -v_k);
            assert!((after[yd] + e * before[yd]).abs() < 1e-12 * v0, "{method}: y'⁺ = −e y'⁻");
            t_k += 2.0 * e * v_k / G;
        }
    }
}

#[test]
fn bounces_that_die_out_end_as_zeno_near_the_accumulation_time_with_all_energy_lost() {
    let (e, h0, m) = (0.9f64, 1.0f64, 1.0f64);
    let t_inf = (2.0 * h0 / G).sqrt() * (1.0 + e) / (1.0 - e);
    let (code, rows, summary) = simulate(&example("bouncing_ball.toml"), &["--until", "20"]);
    assert_eq!(code, Some(1), "Zeno is a failure: {summary}");
    assert_eq!(summary["failure_reason"]["code"], "zeno");
    assert_eq!(summary["failure_reason"]["impact"], "floor");
    let t_end = summary["t_final"].as_f64().unwrap();
    assert!(t_end < t_inf && t_inf - t_end < 1e-3, "ends at {t_end}, before t∞ = {t_inf}");
    let lost = summary["energy_lost_at_impacts"].as_f64().unwrap();
    assert!((lost - m * G * h0).abs() < 1e-6, "lost {lost} of m g h0 = {}", m * G * h0);
    assert_eq!(summary["impacts"][0]["name"], "floor");
    // The run ends after the last impact, its row after written.
    assert_eq!(summary["impacts"][0]["count"].as_u64().unwrap() as usize, rows.instants());
    assert_eq!(rows.impacts().len(), rows.instants());
    // The audit leaves the jumps out: H drifts at round-off, and its jumps sum to the loss.
    let h = &summary["invariants"]["H"];
    assert!(h["max_rel_drift"].as_f64().unwrap() < 1e-9, "{h}");
    assert!((h["impact_change"].as_f64().unwrap() + lost).abs() < 1e-9, "{h}");
    // The message says why, and the CSV keeps the rows.
    assert!(summary["failure"].as_str().unwrap().contains("accumulate (Zeno)"), "{summary}");
    assert!(rows.rows.len() > 100);
}

#[test]
fn a_plastic_impact_ends_the_run_at_the_floor() {
    let (code, rows, summary) = simulate(&example("bouncing_ball.toml"), &["--until", "2", "--set", "e=0"]);
    assert_eq!(code, Some(1));
    assert_eq!(summary["failure_reason"]["code"], "zeno");
    assert!(summary["failure"].as_str().unwrap().contains("plastic (e = 0)"), "{summary}");
    assert_eq!((rows.instants(), rows.impacts().len()), (1, 1));
    // It ends at rest on the floor.
    assert_eq!(summary["final"]["y'"], 0.0);
    assert!((summary["energy_lost_at_impacts"].as_f64().unwrap() - G).abs() < 1e-9);
}

#[test]
fn newtons_cradle_passes_the_momentum_along_and_keeps_the_energy() {
    let (code, rows, summary) = simulate(&example("newtons_cradle.toml"), &["--until", "2"]);
    assert_eq!(code, Some(0), "{summary}");
    let v = |row: &[f64]| [row[rows.col("x1'")], row[rows.col("x2'")], row[rows.col("x3'")]];
    let impacts = rows.impacts();
    assert_eq!(impacts.len(), 1, "one instant: ball 1 strikes 2, and 2 strikes 3");
    let (before, after, label) = impacts[0];
    assert_eq!(label, "impact ball23 after");
    assert_eq!(v(before), [1.0, 0.0, 0.0]);
    let v_after = v(after);
    for (got, want) in v_after.iter().zip([0.0, 0.0, 1.0]) {
        assert!((got - want).abs() < 1e-12, "{v_after:?}");
    }
    let momentum: f64 = v_after.iter().sum();
    let energy: f64 = v_after.iter().map(|x| x * x / 2.0).sum();
    assert!((momentum - 1.0).abs() < 1e-12 && (energy - 0.5).abs() < 1e-12);
    assert!(summary["energy_lost_at_impacts"].as_f64().unwrap().abs() < 1e-12);
    assert_eq!(summary["impacts"][0]["count"], 1);
    assert_eq!(summary["impacts"][1]["count"], 1);
    // At the end ball 3 is at 0.2 + 1.7 and the others where they stopped.
    let last = &rows.rows.last().unwrap().0;
    assert!((last[rows.col("x3")] - 1.9).abs() < 1e-9, "{last:?}");
}

/// At e = 1/2 the instant takes three impacts in turn: ball 1 on 2, 2 on 3,
/// then 1 on 2 again (ball 2 left slower than ball 1), leaving the balls
/// parting at 13/64, 15/64 and 9/16 with the momentum kept.
#[test]
fn an_inelastic_cradle_keeps_the_momentum_and_loses_energy() {
    let (code, rows, summary) = simulate(&example("newtons_cradle.toml"), &["--until", "3", "--set", "e=0.5"]);
    assert_eq!(code, Some(0), "{summary}");
    let impacts = rows.impacts();
    assert_eq!(impacts.len(), 1, "one instant");
    let (before, after, label) = impacts[0];
    assert_eq!(label, "impact ball12 after", "ball 1 strikes ball 2 last");
    let v = |r: &[f64]| [r[rows.col("x1'")], r[rows.col("x2'")], r[rows.col("x3'")]];
    assert_eq!(v(before), [1.0, 0.0, 0.0]);
    for (got, want) in v(after).iter().zip([13.0 / 64.0, 15.0 / 64.0, 9.0 / 16.0]) {
        assert!((got - want).abs() < 1e-12, "{:?}", v(after));
    }
    let p: f64 = v(after).iter().sum();
    let energy: f64 = v(after).iter().map(|x| x * x / 2.0).sum();
    assert!((p - 1.0).abs() < 1e-12);
    let lost = summary["energy_lost_at_impacts"].as_f64().unwrap();
    assert!((0.5 - energy - lost).abs() < 1e-12, "{lost} against {}", 0.5 - energy);
    assert_eq!(summary["impacts"][0]["count"], 2);
    assert_eq!(summary["impacts"][1]["count"], 1);
}

/// The rod of length l falls without turning and strikes with end A at angle
/// θ: through the impact its angular momentum about A is kept (the impulse
/// acts at A), and it loses (1 − e²)/2 · m v²/(1 + 3 cos²θ).
#[test]
fn a_falling_rod_keeps_its_angular_momentum_about_the_struck_end() {
    let (m, l, e, th0) = (1.0f64, 1.0f64, 0.5f64, 0.5f64);
    let (code, rows, _) =
        simulate(&example("falling_rod.toml"), &["--until", "0.5", "--rtol", "1e-12", "--set", "e=0.5"]);
    assert_eq!(code, Some(0));
    let (before, after, label) = rows.impacts()[0];
    assert_eq!(label, "impact end_a after");
    let c = |name: &str| rows.col(name);
    let i = m * l * l / 12.0;
    let about_a = |r: &[f64]| {
        let th = r[c("th")];
        // G − A = (l/2)(cos θ, sin θ); L_A = I θ' + m (G − A) × v_G.
        let (dx, dy) = (0.5 * l * th.cos(), 0.5 * l * th.sin());
        i * r[c("th'")] + m * (dx * r[c("y'")] - dy * r[c("x'")])
    };
    assert!((about_a(before) - about_a(after)).abs() < 1e-10, "{} against {}", about_a(before), about_a(after));
    let v = before[c("y'")].abs();
    assert!((v - (2.0 * G * (1.0 - 0.5 * l * th0.sin())).sqrt()).abs() < 1e-9);
    let energy = |r: &[f64]| r[c("H")];
    let lost = energy(before) - energy(after);
    let want = (1.0 - e * e) / 2.0 * m * v * v / (1.0 + 3.0 * th0.cos().powi(2));
    assert!((lost - want).abs() < 1e-9 * want, "{lost} against {want}");
    // The struck end leaves the floor at e times the speed it met it with.
    let end_speed = |r: &[f64]| r[c("y'")] - 0.5 * l * r[c("th")].cos() * r[c("th'")];
    // (The state after is lifted 1e-12 off the floor, which moves θ by as little.)
    assert!((end_speed(after) + e * end_speed(before)).abs() < 1e-10);
}

#[test]
fn a_pendulum_against_a_wall_bounces_back_from_the_wall_with_e_times_its_speed() {
    let (code, rows, summary) = simulate(&example("pendulum_wall.toml"), &["--until", "10", "--rtol", "1e-12"]);
    assert_eq!(code, Some(0), "{summary}");
    let (th, thd) = (rows.col("th"), rows.col("th'"));
    let impacts = rows.impacts();
    assert!(impacts.len() >= 5);
    for (before, after, _) in &impacts {
        assert!((before[th] - 0.3).abs() < 1e-9 && (after[th] - 0.3).abs() < 1e-9);
        assert!(before[thd] > 0.0 && (after[thd] + 0.8 * before[thd]).abs() < 1e-12);
    }
    // Between impacts the energy is kept; at e = 1 over the whole run.
    let (code, _, elastic) =
        simulate(&example("pendulum_wall.toml"), &["--until", "10", "--rtol", "1e-12", "--set", "e=1"]);
    assert_eq!(code, Some(0));
    assert!(elastic["energy_lost_at_impacts"].as_f64().unwrap().abs() < 1e-12);
    let h = &elastic["invariants"]["H"];
    assert!(
        ((h["final"].as_f64().unwrap() - h["initial"].as_f64().unwrap()) / h["initial"].as_f64().unwrap()).abs() < 1e-9
    );
}

/// A floor rising at speed u, y ≥ u t: the law holds for the velocity
/// relative to it, y'⁺ − u = −e (y'⁻ − u).
#[test]
fn a_moving_floor_reflects_the_relative_velocity() {
    let model = TempFile::with_text(
        "moving-floor",
        "coordinates = [\"y\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\nu = 0.5\ne = 0.7\n\
         [[particles]]\nmass = \"1\"\nposition = [\"0\", \"y\"]\n\
         [[impacts]]\nsurface = \"y - u*t\"\nrestitution = \"e\"\n[initial]\ny = 1\n\"y'\" = 0\n",
    );
    let (code, rows, _) = simulate(model.path(), &["--until", "1.5", "--rtol", "1e-12"]);
    assert_eq!(code, Some(0));
    let (t, y, yd) = (rows.col("t"), rows.col("y"), rows.col("y'"));
    let impacts = rows.impacts();
    assert!(!impacts.is_empty());
    for (before, after, label) in impacts {
        assert_eq!(label, "impact impact1 after", "the default name");
        assert!((before[y] - 0.5 * before[t]).abs() < 1e-9, "on the floor");
        assert!((after[yd] - 0.5 + 0.7 * (before[yd] - 0.5)).abs() < 1e-12);
    }
}

#[test]
fn derive_states_the_law_with_its_gradient_and_normal_velocity() {
    let r = lagrange(&["derive", &example("falling_rod.toml"), "--format", "json"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let v = r.json();
    let floor = &v["impacts"][0];
    assert_eq!(floor["name"], "end_a");
    assert_eq!(floor["surface"], "y - l*sin(th)/2");
    assert_eq!(floor["gradient"], serde_json::json!(["0", "1", "-l*cos(th)/2"]));
    assert_eq!(floor["rate"], "0");
    assert_eq!(floor["normal_velocity"], "y' - l*th'*cos(th)/2");
    assert_eq!(floor["restitution"], "e");
    assert!(floor["law"].as_str().unwrap().contains("(1 + e) M⁻¹∇φ"));
    let text = lagrange(&["derive", &example("falling_rod.toml")]);
    assert!(text.stdout.contains("end_a: y - l*sin(th)/2 ≥ 0,  restitution e"), "{}", text.stdout);
    assert!(text.stdout.contains("end_b: y + l*sin(th)/2 ≥ 0,  restitution e"), "{}", text.stdout);
    // Models without impacts have no such field.
    let plain = lagrange(&["derive", "examples/pendulum.toml", "--format", "json"]).json();
    assert!(plain.get("impacts").is_none());
}

/// Bad input exits 2 and names the place.
#[test]
fn bad_impacts_are_refused_with_their_place() {
    let ball = std::fs::read_to_string(example("bouncing_ball.toml")).unwrap();
    let cases: Vec<(String, &[&str], &str)> = vec![
        (ball.replace("restitution = \"e\"", "restitution = 1.5"), &[], "must be between 0 and 1, not 1.5"),
        (ball.clone(), &["--set", "e=2"], "the restitution of impact 'floor' must be between 0 and 1, not 2"),
        (
            ball.replace("y = \"h0\"", "y = -0.5"),
            &[],
            "the start is on the wrong side of the surface of impact 'floor'",
        ),
        (ball.replace("surface = \"y\"", "surface = \"h0 - 1\""), &[], "does not depend on the coordinates"),
        (ball.replace("surface = \"y\"", "surface = \"y'\""), &[], "'y'' is not allowed here"),
        (ball.replace("surface = \"y\"\n", ""), &[], "the impact has no `surface`"),
        (ball.replace("restitution = \"e\"\n", ""), &[], "impact 'floor' has no `restitution`"),
        (ball.replace("name = \"floor\"", "name = \"floor\"\nsurfaces = \"y\""), &[], "unknown field `surfaces`"),
        (
            format!("{ball}\n[[impacts]]\nname = \"floor\"\nsurface = \"y + 1\"\nrestitution = 1\n"),
            &[],
            "impact 'floor' is named twice",
        ),
    ];
    for (text, extra, expect) in cases {
        let model = TempFile::with_text("bad-impact", &text);
        let mut args = vec!["simulate", model.path(), "--until", "1"];
        args.extend_from_slice(extra);
        let r = lagrange(&args);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.contains(expect), "expected `{expect}`:\n{}", r.describe());
        assert!(r.stderr.contains(model.path()), "the file is named:\n{}", r.describe());
    }
    // With constraints: not supported yet, said so.
    let constrained =
        std::fs::read_to_string(repo_root().join("examples/constraints/pendulum_cartesian.toml")).unwrap();
    let model = TempFile::with_text(
        "constrained-impact",
        &format!("{constrained}\n[[impacts]]\nsurface = \"y + 2\"\nrestitution = 1\n"),
    );
    let r = lagrange(&["derive", model.path()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("impacts in a model with [[constraints]] are not supported yet"), "{}", r.describe());
    // A sweep has no impact events: refused rather than run through the floor.
    let r = lagrange(&["sweep", &example("bouncing_ball.toml"), "--grid", "h0=1:2:3", "--until", "1"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("a sweep does not run models with [[impacts]] yet"), "{}", r.describe());
}

/// `sweep --section` runs `simulate`'s own runs, impacts and all: each run's
/// points are those of `simulate --section` with its start.
#[test]
fn a_sweep_of_sections_runs_the_impacts() {
    let out = TempFile::new("impact-sweep", "csv");
    let wall = example("pendulum_wall.toml");
    let r =
        lagrange(&["sweep", &wall, "--grid", "e=0.5;1", "--until", "10", "--section", "th' = 0", "--out", out.path()]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let text = std::fs::read_to_string(out.path()).unwrap();
    let single = TempFile::new("impact-single", "csv");
    let s = lagrange(&[
        "simulate",
        &wall,
        "--set",
        "e=1",
        "--until",
        "10",
        "--section",
        "th' = 0",
        "--rtol",
        "1e-10",
        "--out",
        single.path(),
    ]);
    assert_eq!(s.code, Some(0), "{}", s.describe());
    let single = std::fs::read_to_string(single.path()).unwrap();
    let run1: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("1,1,")).collect();
    let points: Vec<&str> = single.lines().skip(1).collect();
    assert!(points.len() >= 5);
    assert_eq!(run1, points, "run 1 (e = 1) is simulate's run with e = 1");
}

/// A ball set on its floor at rest is a resting contact, which runs do not
/// model: the run ends saying so, not advising more samples (which cannot
/// help). A ball that has bounced and is then found past the floor is still
/// the missed crossing it was.
#[test]
fn a_start_resting_on_a_surface_is_named_as_resting_contact() {
    let ball = example("bouncing_ball.toml");
    let r = lagrange(&["simulate", &ball, "--until", "1", "--set", "h0=0", "--summary", "json"]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(
        r.stderr.contains("the motion starts resting on the surface of impact 'floor'")
            && r.stderr.contains("resting contact is not modelled"),
        "{}",
        r.describe()
    );
    assert!(!r.stderr.contains("more output samples"), "{}", r.describe());
    assert_eq!(r.json()["failure_reason"]["code"], "surface_crossed");
    // Newton's cradle starts with balls touching at rest and nothing pressing them: it runs.
    let (code, _, _) = simulate(&example("newtons_cradle.toml"), &["--until", "1"]);
    assert_eq!(code, Some(0));
}
