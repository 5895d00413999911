//! Mechanisms as engineers write them, run through the binary: bodies in a tree
//! (planar bodies, a body without angles, a body in its parent's frame), loads
//! at points and on bodies, and inputs u(t). Each example is checked against
//! results worked out here by hand: the double compound pendulum's normal
//! modes, the cart's momentum under its input force, and the angular momentum
//! in space of a body under a torque fixed in space.

use crate::common;

use crate::common::{json, ok, run as lagrange, Csv, TempFile};

/// The double compound pendulum's frequencies against the 2×2 secular equation
/// of T and U written from the rods' kinematics: the lower rod's centre moves
/// at l1 a' + (l2/2)(a' + b') about the straight-down equilibrium.
#[test]
fn a_chain_of_rods_has_the_hand_worked_normal_modes() {
    let v = json(&["modes", "examples/compound_pendulum.toml", "--at", "a=0", "--at", "b=0", "--format", "json"]);
    let (m1, m2, l1, l2, g) = (1.0f64, 0.5f64, 1.0f64, 0.8f64, 9.81f64);
    let t = [
        [
            m1 * l1 * l1 / 3.0 + m2 * (l1 + l2 / 2.0).powi(2) + m2 * l2 * l2 / 12.0,
            m2 * (l1 + l2 / 2.0) * l2 / 2.0 + m2 * l2 * l2 / 12.0,
        ],
        [0.0, m2 * l2 * l2 / 4.0 + m2 * l2 * l2 / 12.0],
    ];
    let t = [[t[0][0], t[0][1]], [t[0][1], t[1][1]]];
    // U = m1 g (−l1/2 cos a) + m2 g (−l1 cos a − l2/2 cos(a + b)), its Hessian at 0.
    let u =
        [[g * (m1 * l1 / 2.0 + m2 * l1 + m2 * l2 / 2.0), g * m2 * l2 / 2.0], [g * m2 * l2 / 2.0, g * m2 * l2 / 2.0]];
    // det(U − w T) = 0: a w² + b w + c = 0.
    let a = t[0][0] * t[1][1] - t[0][1] * t[0][1];
    let b = -(u[0][0] * t[1][1] + u[1][1] * t[0][0] - 2.0 * u[0][1] * t[0][1]);
    let c = u[0][0] * u[1][1] - u[0][1] * u[0][1];
    let disc = (b * b - 4.0 * a * c).sqrt();
    let want = [((-b - disc) / (2.0 * a)).sqrt(), ((-b + disc) / (2.0 * a)).sqrt()];
    let got: Vec<f64> = v["frequencies"].as_array().unwrap().iter().map(|f| f.as_f64().unwrap()).collect();
    for k in 0..2 {
        assert!((got[k] - want[k]).abs() < 1e-10 * want[k], "Ω{}: {} vs {}", k + 1, got[k], want[k]);
        for j in 0..2 {
            assert!((v["T"][k][j].as_f64().unwrap() - t[k][j]).abs() < 1e-12, "T[{k}][{j}]");
        }
    }
}

/// The cart is pushed by F = F0 sin 2t and nothing else acts along x, so its
/// momentum p_x = (M + m)x' + m l th' cos th grows as F0 (1 − cos 2t)/2.
#[test]
fn an_input_force_changes_the_cart_momentum_as_its_integral() {
    let out = TempFile::new("cart", "csv");
    ok(&["simulate", "examples/cart_pendulum.toml", "--until", "6", "--samples", "61", "--out", out.path()]);
    let csv = Csv::read(out.path());
    let (mc, m, l, f0) = (2.0f64, 0.5f64, 0.4f64, 1.0f64);
    let (t, xd, th, thd) = (csv.column("t"), csv.column("x'"), csv.column("th"), csv.column("th'"));
    for k in 0..t.len() {
        let p = (mc + m) * xd[k] + m * l * thd[k] * th[k].cos();
        let want = f0 * (1.0 - (2.0 * t[k]).cos()) / 2.0;
        assert!((p - want).abs() < 1e-8, "p_x = {p} at t = {}, want {want}", t[k]);
    }
    assert!(th.iter().any(|&x| (x - 0.2).abs() > 1e-2), "the rod swings");
    // derive keeps F and tau as symbols and shows B = ∂f/∂u.
    let d = json(&["derive", "examples/cart_pendulum.toml", "--format", "json"]);
    assert_eq!(d["B"], serde_json::json!([["1", "0"], ["0", "1"]]));
    assert_eq!(d["inputs"][0]["value"], "F0*sin(2*t)");
    assert_eq!(d["inputs_affine"], true);
}

