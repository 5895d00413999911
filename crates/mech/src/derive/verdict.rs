//! The verdicts of a derivation as data: why H is or is not the energy, why it
//! is or is not conserved, why it is not given in closed form, why each
//! conserved quantity is conserved, and which facts could not be decided (a
//! zero that is neither proven nor refuted, see [`crate::probe`]), so that
//! nothing is claimed on them. Each reason is an enum variant with the
//! facts it rests on; its `Display` is the sentence the notes would write, and
//! [`code`](ConservationReason::code) a stable name a program can branch on
//! (the `reasons` of the `lagrange.derive/1` report).

use crate::probe::UNDECIDED;
use serde::Serialize;
use std::fmt;

/// Why H = Σ q'·p − L is or is not the energy T + U₀, step by step (notes 2.4.2).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum EnergyReason {
    /// T is a homogeneous quadratic function of the velocities.
    KineticHomogeneous,
    /// T has terms linear in or free of the velocities (rheonomic positions).
    KineticNotHomogeneous,
    /// U depends on the velocities; only its velocity-free part is energy.
    VelocityDependentPotential,
    /// The conclusion: H equals T + U₀.
    IsEnergy,
    /// The conclusion: H differs from T + U₀.
    NotEnergy,
    /// The model gives only L, so T and U are not known separately.
    OnlyLagrangian,
    /// Σ q'·∂T/∂q' − 2T could be neither proven nor refuted to be 0.
    HomogeneityUndecided,
    /// U − U₀ could be neither proven nor refuted to be 0.
    VelocityDependenceUndecided,
    /// The conclusion: h − (T + U₀) could be neither proven nor refuted to be 0.
    EnergyUndecided,
}

/// What could not be decided about a coordinate, so that it is not claimed
/// cyclic or its momentum is not claimed conserved.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum CyclicReason {
    /// ∂L/∂q could be neither proven nor refuted to be 0: q is not listed as cyclic.
    Undecided {
        /// The coordinate's name.
        coordinate: String,
    },
    /// q is cyclic, but whether ∂R/∂q' and Q_q are 0 could not be decided:
    /// p_q is not claimed conserved.
    MomentumUndecided {
        /// The coordinate's name.
        coordinate: String,
    },
}

/// A term of dH/dt = −∂L/∂t − Σ q'·∂R/∂q' + Σ Q·q'.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RateTerm {
    /// −∂L/∂t.
    ExplicitTime,
    /// − Σ q'·∂R/∂q'.
    Dissipation,
    /// + Σ Q·q'.
    GeneralizedForces,
}

/// Why H is or is not conserved.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum ConservationReason {
    /// L depends explicitly on the time.
    ExplicitTime,
    /// Rayleigh's dissipation function takes energy out.
    Dissipation,
    /// Generalized forces act on these coordinates and do work.
    GeneralizedForces {
        /// The coordinates with a nonzero Q.
        coordinates: Vec<String>,
    },
    /// The conclusion: dH/dt is the sum of these terms, not zero.
    Rate {
        /// The terms present.
        terms: Vec<RateTerm>,
    },
    /// Nothing changes H: dH/dt = −∂L/∂t = 0.
    Conserved,
    /// L is free of t, but these constraints depend on it and their forces do work.
    ConstraintWork {
        /// The constraints with a_t ≠ 0.
        constraints: Vec<String>,
    },
    /// H − W is conserved instead (W the work of the constraint forces).
    WorkBalance,
    /// The constraints are free of t: their forces do no work, H stays conserved.
    ConstraintsDoNoWork,
    /// These terms of dH/dt could be neither proven nor refuted to be 0: H is
    /// not claimed conserved.
    Undecided {
        /// The terms in question.
        terms: Vec<RateTerm>,
    },
    /// Whether these constraints' time terms a_t are 0 could not be decided:
    /// H is not claimed conserved.
    ConstraintWorkUndecided {
        /// The constraints in question.
        constraints: Vec<String>,
    },
}

/// Why H is not given in closed form.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum HamiltonianReason {
    /// L is not quadratic in the velocities: p = ∂L/∂q' has no closed-form inverse.
    NotQuadratic,
    /// M couples this many coordinates densely: H would be too long to print.
    TooLong {
        /// The size of the largest block of M.
        coupled: usize,
    },
}

