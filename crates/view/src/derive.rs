//! The human formats of `derive`: text that reads like the lecture notes, and
//! LaTeX. (JSON is the `mech::DeriveReport` serialized as it is.)
//!
//! Enter with [`text`] or [`latex`]. One walk over the derivation ([`layout`])
//! decides what is shown and in which order, as a sequence of [`Item`]s; the
//! two renderings ([`Text`], [`Latex`]) write each item their way, or not at
//! all: LaTeX gives the equations, the text also the verdicts and their reasons.

use mech::{BodyMotion, Constraint, Derivation};
use std::fmt::Write;
use sym::ExprId;

/// The derivation as text, with the notes' names and the reasons behind each verdict.
pub fn text(d: &Derivation) -> String {
    let mut r = Text { d, names: d.coordinate_names(), o: String::new() };
    layout(d, &mut |item| r.item(item));
    r.o
}

/// The derivation as LaTeX (an `align*` environment per section).
pub fn latex(d: &Derivation) -> String {
    let q = d.q().iter().map(|&q| d.pool().latex(q).to_string()).collect();
    let mut r = Latex { d, q, o: String::new(), blocks: Default::default() };
    layout(d, &mut |item| r.item(item));
    r.finish()
}

/// One thing the layout puts down.
enum Item<'a> {
    /// The model's name, its coordinates (and constraints) and parameters.
    Title,
    /// An expression the model defines: T, U, L or R.
    Define(Defined, ExprId),
    /// The generalized force on coordinate `i`, when it is not zero.
    Force(usize, ExprId),
    /// A rigid body's angular velocity and momentum.
    Body(&'a BodyMotion),
    /// The start of a section.
    Heading(Section),
    /// The momentum of coordinate `i`.
    Momentum(usize, ExprId),
    /// The equation of motion `E_i = 0` of coordinate `i`.
    Equation(usize, ExprId),
    /// The equations as `M q'' = f`.
    MassMatrixForm,
    /// One constraint.
    Constraint(&'a Constraint),
    /// What the constraints imply together.
    ConstraintNotes,
    /// The equation with multipliers of coordinate `i`.
    MultiplierEquation(usize, ExprId),
    /// How q'' and λ are found, and the constraint forces.
    ConstraintForces,
    /// The cyclic coordinates and what they conserve.
    Cyclic,
    /// H, or why it has no closed form.
    Hamiltonian(Option<ExprId>),
    /// Whether H is the energy and whether it is conserved, with the reasons.
    Verdicts,
    /// Hamilton's equations of coordinate `i`: `q' = dq`, `p' = dp`.
    HamiltonEquation(usize, ExprId, ExprId),
}

/// The expressions a model defines.
#[derive(Clone, Copy)]
enum Defined {
    Kinetic,
    Potential,
    Lagrangian,
    Dissipation,
}

/// The sections, in the order the layout gives them.
#[derive(Clone, Copy)]
enum Section {
    Momenta,
    Equations,
    Constraints,
    Multipliers,
    Hamiltonian,
    Hamilton,
}

/// Walks the derivation in order, handing each item to `emit`.
fn layout<'a>(d: &'a Derivation, emit: &mut impl FnMut(Item<'a>)) {
    let pool = d.pool();
    emit(Item::Title);
    if let Some(t) = d.kinetic() {
        emit(Item::Define(Defined::Kinetic, t));
    }
    if let Some(u) = d.potential() {
        emit(Item::Define(Defined::Potential, u));
    }
    emit(Item::Define(Defined::Lagrangian, d.lagrangian()));
    if let Some(r) = d.dissipation() {
        emit(Item::Define(Defined::Dissipation, r));
    }
    for (i, &f) in d.forces().iter().enumerate() {
        if !pool.is_zero(f) {
            emit(Item::Force(i, f));
        }
    }
    for b in d.bodies() {
        emit(Item::Body(b));
    }
    emit(Item::Heading(Section::Momenta));
    for (i, &p) in d.momenta().iter().enumerate() {
        emit(Item::Momentum(i, p));
    }
    emit(Item::Heading(Section::Equations));
    for (i, &e) in d.equations().iter().enumerate() {
        emit(Item::Equation(i, e));
    }
    emit(Item::MassMatrixForm);
    if !d.constraints().is_empty() {
        emit(Item::Heading(Section::Constraints));
        for c in &d.constraints().list {
            emit(Item::Constraint(c));
        }
        emit(Item::ConstraintNotes);
        emit(Item::Heading(Section::Multipliers));
        for (i, &e) in d.constraints().multiplier_equations.iter().enumerate() {
            emit(Item::MultiplierEquation(i, e));
        }
        emit(Item::ConstraintForces);
    }
    emit(Item::Cyclic);
    emit(Item::Heading(Section::Hamiltonian));
    emit(Item::Hamiltonian(d.hamiltonian()));
    emit(Item::Verdicts);
    if let Some(eqs) = &d.hamilton() {
        emit(Item::Heading(Section::Hamilton));
        for (i, &(dq, dp)) in eqs.iter().enumerate() {
            emit(Item::HamiltonEquation(i, dq, dp));
        }
    }
}

/// "" for one, "s" otherwise.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// The text rendering: every item, one or more lines each.
struct Text<'a> {
    d: &'a Derivation,
    names: Vec<&'a str>,
    o: String,
}

