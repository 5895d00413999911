//! The sections of a model file, one reader each, in the order
//! [`Model::parse_with`](super::Model::parse_with) calls them: each checks its
//! own names and values against what the sections before it declared.

use super::urdf::named::Imported;
use super::{
    body, check_identifier, check_not_generated, constraint, coordinate_list, gravity, urdf, Body, CheckKind,
    ConstraintSpec, Coordinate, Gravity, InitialValue, Input, Located, NumOrText, Parameter, Particle, RawModel,
    Reader, Scope, ValueCheck, RANK_COORDINATE, RANK_MOMENTUM, RANK_PARAMETER, RANK_TIME,
};
use crate::error::ModelError;
use toml::Spanned;

/// `coordinates` (or the imported robot's): names of their own, each once.
pub(super) fn coordinates(r: &mut Reader<'_>, raw: &RawModel, imported: Option<&Imported>) -> Result<(), ModelError> {
    let coords = imported.map_or(raw.coordinates.as_ref(), |i| i.raw.coordinates.as_ref());
    let coords = coords.ok_or_else(|| {
        ModelError::whole("the model has no `coordinates`")
            .with_help("list the generalized coordinates before the first table, e.g. coordinates = [\"th\"]")
    })?;
    if coords.get_ref().is_empty() {
        return Err(ModelError::at(coords.span(), "`coordinates` is empty: expected at least one name"));
    }
    let nest = |e: ModelError| imported.map_or_else(|| e.clone(), |i| i.nest(e.clone()));
    for c in coords.get_ref() {
        check_identifier(c, "coordinate").map_err(nest)?;
        check_not_generated(c, "coordinate", true).map_err(nest)?;
        if let Some(prev) = r.coordinates.iter().find(|p| &p.name == c.get_ref()) {
            let _ = prev;
            return Err(nest(ModelError::at(c.span(), format!("coordinate '{}' is listed twice", c.get_ref()))));
        }
        let span = imported.map_or(c.span(), |i| i.span.clone());
        r.coordinates.push(Coordinate { name: c.get_ref().clone(), span });
    }
    Ok(())
}

/// `[parameters]` in file order after the imported ones the model does not
/// set itself, then the `--set` overrides; and the symbols' order for
/// printing (parameters, time, coordinates, momenta).
pub(super) fn parameters(
    r: &mut Reader<'_>,
    raw: &RawModel,
    imported: Option<&Imported>,
    overrides: &[(String, f64)],
) -> Result<(), ModelError> {
    // The imported parameters (g) that the model does not set itself.
    if let Some(i) = imported {
        let mut params: Vec<(&Spanned<String>, &Spanned<f64>)> = i.raw.parameters.iter().collect();
        params.sort_by_key(|(k, _)| k.span().start);
        for (k, v) in params {
            if !raw.parameters.keys().any(|m| m.get_ref() == k.get_ref()) {
                r.parameters.push(Parameter { name: k.get_ref().clone(), value: *v.get_ref(), span: i.span.clone() });
            }
        }
    }

    // Parameters, in file order.
    let mut params: Vec<(&Spanned<String>, &Spanned<f64>)> = raw.parameters.iter().collect();
    params.sort_by_key(|(k, _)| k.span().start);
    for (k, v) in params {
        check_identifier(k, "parameter")?;
        check_not_generated(k, "parameter", false)?;
        if r.is_coordinate(k.get_ref()) {
            return Err(ModelError::at(k.span(), format!("parameter '{}' has the name of a coordinate", k.get_ref()))
                .with_help("a name is either a coordinate or a parameter; rename one of them"));
        }
        if let Some(q) = k.get_ref().strip_prefix("p_") {
            if r.is_coordinate(q) {
                return Err(ModelError::at(
                    k.span(),
                    format!("parameter '{}' has the name of the momentum conjugate to '{q}'", k.get_ref()),
                ));
            }
        }
        if !v.get_ref().is_finite() {
            return Err(ModelError::at(v.span(), format!("parameter '{}' must be finite", k.get_ref())));
        }
        r.parameters.push(Parameter { name: k.get_ref().clone(), value: *v.get_ref(), span: k.span() });
    }
    for (name, value) in overrides {
        match r.parameters.iter_mut().find(|p| &p.name == name) {
            Some(p) => p.value = crate::error::finite_override(name, *value)?,
            None => {
                let known: Vec<&str> = r.parameters.iter().map(|p| p.name.as_str()).collect();
                return Err(ModelError::setting(
                    crate::error::Setting::Parameter { name: name.clone() },
                    format!("the model has no parameter '{name}'"),
                )
                .with_help(format!("its parameters are: {}", known.join(", "))));
            }
        }
    }
    // Symbol order for printing: parameters, time, coordinates, momenta.
    for p in &r.parameters {
        r.pool.set_rank(&p.name, RANK_PARAMETER);
    }
    r.pool.set_rank("t", RANK_TIME);
    for c in &r.coordinates {
        r.pool.set_rank(&c.name, RANK_COORDINATE);
        r.pool.set_rank(&format!("p_{}", c.name), RANK_MOMENTUM);
    }
    Ok(())
}