/// Why a quantity is conserved.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "code", rename_all = "snake_case")]
pub enum ConservedReason {
    /// The coordinate is cyclic: its momentum is constant.
    Cyclic {
        /// The coordinate's name.
        coordinate: String,
    },
    /// H is the energy, and it is conserved.
    EnergyConserved,
    /// H is conserved, but it is not the energy T + U.
    HamiltonianConserved,
    /// H is conserved; whether it is the energy T + U is not known (the model
    /// gives only L, or it could not be decided).
    HamiltonianConservedEnergyUnknown,
    /// Noether: L is unchanged by the generator, or changes only by a total
    /// time derivative dF/dt; Q = Σ p·ξ − F is constant.
    Symmetry {
        /// The transformation.
        generator: Generator,
        /// F(q, t) with δL = dF/dt, printed; absent when L is unchanged (F = 0).
        #[serde(rename = "F", skip_serializing_if = "Option::is_none")]
        f: Option<String>,
    },
}

/// What a symmetry transformation does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GeneratorKind {
    /// Every particle and body moved by the same vector.
    Translation,
    /// Every particle turned about an axis through the origin.
    Rotation,
    /// Coordinates shifted by constants.
    Shift,
}

/// A continuous point transformation q → q + ε ξ(q, t), as found by the
/// symmetry search.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Generator {
    /// Translation, rotation, or shift of coordinates.
    pub kind: GeneratorKind,
    /// The axis of a translation or rotation (`x`, `y`, `z`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<String>,
    /// The coordinates a shift moves.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub coordinates: Vec<String>,
    /// ξ per coordinate that moves, printed in the expression language.
    #[serde(serialize_with = "ordered_map")]
    pub xi: Vec<(String, String)>,
    /// What moves, for the sentence: "every particle", "every particle and
    /// body", "every body" or "the body".
    #[serde(skip)]
    pub moved: String,
}

/// Serializes pairs as a map in their order.
fn ordered_map<S: serde::Serializer>(pairs: &[(String, String)], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(pairs.len()))?;
    for (k, v) in pairs {
        map.serialize_entry(k, v)?;
    }
    map.end()
}

impl Generator {
    /// What the transformation does, as a phrase ("rotating every particle about z").
    fn action(&self) -> String {
        let what = &self.moved;
        let axis = self.axis.as_deref().unwrap_or("?");
        match self.kind {
            GeneratorKind::Translation => format!("translating {what} along {axis}"),
            GeneratorKind::Rotation => format!("rotating {what} about {axis}"),
            GeneratorKind::Shift => match self.coordinates.as_slice() {
                [one] => format!("shifting {one}"),
                _ => {
                    let moves: Vec<String> = self
                        .xi
                        .iter()
                        .map(|(q, x)| match x.as_str() {
                            "1" => format!("{q} by ε"),
                            "-1" => format!("{q} by −ε"),
                            _ => format!("{q} by {x}·ε"),
                        })
                        .collect();
                    format!("shifting {}", moves.join(" and "))
                }
            },
        }
    }

    /// What the conserved quantity is called in physics.
    fn meaning(&self) -> String {
        let axis = self.axis.as_deref().unwrap_or("?");
        match self.kind {
            GeneratorKind::Translation => format!("the momentum along {axis}"),
            GeneratorKind::Rotation => format!("the angular momentum about {axis}"),
            GeneratorKind::Shift => "Σ p·ξ".to_string(),
        }
    }
}

/// Why H is or is not the energy, and is or is not conserved.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Verdicts {
    /// The reasons behind `hamiltonian_is_energy`.
    pub energy: Vec<EnergyReason>,
    /// The reasons behind `hamiltonian_conserved`.
    pub conservation: Vec<ConservationReason>,
    /// Why H is not given in closed form, when it is not.
    pub hamiltonian: Vec<HamiltonianReason>,
    /// The coordinates whose cyclicity or conserved momentum could not be decided.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cyclic: Vec<CyclicReason>,
}

