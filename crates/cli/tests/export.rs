//! `lagrange export --to c` through the real binary: the file compiles with
//! `cc -std=c99 -Wall -Wextra -Werror`, and a small program that includes it
//! and integrates `lagrange_rhs` with classical Runge–Kutta reproduces
//! `lagrange simulate` of the double pendulum (with its default parameters
//! and with g changed through `params`, as `--set g=` does), of Kepler's
//! problem and of a chain of ten rods (a tree of bodies: q'' by the
//! articulated-body algorithm); the cart pendulum with its inputs in t and as
//! arguments (`lagrange_rhs_u` against `--set F0=`, B against f(u) − f(0)); the
//! Cartesian pendulum with its constraint (the multiplier against the run's);
//! M, h and the energy agree with the derivation's values at the start; a
//! singular M makes `lagrange_rhs` return 1; a failed export (bad model, or
//! abs() where Python's Jacobian is asked) is exit 2 and leaves an existing
//! file alone; an FMU holds its description, source and binary, and without a
//! C compiler is refused with exit 2 (FMPy runs the FMUs: `test_fmu.py`).

use crate::common;
use crate::common::{json, ok, run, scratch};
use std::path::Path;
use std::process::Command;

/// Exports `model` to C under `name` in this test's scratch folder.
fn export(model: &str, name: &str) -> std::path::PathBuf {
    let out = scratch("export", name);
    ok(&["export", model, "--to", "c", "-o", out.to_str().unwrap()]);
    out
}

/// Compiles `main` (a C program that includes the exported file `c`) and
/// runs it; its output, one number per line.
fn compile_and_run(c: &Path, main: &str, tag: &str) -> Vec<f64> {
    let cc = sym::c_compiler().expect("the export tests need the system C compiler (cc)");
    let source = scratch("export", &format!("{tag}_main.c"));
    let binary = scratch("export", &format!("{tag}_main"));
    std::fs::write(&source, format!("#include \"{}\"\n#include <stdio.h>\n{main}", c.display())).unwrap();
    let built = Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2", "-o"])
        .arg(&binary)
        .arg(&source)
        .arg("-lm")
        .output()
        .unwrap();
    assert!(built.status.success(), "cc failed:\n{}", String::from_utf8_lossy(&built.stderr));
    let run = Command::new(&binary).output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    String::from_utf8(run.stdout).unwrap().lines().map(|l| l.trim().parse().expect("a number")).collect()
}

/// A C `main` that integrates from `y0` to `until` with RK4 in `steps` steps
/// (parameters the defaults, `set` assignments applied), then prints the state.
fn rk4_main(y0: &[f64], until: f64, steps: usize, set: &str) -> String {
    let init: Vec<String> = y0.iter().map(|v| format!("{v:?}")).collect();
    format!(
        r#"
int main(void) {{
    enum {{ S = 2 * LAGRANGE_N }};
    double p[LAGRANGE_N_PARAMETERS + 1], y[S] = {{{init}}}, k1[S], k2[S], k3[S], k4[S], z[S];
    for (int i = 0; i <= LAGRANGE_N_PARAMETERS; i++) p[i] = lagrange_parameter_defaults[i];
    {set}
    const double h = {until:?} / {steps};
    for (int n = 0; n < {steps}; n++) {{
        double t = n * h;
        if (lagrange_rhs(t, y, p, k1)) return 1;
        for (int i = 0; i < S; i++) z[i] = y[i] + h / 2 * k1[i];
        if (lagrange_rhs(t + h / 2, z, p, k2)) return 1;
        for (int i = 0; i < S; i++) z[i] = y[i] + h / 2 * k2[i];
        if (lagrange_rhs(t + h / 2, z, p, k3)) return 1;
        for (int i = 0; i < S; i++) z[i] = y[i] + h * k3[i];
        if (lagrange_rhs(t + h, z, p, k4)) return 1;
        for (int i = 0; i < S; i++) y[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }}
    for (int i = 0; i < S; i++) printf("%.17g\n", y[i]);
    return 0;
}}
"#,
        init = init.join(", ")
    )
}

/// `lagrange simulate`'s final state [q, q'] at `until`, at a tight tolerance.
fn simulated(model: &str, until: f64, set: &[&str]) -> Vec<f64> {
    let until = until.to_string();
    let mut args = vec!["simulate", model, "--until", &until, "--rtol", "1e-12", "--summary", "json"];
    for s in set {
        args.extend(["--set", s]);
    }
    let v = json(&args);
    let d = json(&["derive", model, "--format", "json"]);
    let names: Vec<String> =
        d["coordinates"].as_array().unwrap().iter().map(|c| c.as_str().unwrap().to_string()).collect();
    let q = names.iter().map(|c| v["final"][c].as_f64().unwrap());
    let qd = names.iter().map(|c| v["final"][format!("{c}'")].as_f64().unwrap());
    q.chain(qd).collect()
}

#[track_caller]
fn agree(got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= tol * w.abs().max(1.0), "{got:?}\nagainst {want:?}");
    }
}

