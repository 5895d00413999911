//! The human formats of `derive`: text that reads like the lecture notes,
//! LaTeX, and MathML in HTML for the report. (JSON is the `mech::DeriveReport`
//! serialized as it is.)
//!
//! Enter with [`text`], [`latex`] or [`mathml`]. One walk over the derivation
//! ([`layout`]) decides what is shown and in which order, as a sequence of
//! [`Item`]s; the three renderings ([`Text`], [`Latex`], [`MathMl`]) write each
//! item their way, or not at all: LaTeX gives the equations, the text and the
//! MathML also the verdicts and their reasons.
//!
//! A large derivation ([`mech::prints_shared`], the same decision as its
//! JSON's) is written with named intermediates: each rendering runs once to
//! list the expressions it prints, [`sym::Pool::share`] names the
//! subexpressions they would repeat, and the second run writes those as
//! `w1`, `w2`, … and ends with their definitions (a `where` section, a last
//! `align*` block, a last table).

use mech::{BodyMotion, Constraint, Derivation};
use std::fmt::Write;
use sym::{ExprId, PrintOptions, Printout};

/// How the renderings of `d` write expressions: as trees when `d` is small;
/// otherwise with the nodes named that the roots `list` prints (given a
/// listing printout, it renders and hands the printout back) would repeat.
fn printout(d: &Derivation, list: impl FnOnce(Printout) -> Printout) -> Printout {
    if !mech::prints_shared(d) {
        return Printout::Trees;
    }
    let roots = list(Printout::roots()).into_roots();
    Printout::Named(d.pool().share(&roots))
}

/// The derivation as text, with the notes' names and the reasons behind each verdict.
pub fn text(d: &Derivation) -> String {
    let render = |out: Printout| {
        let mut r = Text { d, names: d.coordinate_names(), o: String::new(), out };
        layout(d, &mut |item| r.item(item));
        r
    };
    let out = printout(d, |out| render(out).out);
    render(out).finish()
}

/// The derivation as LaTeX (an `align*` environment per section).
pub fn latex(d: &Derivation) -> String {
    let render = |out: Printout| {
        let q = d.q().iter().map(|&q| d.pool().latex(q).to_string()).collect();
        let mut r = Latex { d, q, o: String::new(), blocks: Default::default(), out };
        layout(d, &mut |item| r.item(item));
        r
    };
    let out = printout(d, |out| render(out).out);
    render(out).finish()
}

/// The derivation as an HTML fragment, `<section class="derivation">`: a
/// heading (`<h3>`) per section, each group of equations one
/// `<math display="block">` table, and the verdicts and their reasons as
/// paragraphs. It holds no entity but XML's, so it is also well-formed XML.
pub fn mathml(d: &Derivation) -> String {
    let render = |out: Printout| {
        let mut r = MathMl::new(d, out, None);
        layout(d, &mut |item| r.item(item));
        r
    };
    let out = printout(d, |out| render(out).out);
    render(out).finish()
}

/// The derivation as [`mathml`] writes it when that takes at most `budget`
/// bytes as `size` counts them (a page may escape it); otherwise its outline: the model, the cyclic coordinates and the
/// verdicts with their reasons, without the expressions, and a paragraph
/// saying what was left out and that `lagrange derive` prints it. A page that
/// must open quickly (the report) cannot hold a large mechanism's equations:
/// a chain of 50 rods takes 20 MB of MathML, most of it named intermediates.
pub fn mathml_within(d: &Derivation, budget: usize, size: impl Fn(&str) -> usize) -> String {
    let whole = mathml(d);
    let bytes = size(&whole);
    if bytes <= budget {
        return whole;
    }
    let mut r = MathMl::new(d, Printout::Trees, Some(Outline { whole: bytes, budget }));
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
    /// The inputs u, their values in runs, and B = ∂f/∂u.
    Inputs,
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
    if !d.inputs().is_empty() {
        emit(Item::Inputs);
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
    out: Printout,
}

impl Text<'_> {
    fn s(&self, e: ExprId) -> String {
        self.out.write(self.d.pool(), e, PrintOptions::text())
    }

    /// The text, with the named intermediates' definitions last.
    fn finish(mut self) -> String {
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

/// The tags of a constraint: its kind, whether it depends on time, and for a
/// velocity constraint whether it is integrable.
fn constraint_tags(c: &Constraint) -> Vec<&'static str> {
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
    tags.into_iter().flatten().collect()
}

/// Whether H is the energy, as a sentence without its reasons.
fn energy_verdict(d: &Derivation) -> &'static str {
    match d.hamiltonian_is_energy() {
        Some(true) => "H is the energy",
        Some(false) => "H is not the energy",
        None => "whether H is the energy is not known",
    }
}

