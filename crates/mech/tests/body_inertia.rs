//! A body's inertia tensor: any rigid body's is accepted, a zero moment (a
//! thin rod about its axis) included; only a singular total mass matrix is
//! refused, naming the coordinate that has no inertia, at the body.

const ROD: &str = r#"
coordinates = ["al", "be", "ga"]
gravity = "g"
[parameters]
m = 1.0
l = 2.0
g = 9.81
[[bodies]]
mass = "m"
inertia = ["m*l^2/12", "m*l^2/12", "0"]
angles = ["al", "be", "ga"]
center_of_mass = ["0", "0", "l/2"]
"#;

#[test]
fn a_thin_rod_is_read_and_its_idle_spin_is_named_at_the_body() {
    let model = mech::Model::parse(ROD, &[]).expect("a thin rod is a rigid body");
    let e = mech::Derivation::new(model).expect_err("the spin about the rod's axis has no inertia");
    assert!(e.message.contains("the coordinate 'ga' has no inertia"), "{}", e.message);
    let body = ROD.find("[[bodies]]").unwrap();
    assert_eq!(e.span.clone().map(|s| s.start), Some(body), "{:?}", e.span);
}

#[test]
fn a_tensor_no_body_has_is_refused_where_it_is_written() {
    for (inertia, why) in [
        (r#"["1", "-1", "1"]"#, "negative"),
        (r#"["1", "1", "3"]"#, "exceeds the sum of the other two"),
        (r#"[["1", "0.5", "0"], ["0", "1", "0"], ["0", "0", "1"]]"#, "not symmetric: I12 = 0.5 but I21 = 0"),
    ] {
        let text = ROD.replace(r#"["m*l^2/12", "m*l^2/12", "0"]"#, inertia);
        let e = mech::Model::parse(&text, &[]).expect_err(inertia);
        assert!(e.message.contains(why), "{inertia}: {}", e.message);
        let at = text.find(inertia).unwrap();
        assert_eq!(e.span, Some(at..at + inertia.len()), "{inertia}");
    }
}