/// `linearize` keeps the inputs and gives B: the cart and rod's accelerations
/// respond to (F, tau) through M⁻¹, M = [[M + m, m l], [m l, 4 m l²/3]] at th = 0,
/// and A's th column is M⁻¹ (0, −m g l).
#[test]
fn linearize_gives_b_for_the_inputs() {
    let v = json(&["linearize", "examples/cart_pendulum.toml", "--at", "x=0", "--at", "th=0", "--format", "json"]);
    assert_eq!(v["inputs"], serde_json::json!(["F", "tau"]));
    let (mc, m, l, g) = (2.0f64, 0.5f64, 0.4f64, 9.81f64);
    let (a, b, c) = (mc + m, m * l, 4.0 * m * l * l / 3.0);
    let det = a * c - b * b;
    let inv = [[c / det, -b / det], [-b / det, a / det]];
    for i in 0..2 {
        for j in 0..2 {
            let got = v["B"][2 + i][j].as_f64().unwrap();
            assert!((got - inv[i][j]).abs() < 1e-12 * inv[i][j].abs().max(1.0), "B[{}][{j}] = {got}", 2 + i);
            assert_eq!(v["B"][i][j].as_f64().unwrap(), 0.0);
        }
        let got = v["A"][2 + i][1].as_f64().unwrap();
        let want = -inv[i][1] * m * g * l;
        assert!((got - want).abs() < 1e-12 * want.abs(), "A[{}][1] = {got}, want {want}", 2 + i);
    }
}

/// A torque fixed in space on a free asymmetric body: L in space (Dᵀ L_body,
/// with D = R_z(ps) R_y(th) R_x(ph) written out here) grows as L(0) + τ t.
#[test]
fn a_torque_fixed_in_space_adds_to_the_angular_momentum_in_space() {
    let out = TempFile::new("torque", "csv");
    ok(&["simulate", "examples/tops/torqued_body.toml", "--until", "10", "--samples", "101", "--out", out.path()]);
    let csv = Csv::read(out.path());
    let turn = |k: usize, a: f64| -> [[f64; 3]; 3] {
        let (s, c) = a.sin_cos();
        match k {
            0 => [[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]],
            1 => [[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]],
            _ => [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]],
        }
    };
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    };
    let space = |k: usize| -> [f64; 3] {
        let (ph, th, ps) = (csv.column("ph")[k], csv.column("th")[k], csv.column("ps")[k]);
        let d = mul(turn(2, ps), mul(turn(1, th), turn(0, ph)));
        let lb = [csv.column("L1")[k], csv.column("L2")[k], csv.column("L3")[k]];
        std::array::from_fn(|i| (0..3).map(|j| d[j][i] * lb[j]).sum())
    };
    let l0 = space(0);
    let t = csv.column("t");
    for k in 0..t.len() {
        let l = space(k);
        let want = [l0[0], l0[1] + 0.2 * t[k], l0[2]];
        for i in 0..3 {
            assert!((l[i] - want[i]).abs() < 1e-7, "L_space{} = {} at t = {}, want {}", i + 1, l[i], t[k], want[i]);
        }
    }
}