/// Whether H is conserved, as a sentence without its reasons.
fn conservation_verdict(d: &Derivation) -> &'static str {
    if d.hamiltonian_conserved() {
        "H is conserved"
    } else {
        "H is not conserved"
    }
}

/// What becomes of the momentum of cyclic coordinate `i`: conserved, or why not.
fn cyclic_momentum(d: &Derivation, names: &[&str], i: usize) -> &'static str {
    let pool = d.pool();
    if d.conserved().iter().any(|c| c.name == format!("p_{}", names[i])) {
        "is conserved"
    } else if d.constraints().list.iter().any(|c| !pool.is_zero(c.jacobian[i])) {
        "would be conserved, but a constraint force acts on it"
    } else if d
        .verdicts()
        .cyclic
        .iter()
        .any(|r| matches!(r, mech::CyclicReason::MomentumUndecided { coordinate } if *coordinate == names[i]))
    {
        "would be conserved, but whether dissipation or a force acts on it is not known"
    } else {
        "would be conserved, but dissipation or a force acts on it"
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
    blocks: [Vec<(String, Option<String>)>; 4],
    out: Printout,
}

impl Latex<'_> {
    /// The blocks: the definitions and equations of motion, the constraints
    /// and the equations with multipliers, Hamilton's equations.
    const MAIN: usize = 0;
    const CONSTRAINTS: usize = 1;
    const HAMILTON: usize = 2;
    /// The named intermediates' definitions.
    const WHERE: usize = 3;

    fn l(&self, e: ExprId) -> String {
        self.out.write(self.d.pool(), e, PrintOptions::latex())
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
            | Item::Inputs
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
    fn finish(mut self) -> String {
        if let Some(shared) = self.out.shared() {
            let pool = self.d.pool();
            for (k, (_, id)) in shared.definitions().enumerate() {
                let row = format!(
                    "{} &= {}",
                    shared.print(pool, id, PrintOptions::latex()),
                    shared.print_definition(pool, id, PrintOptions::latex())
                );
                let comment = (k == 0).then(|| "where".to_string());
                self.blocks[Self::WHERE].push((row, comment));
            }
        }
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

/// The MathML rendering: an HTML fragment with a heading per section, the
/// equations as `<mtable>` rows in block `<math>` elements (as LaTeX's
/// `align*`), and, as the text says them, the verdicts and their reasons in
/// paragraphs. Rows gather until prose follows, then go down as one table.
struct MathMl<'a> {
    d: &'a Derivation,
    /// The coordinates' names, for the sentences shared with the text.
    names: Vec<&'a str>,
    /// Each coordinate in MathML.
    q: Vec<String>,
    o: String,
    /// The rows not yet set.
    rows: Vec<Row>,
    out: Printout,
    /// Set when only the outline is written (see [`mathml_within`]).
    outline: Option<Outline>,
}

/// The sizes behind an outline: the whole derivation's and the room there was.
#[derive(Clone, Copy)]
struct Outline {
    whole: usize,
    budget: usize,
}

/// One row of an equation table: cells alternately right- and left-aligned
/// (`T`, `= …`, as `align*` pairs them), then an optional note.
struct Row {
    cells: Vec<String>,
    note: Option<String>,
}

/// `∂top/∂bottom` in MathML.
fn partial(top: &str, bottom: &str) -> String {
    format!("<mfrac><mrow><mo>∂</mo>{top}</mrow><mrow><mo>∂</mo>{bottom}</mrow></mfrac>")
}

/// A dot over `base`: its time derivative.
fn dotted(base: &str) -> String {
    format!("<mover>{base}<mo>˙</mo></mover>")
}

/// A dot over a printed symbol: over its base when it has a subscript, so
/// `p_θ` becomes ṗ_θ as `p_th'` prints.
fn dotted_symbol(symbol: &str) -> String {
    let base_and_sub = symbol.strip_prefix("<msub><mi>").and_then(|rest| rest.split_once("</mi>"));
    match base_and_sub {
        Some((base, sub)) => format!("<msub>{}{sub}", dotted(&format!("<mi>{base}</mi>"))),
        None => dotted(symbol),
    }
}

/// A MathML identifier with a subscript.
fn sub(base: &str, subscript: &str) -> String {
    format!("<msub><mi>{base}</mi>{subscript}</msub>")
}

/// `(items)`, comma separated: a tuple or a row vector.
fn tuple(items: &[String]) -> String {
    format!("<mrow><mo>(</mo>{}<mo>)</mo></mrow>", items.join("<mo>,</mo>"))
}

/// Plain text, escaped for HTML and MathML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Inline math.
fn inline(math: &str) -> String {
    format!("<math>{math}</math>")
}

const EQUALS: &str = "<mo>=</mo>";
const MINUS: &str = "<mo>&#x2212;</mo>";

impl<'a> MathMl<'a> {
    fn new(d: &'a Derivation, out: Printout, outline: Option<Outline>) -> MathMl<'a> {
        MathMl {
            d,
            names: d.coordinate_names(),
            q: d.q().iter().map(|&q| d.pool().mathml(q).to_string()).collect(),
            o: String::from("<section class=\"derivation\">\n"),
            rows: Vec::new(),
            out,
            outline,
        }
    }

    fn m(&self, e: ExprId) -> String {
        self.out.write(self.d.pool(), e, PrintOptions::mathml())
    }

    /// `lhs = rhs` as a row, with a note in words (and math).
    fn row(&mut self, lhs: String, rhs: String, note: Option<String>) {
        self.rows.push(Row { cells: vec![lhs, format!("{EQUALS}{rhs}")], note });
    }

    /// A note at the end of a row: words, then math.
    fn note(words: &str, math: &str) -> Option<String> {
        Some(format!("<mtext>{}&#xA0;</mtext>{math}", escape(words)))
    }

    /// Sets the gathered rows as one table.
    fn flush(&mut self) {
        if self.rows.is_empty() {
            return;
        }
        self.o.push_str("<math display=\"block\"><mtable>");
        for row in std::mem::take(&mut self.rows) {
            self.o.push_str("<mtr>");
            for (k, cell) in row.cells.iter().enumerate() {
                let align = if k % 2 == 0 { "right" } else { "left" };
                let _ = write!(self.o, "<mtd columnalign=\"{align}\" style=\"text-align: {align}\">{cell}</mtd>");
            }
            if let Some(note) = row.note {
                let _ = write!(
                    self.o,
                    "<mtd columnalign=\"left\" style=\"text-align: left; padding-left: 2em; white-space: nowrap\">{note}</mtd>"
                );
            }
            self.o.push_str("</mtr>");
        }
        self.o.push_str("</mtable></math>\n");
    }

    /// A paragraph of HTML, after the rows before it.
    fn para(&mut self, html: &str) {
        self.flush();
        let _ = writeln!(self.o, "<p>{html}</p>");
    }

    /// A list of reasons, each plain text.
    fn reasons<T: std::fmt::Display>(&mut self, reasons: &[T]) {
        if reasons.is_empty() {
            return;
        }
        self.flush();
        self.o.push_str("<ul>");
        for r in reasons {
            let _ = write!(self.o, "<li>{}</li>", escape(&r.to_string()));
        }
        self.o.push_str("</ul>\n");
    }

    fn heading(&mut self, html: &str) {
        self.flush();
        let _ = writeln!(self.o, "<h3>{html}</h3>");
    }

    fn item(&mut self, item: Item<'_>) {
        if let Some(outline) = self.outline {
            self.outline_item(item, outline);
            return;
        }
        let d = self.d;
        let pool = d.pool();
        match item {
            Item::Title => {
                let (n, qs) = (self.q.len(), self.q.iter().map(|q| inline(q)).collect::<Vec<_>>().join(", "));
                let name = format!("<strong>{}</strong>", escape(&d.model().name));
                if d.constraints().is_empty() {
                    self.para(&format!("{name}: {n} degree{} of freedom: {qs}", plural(n)));
                } else {
                    let (k, m) = (d.constraints().degrees_of_freedom, d.constraints().list.len());
                    self.para(&format!(
                        "{name}: {n} coordinate{}: {qs}; {m} constraint{}: {k} degree{} of freedom",
                        plural(n),
                        plural(m),
                        plural(k)
                    ));
                }
                self.parameters();
                self.heading("Lagrangian");
            }
            Item::Define(what, e) => {
                let (name, words) = match what {
                    Defined::Kinetic => ("T", "kinetic energy"),
                    Defined::Potential => ("U", "potential"),
                    Defined::Lagrangian => ("L", "Lagrangian"),
                    Defined::Dissipation => ("R", "dissipation"),
                };
                self.row(format!("<mi>{name}</mi>"), self.m(e), Self::note(words, ""));
            }
            Item::Force(i, f) => {
                self.row(sub("Q", &self.q[i]), self.m(f), Self::note("generalized force", ""));
            }
            Item::Inputs => {
                let names_u: Vec<String> = d.model().inputs.iter().map(|u| escape(&u.name)).collect();
                self.para(&format!("Inputs u = ({}), symbols here; B = ∂f/∂u:", names_u.join(", ")));
                for (i, row) in d.input_matrix().iter().enumerate() {
                    let row: Vec<String> = row.iter().map(|&b| self.m(b)).collect();
                    self.row(sub("B", &self.q[i]), tuple(&row), None);
                }
            }
            Item::Body(b) => {
                self.para(&format!("Rigid body ‘{}’ (body frame, notes A.5)", escape(&b.name)));
                for k in 0..3 {
                    let note = if k == 0 { Self::note("angular velocity", "") } else { None };
                    self.row(sub("ω", &format!("<mn>{}</mn>", k + 1)), self.m(b.omega[k]), note);
                }
                for k in 0..3 {
                    let note = if k == 0 { Self::note("angular momentum", "") } else { None };
                    self.row(sub("L", &format!("<mn>{}</mn>", k + 1)), self.m(b.angular_momentum[k]), note);
                }
            }
            Item::Heading(section) => self.section(section),
            Item::Momentum(i, p) => self.row(self.m(d.p()[i]), self.m(p), None),
            Item::Equation(i, e) | Item::MultiplierEquation(i, e) => {
                self.row("<mn>0</mn>".into(), self.m(e), Self::note("for", &self.q[i]));
            }
            Item::MassMatrixForm => self.mass_matrix_form(),
            Item::Constraint(c) => {
                let words = format!("{} ({})", c.name, constraint_tags(c).join(", "));
                self.row("<mn>0</mn>".into(), self.m(c.expr), Self::note(&words, ""));
                let row: Vec<String> = c.jacobian.iter().map(|&e| self.m(e)).collect();
                let mut a = format!("A row: {}", inline(&tuple(&row)));
                if !pool.is_zero(c.time_term) {
                    let _ = write!(
                        a,
                        ", {}",
                        inline(&format!("{}{EQUALS}{}", sub("a", "<mi>t</mi>"), self.m(c.time_term)))
                    );
                }
                self.para(&a);
                for line in &c.explanation {
                    self.para(&escape(line));
                }
            }
            Item::ConstraintNotes => {
                for line in &d.constraints().explanation {
                    self.para(&escape(line));
                }
            }
            Item::ConstraintForces => self.constraint_forces(),
            Item::Cyclic => self.cyclic(),
            Item::Hamiltonian(Some(h)) => self.row("<mi>H</mi>".into(), self.m(h), None),
            Item::Hamiltonian(None) => {
                self.para("Not in closed form; the energy function is");
                let qd = dotted("<mi>q</mi>");
                let h = format!("<mi>h</mi>{}", tuple(&["<mi>q</mi>".into(), qd, "<mi>t</mi>".into()]));
                self.row(h, self.m(d.energy_function()), None);
                self.reasons(&d.verdicts().hamiltonian);
            }
            Item::Verdicts => {
                if let Some(e) = d.energy() {
                    self.row("<mi>T</mi><mo>+</mo><mi>U</mi>".into(), self.m(e), Self::note("energy", ""));
                }
                self.para(&format!("{}:", energy_verdict(d)));
                self.reasons(&d.verdicts().energy);
                self.para(&format!("{}:", conservation_verdict(d)));
                self.reasons(&d.verdicts().conservation);
            }
            Item::HamiltonEquation(i, dq, dp) => {
                let (qd, pd) = (self.m(d.qd()[i]), dotted_symbol(&self.m(d.p()[i])));
                let cells =
                    vec![qd, format!("{EQUALS}{}<mo>,</mo>", self.m(dq)), pd, format!("{EQUALS}{}", self.m(dp))];
                self.rows.push(Row { cells, note: None });
            }
        }
    }

    /// The parameters and their values, when there are any.
    fn parameters(&mut self) {
        let parameters = &self.d.model().parameters;
        if !parameters.is_empty() {
            let ps: Vec<String> = parameters.iter().map(|p| escape(&format!("{} = {}", p.name, p.value))).collect();
            self.para(&format!("Parameters: {}", ps.join(", ")));
        }
    }

    /// What the outline keeps of an item: the title, the words of the
    /// constraints, the cyclic coordinates and the verdicts, no expression.
    fn outline_item(&mut self, item: Item<'_>, outline: Outline) {
        let d = self.d;
        let mb = |bytes: usize| format!("{:.2} MB", bytes as f64 / 1e6);
        match item {
            Item::Title => {
                let (n, qs) = (self.q.len(), self.q.iter().map(|q| inline(q)).collect::<Vec<_>>().join(", "));
                self.para(&format!("<strong>{}</strong>: {n} coordinate{}: {qs}", escape(&d.model().name), plural(n)));
                self.parameters();
                self.para(&format!(
                    "Its equations of motion, typeset, take {}, more than this page holds ({}): \
                     <code>lagrange derive</code> prints them all, as text, LaTeX or JSON. Here are its verdicts.",
                    mb(outline.whole),
                    mb(outline.budget)
                ));
            }
            Item::ConstraintNotes => {
                self.heading("Constraints");
                for line in &d.constraints().explanation {
                    self.para(&escape(line));
                }
            }
            Item::Cyclic => self.cyclic(),
            Item::Heading(Section::Hamiltonian) => self.heading("Hamiltonian"),
            Item::Hamiltonian(None) => {
                self.para("H has no closed form:");
                self.reasons(&d.verdicts().hamiltonian);
            }
            Item::Verdicts => {
                self.para(&format!("{}:", energy_verdict(d)));
                self.reasons(&d.verdicts().energy);
                self.para(&format!("{}:", conservation_verdict(d)));
                self.reasons(&d.verdicts().conservation);
            }
            _ => {}
        }
    }

    fn section(&mut self, section: Section) {
        let d = self.d;
        let pool = d.pool();
        let forced = d.forces().iter().any(|f| !pool.is_zero(*f));
        let dissipative = d.dissipation().is_some();
        let (q, qd, l) = ("<mi>q</mi>", dotted("<mi>q</mi>"), "<mi>L</mi>");
        match section {
            Section::Momenta => self.heading(&format!(
                "Generalized momenta {}",
                inline(&format!("{}{EQUALS}{}", sub("p", q), partial(l, &qd)))
            )),
            Section::Equations => {
                let mut lhs = format!(
                    "<mfrac><mi>d</mi><mrow><mi>d</mi><mi>t</mi></mrow></mfrac>{}{MINUS}{}",
                    partial(l, &qd),
                    partial(l, q)
                );
                if dissipative {
                    let _ = write!(lhs, "<mo>+</mo>{}", partial("<mi>R</mi>", &qd));
                }
                if forced {
                    let _ = write!(lhs, "{MINUS}<mi>Q</mi>");
                }
                self.heading(&format!("Euler–Lagrange equations {}", inline(&format!("{lhs}{EQUALS}<mn>0</mn>"))));
            }
            Section::Constraints => {
                self.heading("Constraints");
                self.para(&format!(
                    "{} for {}; the velocity coefficients for {}",
                    inline(&format!("<mi>A</mi>{EQUALS}{}", partial("<mi>f</mi>", q))),
                    inline(&format!("<mi>f</mi><mo>(</mo>{q}<mo>,</mo><mi>t</mi><mo>)</mo>{EQUALS}<mn>0</mn>")),
                    inline(&format!(
                        "<mi>a</mi><mo>(</mo>{q}<mo>,</mo><mi>t</mi><mo>)</mo><mo>&#x22C5;</mo>{qd}<mo>+</mo>{}{EQUALS}<mn>0</mn>",
                        sub("a", "<mi>t</mi>")
                    ))
                ));
            }
            Section::Multipliers => {
                let lambdas: Vec<String> = d.constraints().list.iter().map(|c| self.m(c.multiplier)).collect();
                self.heading(&format!(
                    "Equations with multipliers {}, {}",
                    inline(&format!(
                        "<mi>M</mi>{}{EQUALS}<mi>f</mi><mo>+</mo><msup><mi>A</mi><mi>T</mi></msup><mi>λ</mi>",
                        dotted_twice(q)
                    )),
                    inline(&format!("<mi>λ</mi>{EQUALS}{}", tuple(&lambdas)))
                ));
            }
            Section::Hamiltonian => self.heading(&format!(
                "Hamiltonian {}, in (q, p, t)",
                inline(&format!("<mi>H</mi>{EQUALS}<mo>∑</mo>{qd}<mi>p</mi>{MINUS}{l}"))
            )),
            Section::Hamilton => {
                let h = "<mi>H</mi>";
                let mut pd = format!("{MINUS}{}", partial(h, q));
                if dissipative || forced {
                    let _ = write!(pd, "{MINUS}{}<mo>+</mo><mi>Q</mi>", partial("<mi>R</mi>", &qd));
                }
                self.heading(&format!(
                    "Hamilton’s equations {}, {}",
                    inline(&format!("{qd}{EQUALS}{}", partial(h, "<mi>p</mi>"))),
                    // In its own row the minus is a sign, not a binary operator.
                    inline(&format!("{}{EQUALS}<mrow>{pd}</mrow>", dotted("<mi>p</mi>")))
                ));
            }
        }
    }

    /// `M q̈ = f` with M, q̈ and f as matrices.
    fn mass_matrix_form(&mut self) {
        let d = self.d;
        let (q, qd) = ("<mi>q</mi>", dotted("<mi>q</mi>"));
        self.heading(&format!(
            "In the form {}",
            inline(&format!(
                "<mi>M</mi><mo>(</mo>{q}<mo>,</mo><mi>t</mi><mo>)</mo>{}{EQUALS}<mi>f</mi><mo>(</mo>{q}<mo>,</mo>{qd}<mo>,</mo><mi>t</mi><mo>)</mo>",
                dotted_twice(q)
            ))
        ));
        let cells: Vec<Vec<String>> =
            d.mass_matrix().iter().map(|row| row.iter().map(|&e| self.m(e)).collect()).collect();
        let qdd: Vec<Vec<String>> = d.qdd().iter().map(|&e| vec![self.m(e)]).collect();
        let f: Vec<Vec<String>> = d.forcing().iter().map(|&e| vec![self.m(e)]).collect();
        self.row(format!("{}{}", matrix(&cells), matrix(&qdd)), matrix(&f), None);
    }

    fn constraint_forces(&mut self) {
        let d = self.d;
        let set = d.constraints();
        self.para(&format!(
            "With the constraints differentiated to {} (index reduction), {} and λ follow at each instant.",
            inline(&format!("<mi>A</mi>{}{EQUALS}<mi>c</mi>", dotted_twice("<mi>q</mi>"))),
            inline(&dotted_twice("<mi>q</mi>"))
        ));
        self.heading(&format!(
            "Constraint forces {} (generalized)",
            inline(&format!("<mi>Q</mi>{EQUALS}<msup><mi>A</mi><mi>T</mi></msup><mi>λ</mi>"))
        ));
        for (i, &f) in set.generalized_forces.iter().enumerate() {
            self.row(sub("Q", &self.q[i]), self.m(f), None);
        }
        if let Some(parts) = &set.cartesian_forces {
            self.para(&format!(
                "Cartesian, on each particle ({} with {}):",
                inline("<mi>F</mi>"),
                inline(&format!(
                    "<mi>Q</mi>{EQUALS}<msup><mrow><mo>(</mo>{}<mo>)</mo></mrow><mi>T</mi></msup><mi>F</mi>",
                    partial("<mi>x</mi>", "<mi>q</mi>")
                ))
            ));
            for (k, f) in parts.iter().enumerate() {
                let comps: Vec<String> = f.iter().map(|&e| self.m(e)).collect();
                self.row(
                    sub("F", &format!("<mn>{}</mn>", k + 1)),
                    tuple(&comps),
                    Self::note("on particle", &format!("<mn>{}</mn>", k + 1)),
                );
            }
        }
    }

    /// The cyclic coordinates and what becomes of their momenta, as the text says it.
    fn cyclic(&mut self) {
        let d = self.d;
        self.heading("Cyclic coordinates");
        let undecided = &d.verdicts().cyclic;
        if d.cyclic().is_empty() && undecided.is_empty() {
            self.para("None: L depends on every coordinate.");
            return;
        }
        if d.cyclic().is_empty() {
            self.para("None shown.");
        }
        for &i in d.cyclic() {
            let q = &self.q[i];
            let sentence = format!(
                "{}: {}, so {} {}.",
                inline(q),
                inline(&format!("{}{EQUALS}<mn>0</mn>", partial("<mi>L</mi>", q))),
                match self.outline {
                    None => inline(&format!("{}{EQUALS}{}", self.m(d.p()[i]), self.m(d.momenta()[i]))),
                    Some(_) => inline(&self.m(d.p()[i])),
                },
                cyclic_momentum(d, &self.names, i)
            );
            self.para(&sentence);
        }
        for reason in undecided {
            self.para(&escape(&reason.to_string()));
        }
    }

    fn finish(mut self) -> String {
        if let Printout::Named(shared) = std::mem::replace(&mut self.out, Printout::Trees) {
            self.heading("Where");
            let pool = self.d.pool();
            for (_, id) in shared.definitions() {
                self.row(
                    shared.print(pool, id, PrintOptions::mathml()).to_string(),
                    shared.print_definition(pool, id, PrintOptions::mathml()).to_string(),
                    None,
                );
            }
        }
        self.flush();
        self.o.push_str("</section>\n");
        self.o
    }
}

/// Two dots over `base`: its second time derivative.
fn dotted_twice(base: &str) -> String {
    format!("<mover>{base}<mo>¨</mo></mover>")
}

/// A matrix in square brackets, its entries centred.
fn matrix(rows: &[Vec<String>]) -> String {
    let mut o = String::from("<mrow><mo>[</mo><mtable>");
    for row in rows {
        o.push_str("<mtr>");
        for cell in row {
            let _ = write!(o, "<mtd>{cell}</mtd>");
        }
        o.push_str("</mtr>");
    }
    o.push_str("</mtable><mo>]</mo></mrow>");
    o
}

/// User text inside a LaTeX comment: a line break would end the comment and
/// turn the rest into live LaTeX (`\input{...}`), so every control character
/// becomes a space.
fn comment_text(text: &str) -> String {
    text.chars().map(|c| if c.is_control() { ' ' } else { c }).collect()
}

#[cfg(test)]
mod tests {
    use super::{latex, mathml, mathml_within, text};

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

    /// The block `<math>` elements of a fragment, as text.
    fn blocks(html: &str) -> Vec<&str> {
        html.split("<math display=\"block\">").skip(1).map(|b| b.split("</math>").next().unwrap_or(b)).collect()
    }

    /// Checks that the fragment of `d` is well-formed, a section with no text
    /// outside its children, and that every equation the derivation holds is
    /// set in a block `<math>`.
    #[track_caller]
    fn check_mathml(d: &mech::Derivation) -> String {
        let out = mathml(d);
        let doc = roxmltree::Document::parse(&out).unwrap_or_else(|e| panic!("{e}: not well-formed:\n{out}"));
        let section = doc.root_element();
        assert_eq!((section.tag_name().name(), section.attribute("class")), ("section", Some("derivation")));
        let blocks = blocks(&out);
        let pool = d.pool();
        let mut equations: Vec<sym::ExprId> = d.momenta().to_vec();
        equations.extend(d.equations());
        equations.extend(d.forcing());
        equations.extend(d.hamiltonian());
        equations.extend(d.constraints().list.iter().map(|c| c.expr));
        equations.extend(d.hamilton().unwrap_or_default().iter().flat_map(|&(dq, dp)| [dq, dp]));
        for e in equations {
            let m = pool.mathml(e).to_string();
            assert!(blocks.iter().any(|b| b.contains(&m)), "{} is in no block of\n{out}", pool.display(e));
        }
        out
    }

    #[test]
    fn a_derivation_past_the_budget_is_outlined_with_its_verdicts() {
        let d = derive(FREE);
        let whole = mathml(&d);
        assert_eq!(mathml_within(&d, whole.len(), str::len), whole);
        let outline = mathml_within(&d, whole.len() - 1, str::len);
        let doc = roxmltree::Document::parse(&outline).unwrap_or_else(|e| panic!("{e}: not well-formed:\n{outline}"));
        assert_eq!(doc.root_element().attribute("class"), Some("derivation"));
        // No equation, and a pointer to where they are.
        assert!(!outline.contains("<math display=\"block\">"), "{outline}");
        assert!(outline.contains("<code>lagrange derive</code> prints them all"), "{outline}");
        // The cyclic coordinate, with its momentum named, not written out.
        check_contains(&outline, &["Cyclic coordinates", "is conserved", "H is the energy", "Hamiltonian"]);
        assert!(!outline.contains(&d.pool().mathml(d.momenta()[1]).to_string()), "{outline}");
    }

    #[test]
    fn mathml_sets_the_equations_and_says_the_verdicts() {
        let d = derive(PENDULUM);
        let out = check_mathml(&d);
        let doc = roxmltree::Document::parse(&out).expect("well-formed");
        let headings: Vec<String> = doc
            .descendants()
            .filter(|n| n.has_tag_name("h3"))
            .map(|h| h.children().find(|c| c.is_text()).and_then(|t| t.text()).unwrap_or_default().trim().to_string())
            .collect();
        assert_eq!(
            headings,
            [
                "Lagrangian",
                "Generalized momenta",
                "Euler–Lagrange equations",
                "In the form",
                "Cyclic coordinates",
                "Hamiltonian",
                "Hamilton’s equations"
            ]
        );
        // T, U, L; the momentum; the equation of motion; M q'' = f; H and T + U; Hamilton's equations.
        assert_eq!(blocks(&out).len(), 6, "{out}");
        check_contains(
            &out,
            &[
                "<p><strong>pendulum</strong>: 1 degree of freedom: <math><mi>θ</mi></math></p>",
                "<p>None: L depends on every coordinate.</p>",
                "<p>H is the energy:</p>",
                "<p>H is conserved:</p>",
                "<mtext>for&#xA0;</mtext><mi>θ</mi>",
            ],
        );
        for reason in d
            .verdicts()
            .energy
            .iter()
            .map(ToString::to_string)
            .chain(d.verdicts().conservation.iter().map(ToString::to_string))
        {
            check_contains(
                &out,
                &[&format!("<li>{}</li>", reason.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;"))],
            );
        }

        let out = check_mathml(&derive(FREE));
        check_contains(&out, &["<p><math><mi>θ</mi></math>: <math>", "</math> is conserved.</p>"]);
        // The model's name is text, not markup.
        let out = check_mathml(&derive(&PENDULUM.replace("name = \"pendulum\"", "name = \"<b>&</b>\"")));
        check_contains(&out, &["<strong>&lt;b&gt;&amp;&lt;/b&gt;</strong>"]);
    }

    /// The benchmark bicycle, the one example large enough to print with named intermediates.
    const BICYCLE: &str = include_str!("../../../examples/bicycle/benchmark_bicycle.toml");

    /// The names `w1`, `w2`, … a text uses, each once, in order.
    fn names_in(text: &str) -> Vec<usize> {
        let mut names: Vec<usize> = text
            .split(|c: char| !c.is_ascii_alphanumeric())
            .filter_map(|word| word.strip_prefix('w')?.parse().ok())
            .collect();
        names.sort_unstable();
        names.dedup();
        names
    }

    /// The bicycle's text (1.5 MB as trees), LaTeX and MathML name each
    /// shared subexpression once and define every name they use, in a last
    /// section, each definition using only the names before it.
    #[test]
    fn a_large_derivation_prints_each_shared_subexpression_once() {
        let d = derive(BICYCLE);
        let out = text(&d);
        assert!(out.len() < 1_000_000, "{} bytes", out.len());
        let (body, defs) = out.split_once("\nwhere\n").expect("a where section");
        let mut defined = Vec::new();
        for line in defs.lines() {
            let (name, expr) = line.trim_start().split_once(" = ").expect("name = expr");
            for k in names_in(expr) {
                assert!(defined.contains(&k), "{name} uses w{k} before its definition");
            }
            defined.extend(names_in(name));
        }
        let used = names_in(body);
        assert!(used.len() > 100, "{} names used", used.len());
        for k in used {
            assert!(defined.contains(&k), "w{k} is used and not defined");
        }
        let out = latex(&d);
        let (_, block) = out.rsplit_once("\\begin{align*}").expect("blocks");
        assert!(block.starts_with("\nw_{1} &= ") && block.contains("  % where"), "{}", &block[..200]);
        let out = mathml(&d);
        roxmltree::Document::parse(&out).unwrap_or_else(|e| panic!("{e}: not well-formed"));
        let (_, last) = out.rsplit_once("<h3>Where</h3>").expect("a last table");
        assert!(last.contains("<msub><mi>w</mi><mn>1</mn></msub></mtd>"), "{}", &last[..400]);
    }

    #[test]
    fn mathml_of_every_example_model_is_well_formed() {
        let root = format!("{}/../../examples", env!("CARGO_MANIFEST_DIR"));
        let mut seen = 0;
        for dir in ["", "/tops", "/constraints"] {
            let dir = format!("{root}{dir}");
            let mut paths: Vec<_> = std::fs::read_dir(&dir)
                .expect("the examples are there")
                .map(|e| e.expect("a directory entry").path())
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect();
            paths.sort();
            for path in paths {
                let text = std::fs::read_to_string(&path).expect("readable");
                if !text.lines().any(|l| l.starts_with("coordinates")) {
                    continue; // a body file, which a model names
                }
                let read = |name: &str| std::fs::read_to_string(format!("{dir}/{name}")).map_err(|e| e.to_string());
                let model = mech::Model::parse_with(&text, &[], &read)
                    .unwrap_or_else(|e| panic!("{}: {}", path.display(), e.message));
                let d = mech::Derivation::new(model).expect("it derives");
                check_mathml(&d);
                seen += 1;
            }
        }
        assert!(seen >= 20, "only {seen} example models");
    }
}
