//! The `[[impacts]]` tables of a model file: unilateral contacts. A surface
//! φ(q, t) ≥ 0 that the motion may reach but not cross, and Newton's
//! coefficient of restitution e for the bounce. What a derivation makes of
//! them (the jump of the velocities) is in `derive/impact.rs`; what a run
//! does at one, in `run/impacts.rs`.

use crate::error::ModelError;
use crate::model::check::{CheckKind, ValueCheck};
use crate::model::{Located, NumOrText, Reader, Scope};
use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;

/// An `[[impacts]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawImpact {
    name: Option<Spanned<String>>,
    surface: Option<Spanned<String>>,
    restitution: Option<Spanned<NumOrText>>,
}

/// A unilateral contact as the model file states it.
#[derive(Debug, Clone)]
pub struct ImpactSpec {
    /// Its name (`impact1`, `impact2`, … by default).
    pub name: String,
    /// Where the name is (the table when the name is the default).
    pub name_span: Range<usize>,
    /// φ(q, t): the motion keeps φ ≥ 0 and bounces where φ reaches 0.
    pub surface: Located,
    /// Newton's coefficient of restitution e, in [0, 1], an expression of the parameters.
    pub restitution: Located,
}

/// Reads every `[[impacts]]` table, named apart from one another and from the
/// model's symbols, each surface a function of the coordinates (and t) only.
pub(crate) fn read_all(
    r: &mut Reader<'_>,
    raw: &[Spanned<RawImpact>],
    has_constraints: bool,
) -> Result<Vec<ImpactSpec>, ModelError> {
    let mut impacts: Vec<ImpactSpec> = Vec::new();
    for (k, table) in raw.iter().enumerate() {
        if has_constraints {
            return Err(ModelError::at(table.span(), "impacts in a model with [[constraints]] are not supported yet")
                .with_help(
                    "write the constrained coordinates out (e.g. a pendulum by its angle, not by x and y with a constraint)",
                ));
        }
        let i = table.get_ref();
        let (name, name_span) = match &i.name {
            Some(n) => {
                crate::source::check_identifier(n, "impact")?;
                (n.get_ref().clone(), n.span())
            }
            None => (format!("impact{}", k + 1), table.span()),
        };
        if impacts.iter().any(|p| p.name == name) {
            return Err(ModelError::at(name_span, format!("impact '{name}' is named twice"))
                .with_help("each impact needs a name of its own (default impact1, impact2, … in file order)"));
        }
        let Some(surface_text) = &i.surface else {
            return Err(ModelError::at(table.span(), "the impact has no `surface`")
                .with_help("write surface = \"phi(q, t)\": the motion keeps phi ≥ 0 and bounces where phi = 0"));
        };
        let what = format!("the surface of impact '{name}'");
        let surface = r.expr(surface_text, Scope::Configuration, &what)?;
        let coordinates: Vec<sym::ExprId> = r.coordinates.iter().map(|c| r.pool.var(&c.name, 0)).collect();
        if coordinates.iter().all(|&q| r.pool.free_of(surface.expr, q)) {
            return Err(ModelError::at(surface_text.span(), format!("{what} does not depend on the coordinates"))
                .with_help("a surface is where a function of the coordinates, phi(q, t), is 0, e.g. surface = \"y\" for the floor y = 0"));
        }
        let Some(e_text) = &i.restitution else {
            return Err(ModelError::at(table.span(), format!("impact '{name}' has no `restitution`"))
                .with_help("write restitution = e with 0 ≤ e ≤ 1: 1 is an elastic bounce, 0 a plastic one"));
        };
        let restitution = r.num_or_expr(e_text, Scope::Parameters, &format!("the restitution of impact '{name}'"))?;
        r.check(ValueCheck {
            kind: CheckKind::Restitution { name: name.clone(), e: restitution.expr },
            span: restitution.span.clone(),
        })?;
        r.check(ValueCheck {
            kind: CheckKind::Surface { name: name.clone(), phi: surface.expr },
            span: surface.span.clone(),
        })?;
        impacts.push(ImpactSpec { name, name_span, surface, restitution });
    }
    Ok(impacts)
}