impl EnergyReason {
    /// The reason's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            EnergyReason::KineticHomogeneous => "kinetic_homogeneous",
            EnergyReason::KineticNotHomogeneous => "kinetic_not_homogeneous",
            EnergyReason::VelocityDependentPotential => "velocity_dependent_potential",
            EnergyReason::IsEnergy => "is_energy",
            EnergyReason::NotEnergy => "not_energy",
            EnergyReason::OnlyLagrangian => "only_lagrangian",
            EnergyReason::HomogeneityUndecided => "homogeneity_undecided",
            EnergyReason::VelocityDependenceUndecided => "velocity_dependence_undecided",
            EnergyReason::EnergyUndecided => "energy_undecided",
        }
    }
}

impl CyclicReason {
    /// The reason's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            CyclicReason::Undecided { .. } => "undecided",
            CyclicReason::MomentumUndecided { .. } => "momentum_undecided",
        }
    }
}

impl fmt::Display for CyclicReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CyclicReason::Undecided { coordinate: c } => write!(
                f,
                "Could not decide whether ∂L/∂{c} is zero ({UNDECIDED}): {c} is not claimed cyclic, nor p_{c} conserved."
            ),
            CyclicReason::MomentumUndecided { coordinate: c } => write!(
                f,
                "{c} is cyclic, but whether dissipation or a generalized force acts on it could not be decided ({UNDECIDED}): p_{c} is not claimed conserved."
            ),
        }
    }
}

impl ConservationReason {
    /// The reason's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            ConservationReason::ExplicitTime => "explicit_time",
            ConservationReason::Dissipation => "dissipation",
            ConservationReason::GeneralizedForces { .. } => "generalized_forces",
            ConservationReason::Rate { .. } => "rate",
            ConservationReason::Conserved => "conserved",
            ConservationReason::ConstraintWork { .. } => "constraint_work",
            ConservationReason::WorkBalance => "work_balance",
            ConservationReason::ConstraintsDoNoWork => "constraints_do_no_work",
            ConservationReason::Undecided { .. } => "undecided",
            ConservationReason::ConstraintWorkUndecided { .. } => "constraint_work_undecided",
        }
    }
}

impl fmt::Display for EnergyReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EnergyReason::KineticHomogeneous => {
                "T is a homogeneous quadratic function of the velocities (no term of T is linear in or free of q')."
            }
            EnergyReason::KineticNotHomogeneous => {
                "T is not homogeneous quadratic in the velocities: it has terms linear in or free of q' (as when the positions x(q, t) depend on time)."
            }
            EnergyReason::VelocityDependentPotential => {
                "U depends on the velocities (a generalized potential); only its velocity-independent part enters the energy."
            }
            EnergyReason::IsEnergy => "So H = Σ q'·p − L equals T + U: H is the energy.",
            EnergyReason::NotEnergy => "So H = Σ q'·p − L differs from T + U: H is not the energy.",
            EnergyReason::OnlyLagrangian => {
                "The model gives only L, so T and U (and hence the energy) are not known separately."
            }
            EnergyReason::HomogeneityUndecided => {
                "Could not decide whether T is homogeneous quadratic in the velocities, that is whether Σ q'·∂T/∂q' − 2T is zero (no exact rewriting reduces it to 0, and no probe point shows it nonzero)."
            }
            EnergyReason::VelocityDependenceUndecided => {
                "Could not decide whether U depends on the velocities, that is whether U − U(q' = 0) is zero (no exact rewriting reduces it to 0, and no probe point shows it nonzero)."
            }
            EnergyReason::EnergyUndecided => {
                "So whether H = Σ q'·p − L equals T + U could not be decided (no exact rewriting reduces their difference to 0, and no probe point shows it nonzero): nothing is claimed."
            }
        })
    }
}

