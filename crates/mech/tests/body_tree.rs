//! Body trees: bodies turning about one axis, bodies without angles, and bodies
//! placed in a parent's frame. Each tree's T, U and momenta are checked against
//! the same bodies as clusters of point masses, placed numerically with the
//! rotations multiplied out here and their velocities taken by central
//! differences, so that nothing of the derivation's own tree code is reused.

use crate::common::{derive, show};

/// Body-frame points (mass, r) of a rigid cluster, not coplanar.
const CLUSTER: [(f64, [f64; 3]); 4] =
    [(1.0, [0.3, -0.2, 0.5]), (2.0, [-0.4, 0.1, 0.2]), (0.5, [0.1, 0.6, -0.3]), (1.5, [0.2, 0.3, 0.4])];

/// A cluster's mass, centre of mass and inertia tensor about its origin.
fn mass_properties(points: &[(f64, [f64; 3])]) -> (f64, [f64; 3], [[f64; 3]; 3]) {
    let total: f64 = points.iter().map(|p| p.0).sum();
    let mut com = [0.0; 3];
    let mut inertia = [[0.0; 3]; 3];
    for &(m, r) in points {
        let r2: f64 = r.iter().map(|x| x * x).sum();
        for i in 0..3 {
            com[i] += m * r[i] / total;
            for j in 0..3 {
                inertia[i][j] += m * (if i == j { r2 } else { 0.0 } - r[i] * r[j]);
            }
        }
    }
    (total, com, inertia)
}

/// The body table of a cluster (tensor about its reference point, full 3×3).
fn cluster_table(name: &str, extra: &str) -> String {
    let (m, c, i) = mass_properties(&CLUSTER);
    let rows: Vec<String> = i.iter().map(|r| format!("[{:?}, {:?}, {:?}]", r[0], r[1], r[2])).collect();
    format!(
        "[[bodies]]\nname = \"{name}\"\nmass = {m:?}\ninertia = [{}]\ncenter_of_mass = [{:?}, {:?}, {:?}]\n{extra}",
        rows.join(", "),
        c[0],
        c[1],
        c[2]
    )
}

/// The passive turn about axis k (space → body components), as the notes write R_z.
fn turn(k: usize, a: f64) -> [[f64; 3]; 3] {
    let (s, c) = a.sin_cos();
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let mut m = [[0.0; 3]; 3];
    m[k][k] = 1.0;
    m[i][i] = c;
    m[j][j] = c;
    m[i][j] = s;
    m[j][i] = -s;
    m
}

fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Dᵀ v: body components to space components.
fn to_space(d: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| d[k][i] * v[k]).sum())
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] + b[i])
}

/// Where the points of a model are at (q, t): (mass, space position) of each.
type Placer<'a> = &'a dyn Fn(&[f64], f64) -> Vec<(f64, [f64; 3])>;

/// T and U (gravity g along −z) of point clusters placed by `place(q, t)`.
fn points_energy(place: Placer<'_>, q: &[f64], qd: &[f64], t: f64, g: f64) -> (f64, f64) {
    let h = 1e-5;
    let at = |s: f64| {
        let qs: Vec<f64> = q.iter().zip(qd).map(|(a, b)| a + s * b).collect();
        place(&qs, t + s)
    };
    let (ahead, behind, now) = (at(h), at(-h), at(0.0));
    let mut kinetic = 0.0;
    let mut potential = 0.0;
    for k in 0..now.len() {
        let v: Vec<f64> = (0..3).map(|i| (ahead[k].1[i] - behind[k].1[i]) / (2.0 * h)).collect();
        kinetic += 0.5 * now[k].0 * v.iter().map(|x| x * x).sum::<f64>();
        potential += now[k].0 * g * now[k].1[2];
    }
    (kinetic, potential)
}

fn value(d: &mech::Derivation, e: sym::ExprId, names: &[&str], q: &[f64], qd: &[f64], t: f64) -> f64 {
    let env = |n: &str| {
        if n == "t" {
            return Some(t);
        }
        if let Some(k) = names.iter().position(|c| *c == n) {
            return Some(q[k]);
        }
        if let Some(k) = names.iter().position(|c| format!("{c}'") == n) {
            return Some(qd[k]);
        }
        d.model().parameter(n)
    };
    d.pool().eval(e, &env).unwrap()
}

#[track_caller]
fn assert_close(what: &str, got: f64, want: f64) {
    assert!((got - want).abs() < 1e-7 * (1.0 + want.abs()), "{what}: derived {got}, points give {want}");
}

