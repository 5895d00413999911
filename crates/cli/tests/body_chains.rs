//! Chains of rigid bodies, each hinged on the one before (issue #29, case 4;
//! issue #30): ten rods derive in well under a second now that turns about one
//! axis compose to one angle sum, and forty, past the expanded derivation's
//! bound, derive on the shared path and move as the same chain of particles.

use crate::common;

use crate::common::{run, TempFile};

/// A planar chain of `n` equal rods, rod k hanging from the end of rod k − 1
/// and turning by its own relative angle qk.
fn chain(n: usize) -> String {
    let coordinates: Vec<String> = (1..=n).map(|k| format!("\"q{k}\"")).collect();
    let mut text = format!(
        "name = \"chain of {n} rods\"\ncoordinates = [{}]\ngravity = \"g\"\n\n[parameters]\ng = 9.81\nm = 1.0\nl = 1.0\n",
        coordinates.join(", ")
    );
    for k in 1..=n {
        text += &format!("\n[[bodies]]\nname = \"r{k}\"\n");
        if k > 1 {
            text += &format!("parent = \"r{}\"\nposition = [\"0\", \"-l\"]\n", k - 1);
        }
        text += &format!("mass = \"m\"\ninertia = \"m*l^2/3\"\nangle = \"q{k}\"\ncenter_of_mass = [\"0\", \"-l/2\"]\n");
    }
    text += "\n[initial]\n";
    for k in 1..=n {
        text += &format!("q{k} = 0.1\n\"q{k}'\" = 0\n");
    }
    text
}

#[test]
fn ten_rods_derive_with_the_mass_matrix_of_the_physics() {
    let model = TempFile::with_text("chain10", &chain(10));
    let r = run(&["derive", model.path(), "--format", "json"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let v = r.json();
    let m = v["mass_matrix"].as_array().expect("a mass matrix");
    assert_eq!(m.len(), 10);
    // The last rod turning alone about its pivot: m l²/3, whatever the rest does.
    assert_eq!(m[9][9].as_str(), Some("l^2*m/3"), "{}", m[9][9]);
    // Rotating the whole chain about the first pivot changes nothing but U: q1 is
    // not cyclic (gravity), and H is the conserved energy.
    assert_eq!(v["hamiltonian_is_energy"], true);
    assert_eq!(v["hamiltonian_conserved"], true);
}

/// The chain of `n` rods with each rod's mass at its far end (its moment about
/// the pivot, the body's reference point, m l²), and the same written as
/// particles in the same relative angles.
fn point_mass_chains(n: usize) -> (String, String) {
    let bodies = chain(n)
        .replace("inertia = \"m*l^2/3\"", "inertia = \"m*l^2\"")
        .replace("center_of_mass = [\"0\", \"-l/2\"]", "center_of_mass = [\"0\", \"-l\"]");
    let coordinates: Vec<String> = (1..=n).map(|k| format!("\"q{k}\"")).collect();
    let mut particles = format!(
        "coordinates = [{}]\ngravity = \"g\"\n\n[parameters]\ng = 9.81\nm = 1.0\nl = 1.0\n",
        coordinates.join(", ")
    );
    let (mut x, mut y, mut angle) = (Vec::new(), Vec::new(), String::new());
    for k in 1..=n {
        angle = if k == 1 { "q1".into() } else { format!("{angle} + q{k}") };
        x.push(format!("l*sin({angle})"));
        y.push(format!("-l*cos({angle})"));
        particles +=
            &format!("\n[[particles]]\nmass = \"m\"\nposition = [\"{}\", \"{}\"]\n", x.join(" + "), y.join(" + "));
    }
    particles += "\n[initial]\n";
    for k in 1..=n {
        particles += &format!("q{k} = 0.1\n\"q{k}'\" = 0\n");
    }
    (bodies, particles)
}

/// Forty rods are past the expanded derivation's bound: the shared path
/// derives them, every command that derives runs, and the motion is the one of
/// the same chain written as particles (a different path through the kinematics).
#[test]
fn forty_rods_derive_on_the_shared_path_and_move_as_the_particle_chain() {
    let (bodies, particles) = point_mass_chains(40);
    let bodies = TempFile::with_text("chain40", &bodies);
    let particles = TempFile::with_text("particles40", &particles);
    let mut finals = Vec::new();
    for model in [&bodies, &particles] {
        let out = TempFile::new("chain40", "csv");
        let r = run(&["simulate", model.path(), "--until", "0.3", "--method", "dop853", "--out", out.path()]);
        assert_eq!(r.code, Some(0), "{}", r.describe());
        let csv = common::Csv::read(out.path());
        let last: Vec<f64> = (1..=40).map(|k| *csv.column(&format!("q{k}")).last().unwrap()).collect();
        finals.push(last);
    }
    for k in 0..40 {
        assert!(
            (finals[0][k] - finals[1][k]).abs() < 1e-7,
            "q{}: bodies {} particles {}",
            k + 1,
            finals[0][k],
            finals[1][k]
        );
    }
    // Hanging straight down is a stable equilibrium: every eigenvalue of the
    // linearization is imaginary (40 pairs), for the shared path's M and f.
    let at: Vec<String> = (1..=40).map(|k| format!("q{k}=0")).collect();
    let mut args = vec!["linearize", bodies.path(), "--format", "json", "--at"];
    args.extend(at.iter().map(String::as_str));
    let r = run(&args);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let v = r.json();
    assert_eq!(v["stability"], "marginal", "{}", v["stability"]);
}
