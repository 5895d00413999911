//! Hostile input that once gave wrong or unbounded results (issue #15), each a
//! regression test: files that are not regular or too large, outputs that would
//! overwrite an input, and user text that must not become live LaTeX.

use crate::common::{close, json, repo_root, run, scratch};

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
    // Another test's child, forked but not yet exec'd, may hold a copy of the
    // descriptor (and so the lock) for a moment after the drop.
    let mut r = run(&["simulate", "examples/pendulum.toml", "--until", "1", "--out", &o]);
    for _ in 0..50 {
        if r.code == Some(0) || !r.stderr.contains("in use by another run") {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
        r = run(&["simulate", "examples/pendulum.toml", "--until", "1", "--out", &o]);
    }
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

/// Every error is said once: the `file:line:col: message` line, then a drawing
/// of the place without a second copy of the message.
#[test]
fn an_error_is_printed_once() {
    let r = run(&["derive", "crates/cli/tests/bad/unknown_name.toml"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert_eq!(r.stderr.matches("unknown name 'y'").count(), 2, "the line and the label under the name:\n{}", r.stderr);
    assert!(!r.stderr.contains("Error:"), "{}", r.stderr);
}

/// Common slips get a hint that shows the fix.
#[test]
fn slips_get_hints_that_show_the_fix() {
    let model = scratch("hostile-hints", "implicit_product.toml");
    std::fs::write(&model, "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - 2x^2\"\n").unwrap();
    refused(&["derive", &model.to_string_lossy()], "a product needs its '*': write 2*x");
    let model = scratch("hostile-hints", "bare_primed_key.toml");
    std::fs::write(&model, "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^2\"\n[initial]\nx = 1\nx' = 0\n").unwrap();
    refused(&["simulate", &model.to_string_lossy(), "--until", "1"], "a key with a prime must be quoted: \"x'\" = ...");
}

/// A spherical pendulum started at the pole: M is singular there, and the
/// message names the coordinate without inertia instead of a bare pivot.
#[test]
fn a_singular_start_names_the_coordinate() {
    let model = scratch("hostile-singular", "spherical.toml");
    std::fs::write(
        &model,
        "coordinates = [\"th\", \"ph\"]\nlagrangian = \"(th'^2 + sin(th)^2*ph'^2)/2 + cos(th)\"\n\
         [initial]\nth = 0\nph = 0\n\"th'\" = 0.1\n\"ph'\" = 0.5\n",
    )
    .unwrap();
    let m = model.to_string_lossy();
    for method in ["dop853", "gauss6"] {
        refused(
            &["simulate", &m, "--until", "1", "--method", method],
            "the mass matrix M is singular at the start (th = 0, ph = 0): the velocity of ph has no inertia there",
        );
    }
    let away = scratch("hostile-singular", "spherical_away.toml");
    std::fs::write(&away, std::fs::read_to_string(&model).unwrap().replace("th = 0\n", "th = 0.1\n")).unwrap();
    let r = run(&["simulate", &away.to_string_lossy(), "--until", "1"]);
    assert_eq!(r.code, Some(0), "away from the pole it runs: {}", r.describe());
}

/// Dependent constraints: the message names them, and tells constraints that
/// contradict each other at the start from ones that merely repeat.
#[test]
fn dependent_constraints_are_named_and_contradictions_told_apart() {
    let model = |second: &str| {
        let path = scratch("hostile-constraints", &format!("c{}.toml", second.len()));
        std::fs::write(
            &path,
            format!(
                "coordinates = [\"x\", \"y\"]\nlagrangian = \"(x'^2 + y'^2)/2 - y\"\n\
                 [[constraints]]\nname = \"a\"\nholonomic = \"x\"\n\
                 [[constraints]]\nname = \"b\"\nholonomic = \"{second}\"\n\
                 [initial]\nx = 0\ny = 0\n\"x'\" = 0\n\"y'\" = 0\n"
            ),
        )
        .unwrap();
        path
    };
    let contradictory = model("x - 1");
    let r = run(&["simulate", &contradictory.to_string_lossy(), "--until", "1"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("the constraints 'a', 'b' are not independent"), "{}", r.stderr);
    assert!(
        r.stderr.contains("'a' holds but 'b' does not ('b' = -1.000e0): they may contradict each other"),
        "{}",
        r.stderr
    );
    let repeated = model("2*x");
    let r = run(&["simulate", &repeated.to_string_lossy(), "--until", "1"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("drop one of 'a', 'b', which follows from the others"), "{}", r.stderr);
    assert!(!r.stderr.contains("contradict"), "{}", r.stderr);
}

/// An output that cannot be created is bad input (exit 2) in every command,
/// found before anything is computed.
#[test]
fn an_output_that_cannot_be_created_is_refused_in_every_command() {
    let nowhere = scratch("hostile-outputs", "x").with_file_name("no-such-folder").join("out");
    let csv = nowhere.with_extension("csv").to_string_lossy().into_owned();
    let svg = nowhere.with_extension("svg").to_string_lossy().into_owned();
    let folder = scratch("hostile-outputs", "x").parent().unwrap().to_string_lossy().into_owned();
    for args in [
        vec!["simulate", "examples/pendulum.toml", "--until", "1", "--out", &csv],
        vec!["simulate", "examples/pendulum.toml", "--until", "1", "--plot", &svg],
        vec!["orbit", "examples/kepler.toml", "--plot", &svg],
        vec!["modes", "examples/triatomic.toml", "--animate", &svg],
        vec!["top", "examples/tops/heavy_top.toml", "--plot", &folder],
        vec!["extremal", "examples/extremal/brachistochrone.toml", "--plot", &folder],
    ] {
        let r = run(&args);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(
            r.stderr.contains("does not exist") || r.stderr.contains("is a folder; an output must name a file"),
            "{}",
            r.describe()
        );
    }
}

/// An extremal problem whose extremals oscillate a hundred and fifty times
/// between the ends: y'' = −y over [0, 1000] has the extremal
/// y = sin(x)/sin(1000), which the search once missed for want of steps and
/// then declared not to exist (Goldschmidt's message). Over [0, 10⁵] the
/// search cannot follow the family, and says it could not decide.
#[test]
fn an_oscillating_extremal_is_found_and_an_unfollowable_one_is_undecided() {
    let problem = |x1: &str| {
        let path = scratch("hostile-extremal", &format!("osc{x1}.toml"));
        std::fs::write(
            &path,
            format!(
                "independent = \"x\"\nunknown = \"y\"\nintegrand = \"y'^2 - y^2\"\n[boundary]\nstart = [0, 0]\nend = [{x1}, 1]\n"
            ),
        )
        .unwrap();
        path
    };
    let report = json(&["extremal", &problem("1000").to_string_lossy(), "--format", "json"]);
    let slope = report["extremals"][0]["start_slope"].as_f64().unwrap();
    close(slope, 1.0 / 1000f64.sin(), 1e-8);
    assert!(report["unfinished_shots"].as_u64().unwrap() > 0, "the steep members are not followed to the end");
    let r = run(&["extremal", &problem("100000").to_string_lossy()]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(r.stderr.contains("could not decide whether an extremal joins the end points"), "{}", r.describe());
    assert!(!r.stderr.contains("Goldschmidt"), "{}", r.describe());
}

/// An integrand that is not real at an end is bad input, not "singular at
/// both end points" or "no extremal".
#[test]
fn an_integrand_not_real_at_an_end_is_refused() {
    let never = scratch("hostile-extremal", "never_real.toml");
    std::fs::write(
        &never,
        "independent = \"x\"\nunknown = \"y\"\nintegrand = \"sqrt(-1 - y'^2)\"\n[boundary]\nstart = [0, 0]\nend = [1, 1]\n",
    )
    .unwrap();
    refused(&["extremal", &never.to_string_lossy()], ":5:9: the integrand is not real at the start (x, y) = (0, 0)");
    let text = std::fs::read_to_string(repo_root().join("examples/extremal/brachistochrone.toml")).unwrap();
    let above = scratch("hostile-extremal", "brachistochrone_above.toml");
    std::fs::write(&above, text.replace("end = [1.0, 0.8]", "end = [1.0, -0.5]")).unwrap();
    refused(&["extremal", &above.to_string_lossy()], "the integrand is not real at the end (x, y) = (1, -0.5)");
}
