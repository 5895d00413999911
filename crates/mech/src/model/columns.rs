//! The names of the columns runs write, each with the model name that makes it,
//! and the check that no two columns share a name.
//!
//! `simulate`'s CSV ([`simulate_columns`]) and a sweep's (`crate::sweep`) are
//! named here or from the same functions ([`body_columns`],
//! [`constraint_columns`]), so that the check sees every name a run writes:
//! a body `lambda` (columns `lambda_omega1`, …) beside a constraint `omega1`
//! (multiplier `lambda_omega1`) is refused when the model is read, at the later
//! name, instead of writing one column twice.

use crate::error::ModelError;
use crate::model::{ConstraintKind, Model};
use std::ops::Range;

/// One column of an output, with what makes it.
#[derive(Debug, Clone)]
pub(crate) struct Column {
    /// The column's name.
    pub name: String,
    /// What makes it, for the error: "constraint 'c1' (its multiplier)".
    pub origin: String,
    /// Where the name that makes it is written (None: lagrange's own column).
    pub span: Option<Range<usize>>,
}

impl Column {
    fn fixed(name: &str, origin: &str) -> Column {
        Column { name: name.into(), origin: origin.into(), span: None }
    }
}

/// The ω and L columns of bodies named `names`: `omega1..3`, `L1..3`, prefixed
/// with `NAME_` when there is more than one body.
pub fn body_columns(names: &[&str]) -> Vec<String> {
    let mut cols = Vec::new();
    for name in names {
        let prefix = if names.len() > 1 { format!("{name}_") } else { String::new() };
        cols.extend((1..=3).map(|k| format!("{prefix}omega{k}")));
        cols.extend((1..=3).map(|k| format!("{prefix}L{k}")));
    }
    cols
}

/// The columns of constraint `name`: `lambda_NAME`, `force_NAME`,
/// `residual_NAME` and, for a holonomic one, `residual_NAME'`.
pub fn constraint_columns(name: &str, kind: ConstraintKind) -> Vec<String> {
    let mut cols = vec![format!("lambda_{name}"), format!("force_{name}"), format!("residual_{name}")];
    if kind == ConstraintKind::Holonomic {
        cols.push(format!("residual_{name}'"));
    }
    cols
}

/// Every column `simulate`'s CSV may have for `model`: `t`, the coordinates
/// and velocities, the invariants a derivation may find (H, E, the momentum
/// `p_q` of any coordinate), the bodies' ω and L, the constraints' columns,
/// `W_constraints` and `event`.
pub(crate) fn simulate_columns(model: &Model) -> Vec<Column> {
    let mut cols = vec![Column::fixed("t", "the time")];
    for c in &model.coordinates {
        let span = Some(c.span.clone());
        let origin = format!("coordinate '{}'", c.name);
        cols.push(Column { name: c.name.clone(), origin: origin.clone(), span: span.clone() });
        cols.push(Column { name: format!("{}'", c.name), origin: format!("{origin} (its velocity)"), span });
    }
    cols.push(Column::fixed("H", "the Hamiltonian"));
    cols.push(Column::fixed("E", "the energy"));
    for c in &model.coordinates {
        let origin = format!("coordinate '{}' (its momentum, when conserved)", c.name);
        cols.push(Column { name: format!("p_{}", c.name), origin, span: Some(c.span.clone()) });
    }
    let names: Vec<&str> = model.bodies.iter().map(|b| b.name.as_str()).collect();
    for (b, body_cols) in model.bodies.iter().zip(body_columns(&names).chunks(6)) {
        for name in body_cols {
            let origin = format!("body '{}' (its ω and L)", b.name);
            cols.push(Column { name: name.clone(), origin, span: Some(b.name_span.clone()) });
        }
    }
    for c in &model.constraints {
        for name in constraint_columns(&c.name, c.kind) {
            let origin = format!("constraint '{}'", c.name);
            cols.push(Column { name, origin, span: Some(c.name_span.clone()) });
        }
    }
    if !model.constraints.is_empty() {
        cols.push(Column::fixed("W_constraints", "the constraints' work"));
    }
    cols.push(Column::fixed("event", "the events"));
    cols
}

/// An error at the later in the file of the two names that make one column
/// name, saying what makes each.
pub(crate) fn refuse_duplicates(cols: &[Column], output: &str) -> Result<(), ModelError> {
    let mut seen: rustc_hash::FxHashMap<&str, &Column> = rustc_hash::FxHashMap::default();
    for col in cols {
        let Some(first) = seen.insert(&col.name, col) else { continue };
        let message = format!(
            "{output} would have two columns '{}': one from {}, one from {}",
            col.name, first.origin, col.origin
        );
        let help = "rename one of them: every column of an output has a name of its own";
        // The later name in the file (lagrange's own columns have none).
        let span = [&col.span, &first.span].into_iter().flatten().max_by_key(|s| s.start).cloned();
        return Err(match span {
            Some(span) => ModelError::at(span, message),
            None => ModelError::whole(message),
        }
        .with_help(help));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reads a model with two bodies and a constraint, with the names given,
    /// and returns the error's message and the text it points at.
    #[track_caller]
    fn check(bodies: [&str; 2], constraint: &str, expect: Option<(&str, &str)>) {
        let body = |name: &str, angle: &str| {
            format!("[[bodies]]\nname = \"{name}\"\nmass = 1\ninertia = 1\nangle = \"{angle}\"\nposition = [\"0\", \"0\"]\n")
        };
        let text = format!(
            "coordinates = [\"a\", \"b\"]\n{}{}[[constraints]]\nname = \"{constraint}\"\nholonomic = \"a - b\"\n",
            body(bodies[0], "a"),
            body(bodies[1], "b")
        );
        match (Model::parse(&text, &[]), expect) {
            (Ok(_), None) => {}
            (Err(e), Some((message, at))) => {
                assert!(e.message.contains(message), "{}", e.message);
                assert_eq!(&text[e.span.clone().expect("a place")], at, "{text}");
            }
            (Ok(_), Some(_)) => panic!("accepted: {text}"),
            (Err(e), None) => panic!("{}: {text}", e.message),
        }
    }

    #[test]
    fn two_columns_of_one_name_are_refused_at_the_later_name() {
        check(["lambda", "arm"], "omega1", Some(("two columns 'lambda_omega1'", "\"omega1\"")));
        check(["force", "arm"], "L2", Some(("two columns 'force_L2'", "\"L2\"")));
        check(["residual", "arm"], "L3", Some(("two columns 'residual_L3'", "\"L3\"")));
        check(["arm", "lambda"], "omega1", Some(("two columns 'lambda_omega1'", "\"omega1\"")));
        check(["lambda", "arm"], "rod", None);
        check(["left", "right"], "omega1", None);
    }
}
