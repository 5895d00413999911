//! The MathML rendering of a derivation, for the report: an HTML fragment,
//! whole or (past a page's budget) in outline.

use mech::Derivation;
use std::fmt::Write;
use sym::{ExprId, PrintOptions, Printout};

use super::{
    conservation_verdict, constraint_tags, cyclic_momentum, energy_verdict, plural, symmetries, Defined, Item, Section,
};
use crate::markup::text as escape;

/// The MathML rendering: an HTML fragment with a heading per section, the
/// equations as `<mtable>` rows in block `<math>` elements (as LaTeX's
/// `align*`), and, as the text says them, the verdicts and their reasons in
/// paragraphs. Rows gather until prose follows, then go down as one table.
pub(super) struct MathMl<'a> {
    pub(super) d: &'a Derivation,
    /// The coordinates' names, for the sentences shared with the text.
    pub(super) names: Vec<&'a str>,
    /// Each coordinate in MathML.
    pub(super) q: Vec<String>,
    pub(super) o: String,
    /// The rows not yet set.
    pub(super) rows: Vec<Row>,
    pub(super) out: Printout,
    /// Set when only the outline is written (see [`mathml_within`]).
    pub(super) outline: Option<Outline>,
}

/// The sizes behind an outline: the whole derivation's and the room there was.
#[derive(Clone, Copy)]
pub(super) struct Outline {
    pub(super) whole: usize,
    pub(super) budget: usize,
}

/// One row of an equation table: cells alternately right- and left-aligned
/// (`T`, `= …`, as `align*` pairs them), then an optional note.
pub(super) struct Row {
    cells: Vec<String>,
    note: Option<String>,
}

/// `∂top/∂bottom` in MathML.
pub(super) fn partial(top: &str, bottom: &str) -> String {
    format!("<mfrac><mrow><mo>∂</mo>{top}</mrow><mrow><mo>∂</mo>{bottom}</mrow></mfrac>")
}

/// A dot over `base`: its time derivative.
pub(super) fn dotted(base: &str) -> String {
    format!("<mover>{base}<mo>˙</mo></mover>")
}

/// A dot over a printed symbol: over its base when it has a subscript, so
/// `p_θ` becomes ṗ_θ as `p_th'` prints.
pub(super) fn dotted_symbol(symbol: &str) -> String {
    let base_and_sub = symbol.strip_prefix("<msub><mi>").and_then(|rest| rest.split_once("</mi>"));
    match base_and_sub {
        Some((base, sub)) => format!("<msub>{}{sub}", dotted(&format!("<mi>{base}</mi>"))),
        None => dotted(symbol),
    }
}

/// A MathML identifier with a subscript.
pub(super) fn sub(base: &str, subscript: &str) -> String {
    format!("<msub><mi>{base}</mi>{subscript}</msub>")
}

/// `(items)`, comma separated: a tuple or a row vector.
pub(super) fn tuple(items: &[String]) -> String {
    format!("<mrow><mo>(</mo>{}<mo>)</mo></mrow>", items.join("<mo>,</mo>"))
}

/// Inline math.
pub(super) fn inline(math: &str) -> String {
    format!("<math>{math}</math>")
}

pub(super) const EQUALS: &str = "<mo>=</mo>";
pub(super) const MINUS: &str = "<mo>&#x2212;</mo>";

impl<'a> MathMl<'a> {
    pub(super) fn new(d: &'a Derivation, out: Printout, outline: Option<Outline>) -> MathMl<'a> {
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

    pub(super) fn item(&mut self, item: Item<'_>) {
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
            Item::Impact(i) => {
                let words = format!("{} (e = {})", i.name, pool.print(i.restitution, sym::PrintOptions::text()));
                self.row(
                    "<mn>0</mn>".into(),
                    format!("<mo>&#x2264;</mo>{}", self.m(i.surface)),
                    Self::note(&words, ""),
                );
                let gradient: Vec<String> = i.gradient.iter().map(|&g| self.m(g)).collect();
                let v_n = sub("v", "<mi>n</mi>");
                self.para(&format!(
                    "{}, {}",
                    inline(&format!("<mo>&#x2207;</mo><mi>&#x3C6;</mi>{EQUALS}{}", tuple(&gradient))),
                    inline(&format!("{v_n}{EQUALS}{}", self.m(i.normal_velocity)))
                ));
            }
            Item::Cyclic => self.cyclic(),
            Item::Symmetries => self.symmetries(),
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
            Item::Symmetries => self.symmetries(),
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
            Section::Impacts => {
                self.heading("Impacts");
                self.para(&format!(
                    "The motion keeps each surface φ(q, t) ≥ 0; where φ = 0 with the normal velocity v_n = ∇φ·q' + ∂φ/∂t < 0, {}. What is conserved holds between impacts: each impact changes what its impulse acts on.",
                    escape(mech::IMPACT_LAW)
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

    /// The conserved quantities of symmetries of L, each with its reason.
    fn symmetries(&mut self) {
        let d = self.d;
        self.heading("Symmetries of L (Noether)");
        for c in symmetries(d) {
            let value = match self.outline {
                None => inline(&format!("<mi>{}</mi>{EQUALS}{}", escape(&c.name), self.m(c.expr))),
                Some(_) => inline(&format!("<mi>{}</mi>", escape(&c.name))),
            };
            self.para(&format!("{value}: {}.", escape(&c.reason.to_string())));
        }
    }

    pub(super) fn finish(mut self) -> String {
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
pub(super) fn dotted_twice(base: &str) -> String {
    format!("<mover>{base}<mo>¨</mo></mover>")
}

/// A matrix in square brackets, its entries centred.
pub(super) fn matrix(rows: &[Vec<String>]) -> String {
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
