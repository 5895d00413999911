//! Test models with known answers, shared by `mech`'s unit tests and its
//! integration tests (`tests/common` includes this file): each is the text of a
//! model file, small enough to read in the test that uses it, with the results
//! the lecture notes print for it.

#![allow(dead_code)] // each test binary uses some of the models

/// The planar pendulum (notes 2.2.1 b (iv), 2.4.2 d (ii)): p = m l² θ', H = p²/(2ml²) − mgl cos θ.
pub const PENDULUM: &str = r#"
name = "pendulum"
coordinates = ["th"]
gravity = "g"
[parameters]
m = 2.0
l = 1.5
g = 9.81
[[particles]]
mass = "m"
position = ["l*sin(th)", "-l*cos(th)"]
[initial]
th = 0.01
"th'" = 0.0
"#;

/// The bead on a wire turning at ω (notes 2.4.2 d (iii)): H is conserved but is not the energy.
pub const ROTATING_WIRE: &str = r#"
coordinates = ["r"]
[parameters]
m = 1.0
om = 2.0
[[particles]]
mass = "m"
position = ["r*cos(om*t)", "r*sin(om*t)"]
[initial]
r = 1.0
"r'" = 0.0
"#;

/// Kepler's problem in polar coordinates (notes 3.1): θ is cyclic, p_θ = μr²θ' conserved.
pub const KEPLER: &str = r#"
coordinates = ["r", "th"]
lagrangian = "mu*(r'^2 + r^2*th'^2)/2 + k/r"
[parameters]
mu = 1.0
k = 1.0
[initial]
r = 1.0
"r'" = 0.0
th = 0.0
"th'" = 1.2
"#;

/// A damped oscillator: Rayleigh's R takes energy out, so H is not conserved.
pub const DAMPED: &str = r#"
coordinates = ["x"]
kinetic = "m*x'^2/2"
potential = "k*x^2/2"
dissipation = "c*x'^2/2"
[parameters]
m = 1.0
k = 4.0
c = 0.1
[initial]
x = 1.0
"x'" = 0.0
"#;

/// The pendulum in Cartesian coordinates with the rod as a holonomic
/// constraint (notes 2.6.3): the multiplier gives the rod's tension.
pub const CONSTRAINED_PENDULUM: &str = r#"
coordinates = ["x", "y"]
gravity = "g"
[parameters]
m = 2.0
l = 1.5
g = 9.81
[[particles]]
mass = "m"
position = ["x", "y"]
[[constraints]]
name = "rod"
holonomic = "x^2 + y^2 - l^2"
[initial]
x = 0.0
y = -1.5
"x'" = 1.0
"y'" = 0.0
"#;

/// x'' = x³ from x = x' = 1: x reaches infinity at t = 1.3110287771 (a run must fail there).
pub const BLOW_UP: &str = r#"
coordinates = ["x"]
kinetic = "x'^2/2"
potential = "-x^4/4"
[initial]
x = 1.0
"x'" = 1.0
"#;

/// The derivation of a model text, which must be valid.
#[track_caller]
pub fn derive(text: &str) -> mech::Derivation {
    let model = mech::Model::parse(text, &[]).unwrap_or_else(|e| panic!("the model does not parse: {e}"));
    mech::Derivation::new(model).unwrap_or_else(|e| panic!("the model does not derive: {e}"))
}

/// An expression of the derivation as text.
pub fn show(d: &mech::Derivation, e: sym::ExprId) -> String {
    d.pool().display(e).to_string()
}