/// `[inputs]`: names for forces and loads, and their values in t for runs.
pub(super) fn inputs(r: &mut Reader<'_>, raw: &RawModel) -> Result<Vec<Input>, ModelError> {
    let mut raw_inputs: Vec<(&Spanned<String>, &Spanned<NumOrText>)> = raw.inputs.iter().collect();
    raw_inputs.sort_by_key(|(k, _)| k.span().start);
    let mut inputs = Vec::new();
    for (k, v) in raw_inputs {
        check_identifier(k, "input")?;
        check_not_generated(k, "input", false)?;
        let name = k.get_ref();
        if r.is_coordinate(name) || r.parameters.iter().any(|p| &p.name == name) || name == "t" {
            return Err(ModelError::at(
                k.span(),
                format!("input '{name}' has the name of a coordinate, a parameter or the time"),
            )
            .with_help("an input is a name of its own"));
        }
        let value = r.num_or_expr(v, Scope::Time, &format!("the value of input '{name}'"))?;
        r.pool.set_rank(name, RANK_PARAMETER);
        r.check(ValueCheck {
            kind: CheckKind::Input { name: name.clone(), value: value.expr },
            span: value.span.clone(),
        })?;
        r.inputs.push(name.clone());
        inputs.push(Input { name: name.clone(), value, span: k.span() });
    }
    Ok(inputs)
}

/// What the system is made of, as [`system`] reads it.
pub(super) struct System {
    pub(super) gravity: Option<Gravity>,
    pub(super) particles: Vec<Particle>,
    pub(super) bodies: Vec<Body>,
    pub(super) lagrangian: Option<Located>,
    pub(super) kinetic: Option<Located>,
    pub(super) potential: Option<Located>,
    pub(super) dissipation: Option<Located>,
}

