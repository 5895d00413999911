//! Gravity as a field vector (`gravity = ["g", "0"]`) besides the notes'
//! strength along −y or −z (`gravity = "g"`): the same mechanics written on
//! other axes gives the same equations, and what cannot be is refused where it
//! is written.

use crate::common::{derive, show};

/// The notes' pendulum (y up, gravity along −y).
const DOWN: &str = r#"
coordinates = ["th"]
gravity = "g"
[parameters]
m = 1.5
l = 0.7
g = 9.81
[[particles]]
mass = "m"
position = ["l*sin(th)", "-l*cos(th)"]
"#;

#[test]
fn a_pendulum_with_gravity_along_plus_x_has_the_notes_equation() {
    // x down the page: the bob at (l cos th, l sin th), gravity along +x.
    let along_x = r#"
coordinates = ["th"]
gravity = ["g", "0"]
[parameters]
m = 1.5
l = 0.7
g = 9.81
[[particles]]
mass = "m"
position = ["l*cos(th)", "l*sin(th)"]
"#;
    let (a, b) = (derive(DOWN), derive(along_x));
    assert_eq!(show(&a, a.forcing()[0]), "-g*l*m*sin(th)");
    assert_eq!(show(&b, b.forcing()[0]), show(&a, a.forcing()[0]));
    assert_eq!(show(&b, b.mass_matrix()[0][0]), "l^2*m");
    assert_eq!(show(&b, b.hamiltonian().unwrap()), show(&a, a.hamiltonian().unwrap()));
}

#[test]
fn a_spherical_pendulum_with_y_up_in_3d_is_the_one_with_z_up() {
    let z_up = r#"
coordinates = ["th", "ph"]
gravity = "g"
[parameters]
m = 1.0
l = 2.0
g = 9.81
[[particles]]
mass = "m"
position = ["l*sin(th)*cos(ph)", "l*sin(th)*sin(ph)", "-l*cos(th)"]
"#;
    // The same bob with the axes renamed: y is up, gravity = (0, −g, 0).
    let y_up = r#"
coordinates = ["th", "ph"]
gravity = ["0", "-g", "0"]
[parameters]
m = 1.0
l = 2.0
g = 9.81
[[particles]]
mass = "m"
position = ["l*sin(th)*sin(ph)", "-l*cos(th)", "l*sin(th)*cos(ph)"]
"#;
    let (a, b) = (derive(z_up), derive(y_up));
    for i in 0..2 {
        assert_eq!(show(&b, b.forcing()[i]), show(&a, a.forcing()[i]), "equation {i}");
    }
    assert_eq!(b.cyclic().len(), 1, "ph stays cyclic");
}

#[test]
fn a_body_falls_along_the_field_vector() {
    // A free body whose centre of mass sits at the reference point (x, y, z):
    // U = −M g·r = M g y for gravity (0, −g, 0).
    let text = r#"
coordinates = ["x", "y", "z", "al", "be", "ga"]
gravity = [0, "-g", 0]
[parameters]
M = 2.0
g = 9.81
[[bodies]]
mass = "M"
inertia = ["1", "2", "3"]
angles = ["al", "be", "ga"]
position = ["x", "y", "z"]
"#;
    let d = derive(text);
    let names = d.coordinate_names();
    let at = |n: &str| names.iter().position(|c| *c == n).unwrap();
    assert_eq!(show(&d, d.forcing()[at("y")]), "-M*g");
    assert_eq!(show(&d, d.forcing()[at("x")]), "0");
    assert_eq!(show(&d, d.forcing()[at("z")]), "0");
}

#[test]
fn a_gravity_vector_that_does_not_fit_the_positions_is_refused_where_it_is() {
    let wrong_size = DOWN.replace("gravity = \"g\"", "gravity = [\"0\", \"-g\", \"0\"]");
    let e = mech::Model::parse(&wrong_size, &[]).expect_err("2-D positions with a 3-vector");
    assert!(e.to_string().contains("the gravity vector has 3 components, so positions have 3, not 2"), "{e}");
    let one = DOWN.replace("gravity = \"g\"", "gravity = [\"g\"]");
    let e = mech::Model::parse(&one, &[]).expect_err("one component");
    assert!(e.to_string().contains("has 2 or 3 components, not 1"), "{e}");
    let start = one.find("[\"g\"]").unwrap();
    assert_eq!(e.span, Some(start..start + 5));
    let unknown = DOWN.replace("gravity = \"g\"", "gravity = [\"0\", \"-G\"]");
    let e = mech::Model::parse(&unknown, &[]).expect_err("unknown name");
    assert!(e.to_string().contains('G'), "{e}");
}