/// A cluster on Euler angles whose reference point moves with a coordinate and
/// the time carries a second cluster, turning about its parent's x axis at an
/// offset that moves with a coordinate, which carries a third without angles
/// of its own: T and U equal the points'.
#[test]
fn a_tree_of_bodies_moves_as_its_points_do() {
    let text = format!(
        "coordinates = [\"x\", \"al\", \"be\", \"ga\", \"ph\", \"s\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n{}{}{}",
        cluster_table("base", "angles = [\"al\", \"be\", \"ga\"]\nposition = [\"x\", \"0.3*x^2\", \"0.5*t\"]\n"),
        cluster_table(
            "arm",
            "parent = \"base\"\nangle = \"ph\"\naxis = \"x\"\nposition = [\"0.4\", \"s\", \"-0.2\"]\n"
        ),
        cluster_table("tip", "parent = \"arm\"\nposition = [\"0\", \"0.7\", \"0.1*s\"]\n"),
    );
    let d = derive(&text);
    let place = |q: &[f64], t: f64| -> Vec<(f64, [f64; 3])> {
        let (x, al, be, ga, ph, s) = (q[0], q[1], q[2], q[3], q[4], q[5]);
        let d_base = mech::euler::rotation_f64(al, be, ga);
        let x_base = [x, 0.3 * x * x, 0.5 * t];
        let d_arm = mul(&turn(0, ph), &d_base);
        let x_arm = add(x_base, to_space(&d_base, [0.4, s, -0.2]));
        let x_tip = add(x_arm, to_space(&d_arm, [0.0, 0.7, 0.1 * s]));
        let mut points = Vec::new();
        for (d, x0) in [(d_base, x_base), (d_arm, x_arm), (d_arm, x_tip)] {
            points.extend(CLUSTER.iter().map(|&(m, r)| (m, add(x0, to_space(&d, r)))));
        }
        points
    };
    let names = ["x", "al", "be", "ga", "ph", "s"];
    for (q, qd, t) in [
        ([0.3, 0.4, 1.1, -0.7, 0.8, -0.3], [0.5, 2.0, 0.7, -1.2, 1.5, 0.4], 0.3),
        ([-1.0, 2.0, 0.3, 1.9, -2.4, 0.6], [-2.2, 0.1, 1.3, 0.6, -0.8, -1.1], 1.7),
    ] {
        let (kinetic, potential) = points_energy(&place, &q, &qd, t, 9.81);
        assert_close("T", value(&d, d.kinetic().unwrap(), &names, &q, &qd, t), kinetic);
        assert_close("U", value(&d, d.potential().unwrap(), &names, &q, &qd, t), potential);
        // p = ∂T/∂q' by differences of the points' T, exact for any step since
        // T is quadratic in q' (a large one keeps the rounding small).
        for k in 0..6 {
            let h = 1.0;
            let mut up = qd;
            up[k] += h;
            let mut down = qd;
            down[k] -= h;
            let p =
                (points_energy(&place, &q, &up, t, 9.81).0 - points_energy(&place, &q, &down, t, 9.81).0) / (2.0 * h);
            assert_close(&format!("p_{}", names[k]), value(&d, d.momenta()[k], &names, &q, &qd, t), p);
        }
    }
    // The tip has no angle of its own: it turns with the arm, ω_tip = ω_arm.
    let (arm, tip) = (&d.bodies()[1], &d.bodies()[2]);
    for k in 0..3 {
        assert_eq!(show(&d, arm.omega[k]), show(&d, tip.omega[k]));
    }
}

