//! A model file that names a URDF (`urdf = "robot.urdf"`, optional
//! `floating_base = true`): the URDF is imported as `lagrange import` would
//! write it, and its coordinates, bodies, gravity, parameters and rest state
//! join the model's own tables (the model's parameters and initial values win).
//!
//! Entry: [`import`], which reads the URDF through the model's file reader and
//! parses the imported model's tables. Everything read from the imported text
//! is placed, in the model file, at the `urdf` value ([`Imported::span`]);
//! errors inside the URDF or the imported text are nested ([`Imported::nest`]).

use crate::error::{ModelError, ModelErrorKind, Within};
use crate::model::body::Body;
use crate::model::gravity::Gravity;
use crate::model::{FileReader, Located, RawModel, Reader};
use std::ops::Range;
use toml::Spanned;

/// A URDF named by a model file, imported.
pub(crate) struct Imported {
    /// The URDF file's name, as the model writes it.
    pub name: String,
    /// The model text the import wrote.
    pub text: String,
    /// Its tables.
    pub raw: RawModel,
    /// Where the model file names the URDF.
    pub span: Range<usize>,
}

impl Imported {
    /// An error at a place in the imported text, shown nested at the `urdf` value.
    pub fn nest(&self, e: ModelError) -> ModelError {
        let mut err =
            ModelError::at(self.span.clone(), format!("in the model imported from {}: {}", self.name, e.message));
        err.help.clone_from(&e.help);
        err.within = Some(Box::new(Within {
            what: "imported model".into(),
            name: self.name.clone(),
            text: self.text.clone(),
            error: e,
        }));
        err
    }
}

/// Reads the URDF `urdf` names (relative to the model, through `files`) and
/// imports it. `floating_base` is the model's optional flag.
pub(crate) fn import(
    urdf: &Spanned<String>,
    floating_base: Option<&Spanned<bool>>,
    files: &FileReader,
) -> Result<Imported, ModelError> {
    let name = urdf.get_ref().clone();
    let span = urdf.span();
    let text = files(&name).map_err(|e| {
        ModelError::at(span.clone(), format!("cannot read the URDF file '{name}': {e}")).with_kind(ModelErrorKind::File)
    })?;
    let config = super::UrdfConfig { floating_base: floating_base.is_some_and(|f| *f.get_ref()) };
    let model = super::urdf_to_model(&text, &name, &config).map_err(|e| {
        let mut err = ModelError::at(span.clone(), format!("in the URDF file {name}: {}", e.message));
        err.help.clone_from(&e.help);
        err.within =
            Some(Box::new(Within { what: "URDF file".into(), name: name.clone(), text: text.clone(), error: e }));
        err
    })?;
    let mut imported = Imported { name, text: model, raw: RawModel::default(), span };
    imported.raw = crate::model::read_toml(&imported.text, "model").map_err(|e| imported.nest(e))?;
    Ok(imported)
}

/// What a model naming a URDF may not give as well: the URDF gives the
/// coordinates and the bodies, and a Lagrangian would leave them out.
pub(crate) fn refuse_clashes(raw: &RawModel, i: &Imported) -> Result<(), ModelError> {
    let help = format!(
        "the coordinates and bodies come from {}; importing the URDF as a model file writes them out to edit",
        i.name
    );
    if let Some(c) = &raw.coordinates {
        return Err(
            ModelError::at(c.span(), "a model that names a `urdf` takes its `coordinates` from it").with_help(help)
        );
    }
    if let Some(b) = raw.bodies.first() {
        return Err(
            ModelError::at(b.span(), "a model that names a `urdf` takes its [[bodies]] from it").with_help(help)
        );
    }
    if let Some(l) = &raw.lagrangian {
        return Err(ModelError::at(l.span(), "give either `lagrangian` or `urdf`, not both")
            .with_help("the URDF's bodies give T and gravity's U; add to U with `potential`"));
    }
    Ok(())
}

/// Runs `read` on the imported text: the reader's source is that text
/// meanwhile, its errors are nested, and the checks it records are placed at
/// the `urdf` value.
pub(crate) fn within<'a, T>(
    r: &mut Reader<'a>,
    i: &'a Imported,
    read: impl FnOnce(&mut Reader<'a>) -> Result<T, ModelError>,
) -> Result<T, ModelError> {
    let source = std::mem::replace(&mut r.source, &i.text);
    let first = r.checks.len();
    let out = read(r);
    r.source = source;
    for c in &mut r.checks[first..] {
        c.span = i.span.clone();
    }
    out.map_err(|e| i.nest(e))
}

/// An imported body, placed at the `urdf` value.
pub(crate) fn body_at(mut b: Body, span: &Range<usize>) -> Body {
    b.name_span = span.clone();
    b.span = span.clone();
    b.inertia_span = span.clone();
    b
}

/// The imported gravity, placed at the `urdf` value.
pub(crate) fn gravity_at(g: Gravity, span: &Range<usize>) -> Gravity {
    match g {
        Gravity::Down(l) => Gravity::Down(Located { expr: l.expr, span: span.clone() }),
        Gravity::Field { components, .. } => Gravity::Field {
            components: components.into_iter().map(|l| Located { expr: l.expr, span: span.clone() }).collect(),
            span: span.clone(),
        },
    }
}
