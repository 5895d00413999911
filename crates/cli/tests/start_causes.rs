//! Models that cannot start, refused with their real cause by every command
//! that evaluates them at the start (`linearize`, `modes`, `simulate`,
//! `report`; `sweep` as the row's failure): a coordinate without inertia
//! because a parameter is 0, an input not finite at t = 0, a constraint whose
//! gradient vanishes where it holds (written squared), a constraint without a
//! real value at the start, and a start off a holonomic constraint. Each was
//! reported as "the equations cannot be evaluated" or "the coordinates are
//! singular"; the models are the examples with one thing changed.

use crate::common::{repo_root, run, Run, TempFile};

/// An example's text with `from` replaced by `to` (which must occur).
fn edited(example: &str, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(repo_root().join(example)).expect("the example");
    assert!(text.contains(from), "{example} has no `{from}`");
    text.replace(from, to)
}

/// Runs `command` (with `extra` arguments) on `model` and expects exit 2 and
/// every one of `expect` in the message.
#[track_caller]
fn refused(command: &[&str], model: &str, extra: &[&str], expect: &[&str]) {
    let mut args = command.to_vec();
    args.push(model);
    args.extend(extra);
    let r = run(&args);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    for e in expect {
        assert!(r.stderr.contains(e), "expected `{e}` in:\n{}", r.describe());
    }
}

