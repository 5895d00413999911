//! `lagrange import`: URDF robots as model files. The robots of examples/urdf
//! import, derive, simulate, linearize and report; a two-link arm's small
//! oscillations match the compound double pendulum's worked by hand; broken
//! URDFs (crates/cli/tests/bad_urdf) exit 2 at their place. The comparison with
//! Pinocchio at random states is `pinocchio_urdf.py` beside this file.

mod common;

use common::{is_close, json, ok, run, TempFile};

const EXAMPLES: &[&str] = &["planar_arm", "spatial_arm", "cart_pendulum", "floating_body"];

/// Imports an example into a temporary model file.
fn import(name: &str) -> TempFile {
    let model = TempFile::new(name, "toml");
    ok(&["import", &format!("examples/urdf/{name}.urdf"), "-o", model.path()]);
    model
}

#[test]
fn broken_urdfs_exit_2_at_their_place() {
    // (file, line:col, what the message says)
    let cases = [
        ("malformed", "7:3", "this is not well-formed XML"),
        ("unknown_joint_type", "4:25", "joint 'j' has the unknown type 'ball'"),
        ("missing_link", "6:18", "joint 'j' names the link 'forearm', which the file does not have"),
        ("cycle", "5:3", "the joints form a cycle"),
        ("cycle_off_root", "6:3", "the joints form a cycle: a ← b ← a"),
        ("two_parents", "7:66", "link 'b' is the child of joints 'k' and 'l'"),
        ("no_inertial", "3:3", "link 'arm' moves (joint 'j' is continuous) but it has no <inertial>"),
        ("bad_number", "5:18", "`xyz` is \"0 0 one\": 'one' is not a finite number"),
    ];
    for (name, at, message) in cases {
        let path = format!("crates/cli/tests/bad_urdf/{name}.urdf");
        let r = run(&["import", &path]);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.starts_with(&format!("error: {path}:{at}: {message}")), "{}", r.describe());
        assert!(r.stdout.is_empty(), "{}", r.describe());
    }
    // Every broken file of the folder is in the table.
    let files = std::fs::read_dir(common::repo_root().join("crates/cli/tests/bad_urdf")).unwrap().count();
    assert_eq!(files, cases.len());
}

#[test]
fn examples_derive_simulate_linearize_and_report() {
    for name in EXAMPLES {
        let model = import(name);
        // Stdout and -o write the same model.
        let printed = ok(&["import", &format!("examples/urdf/{name}.urdf")]).stdout;
        assert_eq!(printed, std::fs::read_to_string(&model.0).unwrap());
        let d = json(&["derive", model.path(), "--format", "json"]);
        let n = d["coordinates"].as_array().unwrap().len();
        assert_eq!(d["mass_matrix"].as_array().unwrap().len(), n);
        // Started off rest (every coordinate at 0.3, every rate at 0.2): energy is kept.
        let text = std::fs::read_to_string(&model.0).unwrap();
        let moved = TempFile::with_text(name, &text.replace("' = 0\n", "' = 0.2\n").replace(" = 0\n", " = 0.3\n"));
        let s = json(&["simulate", moved.path(), "--until", "1", "--summary", "json"]);
        let drift = s["invariants"]["H"]["max_rel_drift"].as_f64().unwrap();
        assert!(drift < 1e-8, "{name}: H drifts by {drift}");
        let html = TempFile::new(name, "html");
        ok(&["report", moved.path(), "--until", "0.5", "-o", html.path()]);
        let lin = run(&["linearize", model.path(), "--format", "json"]);
        if *name == "floating_body" {
            // A free body falls: no equilibrium, and linearize says so.
            assert_eq!(lin.code, Some(2), "{}", lin.describe());
        } else {
            assert_eq!(lin.code, Some(0), "{}", lin.describe());
        }
    }
}

#[test]
fn two_link_arm_oscillates_as_the_compound_double_pendulum() {
    // Rods of length 1 hanging along -z, masses m1 = 1, m2 = 0.5, moments
    // about their centres m l²/12 (as in the URDF), both joints about y.
    let (m1, m2, g): (f64, f64, f64) = (1.0, 0.5, 9.81);
    let (c, l1) = (0.5, 1.0);
    let (i1, i2) = (m1 / 12.0, m2 / 12.0);
    // T = ½ q'ᵀ M q', U = ½ qᵀ K q about hanging straight down (relative angles).
    let m22 = i2 + m2 * c * c;
    let m12 = m22 + m2 * l1 * c;
    let m11 = i1 + m1 * c * c + m2 * l1 * l1 + m22 + 2.0 * m2 * l1 * c;
    let (k11, k22) = (g * (m1 * c + m2 * l1) + g * m2 * c, g * m2 * c);
    let k12 = k22;
    // det(K − ω² M) = 0: a ω⁴ − b ω² + k = 0.
    let a = m11 * m22 - m12 * m12;
    let b = k11 * m22 + k22 * m11 - 2.0 * k12 * m12;
    let k = k11 * k22 - k12 * k12;
    let root = (b * b - 4.0 * a * k).sqrt();
    let want = [((b - root) / (2.0 * a)).sqrt(), ((b + root) / (2.0 * a)).sqrt()];

    let model = import("planar_arm");
    let lin = json(&["linearize", model.path(), "--format", "json"]);
    let mut got: Vec<f64> =
        lin["eigenvalues"].as_array().unwrap().iter().filter_map(|e| e["im"].as_f64()).filter(|w| *w > 0.0).collect();
    got.sort_by(f64::total_cmp);
    assert_eq!(got.len(), 2, "{lin}");
    for (w, v) in got.iter().zip(want) {
        assert!(is_close(*w, v, 1e-9, 0.0), "ω = {w}, by hand {v}");
    }
}

#[test]
fn import_refuses_to_overwrite_its_input() {
    let r = run(&["import", "examples/urdf/planar_arm.urdf", "-o", "examples/urdf/planar_arm.urdf"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("is an input of this command"), "{}", r.describe());
}
