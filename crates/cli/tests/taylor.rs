//! The Taylor method end to end: `simulate --method taylor` against closed
//! forms of the notes (Kepler's orbit, the harmonic oscillator), its energy
//! audit on the chaotic double pendulum, and `sweep --method taylor` (batches
//! of trajectories in lock step) against single runs of the same method.

use crate::common;

use crate::common::{json, run, Run};
use serde_json::Value;
use std::f64::consts::PI;

fn summary(args: &[&str]) -> Value {
    let mut all = vec!["simulate"];
    all.extend(args);
    all.extend(["--summary", "json"]);
    if !args.contains(&"--every-step") {
        all.extend(["--samples", "2"]);
    }
    json(&all)
}

fn final_value(s: &Value, name: &str) -> f64 {
    s["final"][name].as_f64().unwrap_or_else(|| panic!("no final {name} in {s}"))
}

#[test]
fn kepler_orbit_closes_after_three_periods() {
    // Notes ch. 3: E = -0.28, a = -k/(2E), T = 2π sqrt(μ a³/k).
    let a: f64 = 1.0 / 0.56;
    let period = 2.0 * PI * a.powf(1.5);
    let until = format!("{:?}", 3.0 * period);
    let s = summary(&["examples/kepler.toml", "--method", "taylor", "--until", &until, "--rtol", "1e-12"]);
    assert_eq!(s["method"], "taylor");
    assert!((final_value(&s, "r") - 1.0).abs() < 1e-10, "{s}");
    assert!(final_value(&s, "r'").abs() < 1e-10, "{s}");
    assert!((final_value(&s, "th") - 6.0 * PI).abs() < 1e-10, "{s}");
    // Long steps: order 15 at 1e-12, a few hundred steps for three orbits.
    let steps = s["steps"].as_u64().unwrap();
    assert!(steps < 600, "{steps} steps");
}