impl fmt::Display for ConservationReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConservationReason::ExplicitTime => f.write_str("L depends explicitly on the time (∂L/∂t ≠ 0)."),
            ConservationReason::Dissipation => f.write_str("The dissipation function R takes energy out."),
            ConservationReason::GeneralizedForces { coordinates } => {
                write!(f, "Generalized forces act on {} and do work.", coordinates.join(", "))
            }
            ConservationReason::Rate { terms } => {
                let mut rate = String::new();
                for (k, term) in terms.iter().enumerate() {
                    let (sign, text) = match term {
                        RateTerm::ExplicitTime => ("−", "∂L/∂t"),
                        RateTerm::Dissipation => ("−", "Σ q'·∂R/∂q'"),
                        RateTerm::GeneralizedForces => ("+", "Σ Q·q'"),
                    };
                    // The first term carries its sign without a space, and a plus not at all.
                    match (k, sign) {
                        (0, "+") => rate.push_str(text),
                        (0, _) => rate.push_str(&format!("{sign}{text}")),
                        _ => rate.push_str(&format!(" {sign} {text}")),
                    }
                }
                write!(f, "So dH/dt = {rate} ≠ 0.")
            }
            ConservationReason::Conserved => f.write_str(
                "L does not depend explicitly on t, and no dissipation or generalized force acts: dH/dt = −∂L/∂t = 0.",
            ),
            ConservationReason::ConstraintWork { constraints } => {
                let one = constraints.len() == 1;
                write!(
                    f,
                    "L does not depend on t, but the constraint{} {} depend{} explicitly on the time: {} force does work, dH/dt = Σ λ·Aq' = −Σ λ a_t ≠ 0.",
                    if one { "" } else { "s" },
                    constraints.join(", "),
                    if one { "s" } else { "" },
                    if one { "its" } else { "their" }
                )
            }
            ConservationReason::WorkBalance => f.write_str(
                "H − W is conserved instead, W = ∫ Aᵀλ·q' dt the work of the constraint forces (simulate audits it as H-W).",
            ),
            ConservationReason::ConstraintsDoNoWork => f.write_str(
                "The constraints do not depend on t: their forces do no work (Aᵀλ·q' = −λ·a_t = 0), so H stays conserved.",
            ),
            ConservationReason::Undecided { terms } => {
                let names: Vec<&str> = terms
                    .iter()
                    .map(|t| match t {
                        RateTerm::ExplicitTime => "∂L/∂t",
                        RateTerm::Dissipation => "the dissipation function R",
                        RateTerm::GeneralizedForces => "the generalized forces Q",
                    })
                    .collect();
                write!(
                    f,
                    "Could not decide whether {} {} zero ({UNDECIDED}): H is not claimed conserved.",
                    names.join(" and "),
                    if names.len() == 1 { "is" } else { "are" }
                )
            }
            ConservationReason::ConstraintWorkUndecided { constraints } => write!(
                f,
                "Could not decide whether the time term a_t of {} is zero ({UNDECIDED}): whether {} force does work is not known, so H is not claimed conserved.",
                constraints.join(", "),
                if constraints.len() == 1 { "its" } else { "their" }
            ),
        }
    }
}

impl HamiltonianReason {
    /// The reason's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            HamiltonianReason::NotQuadratic => "not_quadratic",
            HamiltonianReason::TooLong { .. } => "too_long",
        }
    }
}

impl fmt::Display for HamiltonianReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            HamiltonianReason::NotQuadratic => f.write_str(
                "L is not quadratic in the velocities, so p = ∂L/∂q' cannot be solved for q' in closed form; H is not given.",
            ),
            HamiltonianReason::TooLong { coupled } => write!(
                f,
                "M couples {coupled} coordinates densely: H = ½(p − b)ᵀM⁻¹(p − b) − L₀ written out would be too long to print, so H and Hamilton's equations are left to numerics, which solve M q' = p − b at each step."
            ),
        }
    }
}

impl ConservedReason {
    /// The reason's stable name.
    pub fn code(&self) -> &'static str {
        match self {
            ConservedReason::Cyclic { .. } => "cyclic",
            ConservedReason::EnergyConserved => "energy_conserved",
            ConservedReason::HamiltonianConserved => "hamiltonian_conserved",
            ConservedReason::HamiltonianConservedEnergyUnknown => "hamiltonian_conserved_energy_unknown",
            ConservedReason::Symmetry { .. } => "symmetry",
        }
    }
}

