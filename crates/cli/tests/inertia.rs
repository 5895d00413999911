//! `lagrange inertia` run through the real binary: the notes' cube about its
//! centre and a corner (Sec. 3.2.3 b), every shape's standard moments, the
//! cone's centre of mass, the parallel-axis theorem, a part turned by Euler
//! angles, an exact polynomial density, numeric cubature of exp and Gaussian
//! densities against closed forms, and bad input (exit 2 with file:line:col).

use serde_json::Value;

use crate::common::{close, is_close, json, repo_root, run, scratch, Run};

/// `lagrange inertia ARGS --format json`, which must succeed.
#[track_caller]
fn inertia(args: &[&str]) -> Value {
    let mut all = vec!["inertia"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json"]);
    json(&all)
}

/// A body file in a temporary directory.
fn body(name: &str, text: &str) -> String {
    let path = scratch("inertia", name);
    std::fs::write(&path, text).expect("the body file is written");
    path.display().to_string()
}

fn matrix(v: &Value) -> [[f64; 3]; 3] {
    std::array::from_fn(|j| std::array::from_fn(|k| v[j][k].as_f64().expect("a number")))
}

fn vector(v: &Value) -> [f64; 3] {
    std::array::from_fn(|k| v[k].as_f64().expect("a number"))
}

fn strings(v: &Value) -> Vec<Vec<String>> {
    v.as_array()
        .expect("rows")
        .iter()
        .map(|row| row.as_array().expect("a row").iter().map(|x| x.as_str().expect("a string").to_string()).collect())
        .collect()
}

#[track_caller]
fn close_matrix(got: &[[f64; 3]; 3], want: &[[f64; 3]; 3], rel: f64) {
    let scale = want.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
    for j in 0..3 {
        for k in 0..3 {
            assert!(
                is_close(got[j][k], want[j][k], rel, scale),
                "entry {j}{k}: got {}, want {}\n{got:?}",
                got[j][k],
                want[j][k]
            );
        }
    }
}

fn diag(d: [f64; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|j| std::array::from_fn(|k| if j == k { d[j] } else { 0.0 }))
}

#[test]
fn notes_cube_about_its_centre_and_a_corner() {
    // M = 3, a = 2: M a² = 12.
    let v = inertia(&["examples/bodies/cube.toml", "--set", "M=3", "--set", "a=2"]);
    assert_eq!(v["format"], "lagrange.inertia/1");
    for key in ["mass", "center_of_mass", "about", "tensor", "tensor_exact", "principal_moments", "principal_axes"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    close(v["mass"].as_f64().unwrap(), 3.0, 1e-15);
    assert_eq!(vector(&v["center_of_mass"]), [1.0, 1.0, 1.0]);
    assert_eq!(vector(&v["about"]), [1.0, 1.0, 1.0]);
    let e = strings(&v["tensor_exact"]);
    assert_eq!(e[0], ["M*a^2/6", "0", "0"]);
    assert_eq!(e[1][1], "M*a^2/6");
    assert_eq!(e[2][2], "M*a^2/6");
    close_matrix(&matrix(&v["tensor"]), &diag([2.0; 3]), 1e-15);

    let v = inertia(&["examples/bodies/cube.toml", "--set", "M=3", "--set", "a=2", "--about", "0,0,0"]);
    let e = strings(&v["tensor_exact"]);
    for j in 0..3 {
        for k in 0..3 {
            assert_eq!(e[j][k], if j == k { "2*M*a^2/3" } else { "-M*a^2/4" }, "{j}{k}");
        }
    }
    let t = matrix(&v["tensor"]);
    close_matrix(&t, &[[8.0, -3.0, -3.0], [-3.0, 8.0, -3.0], [-3.0, -3.0, 8.0]], 1e-15);
    // Eigenvalues a²M (2/3 − 1/2) = 2 along (1,1,1) and a²M (2/3 + 1/4) = 11 twice.
    let pm = vector(&v["principal_moments"]);
    close(pm[0], 2.0, 1e-13);
    close(pm[1], 11.0, 1e-13);
    close(pm[2], 11.0, 1e-13);
    let axes: Vec<[f64; 3]> = v["principal_axes"].as_array().unwrap().iter().map(vector).collect();
    for k in 0..3 {
        close(axes[0][k], 3f64.sqrt().recip(), 1e-12);
    }
    // Each axis is a unit eigenvector: I·n = λ n.
    for (n, lam) in axes.iter().zip(pm) {
        for j in 0..3 {
            let tn: f64 = (0..3).map(|k| t[j][k] * n[k]).sum();
            assert!((tn - lam * n[j]).abs() < 1e-12, "{n:?}");
        }
        close(n.iter().map(|x| x * x).sum::<f64>(), 1.0, 1e-14);
    }
}

#[test]
fn the_text_names_the_steps_and_the_symmetry() {
    let Run { code, stdout: text, .. } = run(&["inertia", "examples/bodies/cube.toml", "--about", "0,0,0"]);
    assert_eq!(code, Some(0));
    for needle in ["cube: solid box", "M*a^2/6", "2*M*a^2/3", "-M*a^2/4", "Parallel-axis", "symmetric top", "I1 = "] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
    let Run { stdout: text, .. } = run(&["inertia", "examples/bodies/cube.toml"]);
    assert!(text.contains("spherical top"), "{text}");
    assert!(!text.contains("Parallel-axis"), "{text}");
}

/// The tensor about the centre of mass of one part of mass 2 with the given shape and size.
fn one_part(shape: &str, size: &str) -> Value {
    let text = format!(
        "[parameters]\nM = 2.0\nR = 0.7\nh = 1.3\nL = 1.9\n[[parts]]\nshape = \"{shape}\"\nmass = \"M\"\n{size}center = [0.5, -1, 2]\n"
    );
    inertia(&[&body(&format!("{shape}.toml"), &text)])
}

#[test]
fn every_shape_has_its_standard_moments() {
    let (m, r, h, l) = (2.0, 0.7, 1.3, 1.9);
    let cases: [(&str, &str, [f64; 3], &str); 9] = [
        ("point", "", [0.0; 3], "0"),
        ("rod", "size = [\"L\"]\n", [m * l * l / 12.0, m * l * l / 12.0, 0.0], "L^2*M/12"),
        ("sphere", "size = [\"R\"]\n", [0.4 * m * r * r; 3], "2*M*R^2/5"),
        ("shell", "size = [\"R\"]\n", [2.0 / 3.0 * m * r * r; 3], "2*M*R^2/3"),
        (
            "cylinder",
            "size = [\"R\", \"h\"]\n",
            [m * (3.0 * r * r + h * h) / 12.0, m * (3.0 * r * r + h * h) / 12.0, m * r * r / 2.0],
            "M*(3*R^2 + h^2)/12",
        ),
        (
            "cone",
            "size = [\"R\", \"h\"]\n",
            [3.0 / 80.0 * m * (4.0 * r * r + h * h), 3.0 / 80.0 * m * (4.0 * r * r + h * h), 0.3 * m * r * r],
            "3*M*(4*R^2 + h^2)/80",
        ),
        ("disk", "size = [\"R\"]\n", [m * r * r / 4.0, m * r * r / 4.0, m * r * r / 2.0], "M*R^2/4"),
        ("ring", "size = [\"R\"]\n", [m * r * r / 2.0, m * r * r / 2.0, m * r * r], "M*R^2/2"),
        (
            "box",
            "size = [\"R\", \"h\", \"L\"]\n",
            [m * (h * h + l * l) / 12.0, m * (r * r + l * l) / 12.0, m * (r * r + h * h) / 12.0],
            "M*(L^2 + h^2)/12",
        ),
    ];
    for (shape, size, want, exact_xx) in cases {
        let v = one_part(shape, size);
        close_matrix(&matrix(&v["tensor"]), &diag(want), 1e-14);
        assert_eq!(vector(&v["center_of_mass"]), [0.5, -1.0, 2.0], "{shape}");
        assert_eq!(strings(&v["tensor_exact"])[0][0], exact_xx, "{shape}");
    }
}

#[test]
fn cone_centre_is_h_over_4_above_the_base() {
    // Base in z = 0, apex at z = h = 2, R = 1, M = 1.
    let v = inertia(&["examples/bodies/cone.toml"]);
    assert_eq!(vector(&v["center_of_mass"]), [0.0, 0.0, 0.5]);
    // About the apex: I_x = 3/20 M R² + 3/5 M h² (a textbook result independent of the CM).
    let v = inertia(&["examples/bodies/cone.toml", "--about", "0,0,h"]);
    close_matrix(&matrix(&v["tensor"]), &diag([0.15 + 2.4, 0.15 + 2.4, 0.3]), 1e-14);
    assert_eq!(strings(&v["tensor_exact"])[0][0], "3*M*(R^2 + 4*h^2)/20");
    // About the centre of the base: I_x = M (3R²/20 + h²/10).
    let v = inertia(&["examples/bodies/cone.toml", "--about", "0,0,0"]);
    close(matrix(&v["tensor"])[0][0], 0.15 + 0.4, 1e-14);
}

#[test]
fn parallel_axis_theorem_for_an_offset_sphere() {
    // A sphere (M = 2, R = 0.5) centred at (1, 2, 3), about the origin and about (1, 0, -1).
    let text = "[[parts]]\nshape = \"sphere\"\nmass = 2\nsize = [0.5]\ncenter = [1, 2, 3]\n";
    let path = body("offset_sphere.toml", text);
    let own = 0.4 * 2.0 * 0.25;
    for (about, p) in [("0,0,0", [0.0, 0.0, 0.0]), ("1,0,-1", [1.0, 0.0, -1.0])] {
        let v = inertia(&[&path, "--about", about]);
        let r = [1.0 - p[0], 2.0 - p[1], 3.0 - p[2]];
        let r2: f64 = r.iter().map(|x| x * x).sum();
        let want: [[f64; 3]; 3] = std::array::from_fn(|j| {
            std::array::from_fn(|k| if j == k { own + 2.0 * (r2 - r[j] * r[j]) } else { -2.0 * r[j] * r[k] })
        });
        close_matrix(&matrix(&v["tensor"]), &want, 1e-15);
        assert_eq!(vector(&v["about"]), p);
    }
    // Two parts: the combined CM and the Steiner terms of each.
    let text = "[[parts]]\nshape = \"point\"\nmass = 1\ncenter = [0, 0, 0]\n[[parts]]\nshape = \"point\"\nmass = 3\ncenter = [4, 0, 0]\n";
    let v = inertia(&[&body("two_points.toml", text)]);
    assert_eq!(vector(&v["center_of_mass"]), [3.0, 0.0, 0.0]);
    // Reduced mass 3/4 times the distance² 16 = 12 about any axis ⊥ x through the CM.
    close_matrix(&matrix(&v["tensor"]), &diag([0.0, 12.0, 12.0]), 1e-15);
    assert_eq!(v["symmetry"], "symmetric");
}

/// The notes' rotation D = D_γ D_β D_α, written out here independently of the library.
fn rotation(al: f64, be: f64, ga: f64) -> [[f64; 3]; 3] {
    let (sa, ca) = al.sin_cos();
    let (sb, cb) = be.sin_cos();
    let (sg, cg) = ga.sin_cos();
    let d_a = [[ca, sa, 0.0], [-sa, ca, 0.0], [0.0, 0.0, 1.0]];
    let d_b = [[1.0, 0.0, 0.0], [0.0, cb, sb], [0.0, -sb, cb]];
    let d_g = [[cg, sg, 0.0], [-sg, cg, 0.0], [0.0, 0.0, 1.0]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    };
    mul(d_g, mul(d_b, d_a))
}

#[test]
fn a_turned_box_is_r_i_rt_with_the_same_principal_moments() {
    let (al, be, ga) = (0.3, 1.1, -0.7);
    let text = format!(
        "[[parts]]\nshape = \"box\"\nmass = 12\nsize = [1, 2, 3]\ncenter = [1, 1, 1]\norientation = [{al}, {be}, {ga}]\n"
    );
    let v = inertia(&[&body("turned_box.toml", &text)]);
    let own = [13.0, 10.0, 5.0];
    let d = rotation(al, be, ga);
    // R = Dᵀ: I = Dᵀ diag(own) D.
    let want: [[f64; 3]; 3] =
        std::array::from_fn(|j| std::array::from_fn(|k| (0..3).map(|a| d[a][j] * own[a] * d[a][k]).sum()));
    close_matrix(&matrix(&v["tensor"]), &want, 1e-13);
    assert!(want[0][1].abs() > 0.5, "the test turns the box enough to mix the axes");
    let pm = vector(&v["principal_moments"]);
    for (got, want) in pm.iter().zip([5.0, 10.0, 13.0]) {
        close(*got, want, 1e-13);
    }
    // The axis of the smallest moment is the part's z axis, row 3 of D (up to sign).
    let n = vector(&v["principal_axes"][0]);
    let dot: f64 = (0..3).map(|k| n[k] * d[2][k]).sum();
    close(dot.abs(), 1.0, 1e-12);
    assert!(v["tensor_exact"].is_array(), "a turned part is still exact (in sin and cos of the angles)");
}

#[test]
fn linear_density_is_integrated_exactly() {
    // ρ = rho (1 + x/a) on [0,a]×[0,b]×[0,c] with rho = 2, a = 1, b = 2, c = 3. By hand:
    // M = 3/2 rho a b c = 18, X = (∫ρx)/M = (5/6 rho a² b c)/M = 5a/9,
    // ∫ρx² = 7/12 rho a³ b c = 7, ∫ρy² = 3/2 rho a c b³/3 = 24, ∫ρz² = 3/2 rho a b c³/3 = 54,
    // so about the CM: I_xx = 24 + 54 − M(1 + 2.25) = 19.5,
    // I_yy = 7 + 54 − M(25/81 + 2.25) = 61 − 18·(25/81) − 40.5, I_zz = 7 + 24 − 18·(25/81) − 18.
    let v = inertia(&["examples/bodies/wedge_density.toml"]);
    assert_eq!(v["mass_exact"], "3*a*b*c*rho/2");
    assert_eq!(v["center_of_mass_exact"][0], "5*a/9");
    close(v["mass"].as_f64().unwrap(), 18.0, 1e-15);
    let x2 = 18.0 * 25.0 / 81.0;
    close_matrix(&matrix(&v["tensor"]), &diag([19.5, 61.0 - x2 - 40.5, 31.0 - x2 - 18.0]), 1e-14);
    assert_eq!(v["cubature"], Value::Null);
    // About the origin, an off-diagonal product: −∫ρxy = −(5/6 rho a² b c)(b/2) = −10.
    let v = inertia(&["examples/bodies/wedge_density.toml", "--about", "0,0,0"]);
    close(matrix(&v["tensor"])[0][1], -10.0, 1e-14);
}

/// erf by its Taylor series (plenty for |x| ≤ 3 in a test).
fn erf(x: f64) -> f64 {
    let mut term = x;
    let mut sum = x;
    for n in 1..300 {
        term *= -x * x / f64::from(n);
        sum += term / f64::from(2 * n + 1);
    }
    sum * 2.0 / std::f64::consts::PI.sqrt()
}

#[test]
fn gaussian_density_by_cubature_matches_the_closed_form() {
    let (w, s) = (0.7f64, 1.0f64);
    let g0 = std::f64::consts::PI.sqrt() * w * erf(s / w);
    let g2 = w * w / 2.0 * (g0 - 2.0 * s * (-(s * s) / (w * w)).exp());
    let v = inertia(&["examples/bodies/gaussian_density.toml"]);
    close(v["mass"].as_f64().unwrap(), g0.powi(3), 1e-8);
    close_matrix(&matrix(&v["tensor"]), &diag([2.0 * g0 * g0 * g2; 3]), 1e-8);
    assert_eq!(v["tensor_exact"], Value::Null);
    assert_eq!(v["mass_exact"], Value::Null);
    let err = v["cubature"]["tensor_error"].as_f64().unwrap();
    assert!(err > 0.0 && err < 1e-9, "{err}");
    assert_eq!(v["cubature"]["converged"], true);
    assert_eq!(v["symmetry"], "spherical");
}

#[test]
fn exponential_density_by_cubature_with_an_offset_centre() {
    // ρ = exp(x) on [0,1]³: M = e − 1, ∫xρ = 1, ∫x²ρ = e − 2, ∫y²ρ = (e − 1)/3, ∫xyρ = 1/2.
    let text = "[[parts]]\nshape = \"density\"\ndensity = \"exp(x)\"\nregion = [[0, 1], [0, 1], [0, 1]]\n";
    let v = inertia(&[&body("exp.toml", text), "--about", "0,0,0"]);
    let e = std::f64::consts::E;
    let m = e - 1.0;
    close(v["mass"].as_f64().unwrap(), m, 1e-10);
    let c = vector(&v["center_of_mass"]);
    close(c[0], 1.0 / m, 1e-10);
    close(c[1], 0.5, 1e-10);
    let (xx, yy) = (e - 2.0, m / 3.0);
    let want = [[2.0 * yy, -0.5, -0.5], [-0.5, xx + yy, -m / 4.0], [-0.5, -m / 4.0, xx + yy]];
    close_matrix(&matrix(&v["tensor"]), &want, 1e-9);
    assert_eq!(v["tensor_exact"], Value::Null);
}

/// A bad body file: exit 2, and stderr names the file, line and column and says what is wrong.
#[track_caller]
fn check_bad(name: &str, text: &str, line_col: &str, message: &str) {
    let path = body(name, text);
    let Run { code, stdout, stderr, .. } = run(&["inertia", &path]);
    assert_eq!(code, Some(2), "{stdout}\n{stderr}");
    assert!(stderr.contains(&format!("{path}:{line_col}: ")), "expected {path}:{line_col} in\n{stderr}");
    assert!(stderr.contains(message), "expected {message:?} in\n{stderr}");
}

#[test]
fn bad_bodies_exit_2_with_file_line_and_column() {
    let head = "[parameters]\nM = 1.0\na = 1.0\n\n[[parts]]\n";
    check_bad("unknown_shape.toml", &format!("{head}shape = \"cube\"\nmass = \"M\"\n"), "6:9", "unknown shape 'cube'");
    check_bad("missing_size.toml", &format!("{head}shape = \"box\"\nmass = \"M\"\n"), "5:1", "has no `size`");
    check_bad(
        "negative_mass.toml",
        &format!("{head}shape = \"sphere\"\nmass = \"-2*M\"\nsize = [\"a\"]\n"),
        "7:8",
        "expected a mass ≥ 0",
    );
    check_bad(
        "two_components.toml",
        &format!("{head}shape = \"box\"\nmass = \"M\"\nsize = [\"a\", \"a\"]\n"),
        "8:8",
        "has 3 components",
    );
    check_bad(
        "center_components.toml",
        &format!("{head}shape = \"sphere\"\nmass = \"M\"\nsize = [\"a\"]\ncenter = [0, 0]\n"),
        "9:10",
        "has 3 components",
    );
    check_bad(
        "unknown_parameter.toml",
        &format!("{head}shape = \"sphere\"\nmass = \"M\"\nsize = [\"2*b\"]\n"),
        "8:12",
        "unknown",
    );
    check_bad(
        "infinite_density.toml",
        &format!("{head}shape = \"density\"\ndensity = \"1/(x - 1/2)\"\nregion = [[0, \"a\"], [0, 1], [0, 1]]\n"),
        "7:11",
        "expected a finite value",
    );
    check_bad(
        "singular_density.toml",
        &format!("{head}shape = \"density\"\ndensity = \"1/x\"\nregion = [[0, \"a\"], [0, 1], [0, 1]]\n"),
        "7:11",
        "did not converge",
    );
    check_bad(
        "density_with_mass.toml",
        &format!("{head}shape = \"density\"\nmass = 2\ndensity = \"1\"\nregion = [[0, 1], [0, 1], [0, 1]]\n"),
        "7:8",
        "has no `mass`",
    );
    check_bad(
        "unknown_key.toml",
        &format!("{head}shape = \"point\"\nmass = 1\ncolour = \"red\"\n"),
        "8:1",
        "unknown field",
    );
}

#[test]
fn a_bad_reference_point_exits_2() {
    let Run { code, stderr, .. } = run(&["inertia", "examples/bodies/cube.toml", "--about", "0,b,0"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("--about:1:3"), "{stderr}");
    let Run { code, stderr, .. } = run(&["inertia", "examples/bodies/cube.toml", "--about", "1,2"]);
    assert_eq!(code, Some(2));
    assert!(stderr.contains("expected `com` or a point x,y,z"), "{stderr}");
}

#[test]
fn every_body_example_runs_and_follows_the_contract() {
    let dir = repo_root().join("examples/bodies");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("examples/bodies exists")
        .map(|e| e.expect("a directory entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    for file in files {
        let v = inertia(&[&format!("examples/bodies/{file}")]);
        assert_eq!(v["format"], "lagrange.inertia/1", "{file}");
        assert!(v["mass"].as_f64().unwrap() > 0.0, "{file}");
        let t = matrix(&v["tensor"]);
        let pm = vector(&v["principal_moments"]);
        assert!(pm[0] <= pm[1] && pm[1] <= pm[2], "{file}: {pm:?}");
        // The trace is invariant; a physical tensor obeys the triangle inequality I1 + I2 ≥ I3.
        close(pm.iter().sum(), t[0][0] + t[1][1] + t[2][2], 1e-12);
        assert!(pm[0] + pm[1] >= pm[2] * (1.0 - 1e-12), "{file}: {pm:?}");
        assert!(v["tensor_exact"].is_array() || v["tensor_exact"].is_null(), "{file}");
    }
}

/// Each analysis' `--help` names its own JSON schema and no other command's.
#[test]
fn help_names_each_commands_own_schema() {
    let commands = ["inertia", "modes", "orbit", "top", "extremal"];
    for command in commands {
        let Run { code, stdout, stderr, .. } = run(&[command, "--help"]);
        assert_eq!(code, Some(0), "{stderr}");
        assert!(stdout.contains(&format!("lagrange.{command}/1")), "{command} --help:\n{stdout}");
        for other in commands.iter().filter(|&&o| o != command) {
            assert!(
                !stdout.contains(&format!("lagrange.{other}/1")),
                "{command} --help names {other}'s schema:\n{stdout}"
            );
        }
    }
}

/// A tensor part given the solid cube's tensor M a²/6 · 1 (notes, Sec. 3.2.3 b)
/// at the cube's centre gives what the cube shape gives: about the centre, the
/// corner, and in principal moments.
#[test]
fn a_given_tensor_equal_to_the_cube_agrees_with_the_cube() {
    let given = body(
        "tensor_cube.toml",
        "name = \"cube by its tensor\"\n[parameters]\nM = 1.0\na = 1.0\n\n[[parts]]\nshape = \"tensor\"\nmass = \"M\"\n\
         inertia = [\"M*a^2/6\", \"M*a^2/6\", \"M*a^2/6\"]\ncenter = [\"a/2\", \"a/2\", \"a/2\"]\n",
    );
    let full = body(
        "tensor_cube_full.toml",
        "[parameters]\nM = 1.0\na = 1.0\n\n[[parts]]\nshape = \"tensor\"\nmass = \"M\"\n\
         inertia = [[\"M*a^2/6\", 0, 0], [0, \"M*a^2/6\", 0], [0, 0, \"M*a^2/6\"]]\ncenter = [\"a/2\", \"a/2\", \"a/2\"]\n",
    );
    for about in ["com", "0,0,0", "1,-2,0.5"] {
        let cube = inertia(&["examples/bodies/cube.toml", "--about", about]);
        for file in [&given, &full] {
            let v = inertia(&[file, "--about", about]);
            assert_eq!(v["parts"][0]["shape"], "tensor");
            assert_eq!(v["parts"][0]["method"], "given");
            close(v["mass"].as_f64().unwrap(), cube["mass"].as_f64().unwrap(), 1e-12);
            let (c, w) = (vector(&v["center_of_mass"]), vector(&cube["center_of_mass"]));
            for k in 0..3 {
                close(c[k], w[k], 1e-12);
            }
            close_matrix(&matrix(&v["tensor"]), &matrix(&cube["tensor"]), 1e-12);
            close_matrix(&matrix(&v["tensor_com"]), &matrix(&cube["tensor_com"]), 1e-12);
            let (p, q) = (vector(&v["principal_moments"]), vector(&cube["principal_moments"]));
            for k in 0..3 {
                close(p[k], q[k], 1e-12);
            }
            assert_eq!(v["tensor_exact"], cube["tensor_exact"], "about {about}");
        }
    }
}

/// A given tensor (m1 = 2 at the origin) and a solid sphere (m2 = 1, R = 1) at
/// (3, 0, 0): the tensor about the centre of mass by the parallel-axis theorem,
/// worked by hand here: X = 3 m2/(m1 + m2) = 1, so the tensor part sits at
/// d1 = (−1, 0, 0) and the sphere at d2 = (2, 0, 0), each adding m (|d|² 1 − d dᵀ).
#[test]
fn a_given_tensor_and_an_offset_sphere_follow_steiner() {
    let path = body(
        "tensor_and_sphere.toml",
        "[[parts]]\nname = \"block\"\nshape = \"tensor\"\nmass = 2\n\
         inertia = [[2, -0.5, 0], [-0.5, 3, 0], [0, 0, 4]]\n\n\
         [[parts]]\nname = \"ball\"\nshape = \"sphere\"\nmass = 1\nsize = [1]\ncenter = [3, 0, 0]\n",
    );
    let v = inertia(&[&path]);
    let (m1, m2, r) = (2.0, 1.0, 1.0);
    let given = [[2.0, -0.5, 0.0], [-0.5, 3.0, 0.0], [0.0, 0.0, 4.0]];
    let sphere = 0.4 * m2 * r * r;
    let x = 3.0 * m2 / (m1 + m2);
    let c = vector(&v["center_of_mass"]);
    close(c[0], x, 1e-15);
    assert_eq!([c[1], c[2]], [0.0, 0.0]);
    let (d1, d2) = (0.0 - x, 3.0 - x);
    // m (|d|² 1 − d dᵀ) for d along x: 0 on xx, m d² on yy and zz.
    let want = [
        [given[0][0] + sphere, given[0][1], given[0][2]],
        [given[1][0], given[1][1] + sphere + m1 * d1 * d1 + m2 * d2 * d2, given[1][2]],
        [given[2][0], given[2][1], given[2][2] + sphere + m1 * d1 * d1 + m2 * d2 * d2],
    ];
    // = [[2.4, -0.5, 0], [-0.5, 9.4, 0], [0, 0, 10.4]]
    close_matrix(&matrix(&v["tensor"]), &want, 1e-14);
    assert_eq!(strings(&v["tensor_exact"])[1], ["-1/2", "47/5", "0"]);
    // About the origin (the tensor part's centre): I_O = I_R + M (|R|² 1 − R Rᵀ).
    let o = inertia(&[&path, "--about", "0,0,0"]);
    let mt = m1 + m2;
    let shifted: [[f64; 3]; 3] =
        std::array::from_fn(|j| std::array::from_fn(|k| want[j][k] + if j == k && j > 0 { mt * x * x } else { 0.0 }));
    close_matrix(&matrix(&o["tensor"]), &shifted, 1e-14);
}

#[test]
fn bad_tensors_exit_2_with_file_line_and_column() {
    let head = "[parameters]\nM = 1.0\na = 1.0\n\n[[parts]]\nshape = \"tensor\"\nmass = \"M\"\n";
    check_bad(
        "tensor_asymmetric.toml",
        &format!("{head}inertia = [[1, 0.5, 0],\n           [0.25, 1, 0],\n           [0, 0, 1]]\n"),
        "9:13",
        "the inertia tensor is not symmetric: I12 = 1/2 but I21 = 1/4",
    );
    check_bad(
        "tensor_negative_moment.toml",
        &format!("{head}inertia = [\"a\", \"-a\", \"a\"]\n"),
        "8:17",
        "the moment I22 is -1: expected a moment ≥ 0",
    );
    check_bad(
        "tensor_indefinite.toml",
        &format!("{head}inertia = [[1, 2, 0], [2, 1, 0], [0, 0, 1]]\n"),
        "8:11",
        "not positive semi-definite",
    );
    check_bad("tensor_triangle.toml", &format!("{head}inertia = [1, 1, 3]\n"), "8:11", "break the triangle inequality");
    check_bad("tensor_missing.toml", head, "5:1", "(tensor) has no `inertia`");
    check_bad("tensor_infinite.toml", &format!("{head}inertia = [1, \"1/(a - 1)\", 1]\n"), "8:15", "finite number");
}