impl Text<'_> {
    fn s(&self, e: ExprId) -> String {
        self.d.pool().display(e).to_string()
    }

    /// The width of the `name:` labels before the equations.
    fn label_width(&self) -> usize {
        self.names.iter().map(|n| n.chars().count()).max().unwrap_or(1) + 1
    }

    fn item(&mut self, item: Item<'_>) {
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
                let tags = [
                    Some(c.kind.name()),
                    Some(match c.rheonomic {
                        Some(true) => "rheonomic",
                        Some(false) => "scleronomic",
                        None => "time dependence undecided",
                    }),
                    match (c.kind, c.integrable) {
                        (mech::ConstraintKind::Velocity, Some(true)) => Some("integrable"),
                        (mech::ConstraintKind::Velocity, Some(false)) => Some("not integrable"),
                        (mech::ConstraintKind::Velocity, None) => Some("integrability undecided"),
                        _ => None,
                    },
                ];
                let tags: Vec<&str> = tags.into_iter().flatten().collect();
                let _ = writeln!(o, "  {}: {} = 0   ({})", c.name, self.s(c.expr), tags.join(", "));
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
            Item::Cyclic => self.cyclic(&mut o),
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
                let verdict = match d.hamiltonian_is_energy() {
                    Some(true) => "H is the energy",
                    Some(false) => "H is not the energy",
                    None => "whether H is the energy is not known",
                };
                let _ = writeln!(o, "  {verdict}:");
                for line in &d.verdicts().energy {
                    let _ = writeln!(o, "    {line}");
                }
                let _ = writeln!(o, "  H is {}conserved:", if d.hamiltonian_conserved() { "" } else { "not " });
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
        let pool = d.pool();
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
            let conserved = d.conserved().iter().any(|c| c.name == format!("p_{}", names[i]));
            let _ = writeln!(
                o,
                "  {}: ∂L/∂{} = 0, so p_{} = {} {}",
                names[i],
                names[i],
                names[i],
                self.s(d.momenta()[i]),
                if conserved {
                    "is conserved"
                } else if d.constraints().list.iter().any(|c| !pool.is_zero(c.jacobian[i])) {
                    "would be conserved, but a constraint force acts on it"
                } else if undecided.iter().any(
                    |r| matches!(r, mech::CyclicReason::MomentumUndecided { coordinate } if *coordinate == names[i])
                ) {
                    "would be conserved, but whether dissipation or a force acts on it is not known"
                } else {
                    "would be conserved, but dissipation or a force acts on it"
                }
            );
        }
        for reason in undecided {
            let _ = writeln!(o, "  {reason}");
        }
    }
}

/// The LaTeX rendering: the equations as rows of three `align*` blocks (the
/// definitions and equations of motion, the constraints, Hamilton's
/// equations), joined by `\\` when the blocks are closed.
struct Latex<'a> {
    d: &'a Derivation,
    /// Each coordinate in LaTeX.
    q: Vec<String>,
    /// The title; the blocks follow it.
    o: String,
    /// The rows of each block: the row and its comment.
    blocks: [Vec<(String, Option<String>)>; 3],
}