#[test]
fn the_oscillator_follows_the_cosine_at_every_sample() {
    // examples/oscillator.toml: m = om = 1, x(0) = 1, x'(0) = 0, so x = cos t.
    let csv = std::env::temp_dir().join(format!("lagrange-taylor-osc-{}.csv", std::process::id()));
    let Run { code, stderr: err, .. } = run(&[
        "simulate",
        "examples/oscillator.toml",
        "--method",
        "taylor",
        "--until",
        "50",
        "--rtol",
        "1e-12",
        "--samples",
        "101",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    std::fs::remove_file(&csv).ok();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (t, x, v) =
        (0, header.iter().position(|h| *h == "x").unwrap(), header.iter().position(|h| *h == "x'").unwrap());
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|f| f.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 101);
    // The samples come from the steps' Taylor polynomials (dense output).
    for r in &rows {
        assert!((r[x] - r[t].cos()).abs() < 1e-10, "x({}) = {}", r[t], r[x]);
        assert!((r[v] + r[t].sin()).abs() < 1e-10, "x'({}) = {}", r[t], r[v]);
    }
}

#[test]
fn the_double_pendulum_keeps_its_energy_better_than_dop853_at_the_same_tolerance() {
    let args =
        ["examples/double_pendulum.toml", "--until", "100", "--rtol", "1e-10", "--atol", "1e-10", "--every-step"];
    let taylor = summary(&[&args[..], &["--method", "taylor"]].concat());
    let dop853 = summary(&[&args[..], &["--method", "dop853"]].concat());
    let drift = |s: &Value| s["invariants"]["H"]["max_rel_drift"].as_f64().unwrap();
    assert!(drift(&taylor) < 1e-8, "{}", drift(&taylor));
    assert!(drift(&taylor) < drift(&dop853), "taylor {} dop853 {}", drift(&taylor), drift(&dop853));
    assert!(taylor["steps"].as_u64() < dop853["steps"].as_u64());
    assert_eq!(taylor["rejected_steps"], 0);
}

#[test]
fn a_sweep_in_lock_step_gives_the_single_runs_results() {
    let dir = std::env::temp_dir().join(format!("lagrange-taylor-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("sweep.csv");
    // 3 x 4 = 12 runs: one full batch of 8 and one partial (lanes left idle).
    // One time unit is one Lyapunov segment, so the batch takes the steps a
    // single run takes.
    let Run { code, stderr: err, .. } = run(&[
        "sweep",
        "examples/double_pendulum.toml",
        "--until",
        "1",
        "--grid",
        "a=0.5:2.5:3,b=0:3:4",
        "--method",
        "taylor",
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let table = std::fs::read_to_string(&out).unwrap();
    let mut lines = table.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 12);
    for row in [&rows[0], &rows[7], &rows[8], &rows[11]] {
        let (a, b) = (row[col("a")], row[col("b")]);
        // The single run starts from the model's [initial]: rewrite it at (a, b).
        let variant = std::fs::read_to_string(common::repo_root().join("examples/double_pendulum.toml"))
            .unwrap()
            .replace("a = 2.0", &format!("a = {a}"))
            .replace("b = 2.5", &format!("b = {b}"));
        let file = dir.join(format!("dp_{a}_{b}.toml"));
        std::fs::write(&file, variant).unwrap();
        let single = summary(&[
            file.to_str().unwrap(),
            "--method",
            "taylor",
            "--until",
            "1",
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
        ]);
        for name in ["a", "b", "a'", "b'"] {
            let batch: f64 = row[col(&format!("final_{name}"))].parse().unwrap();
            let alone = final_value(&single, name);
            // The same arithmetic on every lane as in a single run: bit for bit.
            assert_eq!(batch.to_bits(), alone.to_bits(), "{name} at a={a}, b={b}: {batch} vs {alone}");
        }
        let lyapunov: f64 = row[col("lyapunov")].parse().unwrap();
        assert!(lyapunov.is_finite(), "{row:?}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn taylor_is_listed_and_refused_where_it_cannot_run() {
    let Run { code, stdout: out, .. } = run(&["simulate", "--list-methods"]);
    assert_eq!(code, Some(0));
    assert!(out.contains("taylor"), "{out}");
    let Run { code, stderr: err, .. } =
        run(&["simulate", "examples/constraints/pendulum_cartesian.toml", "--method", "taylor", "--until", "1"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("taylor"), "{err}");
}

#[test]
fn a_rigid_body_sweeps_run_by_run_and_agree_with_dop853() {
    // Models with rigid bodies are not batched (their gimbal guard is an
    // event); `--method taylor` runs them one by one, the twin kept between
    // segments. The heavy top's final Euler angles agree with DOP853's.
    let dir = std::env::temp_dir().join(format!("lagrange-taylor-top-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut finals = Vec::new();
    for method in ["taylor", "dop853"] {
        let out = dir.join(format!("{method}.csv"));
        let Run { code, stderr: err, .. } = run(&[
            "sweep",
            "examples/tops/heavy_top.toml",
            "--until",
            "3",
            "--grid",
            "be=0.3:1.2:3",
            "--method",
            method,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, Some(0), "{err}");
        let text = std::fs::read_to_string(&out).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("run"))
            .map(|l| l.split(',').filter(|f| !f.is_empty()).map(|f| f.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 3);
        finals.push(rows);
    }
    for (t, d) in finals[0].iter().zip(&finals[1]) {
        // run, be, t_final, al, be, ga, al', be', ga', energy_drift, lyapunov
        for k in 3..9 {
            assert!((t[k] - d[k]).abs() < 1e-8 * d[k].abs().max(1.0), "column {k}: {t:?} vs {d:?}");
        }
        assert!((t[10] - d[10]).abs() < 1e-4, "lyapunov {} vs {}", t[10], d[10]);
    }
    std::fs::remove_dir_all(&dir).ok();
}