#[test]
fn the_double_pendulum_in_c_moves_as_simulate_says() {
    let c = export("examples/double_pendulum.toml", "double_pendulum.c");
    let y0 = [2.0, 2.5, 0.0, 0.0];
    let got = compile_and_run(&c, &rk4_main(&y0, 2.0, 20000, ""), "dp");
    agree(&got, &simulated("examples/double_pendulum.toml", 2.0, &[]), 1e-8);
    // g is the parameter named "g": set through params, as --set g= does.
    let set = r#"for (int i = 0; i < LAGRANGE_N_PARAMETERS; i++) if (lagrange_parameters[i][0] == 'g' && !lagrange_parameters[i][1]) p[i] = 1.62;"#;
    let got = compile_and_run(&c, &rk4_main(&y0, 2.0, 20000, set), "dp_moon");
    agree(&got, &simulated("examples/double_pendulum.toml", 2.0, &["g=1.62"]), 1e-8);
}

#[test]
fn kepler_s_orbit_in_c_moves_as_simulate_says() {
    let c = export("examples/kepler.toml", "kepler.c");
    let got = compile_and_run(&c, &rk4_main(&[1.0, 0.0, 0.0, 1.2], 5.0, 50000, ""), "kepler");
    agree(&got, &simulated("examples/kepler.toml", 5.0, &[]), 1e-8);
}

/// `n` rods hinged end to end, each turning relative to the one above (from
/// q_k = 0.1 k − 0.3 at rest): a tree of bodies, whose q'' the file computes by
/// the articulated-body algorithm once that is shorter than M, f and their solve.
fn rod_chain(n: usize) -> String {
    let names: Vec<String> = (1..=n).map(|k| format!("\"q{k}\"")).collect();
    let mut text = format!(
        "name = \"{n} rods\"\ncoordinates = [{}]\ngravity = \"g\"\n\n[parameters]\ng = 9.81\nm = 0.1\nl = 0.5\n",
        names.join(", ")
    );
    for k in 1..=n {
        let parent =
            if k > 1 { format!("parent = \"r{}\"\nposition = [\"0\", \"-l\"]\n", k - 1) } else { String::new() };
        text.push_str(&format!(
            "\n[[bodies]]\nname = \"r{k}\"\n{parent}mass = \"m\"\ninertia = \"m*l^2/3\"\nangle = \"q{k}\"\ncenter_of_mass = [\"0\", \"-l/2\"]\n"
        ));
    }
    text.push_str("\n[initial]\n");
    for k in 1..=n {
        text.push_str(&format!("q{k} = {:?}\n\"q{k}'\" = 0.0\n", 0.1 * k as f64 - 0.3));
    }
    text
}

#[test]
fn a_tree_of_bodies_in_c_moves_as_simulate_says() {
    let model = scratch("export", "rods.toml");
    let n = 10;
    std::fs::write(&model, rod_chain(n)).unwrap();
    let model = model.to_str().unwrap();
    let c = export(model, "rods.c");
    assert!(std::fs::read_to_string(&c).unwrap().contains("lagrange_accelerations"), "the articulated-body path");
    let y0: Vec<f64> = (1..=n).map(|k| 0.1 * k as f64 - 0.3).chain(std::iter::repeat_n(0.0, n)).collect();
    let got = compile_and_run(&c, &rk4_main(&y0, 1.0, 20000, ""), "rods");
    agree(&got, &simulated(model, 1.0, &[]), 1e-8);
}

