//! `lagrange export --to c` through the real binary: the file compiles with
//! `cc -std=c99 -Wall -Wextra -Werror`, and a small program that includes it
//! and integrates `lagrange_rhs` with classical Runge–Kutta reproduces
//! `lagrange simulate` of the double pendulum (with its default parameters
//! and with g changed through `params`, as `--set g=` does), of Kepler's
//! problem and of a chain of ten rods (a tree of bodies: q'' by the
//! articulated-body algorithm); M, h and the energy agree with the derivation's values at the
//! start; a singular M makes `lagrange_rhs` return 1; constrained models are
//! refused with exit 2, and a failed export leaves an existing file alone.

mod common;
use common::{json, ok, run, scratch};
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
fn a_constrained_model_is_refused_and_an_existing_file_is_kept() {
    let out = scratch("export", "kept.c");
    std::fs::write(&out, "/* an earlier export */\n").unwrap();
    let r = run(&["export", "examples/constraints/pendulum_cartesian.toml", "--to", "c", "-o", out.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("pendulum_cartesian.toml:"), "{}", r.describe());
    assert!(r.stderr.contains("does not write [[constraints]] yet"), "{}", r.describe());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "/* an earlier export */\n");
    let r = run(&["export", "examples/pendulum.toml", "--to", "fortran", "-o", out.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
}
