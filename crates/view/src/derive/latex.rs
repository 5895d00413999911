//! The LaTeX rendering of a derivation: the equations in `align*` blocks.

use mech::Derivation;
use std::fmt::Write;
use sym::{ExprId, PrintOptions, Printout};

use super::{Defined, Item};

/// The LaTeX rendering: the equations as rows of three `align*` blocks (the
/// definitions and equations of motion, the constraints, Hamilton's
/// equations), joined by `\\` when the blocks are closed.
pub(super) struct Latex<'a> {
    pub(super) d: &'a Derivation,
    /// Each coordinate in LaTeX.
    pub(super) q: Vec<String>,
    /// The title; the blocks follow it.
    pub(super) o: String,
    /// The rows of each block: the row and its comment.
    pub(super) blocks: [Vec<(String, Option<String>)>; 4],
    pub(super) out: Printout,
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

    pub(super) fn item(&mut self, item: Item<'_>) {
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
            Item::Impact(i) => (
                Self::CONSTRAINTS,
                format!("0 &\\le {}", self.l(i.surface)),
                Some(format!("impact {} (restitution ${}$)", i.name, self.l(i.restitution))),
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
            | Item::Symmetries
            | Item::Hamiltonian(None)
            | Item::Verdicts => return,
        };
        self.blocks[block].push((row, comment));
    }

    /// The title, then each block that has rows, every row but a block's last
    /// ending in `\\`.
    pub(super) fn finish(mut self) -> String {
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

/// User text inside a LaTeX comment: a line break would end the comment and
/// turn the rest into live LaTeX (`\input{...}`), so every control character
/// becomes a space.
pub(super) fn comment_text(text: &str) -> String {
    text.chars().map(|c| if c.is_control() { ' ' } else { c }).collect()
}