/// A sweep over g of `model` (`extra` arguments): every row fails at the
/// start with all of `expect` in its failure, so the sweep exits 1 with the
/// first run's reason, and the CSV keeps both rows.
#[track_caller]
fn rows_fail(model: &str, extra: &[&str], expect: &[&str]) {
    let out = TempFile::new("sweep", "csv");
    let mut args = vec!["sweep", model, "--until", "1", "--grid", "g=1:2:2", "--out", out.path()];
    args.extend(extra);
    let r: Run = run(&args);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(r.stderr.contains("every run failed (2); the first, run 0: "), "{}", r.describe());
    for e in expect {
        assert!(r.stderr.contains(e), "expected `{e}` in:\n{}", r.describe());
    }
    let text = std::fs::read_to_string(out.path()).unwrap();
    let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with('#') && !l.starts_with("run,")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    for row in rows {
        for e in expect {
            assert!(row.contains(e), "expected `{e}` in the row {row}");
        }
    }
    // The same rule for the shards and for their merge: every row failed, exit 1.
    let parts = [TempFile::new("sweep-shard", "csv"), TempFile::new("sweep-shard", "csv")];
    for (k, part) in parts.iter().enumerate() {
        let shard = format!("{k}/2");
        let mut args =
            vec!["sweep", model, "--until", "1", "--grid", "g=1:2:2", "--shard", &shard, "--out", part.path()];
        args.extend(extra);
        let r = run(&args);
        assert_eq!(r.code, Some(1), "{}", r.describe());
    }
    let merged = TempFile::new("sweep-merged", "csv");
    let r = run(&["sweep", "--merge", merged.path(), parts[0].path(), parts[1].path()]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(r.stderr.contains("merged 2 shards: 2 runs into"), "{}", r.describe());
    assert!(r.stderr.contains("every run failed (2); the first, run 0: "), "{}", r.describe());
    assert_eq!(
        std::fs::read_to_string(merged.path()).unwrap().lines().filter(|l| l.starts_with(char::is_numeric)).count(),
        2
    );
}

const STARTING: [&[&str]; 4] =
    [&["linearize"], &["modes"], &["simulate", "--until", "1"], &["report", "--until", "1", "-o", "/dev/null"]];

#[test]
fn a_parameter_at_zero_is_named_as_the_coordinate_s_missing_inertia() {
    let pendulum = repo_root().join("examples/pendulum.toml");
    let pendulum = pendulum.to_str().unwrap();
    for (set, name) in [("m=0", "m = 0"), ("l=0", "l = 0")] {
        for command in STARTING {
            let report = command[0] == "report";
            let out = TempFile::new("report", "html");
            let command: Vec<&str> =
                command.iter().map(|a| if report && *a == "/dev/null" { out.path() } else { a }).collect();
            refused(&command, pendulum, &["--set", set], &["the coordinate ph has no inertia", name]);
        }
        rows_fail(pendulum, &["--set", set], &["the coordinate ph has no inertia", name]);
    }
    // Both at 0: both named.
    refused(&["linearize"], pendulum, &["--set", "m=0", "--set", "l=0"], &["because m = 0 and l = 0"]);
    // A body's moment of inertia at 0 (the compound pendulum's I about its pivot).
    let compound = TempFile::with_text(
        "compound",
        "coordinates = [\"a\"]\n[parameters]\nI = 0.0\nk = 1.0\n[[bodies]]\nmass = \"1\"\ninertia = \"I\"\nangle = \"a\"\n\
         [forces]\na = \"-k*a\"\n[initial]\na = 0.5\n\"a'\" = 0\n",
    );
    refused(&["simulate", "--until", "1"], compound.path(), &[], &["the coordinate a has no inertia", "I = 0"]);
    refused(&["linearize"], compound.path(), &[], &["the coordinate a has no inertia", "I = 0"]);
}

#[test]
fn an_input_not_finite_at_t_0_is_named() {
    for (value, how) in [("1/t", "is infinite"), ("log(t)", "is infinite"), ("sqrt(t - 1)", "has no real value")] {
        let text = edited("examples/cart_pendulum.toml", "F = \"F0*sin(2*t)\"", &format!("F = \"{value}\""));
        let model = TempFile::with_text("input", &text);
        let out = TempFile::new("report", "html");
        for command in
            [&["linearize"][..], &["simulate", "--until", "1"], &["report", "--until", "1", "-o", out.path()]]
        {
            refused(command, model.path(), &[], &[&format!("the input 'F' {how} at t = 0"), ":17:5"]);
        }
        rows_fail(model.path(), &[], &[&format!("the input 'F' {how} at t = 0")]);
    }
}

/// The Cartesian pendulum with its constraint or its [initial] x replaced.
fn cartesian(from: &str, to: &str) -> TempFile {
    TempFile::with_text("cartesian", &edited("examples/constraints/pendulum_cartesian.toml", from, to))
}

const CONSTRAINED: [&[&str]; 3] = [&["linearize"], &["simulate", "--until", "1"], &["report", "--until", "1"]];

#[track_caller]
fn refused_everywhere(model: &TempFile, expect: &[&str]) {
    for command in CONSTRAINED {
        let out = TempFile::new("report", "html");
        let extra: &[&str] = if command[0] == "report" { &["-o", out.path()] } else { &[] };
        refused(command, model.path(), extra, expect);
    }
}

#[test]
fn a_constraint_with_a_vanishing_gradient_is_named() {
    let rod = "holonomic = \"x^2 + y^2 - l^2\"";
    for (written, power) in [
        ("(x^2 + y^2 - l^2)^2", true),
        ("(x^2 + y^2 - l^2)^3", true),
        ("(1 + x^2)*(x^2 + y^2 - l^2)^2", true),
        ("(x^2 + y^2 - l^2)^2 + (x - l*sin(1))^2", false),
    ] {
        let model = cartesian(rod, &format!("holonomic = \"{written}\""));
        let mut expect = vec!["the gradient ∂f/∂q of the constraint 'rod' vanishes at the start", ":18:13"];
        if power {
            expect.push("write it unsquared");
        }
        refused_everywhere(&model, &expect);
    }
}

#[test]
fn a_constraint_without_a_real_value_at_the_start_is_named() {
    let rod = "holonomic = \"x^2 + y^2 - l^2\"";
    for extra in ["sqrt(x - 5)", "log(x - 5)", "asin(x + 5)"] {
        let model = cartesian(rod, &format!("holonomic = \"x^2 + y^2 - l^2 + {extra}\""));
        refused_everywhere(&model, &["the constraint 'rod' has no real value at the start (x = 0.84", ":18:13"]);
    }
    // The value is real but the gradient is not: sqrt at 0.
    let model = cartesian(rod, "holonomic = \"x^2 + y^2 - l^2 + sqrt(x - l*sin(1))\"");
    refused_everywhere(&model, &["gradient ∂f/∂q of the constraint 'rod'", "at the start"]);
}

#[test]
fn a_start_off_the_constraint_is_refused_with_its_value_and_the_tolerance() {
    // x = 2 with y = -cos(1): x² + y² − 1 = 4 + cos²(1) − 1 = 3.2919...
    let model = cartesian("x = \"l*sin(1)\"", "x = \"2\"");
    refused_everywhere(
        &model,
        &["violate the constraint 'rod'", "at the start (x = 2, y = -0.54", "is 3.292e0", "tolerance is 5.292e-9"],
    );
    // Off by 1e-6 (beyond round-off) too; within round-off it runs.
    let model = cartesian("x = \"l*sin(1)\"", "x = \"l*sin(1) + 1e-6\"");
    refused_everywhere(&model, &["violate the constraint 'rod'", "is 1.683e-6"]);
    let model = cartesian("x = \"l*sin(1)\"", "x = \"l*sin(1) + 1e-14\"");
    assert_eq!(run(&["linearize", model.path()]).code, Some(0));
}