impl fmt::Display for ConservedReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConservedReason::Cyclic { coordinate: c } => {
                write!(f, "'{c}' is cyclic: L does not depend on it, so p_{c} = ∂L/∂{c}' is constant")
            }
            ConservedReason::EnergyConserved => f.write_str("H is the energy, and it is conserved"),
            ConservedReason::HamiltonianConserved => f.write_str("H is conserved (it is not the energy T + U)"),
            ConservedReason::HamiltonianConservedEnergyUnknown => {
                f.write_str("H is conserved (whether it is the energy T + U is not known)")
            }
            ConservedReason::Symmetry { generator: g, f: None } => {
                write!(f, "L is unchanged by {}: {} is conserved", g.action(), g.meaning())
            }
            ConservedReason::Symmetry { generator: g, f: Some(big_f) } => {
                let meaning = match g.kind {
                    GeneratorKind::Shift => "Σ p·ξ − F".to_string(),
                    _ => format!("{} less F (Σ p·ξ − F)", g.meaning()),
                };
                write!(
                    f,
                    "{} changes L only by a total time derivative dF/dt, F = {big_f}: {meaning} is conserved",
                    capitalize(&g.action())
                )
            }
        }
    }
}

/// The phrase with its first letter upper case.
fn capitalize(s: &str) -> String {
    let mut chars = s.chars();
    match chars.next() {
        Some(c) => c.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check_rate(terms: &[RateTerm], expect: &str) {
        assert_eq!(ConservationReason::Rate { terms: terms.to_vec() }.to_string(), expect);
    }

    #[test]
    fn the_rate_of_h_names_each_term_with_its_sign() {
        check_rate(&[RateTerm::ExplicitTime], "So dH/dt = −∂L/∂t ≠ 0.");
        check_rate(&[RateTerm::GeneralizedForces], "So dH/dt = Σ Q·q' ≠ 0.");
        check_rate(&[RateTerm::Dissipation, RateTerm::GeneralizedForces], "So dH/dt = −Σ q'·∂R/∂q' + Σ Q·q' ≠ 0.");
        check_rate(
            &[RateTerm::ExplicitTime, RateTerm::Dissipation, RateTerm::GeneralizedForces],
            "So dH/dt = −∂L/∂t − Σ q'·∂R/∂q' + Σ Q·q' ≠ 0.",
        );
    }

    #[test]
    fn a_symmetry_serializes_with_its_generator_and_f() {
        let generator = Generator {
            kind: GeneratorKind::Rotation,
            axis: Some("z".into()),
            coordinates: Vec::new(),
            xi: vec![("x".into(), "-y".into()), ("y".into(), "x".into())],
            moved: "every particle".into(),
        };
        let r = ConservedReason::Symmetry { generator: generator.clone(), f: None };
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            r#"{"code":"symmetry","generator":{"kind":"rotation","axis":"z","xi":{"x":"-y","y":"x"}}}"#
        );
        assert_eq!(r.code(), "symmetry");
        assert_eq!(
            r.to_string(),
            "L is unchanged by rotating every particle about z: the angular momentum about z is conserved"
        );
        let shift = Generator {
            kind: GeneratorKind::Shift,
            axis: None,
            coordinates: vec!["a".into(), "b".into()],
            xi: vec![("a".into(), "1".into()), ("b".into(), "-1".into())],
            moved: "every particle".into(),
        };
        let r = ConservedReason::Symmetry { generator: shift, f: Some("k*t".into()) };
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            r#"{"code":"symmetry","generator":{"kind":"shift","coordinates":["a","b"],"xi":{"a":"1","b":"-1"}},"F":"k*t"}"#
        );
        assert_eq!(
            r.to_string(),
            "Shifting a by ε and b by −ε changes L only by a total time derivative dF/dt, F = k*t: Σ p·ξ − F is conserved"
        );
    }

    #[test]
    fn reasons_serialize_with_their_code_and_facts() {
        let r = ConservationReason::GeneralizedForces { coordinates: vec!["x".into()] };
        assert_eq!(serde_json::to_string(&r).unwrap(), r#"{"code":"generalized_forces","coordinates":["x"]}"#);
        assert_eq!(serde_json::to_string(&EnergyReason::IsEnergy).unwrap(), r#"{"code":"is_energy"}"#);
        assert_eq!(r.code(), "generalized_forces");
        let c = CyclicReason::Undecided { coordinate: "x".into() };
        assert_eq!(serde_json::to_string(&c).unwrap(), r#"{"code":"undecided","coordinate":"x"}"#);
        assert!(c.to_string().starts_with("Could not decide whether ∂L/∂x is zero"), "{c}");
    }
}