#[test]
fn the_mass_matrix_h_and_the_energy_are_the_derivation_s() {
    let c = export("examples/double_pendulum.toml", "double_pendulum_m.c");
    // At a = 2, b = 2.5 at rest: M = [[2, cos(a − b)], [cos(a − b), 1]], h = E = U.
    let main = r#"
int main(void) {
    double y[4] = {2.0, 2.5, 0.0, 0.0}, m[4];
    lagrange_mass_matrix(0.0, y, lagrange_parameter_defaults, m);
    for (int i = 0; i < 4; i++) printf("%.17g\n", m[i]);
    printf("%.17g\n%.17g\n", lagrange_hamiltonian(0.0, y, lagrange_parameter_defaults),
           lagrange_energy(0.0, y, lagrange_parameter_defaults));
    printf("%d\n", LAGRANGE_N_PARAMETERS);
    return 0;
}
"#;
    let got = compile_and_run(&c, main, "dp_m");
    let c_ab = (2.0f64 - 2.5).cos();
    let u = -9.81 * (2.0 * 2.0f64.cos() + 2.5f64.cos());
    agree(&got, &[2.0, c_ab, c_ab, 1.0, u, u, 5.0], 1e-14);
}

#[test]
fn a_singular_mass_matrix_makes_the_right_hand_side_return_1() {
    // The spherical pendulum at θ = 0: φ' has no inertia there.
    let c = export("examples/spherical_pendulum.toml", "spherical.c");
    let main = r#"
int main(void) {
    double y[4] = {0.0, 0.0, 0.0, 0.0}, dy[4];
    printf("%d\n", lagrange_rhs(0.0, y, lagrange_parameter_defaults, dy));
    y[0] = 0.5;
    printf("%d\n", lagrange_rhs(0.0, y, lagrange_parameter_defaults, dy));
    return 0;
}
"#;
    assert_eq!(compile_and_run(&c, main, "spherical"), [1.0, 0.0]);
}

