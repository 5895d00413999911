//! The `lagrange.derive/1` report: a derivation as plain data (strings in the
//! expression language), ready to serialize as the JSON contract of DESIGN.md.
//!
//! Field names are a contract: add fields freely, rename none.
//!
//! A large derivation (its expressions' trees together past
//! [`sym::SHARING_PAYS_ABOVE`] nodes, [`prints_shared`]) writes each
//! subexpression it would repeat once, in `definitions` (`w1 = …`, children
//! first), and the other fields refer to those names; a small one has no
//! `definitions` and prints as it always has.

use crate::derive::Derivation;
use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;
use sym::{ExprId, PrintOptions, Printout};

/// A map that keeps its insertion order (coordinates and parameters in file order).
#[derive(Debug, Clone, Default)]
pub struct Ordered<V>(pub Vec<(String, V)>);

impl<V: Serialize> Serialize for Ordered<V> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

impl<V> Ordered<V> {
    /// The value for a key.
    pub fn get(&self, key: &str) -> Option<&V> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// A named expression (a conserved quantity).
#[derive(Debug, Clone, Serialize)]
pub struct NamedExpr {
    /// Its name (`p_th`, `H`).
    pub name: String,
    /// The expression in (q, q', t).
    pub expr: String,
    /// Why (for people; not part of the contract).
    pub reason: String,
    /// Why, as a stable code a program can branch on (`cyclic`, `energy_conserved`,
    /// `hamiltonian_conserved`) with its facts (extra field).
    pub why: crate::derive::ConservedReason,
}

/// Hamilton's equations for one coordinate.
#[derive(Debug, Clone, Serialize)]
pub struct HamiltonEquations {
    /// dq/dt in (q, p, t).
    pub dq: String,
    /// dp/dt in (q, p, t), including dissipation and forces.
    pub dp: String,
}

/// The derivation as the JSON contract `lagrange.derive/1`.
#[derive(Debug, Clone, Serialize)]
pub struct DeriveReport {
    /// Always `lagrange.derive/1`.
    pub format: &'static str,
    /// The model's name.
    pub name: String,
    /// Coordinate names in order.
    pub coordinates: Vec<String>,
    /// Parameter values.
    pub parameters: Ordered<f64>,
    /// L.
    pub lagrangian: String,
    /// T, or null for a Lagrangian-only model.
    pub kinetic: Option<String>,
    /// U, or null for a Lagrangian-only model.
    pub potential: Option<String>,
    /// R, or null.
    pub dissipation: Option<String>,
    /// p_q = ∂L/∂q' per coordinate.
    pub momenta: Ordered<String>,
    /// E_q per coordinate.
    pub equations: Ordered<String>,
    /// M in E = M q'' − f.
    pub mass_matrix: Vec<Vec<String>>,
    /// f in E = M q'' − f.
    pub forcing: Vec<String>,
    /// Cyclic coordinates.
    pub cyclic: Vec<String>,
    /// Conserved quantities.
    pub conserved: Vec<NamedExpr>,
    /// H(q, p, t), or null when L is not quadratic in the velocities.
    pub hamiltonian: Option<String>,
    /// T + U₀, or null for a Lagrangian-only model.
    pub energy: Option<String>,
    /// Whether H is the energy, or null when unknown.
    pub hamiltonian_is_energy: Option<bool>,
    /// Whether H is conserved.
    pub hamiltonian_conserved: bool,
    /// Hamilton's equations, or null when H is not given.
    pub hamilton: Option<Ordered<HamiltonEquations>>,
    /// The energy function h = Σ q'·p − L in (q, q', t) (extra field).
    pub energy_function: String,
    /// q' in terms of (q, p, t) (extra field).
    pub velocities: Option<Ordered<String>>,
    /// Whether L depends explicitly on t, or null when that could not be
    /// decided (extra field).
    pub explicit_time: Option<bool>,
    /// Explanations of the verdicts, sentence by sentence (extra field).
    pub explanations: Explanations,
    /// The same verdicts as data: each reason an object with its `code` and
    /// the facts it names, one per sentence of `explanations` (extra field).
    pub reasons: crate::derive::Verdicts,
    /// Each rigid body's body-frame ω and L (extra field; absent without bodies).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodyReport>,
    /// The constraints (extra field, present only with `[[constraints]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<ConstraintReport>,
    /// With constraints: the equations of motion with multipliers,
    /// `E_q − Σ_k lambda_k A_kq` per coordinate (each `= 0`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub multiplier_equations: Option<Ordered<String>>,
    /// With constraints: the generalized constraint force `Aᵀλ` per coordinate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraint_forces: Option<Ordered<String>>,
    /// With constraints and particles whose positions are the coordinates: the
    /// Cartesian constraint force on each particle.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cartesian_constraint_forces: Option<Vec<Vec<String>>>,
    /// With constraints: the degrees of freedom left (n − independent constraints).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub degrees_of_freedom: Option<usize>,
    /// With velocity constraints: whether together they are integrable.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraints_integrable: Option<bool>,
    /// With constraints: the teaching text about the set.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub constraint_explanations: Vec<String>,
    /// The impacts' surfaces and laws (extra field, present only with `[[impacts]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub impacts: Vec<ImpactReport>,
    /// The model's inputs u with their values in runs (extra field, present
    /// only with `[inputs]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<InputReport>,
    /// With inputs: B = ∂f/∂u, one row per coordinate (M q'' = f₀ + B u when
    /// `inputs_affine`).
    #[serde(rename = "B", skip_serializing_if = "Option::is_none")]
    pub input_matrix: Option<Vec<Vec<String>>>,
    /// With inputs: whether f is proven affine in u.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inputs_affine: Option<bool>,
    /// The named intermediates of a large derivation, children first: the
    /// other expressions (and later definitions) use their names (extra
    /// field, absent when nothing is named).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub definitions: Vec<Definition>,
}

/// One named intermediate: `name = expr`.
#[derive(Debug, Clone, Serialize)]
pub struct Definition {
    /// Its name, `w1`, `w2`, …: a symbol of no expression of the derivation.
    pub name: String,
    /// The expression it stands for, which may use the names defined before it.
    pub expr: String,
}

/// Whether the outputs of `d` print with named intermediates: whether all the
/// report's expressions written as trees would exceed
/// [`sym::SHARING_PAYS_ABOVE`] nodes. Every output of one derivation (JSON,
/// text, LaTeX, MathML) makes the same decision by it.
pub fn prints_shared(d: &Derivation) -> bool {
    d.pool().sharing_pays(&DeriveReport::roots(d))
}

/// A rigid body's angular velocity and angular momentum, body components.
#[derive(Debug, Clone, Serialize)]
pub struct BodyReport {
    /// The body's name.
    pub name: String,
    /// (ω₁, ω₂, ω₃) in (q, q').
    pub angular_velocity: [String; 3],
    /// (L₁, L₂, L₃) about the reference point.
    pub angular_momentum: [String; 3],
}

/// One input in the derive report: its name and its value in runs.
#[derive(Debug, Clone, Serialize)]
pub struct InputReport {
    /// The input's name.
    pub name: String,
    /// Its value, an expression of t.
    pub value: String,
}

/// One constraint in the report.
#[derive(Debug, Clone, Serialize)]
pub struct ConstraintReport {
    /// Its name.
    pub name: String,
    /// `holonomic` or `velocity`.
    pub kind: &'static str,
    /// The expression that vanishes, as written.
    pub expr: String,
    /// Its row of A, one entry per coordinate.
    pub jacobian: Vec<String>,
    /// The time term a_t.
    pub time_term: String,
    /// Whether it depends explicitly on t (null: could not be decided).
    pub rheonomic: Option<bool>,
    /// Whether its force does work (a_t ≠ 0), the fact behind its `explanation`'s
    /// "its force does work" (extra field; null: could not be decided).
    pub does_work: Option<bool>,
    /// Whether it is integrable on its own (true for holonomic ones).
    pub integrable: Option<bool>,
    /// F with the constraint equivalent to F = const, when found.
    pub integral: Option<String>,
    /// The multiplier's symbol.
    pub multiplier: String,
    /// The teaching text.
    pub explanation: Vec<String>,
}

/// One impact in the report: the surface φ(q, t) ≥ 0 and the law at φ = 0,
/// q'⁺ = q'⁻ − (1 + e) M⁻¹∇φ v_n⁻/(∇φᵀM⁻¹∇φ).
#[derive(Debug, Clone, Serialize)]
pub struct ImpactReport {
    /// Its name.
    pub name: String,
    /// φ(q, t), kept ≥ 0.
    pub surface: String,
    /// ∇φ = ∂φ/∂q, one entry per coordinate.
    pub gradient: Vec<String>,
    /// ∂φ/∂t.
    pub rate: String,
    /// v_n = ∇φ·q' + ∂φ/∂t.
    pub normal_velocity: String,
    /// Newton's coefficient of restitution e.
    pub restitution: String,
    /// The law, in words and symbols.
    pub law: &'static str,
}

/// The impact law as the reports state it.
pub const IMPACT_LAW: &str = "q'⁺ = q'⁻ − (1 + e) M⁻¹∇φ v_n⁻/(∇φᵀ M⁻¹ ∇φ), so that v_n⁺ = −e v_n⁻";

/// The teaching text behind the verdicts.
#[derive(Debug, Clone, Serialize)]
pub struct Explanations {
    /// Why H is or is not the energy.
    pub energy: Vec<String>,
    /// Why H is or is not conserved.
    pub conservation: Vec<String>,
    /// Why H is not given in closed form, when it is not.
    pub hamiltonian: Vec<String>,
    /// Which coordinates could not be decided cyclic, or their momenta conserved.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cyclic: Vec<String>,
}

impl DeriveReport {
    /// Builds the report from a derivation; see the module documentation
    /// for the named intermediates of a large one.
    pub fn new(d: &Derivation) -> DeriveReport {
        let roots = DeriveReport::roots(d);
        if !d.pool().sharing_pays(&roots) {
            return DeriveReport::build(d, &Printout::Trees);
        }
        let shared = d.pool().share(&roots);
        let definitions = shared
            .definitions()
            .map(|(name, id)| Definition {
                name,
                expr: shared.print_definition(d.pool(), id, PrintOptions::text()).to_string(),
            })
            .collect();
        DeriveReport { definitions, ..DeriveReport::build(d, &Printout::Named(shared)) }
    }

