//! Hostile input that once gave wrong or unbounded results (issue #15), each a
//! regression test: files that are not regular or too large, outputs that would
//! overwrite an input, and user text that must not become live LaTeX.

mod common;

use common::{repo_root, run, scratch};

/// Runs the binary and expects bad input: exit 2 with `needle` in the message.
#[track_caller]
fn refused(args: &[&str], needle: &str) {
    let r = run(args);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains(needle), "wanted '{needle}' in:\n{}", r.describe());
}

#[test]
fn a_device_or_a_fifo_is_not_read_as_a_model() {
    refused(&["derive", "/dev/zero"], "not a regular file");
    refused(
        &["sweep", "--merge", &scratch("hostile", "merged.csv").to_string_lossy(), "/dev/zero"],
        "not a regular file",
    );
    // A FIFO without a writer would block an open for reading forever.
    let fifo = scratch("hostile", "fifo.toml");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
    assert!(made, "mkfifo {}", fifo.display());
    refused(&["derive", &fifo.to_string_lossy()], "not a regular file");
}

#[test]
fn a_body_file_that_is_a_device_is_refused() {
    let model = scratch("hostile-body", "top.toml");
    let link = model.with_file_name("zero_body.toml");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    std::fs::write(
        &model,
        "coordinates = [\"al\", \"be\", \"ga\"]\n[[bodies]]\ninertia = \"zero_body.toml\"\nangles = [\"al\", \"be\", \"ga\"]\n",
    )
    .unwrap();
    refused(&["derive", &model.to_string_lossy()], "not a regular file");
}

#[test]
fn a_model_over_the_size_limit_is_refused_without_reading_it_all() {
    let big = scratch("hostile", "big.toml");
    std::fs::write(&big, "#".repeat(3 << 20)).unwrap();
    refused(&["derive", &big.to_string_lossy()], "larger than 1048576 bytes");
}

#[test]
fn an_output_never_overwrites_the_model() {
    let model = scratch("hostile-out", "pendulum.toml");
    let text = std::fs::read_to_string(repo_root().join("examples/pendulum.toml")).unwrap();
    std::fs::write(&model, &text).unwrap();
    let m = model.to_string_lossy();
    refused(&["simulate", &m, "--until", "1", "--out", &m], "is an input of this command");
    refused(&["simulate", &m, "--until", "1", "--plot", &m], "is an input of this command");
    refused(&["orbit", &m, "--plot", &m], "is an input of this command");
    // Another spelling of the same file is the same file.
    let dotted = model.parent().unwrap().join(".").join("pendulum.toml");
    refused(&["simulate", &m, "--until", "1", "--out", &dotted.to_string_lossy()], "is an input");
    assert_eq!(std::fs::read_to_string(&model).unwrap(), text, "the model is untouched");
}