#[test]
fn a_failed_export_keeps_an_existing_file() {
    let out = scratch("export", "kept.py");
    std::fs::write(&out, "# an earlier export\n").unwrap();
    let model = scratch("export", "kinked.toml");
    std::fs::write(&model, "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"abs(x)\"\n").unwrap();
    let r = run(&["export", model.to_str().unwrap(), "--to", "python", "-o", out.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("abs()"), "{}", r.describe());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "# an earlier export\n");
    let r = run(&["export", "examples/pendulum.toml", "--to", "fortran", "-o", out.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    std::fs::write(&model, "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\npotential = \"x^2 +\"\n").unwrap();
    let r = run(&["export", model.to_str().unwrap(), "--to", "c", "-o", out.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("kinked.toml:3:"), "{}", r.describe());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "# an earlier export\n");
}

#[test]
fn the_cart_pendulum_in_c_takes_its_inputs_in_t_or_as_arguments() {
    let c = export("examples/cart_pendulum.toml", "cart_pendulum.c");
    let y0 = [0.0, 0.2, 0.0, 0.0];
    // lagrange_rhs: the inputs take their values in t, F = F0 sin 2t.
    let got = compile_and_run(&c, &rk4_main(&y0, 3.0, 30000, ""), "cart");
    agree(&got, &simulated("examples/cart_pendulum.toml", 3.0, &[]), 1e-8);
    // lagrange_rhs_u with u = (3 sin 2t, 0) moves as --set F0=3 does.
    let main = rk4_main(&y0, 3.0, 30000, "").replace("lagrange_rhs(", "rhs_of_u(");
    let driven = format!(
        "static int rhs_of_u(double t, const double *y, const double *p, double *dy) {{\n    \
         double u[LAGRANGE_N_INPUTS] = {{3.0 * sin(2.0 * t), 0.0}};\n    \
         return lagrange_rhs_u(t, y, p, u, dy);\n}}\n{main}"
    );
    let got = compile_and_run(&c, &driven, "cart_u");
    agree(&got, &simulated("examples/cart_pendulum.toml", 3.0, &["F0=3"]), 1e-8);
    // B: f(u) − f(0) = B u, and f with the values in t is f at lagrange_inputs.
    let main = r#"
int main(void) {
    const double *p = lagrange_parameter_defaults;
    double y[4] = {0.1, 0.7, 0.3, -0.2}, u[2] = {1.5, -0.25}, zero[2] = {0.0, 0.0}, values[2];
    double f[2], f0[2], b[4], fu[2], ft[2];
    lagrange_forcing_u(0.4, y, p, u, f);
    lagrange_forcing_u(0.4, y, p, zero, f0);
    lagrange_input_matrix(0.4, y, p, u, b);
    for (int i = 0; i < 2; i++) printf("%.17g\n%.17g\n", f[i] - f0[i], b[2 * i] * u[0] + b[2 * i + 1] * u[1]);
    lagrange_inputs(0.4, y, p, values);
    lagrange_forcing_u(0.4, y, p, values, fu);
    lagrange_forcing(0.4, y, p, ft);
    for (int i = 0; i < 2; i++) printf("%.17g\n%.17g\n", fu[i], ft[i]);
    printf("%.17g\n%d\n", values[0], lagrange_input_names[0][0] == 'F' && lagrange_input_names[1][0] == 't');
    return 0;
}
"#;
    let got = compile_and_run(&c, main, "cart_b");
    for pair in got[..8].chunks(2) {
        agree(&pair[..1], &pair[1..], 1e-13);
    }
    agree(&got[8..], &[(0.8f64).sin(), 1.0], 1e-15);
}

#[test]
fn a_constrained_model_in_c_moves_with_its_multipliers() {
    let model = "examples/constraints/pendulum_cartesian.toml";
    let c = export(model, "pendulum_cartesian.c");
    let (x0, y0) = (1f64.sin(), -1f64.cos());
    let start = [x0, y0, 0.5 * 1f64.cos(), 0.5 * 1f64.sin()];
    let until = 2.0;
    let got = compile_and_run(&c, &rk4_main(&start, until, 20000, ""), "cartesian");
    agree(&got, &simulated(model, until, &[]), 1e-8);
    // At the end: the residual and its rate are round-off, λ is the run's.
    let finish: Vec<String> = got.iter().map(|v| format!("{v:?}")).collect();
    let main = format!(
        r#"
int main(void) {{
    double y[4] = {{{}}}, r[1], rate[1], lambda[1], a[2];
    lagrange_constraint_residuals({until:?}, y, lagrange_parameter_defaults, r);
    lagrange_constraint_rates({until:?}, y, lagrange_parameter_defaults, rate);
    if (lagrange_multipliers({until:?}, y, lagrange_parameter_defaults, lambda)) return 1;
    lagrange_constraint_jacobian({until:?}, y, lagrange_parameter_defaults, a);
    printf("%.17g\n%.17g\n%.17g\n%.17g\n%.17g\n%d\n", r[0], rate[0], lambda[0], a[0] - 2 * y[0], a[1] - 2 * y[1], LAGRANGE_N_CONSTRAINTS);
    return 0;
}}
"#,
        finish.join(", ")
    );
    let got = compile_and_run(&c, &main, "cartesian_lambda");
    assert!(got[0].abs() < 1e-9 && got[1].abs() < 1e-9, "residuals {got:?}");
    let csv = scratch("export", "cartesian.csv");
    ok(&["simulate", model, "--until", "2", "--rtol", "1e-12", "--out", csv.to_str().unwrap()]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut rows = text.lines().filter(|l| !l.starts_with('#'));
    let column = rows.next().unwrap().split(',').position(|c| c == "lambda_rod").expect("a lambda_rod column");
    let last = rows.next_back().unwrap();
    let lambda: f64 = last.split(',').nth(column).unwrap().parse().unwrap();
    agree(&got[2..3], &[lambda], 1e-7);
    agree(&got[3..], &[0.0, 0.0, 1.0], 1e-15);
}

#[test]
fn an_fmu_without_a_c_compiler_is_refused_and_an_existing_file_is_kept() {
    let out = scratch("export", "kept.fmu");
    std::fs::write(&out, "an earlier export").unwrap();
    let r = Command::new(env!("CARGO_BIN_EXE_lagrange"))
        .args(["export", "examples/double_pendulum.toml", "--to", "fmu", "-o", out.to_str().unwrap()])
        .current_dir(common::repo_root())
        .env("LAGRANGE_CC", "/nonexistent/cc")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("needs a C compiler") && stderr.contains("/nonexistent/cc"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "an earlier export");
}

#[test]
fn an_fmu_holds_its_description_its_source_and_a_binary_for_this_machine() {
    let out = scratch("export", "cart_pendulum.fmu");
    ok(&["export", "examples/cart_pendulum.toml", "--to", "fmu", "-o", out.to_str().unwrap()]);
    let bytes = std::fs::read(&out).unwrap();
    // A zip (local file header) holding the three entries, by name.
    assert_eq!(&bytes[..4], b"PK\x03\x04");
    let text = String::from_utf8_lossy(&bytes);
    let binary = if cfg!(target_os = "macos") {
        "binaries/darwin64/cart_pendulum.dylib"
    } else {
        "binaries/linux64/cart_pendulum.so"
    };
    for entry in ["modelDescription.xml", "sources/cart_pendulum.c", binary] {
        assert!(text.contains(entry), "no {entry} in the archive");
    }
    for line in [
        r#"modelIdentifier="cart_pendulum""#,
        r#"<ScalarVariable name="F" valueReference="13""#,
        r#"causality="input""#,
        r#"<ScalarVariable name="solver.tolerance""#,
    ] {
        assert!(text.contains(line), "no {line} in the model description");
    }
}

/// `-o` naming a pipe or a device writes into it and leaves it one (renaming
/// the export onto it once replaced /dev/null with a regular file); a link is
/// followed and stays a link.
#[test]
fn an_export_into_a_pipe_or_through_a_link_leaves_them_in_place() {
    use std::os::unix::fs::FileTypeExt;
    let printed = run(&["export", "examples/pendulum.toml", "--to", "c", "-o", "/dev/stdout"]);
    assert_eq!(printed.code, Some(0), "{}", printed.describe());
    assert!(printed.stdout.contains("lagrange_rhs"), "{}", printed.describe());

    let fifo = scratch("export-nodes", "pipe.py");
    let _ = std::fs::remove_file(&fifo);
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).expect("the pipe reads"))
    };
    ok(&["export", "examples/pendulum.toml", "--to", "python", "-o", fifo.to_str().unwrap()]);
    assert!(reader.join().unwrap().contains("def rhs("));
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "the pipe is still a pipe");

    let target = scratch("export-nodes", "target.c");
    let link = scratch("export-nodes", "link.c");
    std::fs::write(&target, "old").unwrap();
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(&target, &link).unwrap();
    ok(&["export", "examples/pendulum.toml", "--to", "c", "-o", link.to_str().unwrap()]);
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link is still a link");
    assert!(std::fs::read_to_string(&target).unwrap().contains("lagrange_rhs"));
}

/// Exported code has no events: a model with `[[impacts]]` is refused (exit 2,
/// at the impact), for every target, and nothing is written, where it was once
/// exported without a word and its ball fell through the floor.
#[test]
fn a_model_with_impacts_is_refused_at_its_impact() {
    for (to, name) in [("c", "ball.c"), ("python", "ball.py"), ("fmu", "ball.fmu")] {
        let out = scratch("export-impacts", name);
        let _ = std::fs::remove_file(&out);
        let r = run(&["export", "examples/impacts/bouncing_ball.toml", "--to", to, "-o", out.to_str().unwrap()]);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(
            r.stderr.starts_with("error: examples/impacts/bouncing_ball.toml:20:8: impact 'floor' cannot be exported"),
            "{}",
            r.describe()
        );
        assert!(r.stderr.contains("the surface y = 0"), "{}", r.describe());
        assert!(!out.exists(), "{to}: nothing is written");
    }
}