/// A hinge about a tilted axis n (a steering head): the arm turns by ph about
/// n = (1, 2, 2)/3 of its parent's axes, D_rel = cos ph + (1 − cos ph) n nᵀ −
/// sin ph [n]ₓ written out here, and T, U agree with the points'.
#[test]
fn a_hinge_about_a_tilted_axis_moves_as_its_points_do() {
    let text = format!(
        "coordinates = [\"x\", \"be\", \"ph\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n{}{}",
        cluster_table("base", "angle = \"be\"\naxis = \"y\"\nposition = [\"x\", \"0\", \"0.2*t\"]\n"),
        cluster_table(
            "arm",
            "parent = \"base\"\nangle = \"ph\"\naxis = [\"1\", \"2\", \"2\"]\nposition = [\"0.5\", \"0\", \"0.3\"]\n"
        ),
    );
    let d = derive(&text);
    let n = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let hinge = |a: f64| -> [[f64; 3]; 3] {
        let (s, c) = a.sin_cos();
        let cross = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
        std::array::from_fn(|i| {
            std::array::from_fn(|j| if i == j { c } else { 0.0 } + (1.0 - c) * n[i] * n[j] - s * cross[i][j])
        })
    };
    let place = |q: &[f64], t: f64| -> Vec<(f64, [f64; 3])> {
        let d_base = turn(1, q[1]);
        let x_base = [q[0], 0.0, 0.2 * t];
        let d_arm = mul(&hinge(q[2]), &d_base);
        let x_arm = add(x_base, to_space(&d_base, [0.5, 0.0, 0.3]));
        let mut points = Vec::new();
        for (d, x0) in [(d_base, x_base), (d_arm, x_arm)] {
            points.extend(CLUSTER.iter().map(|&(m, r)| (m, add(x0, to_space(&d, r)))));
        }
        points
    };
    let names = ["x", "be", "ph"];
    for (q, qd, t) in [([0.3, 0.4, 1.1], [0.5, 2.0, -0.7], 0.3), ([-1.0, 2.0, -2.3], [-2.2, 0.1, 1.3], 1.7)] {
        let (kinetic, potential) = points_energy(&place, &q, &qd, t, 9.81);
        assert_close("T", value(&d, d.kinetic().unwrap(), &names, &q, &qd, t), kinetic);
        assert_close("U", value(&d, d.potential().unwrap(), &names, &q, &qd, t), potential);
    }
}

/// The notes' physical pendulum (a rigid body about a fixed pivot, one angle):
/// I θ'' = −M g l sin θ, with I the moment about the pivot.
#[test]
fn a_planar_body_is_the_physical_pendulum() {
    let d = derive(
        r#"
coordinates = ["th"]
gravity = "g"
[parameters]
M = 2.0
l = 0.5
I = 0.7
g = 9.81
[[bodies]]
mass = "M"
inertia = "I"
angle = "th"
center_of_mass = ["0", "-l"]
"#,
    );
    assert_eq!(show(&d, d.kinetic().unwrap()), "I*th'^2/2");
    assert_eq!(show(&d, d.potential().unwrap()), "-M*g*l*cos(th)");
    assert_eq!(show(&d, d.mass_matrix()[0][0]), "I");
    assert_eq!(show(&d, d.forcing()[0]), "-M*g*l*sin(th)");
}

/// A rod on a cart: the cart a body without angles, the rod a planar child at
/// the cart's reference point. T is the textbook one,
/// ½(M + m)x'² + m l x' θ' cos θ + ½(I_c + m l²)θ'², with l the distance to the
/// rod's centre and I_c its moment about the centre.
#[test]
fn a_rod_on_a_cart_is_the_textbook_cart_pendulum() {
    let d = derive(
        r#"
coordinates = ["x", "th"]
gravity = "g"
[parameters]
M = 3.0
m = 0.8
l = 0.6
g = 9.81
[[bodies]]
name = "cart"
mass = "M"
position = ["x", "0"]
[[bodies]]
name = "rod"
parent = "cart"
mass = "m"
inertia = "m*(2*l)^2/3"
angle = "th"
center_of_mass = ["0", "-l"]
"#,
    );
    let names = ["x", "th"];
    for (q, qd) in [([0.3f64, 0.4], [1.1f64, -0.7]), ([-1.0, 2.5], [0.2, 1.9])] {
        let (m_cart, m, l) = (3.0, 0.8, 0.6);
        let i_c = m * (2.0 * l) * (2.0 * l) / 12.0;
        let want = 0.5 * (m_cart + m) * qd[0] * qd[0]
            + m * l * qd[0] * qd[1] * q[1].cos()
            + 0.5 * (i_c + m * l * l) * qd[1] * qd[1];
        assert_close("T", value(&d, d.kinetic().unwrap(), &names, &q, &qd, 0.0), want);
        assert_close("U", value(&d, d.potential().unwrap(), &names, &q, &qd, 0.0), -m * 9.81 * l * q[1].cos());
    }
}