/// The leaning disc (a body on Euler angles with rolling constraints), started
/// upright without lean, rolls straight along x at its speed v.
#[test]
fn an_upright_rolling_disc_rolls_straight() {
    let out = TempFile::new("disc", "csv");
    let args = ["--until", "5", "--samples", "51", "--set", "lean=0", "--set", "v=1.5", "--out", out.path()];
    ok(&[&["simulate", "examples/constraints/rolling_disc.toml"][..], &args[..]].concat());
    let csv = Csv::read(out.path());
    let (t, x, y, th) = (csv.column("t"), csv.column("x"), csv.column("y"), csv.column("th"));
    for k in 0..t.len() {
        assert!((x[k] - 1.5 * t[k]).abs() < 1e-9, "x = {} at t = {}", x[k], t[k]);
        assert!(
            y[k].abs() < 1e-9 && (th[k] - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
            "y = {}, th = {}",
            y[k],
            th[k]
        );
    }
}

/// The coin whose contact is stated (`rolling = "coin"`, the centre's height a
/// coordinate held by the contact constraint) moves as the disc whose
/// constraints are written by hand with the height worked out, and its centre
/// stays at R sin(th).
#[test]
fn a_stated_rolling_contact_moves_as_the_hand_written_one() {
    let (a, b) = (TempFile::new("coin", "csv"), TempFile::new("disc", "csv"));
    ok(&["simulate", "examples/constraints/rolling_coin.toml", "--until", "5", "--samples", "51", "--out", a.path()]);
    ok(&["simulate", "examples/constraints/rolling_disc.toml", "--until", "5", "--samples", "51", "--out", b.path()]);
    let (coin, disc) = (Csv::read(a.path()), Csv::read(b.path()));
    for name in ["x", "y", "ph", "th", "ps", "x'", "th'"] {
        let (p, q) = (coin.column(name), disc.column(name));
        for k in 0..p.len() {
            assert!((p[k] - q[k]).abs() < 1e-7 * (1.0 + q[k].abs()), "{name}: {} vs {} (row {k})", p[k], q[k]);
        }
    }
    let (z, th) = (coin.column("z"), coin.column("th"));
    for k in 0..z.len() {
        assert!((z[k] - 0.5 * th[k].sin()).abs() < 1e-9, "z = {} at th = {}", z[k], th[k]);
    }
}

/// The upright rolling disc, a body with rolling constraints, linearized about
/// rolling straight at spin W: its lean obeys λ² = (4/5)(g/R − 3W²) (a thin
/// disc; the classic bound W² > g/3R), so W = 2 falls over and W = 4 wobbles.
/// The same with the contact stated (rolling_coin, its height eliminated).
#[test]
fn the_rolling_disc_is_stable_above_the_classic_speed() {
    let (g, r) = (9.81f64, 0.5f64);
    for (file, extra) in [
        ("examples/constraints/rolling_disc.toml", &[][..]),
        ("examples/constraints/rolling_coin.toml", &["--at", "z=0.5"][..]),
    ] {
        for w in [2.0f64, 4.0] {
            let (rate, v) = (format!("ps={}", -w), format!("v={}", r * w));
            let mut args = vec!["linearize", file, "--about", "steady", "--rate", &rate, "--set", &v];
            args.extend(["--at", "th=1.5707963267948966", "--format", "json"]);
            args.extend(extra);
            let out = json(&args);
            let lam2 = 0.8 * (g / r - 3.0 * w * w);
            let nonzero: Vec<(f64, f64)> = out["eigenvalues"]
                .as_array()
                .unwrap()
                .iter()
                .map(|e| (e["re"].as_f64().unwrap(), e["im"].as_f64().unwrap()))
                .filter(|(re, im)| re.abs() + im.abs() > 1e-9)
                .collect();
            assert_eq!(nonzero.len(), 2, "{file} W = {w}: {nonzero:?}");
            let (re, im) = nonzero[0];
            let size = lam2.abs().sqrt();
            if lam2 > 0.0 {
                assert!((re.abs() - size).abs() < 1e-9 && im.abs() < 1e-9, "{file} W = {w}: {re} {im}, want ±{size}");
                assert_eq!(out["stability"], "unstable");
            } else {
                assert!((im.abs() - size).abs() < 1e-9 && re.abs() < 1e-9, "{file} W = {w}: {re} {im}, want ±{size}i");
            }
        }
    }
}

/// What a load or an input cannot be is refused at its entry (exit 2).
#[test]
fn bad_loads_and_inputs_exit_2_at_the_entry() {
    let cart = std::fs::read_to_string(common::repo_root().join("examples/cart_pendulum.toml")).unwrap();
    let coin = std::fs::read_to_string(common::repo_root().join("examples/constraints/rolling_coin.toml")).unwrap();
    let rolling = [
        ("rolling = \"coin\" ", "rolling = \"wheel\" ", "'wheel' is not a body of the model", "\"wheel\""),
        ("radius = \"R\"\n", "", "the rolling contact has no `radius`", "[[constraints]]"),
        ("contact = \"constraint\"  ", "contact = \"glued\"  ", "not a kind of contact", "\"glued\""),
        ("rolling = \"coin\" ", "velocity = \"x'\" ", "`radius` belongs to a rolling contact", "\"R\"\ncontact"),
    ];
    let cases = [
        ("body = \"cart\"\nforce", "body = \"truck\"\nforce", "the model does not have", "\"truck\""),
        ("body = \"rod\"\ntorque", "torque", "the load has no `body`", "\"tau\""),
        ("torque = \"tau\"", "torque = \"tau\"\nforce = [\"1\", \"0\"]", "a force or a torque, not both", "\"tau\""),
        ("force = [\"F\", \"0\"]", "force = [\"F\", \"0\", \"0\"]", "3 components, not 2", "[\"F\", \"0\", \"0\"]"),
        ("force = [\"F\", \"0\"]", "force = [\"F\", \"0\"]\naxes = \"diagonal\"", "not a set of axes", "\"diagonal\""),
        ("F = \"F0*sin(2*t)\"", "F = \"F0*sin(2*x)\"", "'x' is not allowed here", "x)\""),
        ("F = \"F0*sin(2*t)\"", "g = \"t\"", "name of a coordinate, a parameter", "g = \"t\""),
        // Loads that would vanish from the equations: a torque on a body that
        // does not turn, x and y torques in a planar model, a force at a point
        // no coordinate moves.
        ("body = \"rod\"\ntorque", "body = \"cart\"\ntorque", "'cart' does not turn", "\"tau\""),
        ("torque = \"tau\"", "torque = [\"0\", \"0\", \"tau\"]", "one value, about z", "[\"0\", \"0\", \"tau\"]"),
        (
            "body = \"cart\"\nforce = [\"F\", \"0\"]",
            "force = [\"F\", \"0\"]\nat = [\"1\", \"t\"]",
            "no coordinate moves",
            "[\"1\", \"t\"]",
        ),
    ];
    let all = cases.iter().map(|c| (&cart, c)).chain(rolling.iter().map(|c| (&coin, c)));
    for (base, &(from, to, what, at)) in all {
        assert_eq!(base.matches(from).count(), 1, "{from}");
        let text = base.replacen(from, to, 1);
        let file = TempFile::with_text("bad-load", &text);
        let r = lagrange(&["derive", file.path()]);
        assert_eq!(r.code, Some(2), "{to}: {}", r.describe());
        assert!(r.stderr.contains(what), "{to}: {}", r.stderr);
        // The line and column of the entry: `at`, found once in the text.
        assert_eq!(text.matches(at).count(), 1, "{at}");
        let offset = text.find(at).unwrap();
        let line = text[..offset].matches('\n').count() + 1;
        let col = offset - text[..offset].rfind('\n').map_or(0, |i| i + 1) + 1;
        assert!(r.stderr.contains(&format!(":{line}:{col}:")), "{to}: want {line}:{col}: {}", r.stderr);
    }
}
