//! The `[[constraints]]` tables of a model file, read into specifications:
//! a name, holonomic or velocity, and the expression. What a derivation makes
//! of them is in [`crate::derive`].

use crate::error::ModelError;
use crate::model::Located;
use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;

/// A `[[constraints]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawConstraint {
    name: Option<Spanned<String>>,
    holonomic: Option<Spanned<String>>,
    velocity: Option<Spanned<String>>,
}

/// Which kind of constraint a model states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintKind {
    /// `f(q, t) = 0`.
    Holonomic,
    /// `a(q, t)·q' + a_t = 0`.
    Velocity,
}

impl ConstraintKind {
    /// `holonomic` or `velocity`, as in the model file and the JSON report.
    pub fn name(self) -> &'static str {
        match self {
            ConstraintKind::Holonomic => "holonomic",
            ConstraintKind::Velocity => "velocity",
        }
    }
}

/// A constraint as the model file states it.
#[derive(Debug, Clone)]
pub struct ConstraintSpec {
    /// Its name (`c1`, `c2`, … by default).
    pub name: String,
    /// Where the name is (the table when the name is the default).
    pub name_span: Range<usize>,
    /// Holonomic or velocity.
    pub kind: ConstraintKind,
    /// The expression that vanishes, with its place in the file.
    pub expr: Located,
}

/// Parses an expression of a constraint: `(text, velocities_allowed, what)`.
pub(crate) type ParseExpr<'a> = &'a mut dyn FnMut(&Spanned<String>, bool, &str) -> Result<Located, ModelError>;

/// Reads one `[[constraints]]` table. `parse(text, velocities_allowed, what)`
/// parses an expression in the model's names.
pub(crate) fn read_spec(
    raw: &Spanned<RawConstraint>,
    index: usize,
    previous: &[ConstraintSpec],
    parse: ParseExpr<'_>,
) -> Result<ConstraintSpec, ModelError> {
    let c = raw.get_ref();
    let (name, name_span) = match &c.name {
        Some(n) => {
            crate::source::check_identifier(n, "constraint")?;
            (n.get_ref().clone(), n.span())
        }
        None => (format!("c{}", index + 1), raw.span()),
    };
    if previous.iter().any(|p| p.name == name) {
        return Err(ModelError::at(name_span, format!("constraint '{name}' is named twice"))
            .with_help("each constraint needs a name of its own (default c1, c2, … in file order)"));
    }
    let (kind, text) = match (&c.holonomic, &c.velocity) {
        (Some(h), None) => (ConstraintKind::Holonomic, h),
        (None, Some(v)) => (ConstraintKind::Velocity, v),
        (Some(_), Some(v)) => {
            return Err(ModelError::at(v.span(), "a constraint is either `holonomic` or `velocity`, not both")
                .with_help("give each constraint its own [[constraints]] table"))
        }
        (None, None) => {
            return Err(ModelError::at(raw.span(), "the constraint has neither `holonomic` nor `velocity`")
                .with_help("write holonomic = \"f(q, t)\" (f = 0) or velocity = \"a(q, t)·q' + a_t\""))
        }
    };
    let what = format!("the {} constraint '{name}'", kind.name());
    let expr = parse(text, kind == ConstraintKind::Velocity, &what)?;
    Ok(ConstraintSpec { name, name_span, kind, expr })
}