/// What a tree cannot be is refused where it is written.
#[test]
fn bad_trees_are_refused_at_the_entry() {
    let base = "coordinates = [\"a\", \"b\", \"c\"]\n[parameters]\nm = 1.0\n";
    let cases = [
        ("[[bodies]]\nname = \"arm\"\nparent = \"base\"\nmass = \"m\"\ninertia = \"1\"\nangle = \"a\"\n", "\"base\"", "no body named 'base' comes before this one"),
        ("[[bodies]]\nmass = \"m\"\ninertia = \"1\"\nangle = \"q\"\n", "\"q\"", "the angle 'q' is not a coordinate"),
        ("[[bodies]]\nmass = \"m\"\ninertia = \"1\"\nangle = \"a\"\naxis = \"w\"\n", "\"w\"", "'w' is not an axis"),
        ("[[bodies]]\nmass = \"m\"\ninertia = \"1\"\nangles = [\"a\", \"b\", \"c\"]\n", "\"1\"", "one moment of inertia is for a body that turns about one axis"),
        ("[[bodies]]\nmass = \"m\"\nangle = \"a\"\n", "[[bodies]]", "turns but has no `inertia`"),
        ("[[bodies]]\nmass = \"m\"\ninertia = \"1\"\nangle = \"a\"\nangles = [\"a\", \"b\", \"c\"]\n", "\"a\"", "either `angles` (three) or `angle` (one)"),
        (
            "[[bodies]]\nname = \"p\"\nmass = \"m\"\ninertia = \"1\"\nangle = \"a\"\naxis = \"x\"\n[[bodies]]\nparent = \"p\"\nmass = \"m\"\ninertia = \"1\"\nangle = \"b\"\n",
            "\"1\"",
            "turns about more than one axis",
        ),
        (
            "[[bodies]]\nmass = \"m\"\ninertia = \"1\"\nangle = \"a\"\naxis = \"x\"\nposition = [\"0\", \"1\"]\n",
            "[\"0\", \"1\"]",
            "this vector has 2 components, not 3",
        ),
    ];
    for (bodies, at, message) in cases {
        let text = format!("{base}{bodies}");
        let e = mech::Model::parse(&text, &[]).map(|_| ()).unwrap_err();
        assert!(e.message.contains(message), "{text}\n→ {}", e.message);
        let span = e.span.clone().expect("located");
        // The entry named: the first `at` in the last body's table.
        let last = text.rfind("[[bodies]]").unwrap();
        let want = last + text[last..].find(at).unwrap();
        assert_eq!(span.start, want, "{text}\n→ {} at {:?}", e.message, &text[span.clone()]);
    }
}

/// A rolling contact (`rolling = "disc"`) makes the constraints written by hand
/// in `examples/constraints/rolling_disc.toml`: v_C + ω × (P − C) = 0 with the
/// contact below the centre, equal at states where the disc stands (0 < th < π).
#[test]
fn a_rolling_contact_makes_the_hand_written_constraints() {
    let hand =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/constraints/rolling_disc.toml"))
            .unwrap();
    let start = hand.find("[[constraints]]").unwrap();
    let end = hand.find("[initial]").unwrap();
    let made = format!(
        "{}[[constraints]]\nname = \"roll\"\nrolling = \"disc\"\nradius = \"R\"\n\n{}",
        &hand[..start],
        &hand[end..]
    );
    let (a, b) = (mech::Model::parse(&hand, &[]).unwrap(), mech::Model::parse(&made, &[]).unwrap());
    assert_eq!(b.constraints.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(), ["roll_x", "roll_y"]);
    let names = ["x", "y", "ph", "th", "ps"];
    for (q, qd) in [
        ([0.3, -0.2, 0.7, 1.2, 2.0], [0.4, -1.1, 0.9, 0.3, -2.5]),
        ([1.0, 2.0, -2.1, 2.6, -0.4], [-0.7, 0.2, -1.4, 1.9, 0.8]),
        ([0.0, 0.0, 3.0, 0.4, 1.0], [1.5, 0.5, 0.2, -0.6, 3.1]),
    ] {
        let env = |n: &str| -> Option<f64> {
            if let Some(k) = names.iter().position(|c| *c == n) {
                return Some(q[k]);
            }
            if let Some(k) = names.iter().position(|c| format!("{c}'") == n) {
                return Some(qd[k]);
            }
            a.parameter(n)
        };
        for k in 0..2 {
            let want = a.pool.eval(a.constraints[k].expr.expr, &env).unwrap();
            let got = b.pool.eval(b.constraints[k].expr.expr, &env).unwrap();
            assert!((got - want).abs() < 1e-12 * (1.0 + want.abs()), "{}: {got} vs {want}", b.constraints[k].name);
        }
    }
    // With contact = "constraint", P_z = R sin(th) − R √(1 − cos²th) vanishes too.
    let kept = made.replace("radius = \"R\"\n", "radius = \"R\"\ncontact = \"constraint\"\n");
    let c = mech::Model::parse(&kept, &[]).unwrap();
    assert_eq!(c.constraints[2].name, "roll_z");
    let env = |n: &str| if n == "th" { Some(1.1) } else { c.parameter(n) };
    assert!(c.pool.eval(c.constraints[2].expr.expr, &env).unwrap().abs() < 1e-15);
}