#[test]
fn a_model_name_cannot_inject_latex() {
    let model = scratch("hostile-latex", "evil.toml");
    let text = std::fs::read_to_string(repo_root().join("examples/pendulum.toml")).unwrap();
    let text = text.replace("name = \"planar pendulum\"", "name = \"a\\n\\\\input{evil}\"");
    std::fs::write(&model, text).unwrap();
    let r = run(&["derive", &model.to_string_lossy(), "--format", "latex"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    // Every line is a comment or LaTeX of our own: none starts with the user's text.
    assert!(r.stdout.lines().all(|l| !l.starts_with("\\input")), "{}", r.stdout);
    assert!(r.stdout.starts_with("% a \\input{evil} (lagrange derive --format latex)"), "{}", r.stdout);
}

#[test]
fn a_name_lagrange_makes_itself_is_refused_where_it_is_written() {
    let cases = [
        ("coordinates = [\"x\", \"p_x\"]\nkinetic = \"x'^2/2 + p_x'^2/2\"\n", "coordinate 'p_x'", "1:21"),
        ("coordinates = [\"H\"]\nkinetic = \"H'^2/2\"\n", "coordinate 'H'", "1:16"),
        ("coordinates = [\"x\", \"lambda_rod\"]\nkinetic = \"x'^2/2\"\n", "coordinate 'lambda_rod'", "1:21"),
        ("coordinates = [\"force_rod\"]\nkinetic = \"force_rod'^2/2\"\n", "coordinate 'force_rod'", "1:16"),
        ("coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\n[parameters]\np_y = 1.0\n", "parameter 'p_y'", "4:1"),
    ];
    for (k, (text, what, place)) in cases.into_iter().enumerate() {
        let model = scratch("hostile-names", &format!("names{k}.toml"));
        std::fs::write(&model, text).unwrap();
        let r = run(&["derive", &model.to_string_lossy()]);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        let first = r.stderr.lines().next().unwrap_or_default();
        assert!(first.contains(&format!(":{place}: {what} has a name that lagrange makes itself")), "{}", r.describe());
    }
}

#[test]
fn a_merged_row_with_extra_columns_is_refused() {
    let shard = scratch("hostile-merge", "shard.csv");
    std::fs::write(&shard, "# lagrange sweep runs=1\nrun,x,failure\n0,1,,extra,cols\n").unwrap();
    let out = shard.with_file_name("merged.csv");
    refused(&["sweep", "--merge", &out.to_string_lossy(), &shard.to_string_lossy()], "line 3: 3 columns expected");
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn nested_powers_cannot_bypass_the_exponent_limit() {
    let model = scratch("hostile-power", "nested.toml");
    std::fs::write(&model, "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"(((x^999)^999)^999)\"\n")
        .unwrap();
    refused(&["derive", &model.to_string_lossy()], ":3:16: in the potential: exponent 998001 is larger than 1000");
}

/// Undefined constants are errors pointing at them, not terms that a product
/// with zero or a cancellation silently removes.
#[test]
fn undefined_constants_do_not_vanish() {
    let cases = [
        ("0*log(0)", "log(0) has no finite value"),
        ("(0/0)*x^2", "division by zero"),
        ("0*(1/0)", "division by zero"),
        ("0*sqrt(-1)", "sqrt(-1) has no finite value"),
        ("x^2*(x-x)/(x-x)", "division by zero"),
    ];
    for (k, (potential, message)) in cases.into_iter().enumerate() {
        let model = scratch("hostile-undefined", &format!("u{k}.toml"));
        std::fs::write(&model, format!("coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"{potential}\"\n"))
            .unwrap();
        refused(&["derive", &model.to_string_lossy()], message);
        refused(&["simulate", &model.to_string_lossy(), "--until", "1"], message);
    }
}

/// An output another run is writing is refused, and its rows are left alone:
/// two runs can no longer interleave their rows in one CSV.
#[test]
fn an_output_in_use_by_another_run_is_refused() {
    let out = scratch("hostile-lock", "shared.csv");
    std::fs::write(&out, "t,ph,ph'\n0,1,0\n").unwrap();
    let held = std::fs::File::open(&out).unwrap();
    held.lock().unwrap();
    let o = out.to_string_lossy();
    refused(&["simulate", "examples/pendulum.toml", "--until", "1", "--out", &o], "in use by another run");
    refused(
        &["sweep", "examples/pendulum.toml", "--until", "1", "--grid", "ph=0.1:0.2:2", "--out", &o],
        "in use by another run",
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "t,ph,ph'\n0,1,0\n");
    drop(held);
    let r = run(&["simulate", "examples/pendulum.toml", "--until", "1", "--out", &o]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(std::fs::read_to_string(&out).unwrap().lines().count() > 1000);
}

/// Runs that cannot be done as asked are refused before they start, not after
/// minutes of work or gigabytes of output.
#[test]
fn impossible_runs_are_refused_up_front() {
    let pendulum = ["simulate", "examples/pendulum.toml", "--until", "10"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> { pendulum.iter().chain(extra).copied().collect() };
    refused(&with(&["--dt", "1e-300"]), "--dt 1e-300 would take 1.000e301 steps");
    refused(&with(&["--dt", "1e6"]), "--dt 1e6 is longer than the spacing of the samples, 1e-2");
    refused(&with(&["--method", "dop853", "--dt", "0.01"]), "--dt applies only to fixed-step methods, and dop853");
    refused(&with(&["--samples", "1000000000000"]), "--samples 1000000000000 is more rows than a run writes");
    refused(
        &["sweep", "examples/pendulum.toml", "--until", "1", "--grid", "ph=0:1:2", "--threads", "100000"],
        "--threads 100000 is more than 1024",
    );
}

/// Messages say what was expected in the model's terms.
#[test]
fn plain_messages_for_values_of_the_wrong_kind() {
    let text = std::fs::read_to_string(repo_root().join("examples/pendulum.toml")).unwrap();
    let model = scratch("hostile-kinds", "mass.toml");
    std::fs::write(&model, text.replace("mass = \"m\"", "mass = true")).unwrap();
    refused(
        &["derive", &model.to_string_lossy()],
        ":15:8: invalid type: boolean `true`, expected a number or an expression string",
    );
    // gravity, like mass, may be a number.
    let model = scratch("hostile-kinds", "gravity.toml");
    std::fs::write(&model, text.replace("gravity = \"g\"", "gravity = 9.81")).unwrap();
    let r = run(&["derive", &model.to_string_lossy()]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(r.stdout.contains("ph: l^2*m*ph'' + 9.81*l*m*sin(ph) = 0"), "{}", r.stdout);
    // A negative tolerance gets our message, not clap's "unexpected argument".
    refused(
        &["simulate", "examples/pendulum.toml", "--until", "1", "--rtol", "-1"],
        "--rtol must be a positive number, not -1",
    );
}
