//! `lagrange import`: URDF robots as model files. The robots of examples/urdf
//! import, derive, simulate, linearize and report; a two-link arm's small
//! oscillations match the compound double pendulum's worked by hand; broken
//! URDFs (crates/cli/tests/bad_urdf) exit 2 at their place. The comparison with
//! Pinocchio at random states is `pinocchio_urdf.py` beside this file.

use crate::common;

use crate::common::{is_close, json, ok, run, TempFile};

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
        (
            "no_moving_joint",
            "3:3",
            "the robot has only fixed joints: every link is welded to the root link 'base_link'",
        ),
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

/// A model naming `urdf` (path relative to the model file) with the example URDF.
fn naming_model(urdf: &str, rest: &str) -> TempFile {
    let path = common::repo_root().join("examples/urdf").join(urdf);
    TempFile::with_text("named", &format!("urdf = {:?}\n{rest}", path.display().to_string()))
}

#[test]
fn a_model_naming_a_urdf_derives_as_the_imported_model() {
    for name in EXAMPLES {
        let floating = if *name == "floating_body" { "" } else { "floating_base = false\n" };
        let named = naming_model(&format!("{name}.urdf"), floating);
        let imported = import(name);
        let a = json(&["derive", named.path(), "--format", "json"]);
        let b = json(&["derive", imported.path(), "--format", "json"]);
        for key in ["coordinates", "mass_matrix", "forcing", "parameters", "lagrangian"] {
            assert_eq!(a[key], b[key], "{name}: {key}");
        }
    }
    // The example adds a spring at the elbow, sets g and starts the shoulder at 0.5.
    let imported = import("planar_arm");
    let text = std::fs::read_to_string(&imported.0).unwrap();
    let text = text.replace("g = 9.81\n", "g = 9.81\nk = 2\n").replace("shoulder = 0\n", "shoulder = 0.5\n")
        + "\n[forces]\nelbow = \"-k*elbow\"\n";
    let by_hand = TempFile::with_text("by_hand", &text);
    let a = json(&["derive", "examples/urdf/planar_arm_model.toml", "--format", "json"]);
    let b = json(&["derive", by_hand.path(), "--format", "json"]);
    for key in ["mass_matrix", "forcing", "parameters"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    // Same start, same motion; the model's g wins over the URDF's.
    let args =
        |m: &str| json(&["simulate", m, "--until", "1", "--summary", "json", "--set", "g=1.62"])["final"].to_string();
    assert_eq!(args("examples/urdf/planar_arm_model.toml"), args(by_hand.path()));
}

#[test]
fn a_model_naming_a_urdf_refuses_at_the_place() {
    let arm = "planar_arm.urdf";
    let cases: Vec<(TempFile, &str, &str)> = vec![
        (naming_model("missing.urdf", ""), "1:8", "cannot read the URDF file"),
        (naming_model("../../crates/cli/tests/bad_urdf/bad_number.urdf", ""), "1:8", "in the URDF file"),
        (naming_model(arm, "[initial]\nwrist = 1\n"), "3:1", "[initial] names 'wrist'"),
        (naming_model(arm, "coordinates = [\"a\"]\n"), "2:15", "takes its `coordinates` from it"),
        (naming_model(arm, "lagrangian = \"a\"\n"), "2:14", "give either `lagrangian` or `urdf`"),
        (naming_model(arm, "[[bodies]]\nmass = 1\nposition = [0, 0]\n"), "2:1", "takes its [[bodies]] from it"),
        (naming_model(arm, "[parameters]\nelbow = 1\n"), "3:1", "parameter 'elbow' has the name of a coordinate"),
        (naming_model(arm, "floating_base = 1\n"), "2:17", ""),
    ];
    for (model, at, message) in &cases {
        let r = run(&["derive", model.path()]);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.starts_with(&format!("error: {}:{at}: ", model.path())), "{}", r.describe());
        assert!(r.stderr.lines().next().unwrap().contains(message), "{}", r.describe());
    }
    // The bad URDF's own place is named too.
    let r = run(&["derive", cases[1].0.path()]);
    assert!(r.stderr.contains("bad_number.urdf:5:18: `xyz` is \"0 0 one\""), "{}", r.describe());
    // floating_base without urdf.
    let lone = TempFile::with_text("lone", "floating_base = true\ncoordinates = [\"a\"]\nkinetic = \"a'^2\"\n");
    let r = run(&["derive", lone.path()]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("1:17: `floating_base` belongs to a model that names a `urdf`"), "{}", r.describe());
    // The URDF is an input: no output may replace it.
    let r = run(&[
        "simulate",
        "examples/urdf/planar_arm_model.toml",
        "--until",
        "0.1",
        "--out",
        "examples/urdf/planar_arm.urdf",
    ]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(r.stderr.contains("is an input of this command"), "{}", r.describe());
}