    /// Every expression the report prints, in order (one listed twice is
    /// printed twice).
    fn roots(d: &Derivation) -> Vec<ExprId> {
        let roots = Printout::roots();
        DeriveReport::build(d, &roots);
        roots.into_roots()
    }

    /// The report with its expressions written as `how` says.
    fn build(d: &Derivation, how: &Printout) -> DeriveReport {
        let pool = d.pool();
        let s = |e: ExprId| how.write(pool, e, PrintOptions::text());
        let names = d.coordinate_names();
        let by_coord = |v: &[ExprId]| Ordered(names.iter().zip(v).map(|(n, &e)| (n.to_string(), s(e))).collect());
        DeriveReport {
            format: "lagrange.derive/1",
            name: d.model.name.clone(),
            coordinates: names.iter().map(|n| n.to_string()).collect(),
            parameters: Ordered(d.model.parameters.iter().map(|p| (p.name.clone(), p.value)).collect()),
            lagrangian: s(d.lagrangian),
            kinetic: d.kinetic.map(s),
            potential: d.potential.map(s),
            dissipation: d.dissipation.map(s),
            momenta: by_coord(&d.momenta),
            equations: by_coord(&d.equations),
            mass_matrix: d.mass_matrix.iter().map(|row| row.iter().map(|&e| s(e)).collect()).collect(),
            forcing: d.forcing.iter().map(|&e| s(e)).collect(),
            cyclic: d.cyclic.iter().map(|&i| names[i].to_string()).collect(),
            conserved: d
                .conserved
                .iter()
                .map(|c| NamedExpr {
                    name: c.name.clone(),
                    expr: s(c.expr),
                    reason: c.reason.to_string(),
                    why: c.reason.clone(),
                })
                .collect(),
            hamiltonian: d.hamiltonian.map(s),
            energy: d.energy.map(s),
            hamiltonian_is_energy: d.hamiltonian_is_energy,
            hamiltonian_conserved: d.hamiltonian_conserved,
            hamilton: d.hamilton.as_ref().map(|eqs| {
                Ordered(
                    names
                        .iter()
                        .zip(eqs)
                        .map(|(n, &(dq, dp))| (n.to_string(), HamiltonEquations { dq: s(dq), dp: s(dp) }))
                        .collect(),
                )
            }),
            energy_function: s(d.energy_function),
            velocities: d.velocities.as_ref().map(|v| by_coord(v)),
            explicit_time: d.explicit_time,
            explanations: Explanations {
                energy: d.verdicts.energy.iter().map(ToString::to_string).collect(),
                conservation: d.verdicts.conservation.iter().map(ToString::to_string).collect(),
                hamiltonian: d.verdicts.hamiltonian.iter().map(ToString::to_string).collect(),
                cyclic: d.verdicts.cyclic.iter().map(ToString::to_string).collect(),
            },
            reasons: d.verdicts.clone(),
            bodies: d
                .bodies
                .iter()
                .map(|b| BodyReport {
                    name: b.name.clone(),
                    angular_velocity: b.omega.map(s),
                    angular_momentum: b.angular_momentum.map(s),
                })
                .collect(),
            constraints: d
                .constraints
                .list
                .iter()
                .map(|c| ConstraintReport {
                    name: c.name.clone(),
                    kind: c.kind.name(),
                    expr: s(c.expr),
                    jacobian: c.jacobian.iter().map(|&e| s(e)).collect(),
                    time_term: s(c.time_term),
                    rheonomic: c.rheonomic,
                    does_work: c.does_work,
                    integrable: c.integrable,
                    integral: c.integral.map(s),
                    multiplier: s(c.multiplier),
                    explanation: c.explanation.clone(),
                })
                .collect(),
            multiplier_equations: (!d.constraints.is_empty()).then(|| by_coord(&d.constraints.multiplier_equations)),
            constraint_forces: (!d.constraints.is_empty()).then(|| by_coord(&d.constraints.generalized_forces)),
            cartesian_constraint_forces: d
                .constraints
                .cartesian_forces
                .as_ref()
                .map(|fs| fs.iter().map(|f| f.iter().map(|&e| s(e)).collect()).collect()),
            degrees_of_freedom: (!d.constraints.is_empty()).then_some(d.constraints.degrees_of_freedom),
            constraints_integrable: d.constraints.integrable,
            constraint_explanations: d.constraints.explanation.clone(),
            impacts: d
                .impacts
                .iter()
                .map(|i| ImpactReport {
                    name: i.name.clone(),
                    surface: s(i.surface),
                    gradient: i.gradient.iter().map(|&g| s(g)).collect(),
                    rate: s(i.rate),
                    normal_velocity: s(i.normal_velocity),
                    restitution: s(i.restitution),
                    law: IMPACT_LAW,
                })
                .collect(),
            inputs: d
                .model
                .inputs
                .iter()
                .map(|u| InputReport { name: u.name.clone(), value: s(u.value.expr) })
                .collect(),
            input_matrix: (!d.inputs.is_empty())
                .then(|| d.input_matrix.iter().map(|row| row.iter().map(|&b| s(b)).collect()).collect()),
            inputs_affine: (!d.inputs.is_empty()).then_some(d.inputs_affine),
            definitions: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;
    use rustc_hash::FxHashMap;
    use sym::Pool;

    fn derive(text: &str) -> Derivation {
        Derivation::new(Model::parse(text, &[]).expect("the model parses")).expect("it derives")
    }

    /// A value for each symbol in [0.3, 1.3), fixed by its name.
    fn value_of(name: &str) -> Option<f64> {
        let h = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
        Some(0.3 + (h >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// Parses each definition in order into `pool`, with the earlier ones
    /// substituted: each name's expression in the symbols of the model.
    fn definitions(pool: &mut Pool, report: &DeriveReport) -> FxHashMap<ExprId, ExprId> {
        let mut map = FxHashMap::default();
        for def in &report.definitions {
            let e = pool.parse(&def.expr).unwrap_or_else(|err| panic!("{} = {}: {err}", def.name, def.expr));
            let value = pool.substitute(e, &map);
            let name = pool.symbol(&def.name);
            map.insert(name, value);
        }
        map
    }

    /// The benchmark bicycle's report is under 1 MB as JSON (1.39 MB with its
    /// expressions as trees) and names its shared subexpressions; its mass
    /// matrix, forcing, momenta and Hamiltonian, read back through the
    /// definitions, have the derivation's values.
    #[test]
    fn a_large_report_defines_each_shared_subexpression_once() {
        let d = derive(include_str!("../../../examples/bicycle/benchmark_bicycle.toml"));
        assert!(prints_shared(&d));
        let report = DeriveReport::new(&d);
        assert!(report.definitions.len() > 100, "{} definitions", report.definitions.len());
        let json = serde_json::to_string(&report).expect("serializes");
        assert!(json.len() < 1_000_000, "{} bytes", json.len());
        // No definition names a symbol of the model (the bicycle has a parameter `w`).
        for def in &report.definitions {
            assert!(d.pool().find_name(&def.name).is_none(), "{} is a name of the model", def.name);
        }
        let mut pool = d.pool().clone();
        let map = definitions(&mut pool, &report);
        let mut pairs: Vec<(ExprId, &str)> = Vec::new();
        for (row, texts) in d.mass_matrix.iter().zip(&report.mass_matrix) {
            pairs.extend(row.iter().copied().zip(texts.iter().map(String::as_str)));
        }
        pairs.extend(d.forcing.iter().copied().zip(report.forcing.iter().map(String::as_str)));
        pairs.extend(d.momenta.iter().copied().zip(report.momenta.0.iter().map(|(_, t)| t.as_str())));
        pairs.extend(d.hamiltonian.zip(report.hamiltonian.as_deref()));
        assert!(pairs.len() >= 80, "{} expressions", pairs.len());
        let mut named = 0;
        for (want, text) in pairs {
            let e = pool.parse(text).unwrap_or_else(|err| panic!("{text}: {err}"));
            named += usize::from(text.contains('w'));
            let back = pool.substitute(e, &map);
            let (a, b) =
                (pool.eval(want, &value_of).expect("evaluates"), pool.eval(back, &value_of).expect("evaluates"));
            assert!((a - b).abs() <= 1e-9 * (1.0 + a.abs()), "{text}: {b} where the derivation has {a}");
        }
        assert!(named > 10, "only {named} expressions use a name");
    }

    /// A small model's report has no definitions, and no `definitions` field.
    #[test]
    fn a_small_report_prints_trees() {
        let d = derive(
            "coordinates = [\"th\"]\ngravity = \"g\"\n[parameters]\ng = 9.81\n\
             [[particles]]\nmass = \"1\"\nposition = [\"sin(th)\", \"-cos(th)\"]\n",
        );
        assert!(!prints_shared(&d));
        let json = serde_json::to_value(DeriveReport::new(&d)).expect("serializes");
        assert!(json.get("definitions").is_none(), "{json}");
        assert_eq!(json["mass_matrix"][0][0], "1");
    }
}