/// What the system is made of: gravity, `[[particles]]`, `[[bodies]]` (or the
/// imported robot's) and the energies the model states, checked to agree
/// with each other.
pub(super) fn system<'a>(
    r: &mut Reader<'a>,
    raw: &RawModel,
    imported: Option<&'a Imported>,
) -> Result<System, ModelError> {
    let gravity = match (&raw.gravity, imported) {
        (None, Some(i)) => {
            urdf::named::within(r, i, |r| i.raw.gravity.as_ref().map(|g| gravity::read(r, g)).transpose())?
                .map(|g| urdf::named::gravity_at(g, &i.span))
        }
        _ => raw.gravity.as_ref().map(|g| gravity::read(r, g)).transpose()?,
    };
    let mut particles = Vec::new();
    for p in &raw.particles {
        let mass = r.num_or_expr(&p.get_ref().mass, Scope::Parameters, "the particle's mass")?.expr;
        let pos = &p.get_ref().position;
        if pos.get_ref().is_empty() || pos.get_ref().len() > 3 {
            return Err(ModelError::at(
                pos.span(),
                format!("a position has 1, 2 or 3 components, not {}", pos.get_ref().len()),
            ));
        }
        let mut position = Vec::new();
        for x in pos.get_ref() {
            position.push(r.num_or_expr(x, Scope::Configuration, "the particle's position")?.expr);
        }
        let potential = p
            .get_ref()
            .potential
            .as_ref()
            .map(|u| r.potential(u, "the particle's potential"))
            .transpose()?
            .map(|l| l.expr);
        match gravity.as_ref().map(Gravity::dimension) {
            Some(None) if position.len() == 1 => {
                return Err(ModelError::at(
                    pos.span(),
                    "gravity needs a vertical axis: give 2-D (x, y) or 3-D (x, y, z) positions",
                )
                .with_help("or give the field vector, e.g. gravity = [\"g\", \"0\"] along +x"));
            }
            Some(Some(n)) if position.len() != n => {
                return Err(ModelError::at(
                    pos.span(),
                    format!("the gravity vector has {n} components, so positions have {n}, not {}", position.len()),
                ));
            }
            _ => {}
        }
        particles.push(Particle { mass, position, potential, span: p.span() });
    }
    let bodies = match imported {
        Some(i) => urdf::named::within(r, i, |r| body::read_all(r, &i.raw.bodies))?
            .into_iter()
            .map(|b| urdf::named::body_at(b, &i.span))
            .collect(),
        None => body::read_all(r, &raw.bodies)?,
    };
    if let (Some(g), Some(b)) = (&gravity, bodies.first()) {
        let n = b.dimension;
        if g.dimension().is_some_and(|d| d != n) {
            return Err(ModelError::at(
                g.span(),
                format!("with these [[bodies]], the gravity vector has {n} components (the bodies' vectors have {n})"),
            ));
        }
        if let Some(p) = particles.iter().find(|p| p.position.len() != n) {
            let axes = if n == 3 { "3-D (x, y, z)" } else { "2-D (x, y)" };
            return Err(ModelError::at(
                p.span.clone(),
                format!("with these [[bodies]], gravity acts in {}: give the particles {axes} positions", &axes[..3]),
            ));
        }
    }
    let lagrangian = raw.lagrangian.as_ref().map(|l| r.expr(l, Scope::State, "the Lagrangian")).transpose()?;
    let kinetic = raw.kinetic.as_ref().map(|l| r.expr(l, Scope::State, "the kinetic energy")).transpose()?;
    let potential = raw.potential.as_ref().map(|l| r.potential(l, "the potential")).transpose()?;
    let dissipation =
        raw.dissipation.as_ref().map(|l| r.expr(l, Scope::State, "the dissipation function")).transpose()?;
    if let Some(l) = &lagrangian {
        let clash = [raw.kinetic.as_ref(), raw.potential.as_ref()].into_iter().flatten().next();
        if let Some(c) = clash {
            return Err(ModelError::at(c.span(), "give either `lagrangian` or `kinetic`/`potential`, not both")
                .with_help("L = T - U: the Lagrangian already contains both energies"));
        }
        if let Some(p) = raw.particles.first() {
            let _ = l;
            return Err(ModelError::at(p.span(), "give either `lagrangian` or [[particles]], not both"));
        }
        if let Some(b) = raw.bodies.first() {
            return Err(ModelError::at(b.span(), "give either `lagrangian` or [[bodies]], not both"));
        }
        if let Some(g) = &raw.gravity {
            return Err(ModelError::at(
                g.span(),
                "`gravity` acts on [[particles]]; put the potential in the Lagrangian",
            ));
        }
    }
    if lagrangian.is_none() && kinetic.is_none() && particles.is_empty() && bodies.is_empty() {
        return Err(ModelError::whole("the model has no kinetic energy")
            .with_help("give [[particles]] with positions, `kinetic` and `potential`, or `lagrangian`"));
    }
    if gravity.is_some() && particles.is_empty() && bodies.is_empty() {
        let g = raw.gravity.as_ref().map(|g| g.span()).unwrap_or(0..0);
        return Err(ModelError::at(g, "`gravity` acts on [[particles]], and the model has none"));
    }
    Ok(System { gravity, particles, bodies, lagrangian, kinetic, potential, dissipation })
}

