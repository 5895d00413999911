//! The derivation through the library's API, on the shared test models of
//! `common`: momenta, `M q'' = f`, cyclic coordinates, H, and the verdicts as
//! data, against what the lecture notes print.

use crate::common;

use crate::common::{derive, show, DAMPED, KEPLER, PENDULUM, ROTATING_WIRE};
use mech::{ConservationReason, ConservedReason, EnergyReason, RateTerm};

#[test]
fn the_pendulum_has_its_momentum_mass_matrix_and_hamiltonian() {
    let d = derive(PENDULUM);
    assert_eq!(d.coordinate_names(), ["th"]);
    assert_eq!(show(&d, d.momenta()[0]), "l^2*m*th'");
    assert_eq!(show(&d, d.mass_matrix()[0][0]), "l^2*m");
    assert_eq!(show(&d, d.forcing()[0]), "-g*l*m*sin(th)");
    assert_eq!(show(&d, d.hamiltonian().expect("L is quadratic")), "p_th^2/(2*l^2*m) - g*l*m*cos(th)");
    assert!(d.cyclic().is_empty());
    assert_eq!(d.hamiltonian_is_energy(), Some(true));
    assert_eq!(d.verdicts().energy, [EnergyReason::KineticHomogeneous, EnergyReason::IsEnergy]);
    assert_eq!(d.verdicts().conservation, [ConservationReason::Conserved]);
    let h = d.conserved().iter().find(|c| c.name == "H").expect("H is conserved");
    assert_eq!(h.reason, ConservedReason::EnergyConserved);
}

#[test]
fn the_bead_on_a_rotating_wire_conserves_an_h_that_is_not_the_energy() {
    let d = derive(ROTATING_WIRE);
    assert!(d.hamiltonian_conserved());
    assert_eq!(d.hamiltonian_is_energy(), Some(false));
    assert_eq!(d.verdicts().energy, [EnergyReason::KineticNotHomogeneous, EnergyReason::NotEnergy]);
    let h = d.conserved().iter().find(|c| c.name == "H").expect("H is conserved");
    assert_eq!(h.reason, ConservedReason::HamiltonianConserved);
    // The sentence is the reason's Display.
    assert_eq!(h.reason.to_string(), "H is conserved (it is not the energy T + U)");
}

#[test]
fn keplers_angle_is_cyclic_and_its_momentum_conserved() {
    let d = derive(KEPLER);
    assert_eq!(d.cyclic(), [1]);
    let p = d.conserved().iter().find(|c| c.name == "p_th").expect("p_th is conserved");
    assert_eq!(p.reason, ConservedReason::Cyclic { coordinate: "th".into() });
    assert_eq!(show(&d, p.expr), "mu*r^2*th'");
    assert_eq!(d.verdicts().energy, [EnergyReason::OnlyLagrangian]);
}

#[test]
fn dissipation_is_why_h_is_not_conserved() {
    let d = derive(DAMPED);
    assert!(!d.hamiltonian_conserved());
    assert_eq!(
        d.verdicts().conservation,
        [ConservationReason::Dissipation, ConservationReason::Rate { terms: vec![RateTerm::Dissipation] }]
    );
    let codes: Vec<&str> = d.verdicts().conservation.iter().map(|r| r.code()).collect();
    assert_eq!(codes, ["dissipation", "rate"]);
}

#[test]
fn the_report_carries_the_reasons_beside_the_sentences() {
    let d = derive(DAMPED);
    let json = serde_json::to_value(mech::DeriveReport::new(&d)).unwrap();
    assert_eq!(json["reasons"]["conservation"][0]["code"], "dissipation");
    assert_eq!(json["reasons"]["conservation"][1]["terms"][0], "dissipation");
    assert_eq!(json["explanations"]["conservation"][0], "The dissipation function R takes energy out.");
}

#[test]
fn the_layout_names_where_q_q_dot_t_and_the_parameters_sit() {
    let d = derive(PENDULUM);
    let layout = d.layout();
    assert_eq!((layout.q(), layout.qd(), layout.t(), layout.parameters()), (0..1, 1..2, 2, 3..6));
    assert_eq!(layout.symbols().len(), layout.len());
    assert_eq!(layout.values(), [0.0, 0.0, 0.0, 2.0, 1.5, 9.81]);
    let names: Vec<String> = layout.symbols().iter().map(|&s| show(&d, s)).collect();
    assert_eq!(names, ["th", "th'", "t", "m", "l", "g"]);
}

#[test]
fn a_singular_mass_matrix_is_an_error_located_in_the_file() {
    let text = "coordinates = [\"x\", \"y\"]\nlagrangian = \"(x' + y')^2/2\"\n";
    let e = mech::Derivation::new(mech::Model::parse(text, &[]).unwrap()).unwrap_err();
    assert!(e.message.contains("singular"), "{}", e.message);
    assert_eq!(&text[e.span.clone().expect("located")], "\"(x' + y')^2/2\"");
}

#[test]
fn an_unknown_parameter_to_set_names_the_setting_not_a_flag() {
    let e = mech::Model::parse(PENDULUM, &[("zz".into(), 1.0)]).unwrap_err();
    assert_eq!(e.setting, Some(mech::Setting::Parameter { name: "zz".into() }));
    assert!(!e.message.contains("--"), "{}", e.message);
}

#[test]
fn a_rheonomic_constraint_makes_h_not_conserved_and_says_which() {
    let text = "coordinates = [\"x\", \"y\"]\nkinetic = \"m*(x'^2 + y'^2)/2\"\n[parameters]\nm = 1.0\nom = 2.0\n\
                [[constraints]]\nname = \"wire\"\nholonomic = \"y*cos(om*t) - x*sin(om*t)\"\n";
    let d = derive(text);
    assert!(!d.hamiltonian_conserved());
    assert_eq!(
        d.verdicts().conservation,
        [ConservationReason::ConstraintWork { constraints: vec!["wire".into()] }, ConservationReason::WorkBalance]
    );
    let json = serde_json::to_value(mech::DeriveReport::new(&d)).unwrap();
    assert_eq!(json["constraints"][0]["does_work"], true);
    assert_eq!(json["reasons"]["conservation"][0]["constraints"][0], "wire");

    // The rod of a pendulum is scleronomic: its force does no work, H stays conserved.
    let d = derive(common::CONSTRAINED_PENDULUM);
    assert!(d.hamiltonian_conserved());
    assert!(d.verdicts().conservation.contains(&ConservationReason::ConstraintsDoNoWork));
    let json = serde_json::to_value(mech::DeriveReport::new(&d)).unwrap();
    assert_eq!(json["constraints"][0]["does_work"], false);
}