impl Latex<'_> {
    /// The blocks: the definitions and equations of motion, the constraints
    /// and the equations with multipliers, Hamilton's equations.
    const MAIN: usize = 0;
    const CONSTRAINTS: usize = 1;
    const HAMILTON: usize = 2;

    fn l(&self, e: ExprId) -> String {
        self.d.pool().latex(e).to_string()
    }

    fn item(&mut self, item: Item<'_>) {
        let d = self.d;
        let (block, row, comment) = match item {
            Item::Title => {
                let _ = writeln!(self.o, "% {} (lagrange derive --format latex)", comment_text(&d.model().name));
                return;
            }
            Item::Define(what, e) => {
                let name = match what {
                    Defined::Kinetic => "T",
                    Defined::Potential => "U",
                    Defined::Lagrangian => "L",
                    Defined::Dissipation => "R",
                };
                (Self::MAIN, format!("{name} &= {}", self.l(e)), None)
            }
            Item::Momentum(i, p) => (Self::MAIN, format!("{} &= {}", self.l(d.p()[i]), self.l(p)), None),
            Item::Equation(i, e) => {
                (Self::MAIN, format!("0 &= {}", self.l(e)), Some(format!("equation of motion for ${}$", self.q[i])))
            }
            Item::Hamiltonian(Some(h)) => (Self::MAIN, format!("H &= {}", self.l(h)), None),
            Item::Constraint(c) => (
                Self::CONSTRAINTS,
                format!("0 &= {}", self.l(c.expr)),
                Some(format!("constraint {} ({})", c.name, c.kind.name())),
            ),
            Item::MultiplierEquation(i, e) => (
                Self::CONSTRAINTS,
                format!("0 &= {}", self.l(e)),
                Some(format!("with multipliers, for ${}$", self.q[i])),
            ),
            Item::HamiltonEquation(i, dq, dp) => {
                let (qd, pd) = (self.l(d.qd()[i]), format!("\\dot{{{}}}", self.l(d.p()[i])));
                (Self::HAMILTON, format!("{} &= {}, & {} &= {}", qd, self.l(dq), pd, self.l(dp)), None)
            }
            // Text only.
            Item::Force(..)
            | Item::Body(_)
            | Item::Heading(_)
            | Item::MassMatrixForm
            | Item::ConstraintNotes
            | Item::ConstraintForces
            | Item::Cyclic
            | Item::Hamiltonian(None)
            | Item::Verdicts => return,
        };
        self.blocks[block].push((row, comment));
    }

    /// The title, then each block that has rows, every row but a block's last
    /// ending in `\\`.
    fn finish(self) -> String {
        let mut o = self.o;
        for rows in self.blocks.iter().filter(|rows| !rows.is_empty()) {
            let _ = writeln!(o, "\\begin{{align*}}");
            for (k, (row, comment)) in rows.iter().enumerate() {
                let end = if k + 1 < rows.len() { " \\\\" } else { "" };
                let _ = match comment {
                    Some(c) => writeln!(o, "{row}{end}  % {}", comment_text(c)),
                    None => writeln!(o, "{row}{end}"),
                };
            }
            let _ = writeln!(o, "\\end{{align*}}");
        }
        o
    }
}

/// User text inside a LaTeX comment: a line break would end the comment and
/// turn the rest into live LaTeX (`\input{...}`), so every control character
/// becomes a space.
fn comment_text(text: &str) -> String {
    text.chars().map(|c| if c.is_control() { ' ' } else { c }).collect()
}

#[cfg(test)]
mod tests {
    use super::{latex, text};

    /// A pendulum: one coordinate, no cyclic one, H the energy.
    const PENDULUM: &str = r#"
name = "pendulum"
coordinates = ["th"]
gravity = "g"
[parameters]
m = 2.0
g = 9.81
[[particles]]
mass = "m"
position = ["sin(th)", "-cos(th)"]
"#;

    /// A free particle in the plane in polar coordinates: th is cyclic.
    const FREE: &str = r#"
name = "free particle"
coordinates = ["r", "th"]
[[particles]]
mass = "1"
position = ["r*cos(th)", "r*sin(th)"]
"#;

    fn derive(text: &str) -> mech::Derivation {
        mech::Derivation::new(mech::Model::parse(text, &[]).expect("the model parses")).expect("it derives")
    }

    #[track_caller]
    fn check_contains(output: &str, expect: &[&str]) {
        for line in expect {
            assert!(output.contains(line), "{line:?} is missing from\n{output}");
        }
    }

    #[test]
    fn text_reads_like_the_notes() {
        let out = text(&derive(PENDULUM));
        assert!(out.starts_with("pendulum\n1 degree of freedom: th\nparameters: m = 2, g = 9.81\n"), "{out}");
        check_contains(
            &out,
            &[
                "generalized momenta p_q = ∂L/∂q'",
                "  p_th = m*th'",
                "cyclic coordinates\n  none: L depends on every coordinate",
                "  H is the energy:",
                "Hamilton's equations",
            ],
        );
        let out = text(&derive(FREE));
        check_contains(&out, &["2 degrees of freedom: r, th", "  th: ∂L/∂th = 0, so p_th = ", "is conserved"]);
    }

    #[test]
    fn latex_gives_the_equations_in_blocks() {
        let out = latex(&derive(PENDULUM));
        assert!(out.starts_with("% pendulum (lagrange derive --format latex)\n\\begin{align*}\n"), "{out}");
        assert_eq!(out.matches("\\begin{align*}").count(), 2, "main and Hamilton blocks: {out}");
        assert_eq!(out.matches("\\begin{align*}").count(), out.matches("\\end{align*}").count());
        check_contains(&out, &["% equation of motion for $\\theta$", "H &= "]);
        // A line break in the model's name would end the comment and run the rest as LaTeX.
        let out = latex(&derive(&PENDULUM.replace("name = \"pendulum\"", "name = \"a\\n\\\\input{x}\"")));
        assert!(out.starts_with("% a \\input{x} (lagrange derive --format latex)\n"), "{out}");
    }
}