/// `[forces]`: a generalized force on each coordinate named.
pub(super) fn forces(r: &mut Reader<'_>, raw: &RawModel) -> Result<Vec<Option<Located>>, ModelError> {
    let mut forces: Vec<Option<Located>> = vec![None; r.coordinates.len()];
    for (k, v) in &raw.forces {
        let Some(i) = r.coordinates.iter().position(|c| &c.name == k.get_ref()) else {
            return Err(ModelError::at(
                k.span(),
                format!("[forces] names '{}', which is not a coordinate", k.get_ref()),
            )
            .with_help(coordinate_list(&r.coordinates)));
        };
        forces[i] = Some(r.expr(v, Scope::Driven, &format!("the force on '{}'", k.get_ref()))?);
    }
    Ok(forces)
}

/// `[initial]` values, then the imported rest state for what the model leaves out.
pub(super) fn initial(
    r: &mut Reader<'_>,
    raw: &RawModel,
    imported: Option<&Imported>,
) -> Result<Vec<InitialValue>, ModelError> {
    let mut initial = Vec::new();
    for (k, v) in &raw.initial {
        let key = k.get_ref();
        let base = key.trim_end_matches('\'');
        let order = (key.len() - base.len()) as u8;
        let Some(coord) = r.coordinates.iter().position(|c| c.name == base) else {
            return Err(ModelError::at(
                k.span(),
                format!("[initial] names '{key}', which is not a coordinate or a velocity"),
            )
            .with_help(coordinate_list(&r.coordinates)));
        };
        if order > 1 {
            return Err(ModelError::at(
                k.span(),
                format!("[initial] gives '{key}': only coordinates and velocities have initial values"),
            ));
        }
        let value = r.num_or_expr(v, Scope::Parameters, &format!("the initial value of '{key}'"))?;
        initial.push(InitialValue { coord, order, value });
    }
    // The imported rest state, for what the model leaves out.
    if let Some(i) = imported {
        for (k, v) in &i.raw.initial {
            let key = k.get_ref();
            let base = key.trim_end_matches('\'');
            let order = (key.len() - base.len()) as u8;
            let Some(coord) = r.coordinates.iter().position(|c| c.name == base) else { continue };
            if initial.iter().any(|x: &InitialValue| x.coord == coord && x.order == order) {
                continue;
            }
            let mut value = r.num_or_expr(v, Scope::Parameters, "an imported initial value").map_err(|e| i.nest(e))?;
            value.span = i.span.clone();
            initial.push(InitialValue { coord, order, value });
        }
    }
    Ok(initial)
}

/// `[[constraints]]` (read by `model/constraint.rs`), named apart from the
/// coordinates and parameters.
pub(super) fn constraints(
    r: &mut Reader<'_>,
    raw: &RawModel,
    bodies: &[Body],
) -> Result<Vec<ConstraintSpec>, ModelError> {
    let mut constraints = Vec::new();
    for (k, c) in raw.constraints.iter().enumerate() {
        let specs = if c.get_ref().is_rolling() {
            constraint::read_rolling(r, c, k, &constraints, bodies)?
        } else {
            vec![constraint::read_spec(c, k, &constraints, &mut |text, scope_state, what| {
                let scope = if scope_state { Scope::State } else { Scope::Configuration };
                r.expr(text, scope, what)
            })?]
        };
        for spec in specs {
            let multiplier = format!("lambda_{}", spec.name);
            if r.is_coordinate(&spec.name) || r.is_parameter(&spec.name) || r.is_parameter(&multiplier) {
                return Err(ModelError::at(
                spec.name_span.clone(),
                format!("constraint '{}' has the name of a coordinate or parameter", spec.name),
            )
            .with_help(format!(
                "give the constraint a name of its own (its multiplier is called {multiplier}, which must not be a parameter either)"
            )));
            }
            constraints.push(spec);
        }
    }
    Ok(constraints)
}
