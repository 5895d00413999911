//! Chains of rigid bodies, each hinged on the one before (issue #29, case 4):
//! ten rods derive in well under a second now that turns about one axis compose
//! to one angle sum, and a chain too long to derive stops at the derivation's
//! bound with exit 2 and the place in the file, for every command that derives.

mod common;

use common::{run, TempFile};

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
        text += &format!("q{k} = 0.1\n");
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

#[test]
fn a_chain_too_long_to_derive_stops_at_the_bound_for_every_command() {
    let model = TempFile::with_text("chain40", &chain(40));
    let p = model.path();
    for args in [
        vec!["derive", p],
        vec!["simulate", p, "--until", "1"],
        vec!["modes", p],
        vec!["linearize", p],
        vec!["report", p, "--until", "1", "-o", "/dev/null"],
    ] {
        let r = run(&args);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.contains("the derivation stopped at its bound of 64 million steps"), "{}", r.describe());
        // Located at the first body, which opens the tree.
        assert!(r.stderr.contains(&format!("{p}:10:1")), "{}", r.describe());
    }
}
