//! Each kind of `ModelError` a caller may branch on comes from the problem it
//! names: a caller reads the kind, never the message.

use mech::{Derivation, Model, ModelError, ModelErrorKind};

fn parse(text: &str) -> Result<Model, ModelError> {
    Model::parse(text, &[])
}

fn derive(text: &str) -> Result<Derivation, ModelError> {
    Derivation::new(parse(text)?)
}

const CARTESIAN_PENDULUM: &str = r#"
name = "pendulum in Cartesian coordinates"
coordinates = ["x", "y"]
gravity = "g"
[parameters]
m = 1.0
l = 1.0
g = 9.81
[[particles]]
mass = "m"
position = ["x", "y"]
[[constraints]]
name = "rod"
holonomic = "x^2 + y^2 - l^2"
[initial]
x = 0.6
y = -0.8
"#;

#[test]
fn a_coordinate_without_inertia_is_a_singular_mass_matrix() {
    let text = r#"
name = "no inertia"
coordinates = ["x", "y"]
[[particles]]
mass = "1"
position = ["x + y"]
"#;
    let e = derive(text).unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::SingularMassMatrix, "{e:?}");
}

#[test]
fn a_start_off_the_constraint_is_a_start_error() {
    let d = derive(CARTESIAN_PENDULUM).unwrap();
    assert!(d.check_constraints_at(&[0.6, -0.8], &[0.0, 0.0]).is_ok());
    let e = d.check_constraints_at(&[0.7, -0.8], &[0.0, 0.0]).unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::Start, "{e:?}");
}

#[test]
fn an_analysis_that_ignores_constraints_is_unsupported() {
    let d = derive(CARTESIAN_PENDULUM).unwrap();
    let e = d.reject_constraints("the normal modes").unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::Unsupported, "{e:?}");
    assert_eq!(e.kind.code(), "unsupported");
}

#[test]
fn a_constraint_free_of_the_coordinates_does_nothing() {
    let text = CARTESIAN_PENDULUM.replace("x^2 + y^2 - l^2", "l - 1");
    let e = derive(&text).unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::DoesNothing, "{e:?}");
}

#[test]
fn a_body_file_that_cannot_be_read_is_a_file_error() {
    let text = r#"
name = "top"
coordinates = ["al", "be", "ga"]
[[bodies]]
name = "cone"
inertia = "no_such_body.toml"
angles = ["al", "be", "ga"]
position = ["0", "0", "0"]
"#;
    let e = parse(text).unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::File, "{e:?}");
}

#[test]
fn other_mistakes_are_invalid() {
    let e = parse("name = \"x\"\ncoordinates = [\"q\"]\nlagrangian = \"q'^2/2 - k*q\"\n").unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::Invalid, "{e:?}");
}
