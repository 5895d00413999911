//! The text rendering of a derivation: it reads like the lecture notes, with
//! the reasons behind each verdict.

use mech::Derivation;
use std::fmt::Write;
use sym::{ExprId, PrintOptions, Printout};

use super::{
    conservation_verdict, constraint_tags, cyclic_momentum, energy_verdict, plural, symmetries, Defined, Item, Section,
};

/// The text rendering: every item, one or more lines each.
pub(super) struct Text<'a> {
    pub(super) d: &'a Derivation,
    pub(super) names: Vec<&'a str>,
    pub(super) o: String,
    pub(super) out: Printout,
}

impl Text<'_> {
    fn s(&self, e: ExprId) -> String {
        self.out.write(self.d.pool(), e, PrintOptions::text())
    }

    /// The text, with the named intermediates' definitions last.
    pub(super) fn finish(mut self) -> String {
        if let Some(shared) = self.out.shared() {
            let _ = writeln!(self.o, "\nwhere");
            for (name, id) in shared.definitions() {
                let _ =
                    writeln!(self.o, "  {name} = {}", shared.print_definition(self.d.pool(), id, PrintOptions::text()));
            }
        }
        self.o
    }

    /// The width of the `name:` labels before the equations.
    fn label_width(&self) -> usize {
        self.names.iter().map(|n| n.chars().count()).max().unwrap_or(1) + 1
    }

    pub(super) fn item(&mut self, item: Item<'_>) {
        let (d, names) = (self.d, &self.names);
        let pool = d.pool();
        let mut o = String::new();
        match item {
            Item::Title => {
                let n = names.len();
                let _ = writeln!(o, "{}", d.model().name);
                if d.constraints().is_empty() {
                    let _ = writeln!(o, "{} degree{} of freedom: {}", n, plural(n), names.join(", "));
                } else {
                    let (k, m) = (d.constraints().degrees_of_freedom, d.constraints().list.len());
                    let _ = writeln!(
                        o,
                        "{} coordinate{}: {}; {} constraint{}: {} degree{} of freedom",
                        n,
                        plural(n),
                        names.join(", "),
                        m,
                        plural(m),
                        k,
                        plural(k)
                    );
                }
                if !d.model().parameters.is_empty() {
                    let ps: Vec<String> =
                        d.model().parameters.iter().map(|p| format!("{} = {}", p.name, p.value)).collect();
                    let _ = writeln!(o, "parameters: {}", ps.join(", "));
                }
                o.push('\n');
            }
            Item::Define(what, e) => {
                let label = match what {
                    Defined::Kinetic => "kinetic energy      T",
                    Defined::Potential => "potential           U",
                    Defined::Lagrangian => "Lagrangian          L",
                    Defined::Dissipation => "dissipation         R",
                };
                let _ = writeln!(o, "{label} = {}", self.s(e));
            }
            Item::Force(i, f) => {
                let _ = writeln!(o, "generalized force   Q_{} = {}", names[i], self.s(f));
            }
            Item::Inputs => {
                let model = d.model();
                let names_u: Vec<String> = d.inputs().iter().map(|&u| self.s(u)).collect();
                let _ = writeln!(o, "\ninputs u = ({}), symbols here; their values in runs:", names_u.join(", "));
                for u in &model.inputs {
                    let _ = writeln!(o, "  {} = {}", u.name, self.s(u.value.expr));
                }
                let form = if d.inputs_affine() { "f = f₀ + B u" } else { "f is not affine in u; B at u" };
                let _ = writeln!(o, "  {form}, B = ∂f/∂u:");
                for (i, row) in d.input_matrix().iter().enumerate() {
                    let row: Vec<String> = row.iter().map(|&b| self.s(b)).collect();
                    let _ = writeln!(o, "    {}: [{}]", names[i], row.join(", "));
                }
            }
            Item::Body(b) => {
                let _ = writeln!(o, "\nrigid body '{}' (body frame, notes A.5)", b.name);
                for k in 0..3 {
                    let _ = writeln!(o, "  angular velocity  ω{} = {}", k + 1, self.s(b.omega[k]));
                }
                for k in 0..3 {
                    let _ = writeln!(o, "  angular momentum  L{} = {}", k + 1, self.s(b.angular_momentum[k]));
                }
            }
            Item::Heading(section) => self.heading(section, &mut o),
            Item::Momentum(i, p) => {
                let _ = writeln!(o, "  p_{} = {}", names[i], self.s(p));
            }
            Item::Equation(i, e) | Item::MultiplierEquation(i, e) => {
                let label_w = self.label_width();
                let _ = writeln!(o, "  {:<label_w$} {} = 0", format!("{}:", names[i]), self.s(e));
            }
            Item::MassMatrixForm => self.mass_matrix_form(&mut o),
            Item::Constraint(c) => {
                let _ = writeln!(o, "  {}: {} = 0   ({})", c.name, self.s(c.expr), constraint_tags(c).join(", "));
                let row: Vec<String> = c.jacobian.iter().map(|&e| self.s(e)).collect();
                let _ = writeln!(
                    o,
                    "    A row = [{}]{}",
                    row.join(", "),
                    if pool.is_zero(c.time_term) { String::new() } else { format!(",  a_t = {}", self.s(c.time_term)) }
                );
                for line in &c.explanation {
                    let _ = writeln!(o, "    {line}");
                }
            }
            Item::ConstraintNotes => {
                for line in &d.constraints().explanation {
                    let _ = writeln!(o, "  {line}");
                }
            }
            Item::ConstraintForces => {
                let set = &d.constraints();
                let _ = writeln!(
                    o,
                    "  with the constraints differentiated to A q'' = c (index reduction), q'' and λ follow at each instant."
                );
                let _ = writeln!(o, "\nconstraint forces  Q = Aᵀλ (generalized)");
                for (i, &f) in set.generalized_forces.iter().enumerate() {
                    let _ = writeln!(o, "  Q_{} = {}", names[i], self.s(f));
                }
                if let Some(parts) = &set.cartesian_forces {
                    let _ = writeln!(o, "  Cartesian, on each particle (F with Q = (∂x/∂q)ᵀF):");
                    for (k, f) in parts.iter().enumerate() {
                        let comps: Vec<String> = f.iter().map(|&e| self.s(e)).collect();
                        let _ = writeln!(o, "    particle {}: F = ({})", k + 1, comps.join(", "));
                    }
                }
            }
            Item::Impact(i) => {
                let _ = writeln!(o, "  {}: {} ≥ 0,  restitution {}", i.name, self.s(i.surface), self.s(i.restitution));
                let gradient: Vec<String> = i.gradient.iter().map(|&g| self.s(g)).collect();
                let _ = writeln!(o, "    ∇φ = [{}]", gradient.join(", "));
                if !pool.is_zero(i.rate) {
                    let _ = writeln!(o, "    ∂φ/∂t = {}", self.s(i.rate));
                }
                let _ = writeln!(o, "    v_n = {}", self.s(i.normal_velocity));
                if d.impacts().last().is_some_and(|last| std::ptr::eq(last, i)) {
                    let _ = writeln!(
                        o,
                        "  what is conserved below holds between impacts: each impact changes what its impulse acts on"
                    );
                }
            }
            Item::Cyclic => self.cyclic(&mut o),
            Item::Symmetries => {
                let _ = writeln!(o, "\nsymmetries of L (Noether: Q = Σ p·ξ − F is conserved when δL = dF/dt)");
                for c in symmetries(d) {
                    let _ = writeln!(o, "  {} = {}", c.name, self.s(c.expr));
                    let _ = writeln!(o, "    {}.", c.reason);
                }
            }
            Item::Hamiltonian(Some(h)) => {
                let _ = writeln!(o, "  H = {}", self.s(h));
            }
            Item::Hamiltonian(None) => {
                let _ = writeln!(o, "  (not in closed form) h(q, q', t) = {}", self.s(d.energy_function()));
                for line in &d.verdicts().hamiltonian {
                    let _ = writeln!(o, "    {line}");
                }
            }
            Item::Verdicts => {
                if let Some(e) = d.energy() {
                    let _ = writeln!(o, "  energy T + U = {}", self.s(e));
                }
                let _ = writeln!(o, "  {}:", energy_verdict(d));
                for line in &d.verdicts().energy {
                    let _ = writeln!(o, "    {line}");
                }
                let _ = writeln!(o, "  {}:", conservation_verdict(d));
                for line in &d.verdicts().conservation {
                    let _ = writeln!(o, "    {line}");
                }
            }
            Item::HamiltonEquation(i, dq, dp) => {
                let _ = writeln!(o, "  {}' = {}", names[i], self.s(dq));
                let _ = writeln!(o, "  p_{}' = {}", names[i], self.s(dp));
            }
        }
        self.o.push_str(&o);
    }

    fn heading(&self, section: Section, o: &mut String) {
        let d = self.d;
        let pool = d.pool();
        let forced = d.forces().iter().any(|f| !pool.is_zero(*f));
        let _ = match section {
            Section::Momenta => writeln!(o, "\ngeneralized momenta p_q = ∂L/∂q'"),
            Section::Equations => writeln!(
                o,
                "\nEuler–Lagrange equations  d/dt ∂L/∂q' − ∂L/∂q{}{} = 0",
                if d.dissipation().is_some() { " + ∂R/∂q'" } else { "" },
                if forced { " − Q" } else { "" }
            ),
            Section::Constraints => writeln!(
                o,
                "\nconstraints (A = ∂f/∂q for f(q, t) = 0; the velocity coefficients for a(q, t)·q' + a_t = 0)"
            ),
            Section::Multipliers => {
                let lambdas: Vec<String> = d.constraints().list.iter().map(|c| self.s(c.multiplier)).collect();
                writeln!(o, "\nequations with multipliers  M q'' = f + Aᵀλ,  λ = ({})", lambdas.join(", "))
            }
            Section::Impacts => writeln!(
                o,
                "\nimpacts (the motion keeps φ(q, t) ≥ 0; where φ = 0 with v_n = ∇φ·q' + ∂φ/∂t < 0: {})",
                mech::IMPACT_LAW
            ),
            Section::Hamiltonian => writeln!(o, "\nHamiltonian  H = Σ q'·p − L, in (q, p, t)"),
            Section::Hamilton => writeln!(
                o,
                "\nHamilton's equations  q' = ∂H/∂p,  p' = −∂H/∂q{}",
                if d.dissipation().is_some() || forced { " − ∂R/∂q' + Q" } else { "" }
            ),
        };
    }

    /// `M q'' = f` as a matrix, its columns aligned.
    fn mass_matrix_form(&self, o: &mut String) {
        let (d, names) = (self.d, &self.names);
        let n = names.len();
        let _ = writeln!(o, "\nin the form M(q, t) q'' = f(q, q', t)");
        let cells: Vec<Vec<String>> =
            d.mass_matrix().iter().map(|row| row.iter().map(|&e| self.s(e)).collect()).collect();
        let widths: Vec<usize> =
            (0..n).map(|j| cells.iter().map(|row| row[j].chars().count()).max().unwrap_or(1)).collect();
        let name_w = names.iter().map(|n| n.chars().count()).max().unwrap_or(1);
        for i in 0..n {
            let row: Vec<String> = (0..n).map(|j| format!("{:<w$}", cells[i][j], w = widths[j])).collect();
            let _ = writeln!(
                o,
                "  {} [ {} ] {:<name_w$}  =  {}",
                if i == n / 2 { "M =" } else { "   " },
                row.join("  "),
                format!("{}''", names[i]),
                self.s(d.forcing()[i]),
                name_w = name_w + 2
            );
        }
    }

    /// The cyclic coordinates, and whether their momenta are conserved.
    fn cyclic(&self, o: &mut String) {
        let (d, names) = (self.d, &self.names);
        let _ = writeln!(o, "\ncyclic coordinates");
        let undecided = &d.verdicts().cyclic;
        if d.cyclic().is_empty() && undecided.is_empty() {
            let _ = writeln!(o, "  none: L depends on every coordinate");
            return;
        }
        if d.cyclic().is_empty() {
            let _ = writeln!(o, "  none shown");
        }
        for &i in d.cyclic() {
            let _ = writeln!(
                o,
                "  {}: ∂L/∂{} = 0, so p_{} = {} {}",
                names[i],
                names[i],
                names[i],
                self.s(d.momenta()[i]),
                cyclic_momentum(d, names, i)
            );
        }
        for reason in undecided {
            let _ = writeln!(o, "  {reason}");
        }
    }
}
