//! Model files: the TOML text a person writes, read into symbols and expressions.
//!
//! [`Model::parse`] checks everything a person can get wrong in a model file
//! (unknown names, duplicated coordinates, parameters that shadow coordinates,
//! accelerations where only velocities make sense, tables not supported yet) and
//! reports it with the byte span of the offending text. Nothing downstream
//! re-reads the text.

use crate::error::ModelError;
use crate::source::{
    check_identifier, check_not_generated, content_offset, number_expr, read_toml, RANK_COORDINATE, RANK_MOMENTUM,
    RANK_PARAMETER, RANK_TIME,
};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use sym::{ExprId, ParseErrorKind, ParseOptions, Pool};
use toml::Spanned;

pub(crate) mod body;
pub(crate) mod check;
pub(crate) mod columns;
pub(crate) mod constraint;
pub(crate) mod frames;
pub(crate) mod gravity;
pub(crate) mod impact;
pub(crate) mod load;
mod read;
pub(crate) mod urdf;

pub use crate::source::Parameter;
pub use body::{Body, Orientation};
pub use check::{CheckKind, ValueCheck};
pub use constraint::{ConstraintKind, ConstraintSpec};
pub use gravity::Gravity;
pub use impact::ImpactSpec;
pub use load::{Load, LoadKind};
pub use urdf::{urdf_to_model, UrdfConfig};

/// A generalized coordinate.
#[derive(Debug, Clone)]
pub struct Coordinate {
    /// Its name (`th`).
    pub name: String,
    /// Where it is declared.
    pub span: Range<usize>,
}

/// A point mass with a position given in terms of the coordinates and time.
#[derive(Debug, Clone)]
pub struct Particle {
    /// Its mass.
    pub mass: ExprId,
    /// Cartesian position, 1 to 3 components, as functions of (q, t).
    pub position: Vec<ExprId>,
    /// An extra potential energy of this particle.
    pub potential: Option<ExprId>,
    /// Where the particle's table is.
    pub span: Range<usize>,
}

/// An expression of the model file with its place in the file.
#[derive(Debug, Clone)]
pub struct Located {
    /// The expression.
    pub expr: ExprId,
    /// Where its text is.
    pub span: Range<usize>,
}

/// An initial value of a coordinate or velocity.
#[derive(Debug, Clone)]
pub struct InitialValue {
    /// Which coordinate.
    pub coord: usize,
    /// 0 for the coordinate, 1 for its velocity.
    pub order: u8,
    /// The value, an expression in the parameters.
    pub value: Located,
}

/// A parsed model: everything in the file, as symbols and expressions in `pool`.
#[derive(Debug, Clone)]
pub struct Model {
    /// The arena holding every expression of the model and its derivation.
    pub pool: Pool,
    /// The model's name.
    pub name: String,
    /// Generalized coordinates, in file order.
    pub coordinates: Vec<Coordinate>,
    /// Parameters, in file order.
    pub parameters: Vec<Parameter>,
    /// Point masses.
    pub particles: Vec<Particle>,
    /// Uniform gravity: along −y (2-D positions) or −z (3-D), or a field vector.
    pub gravity: Option<Gravity>,
    /// `lagrangian = "..."`.
    pub lagrangian: Option<Located>,
    /// `kinetic = "..."`.
    pub kinetic: Option<Located>,
    /// `potential = "..."` (may depend on velocities: a generalized potential).
    pub potential: Option<Located>,
    /// Rayleigh's dissipation function.
    pub dissipation: Option<Located>,
    /// Generalized force per coordinate (`None`: zero).
    pub forces: Vec<Option<Located>>,
    /// Initial values from `[initial]`.
    pub initial: Vec<InitialValue>,
    /// Rigid bodies (`[[bodies]]`).
    pub bodies: Vec<Body>,
    /// Constraints from `[[constraints]]`, in file order.
    pub constraints: Vec<ConstraintSpec>,
    /// Unilateral contacts from `[[impacts]]`, in file order.
    pub impacts: Vec<ImpactSpec>,
    /// Forces at points and torques on bodies (`[[loads]]`).
    pub loads: Vec<Load>,
    /// Named inputs u(t) (`[inputs]`): symbols in the forces and loads, with
    /// the values a run gives them ([`Model::with_inputs_applied`]).
    pub inputs: Vec<Input>,
    /// What must hold at numbers (a body's mass positive, a hinge axis a
    /// direction, a rolling wheel's axle not vertical at the start), checked at
    /// the file's values when read and by [`Model::check_values`] at others.
    pub checks: Vec<ValueCheck>,
}

/// A named input u(t) of `[inputs]`.
#[derive(Debug, Clone)]
pub struct Input {
    /// Its name, a symbol in the forces and loads.
    pub name: String,
    /// Its value in a run, an expression of t and the parameters.
    pub value: Located,
    /// Where its name is written.
    pub span: Range<usize>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawModel {
    name: Option<String>,
    /// A URDF file whose robot the model takes its coordinates and bodies from.
    urdf: Option<Spanned<String>>,
    /// With `urdf`: give the root link six coordinates.
    floating_base: Option<Spanned<bool>>,
    coordinates: Option<Spanned<Vec<Spanned<String>>>>,
    gravity: Option<Spanned<gravity::RawGravity>>,
    lagrangian: Option<Spanned<String>>,
    kinetic: Option<Spanned<String>>,
    potential: Option<Spanned<String>>,
    dissipation: Option<Spanned<String>>,
    #[serde(default)]
    parameters: BTreeMap<Spanned<String>, Spanned<f64>>,
    #[serde(default)]
    particles: Vec<Spanned<RawParticle>>,
    #[serde(default)]
    forces: BTreeMap<Spanned<String>, Spanned<String>>,
    #[serde(default)]
    initial: BTreeMap<Spanned<String>, Spanned<NumOrText>>,
    #[serde(default)]
    bodies: Vec<Spanned<body::RawBody>>,
    #[serde(default)]
    constraints: Vec<Spanned<constraint::RawConstraint>>,
    #[serde(default)]
    impacts: Vec<Spanned<impact::RawImpact>>,
    #[serde(default)]
    loads: Vec<Spanned<load::RawLoad>>,
    #[serde(default)]
    inputs: BTreeMap<Spanned<String>, Spanned<NumOrText>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawParticle {
    mass: Spanned<NumOrText>,
    position: Spanned<Vec<Spanned<NumOrText>>>,
    potential: Option<Spanned<String>>,
}

/// A value that is a number or an expression string (`mass = 1`, `mass = "m"`).
#[derive(Clone)]
pub(crate) enum NumOrText {
    Num(f64),
    Text(String),
}

impl<'de> Deserialize<'de> for NumOrText {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        // A visitor rather than `untagged`, whose error names the Rust type
        // ("did not match any variant of untagged enum NumOrText").
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = NumOrText;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number or an expression string")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumOrText, E> {
                Ok(NumOrText::Num(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumOrText, E> {
                Ok(NumOrText::Num(v as f64))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumOrText, E> {
                Ok(NumOrText::Num(v))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<NumOrText, E> {
                Ok(NumOrText::Text(v.to_string()))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// What an expression may refer to, by context.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Scope {
    /// Parameters only (masses, gravity, initial values).
    Parameters,
    /// Coordinates and time (positions).
    Configuration,
    /// Coordinates, velocities and time (energies).
    State,
    /// Coordinates, velocities, time and the inputs (forces and loads).
    Driven,
    /// The time only (the values of inputs).
    Time,
}

impl Scope {
    fn describe(self) -> &'static str {
        match self {
            Scope::Parameters => "parameters",
            Scope::Configuration => "parameters, coordinates and the time t",
            Scope::State => "parameters, coordinates, velocities (q') and the time t",
            Scope::Driven => "parameters, inputs, coordinates, velocities (q') and the time t",
            Scope::Time => "parameters and the time t",
        }
    }
}

/// Reads a file a model names (e.g. a body file for a rigid body's inertia) by
/// the name written in the model; the error is a sentence. The library does no
/// IO of its own: the caller decides where names point (the command line reads
/// them relative to the model file).
pub type FileReader<'a> = dyn Fn(&str) -> Result<String, String> + 'a;

/// "the coordinates are a, b, c", at most twenty of them named: the help of
/// a table that names one the model does not have.
fn coordinate_list(coordinates: &[Coordinate]) -> String {
    const SHOWN: usize = 20;
    let mut names: Vec<&str> = coordinates.iter().take(SHOWN).map(|c| c.name.as_str()).collect();
    let more = coordinates.len().saturating_sub(SHOWN);
    let more = if more > 0 { format!(" and {more} more") } else { String::new() };
    match names.len() {
        0 => "the model has no coordinates".into(),
        1 => format!("the only coordinate is {}", names[0]),
        _ => {
            let last = if more.is_empty() { names.pop() } else { None };
            match last {
                Some(last) => format!("the coordinates are {} and {last}", names.join(", ")),
                None => format!("the coordinates are {}{more}", names.join(", ")),
            }
        }
    }
}

/// The reader of a model given as text alone: it names no files.
fn no_files(name: &str) -> Result<String, String> {
    Err(format!("this model was given as text, so the file '{name}' cannot be read"))
}

/// Reading state: the source text and the names declared so far.
pub(crate) struct Reader<'a> {
    pub(crate) source: &'a str,
    /// Reads a file the model names (a body file), relative to the model.
    pub(crate) files: &'a FileReader<'a>,
    pub(crate) pool: Pool,
    pub(crate) coordinates: Vec<Coordinate>,
    pub(crate) parameters: Vec<Parameter>,
    /// The inputs' names (`[inputs]`), known to forces and loads.
    pub(crate) inputs: Vec<String>,
    /// The checks at numbers recorded so far ([`ValueCheck`]).
    pub(crate) checks: Vec<ValueCheck>,
}

impl Reader<'_> {
    /// Records a check at numbers and runs it at the parameters' values (a
    /// start check runs when a run starts, [`Model::check_values`]).
    pub(crate) fn check(&mut self, check: ValueCheck) -> Result<(), ModelError> {
        if !check.at_start() {
            let env = |n: &str| self.parameters.iter().find(|p| p.name == n).map(|p| p.value);
            check.run(&self.pool, &env)?;
        }
        self.checks.push(check);
        Ok(())
    }

    fn is_coordinate(&self, name: &str) -> bool {
        self.coordinates.iter().any(|c| c.name == name)
    }

    fn is_parameter(&self, name: &str) -> bool {
        self.parameters.iter().any(|p| p.name == name)
    }

    /// Parses the expression text of a TOML string value.
    fn expr(&mut self, text: &Spanned<String>, scope: Scope, what: &str) -> Result<Located, ModelError> {
        self.expr_str(text.get_ref(), text.span(), scope, what)
    }

    pub(crate) fn expr_str(
        &mut self,
        text: &str,
        span: Range<usize>,
        scope: Scope,
        what: &str,
    ) -> Result<Located, ModelError> {
        let offset = content_offset(self.source, &span, text);
        let coordinates: Vec<String> = self.coordinates.iter().map(|c| c.name.clone()).collect();
        let parameters: Vec<String> = self.parameters.iter().map(|p| p.name.clone()).collect();
        let inputs = &self.inputs;
        let known = |name: &str, order: u8| -> bool {
            if parameters.iter().any(|p| p == name) {
                return order == 0;
            }
            let state = (name == "t" && order == 0) || (order <= 1 && coordinates.iter().any(|c| c == name));
            match scope {
                Scope::Parameters => false,
                Scope::Configuration => order == 0 && (name == "t" || coordinates.iter().any(|c| c == name)),
                Scope::State => state,
                Scope::Driven => state || (order == 0 && inputs.iter().any(|u| u == name)),
                Scope::Time => order == 0 && name == "t",
            }
        };
        let opts = ParseOptions::default().with_known(&known);
        match self.pool.parse_with(text, &opts) {
            Ok(expr) => Ok(Located { expr, span }),
            Err(err) => {
                let at = match offset {
                    Some(o) => {
                        (o + err.span.start as usize)..(o + (err.span.end as usize).max(err.span.start as usize + 1))
                    }
                    None => span.clone(),
                };
                let mut message = format!("in {what}: {err}");
                let mut help = None;
                if let ParseErrorKind::UnknownName { name } = &err.kind {
                    let base = name.trim_end_matches('\'');
                    let primes = name.len() - base.len();
                    if self.is_coordinate(base) || (base == "t") {
                        message = format!("in {what}: '{name}' is not allowed here");
                        help = Some(format!(
                            "{what} may use {}{}",
                            scope.describe(),
                            if primes == 2 { "; accelerations never appear in a model" } else { "" }
                        ));
                    } else if self.is_parameter(base) {
                        message = format!("in {what}: parameter '{base}' cannot be differentiated");
                    } else {
                        help = Some(format!(
                            "{what} may use {}; declare '{base}' under [parameters] or in `coordinates`",
                            scope.describe()
                        ));
                    }
                }
                let mut e = ModelError::at(at, message);
                e.help = help.or_else(|| err.hint(text));
                Err(e)
            }
        }
    }

    /// Parses a potential, which may depend on velocities (a generalized
    /// potential) but must have a value at rest: the energy T + U₀ takes its
    /// velocity-independent part as U₀ = U(q, 0, t), and `-G*m/r'^2` has none.
    fn potential(&mut self, text: &Spanned<String>, what: &str) -> Result<Located, ModelError> {
        let u = self.expr(text, Scope::State, what)?;
        let zero = self.pool.zero();
        let names: Vec<String> = self.coordinates.iter().map(|c| c.name.clone()).collect();
        let at_rest: crate::probe::Subst = names.iter().map(|c| (self.pool.var(c, 1), zero)).collect();
        let u0 = self.pool.substitute(u.expr, &at_rest);
        let undefined = self.pool.reachable(&[u0]).into_iter().find_map(|e| self.pool.undefined_value(e));
        if let Some(value) = undefined {
            let at = match content_offset(self.source, &text.span(), text.get_ref()) {
                Some(o) => o..o + text.get_ref().len(),
                None => text.span(),
            };
            return Err(ModelError::at(
                at,
                format!("{what} has no value at rest: with every velocity q' = 0 it evaluates to {value}"),
            )
            .with_help(
                "the energy T + U takes U at q' = 0; a generalized potential is U(q, t) plus terms in the velocities that vanish at rest",
            ));
        }
        Ok(u)
    }

    pub(crate) fn num_or_expr(
        &mut self,
        v: &Spanned<NumOrText>,
        scope: Scope,
        what: &str,
    ) -> Result<Located, ModelError> {
        match v.get_ref() {
            NumOrText::Num(x) => {
                if !x.is_finite() {
                    return Err(ModelError::at(v.span(), format!("{what} must be a finite number")));
                }
                Ok(Located { expr: number_expr(&mut self.pool, *x), span: v.span() })
            }
            NumOrText::Text(s) => self.expr_str(s, v.span(), scope, what),
        }
    }
}

impl Model {
    /// Reads a model file's text. `overrides` are `--set name=value` pairs,
    /// applied to `[parameters]` (an unknown name is an error).
    pub fn parse(source: &str, overrides: &[(String, f64)]) -> Result<Model, ModelError> {
        Model::parse_with(source, overrides, &no_files)
    }

    /// [`Model::parse`] for a model that may name other files (body files in
    /// `[[bodies]]`), which `files` reads.
    pub fn parse_with(source: &str, overrides: &[(String, f64)], files: &FileReader) -> Result<Model, ModelError> {
        let raw: RawModel = read_toml(source, "model")?;
        let imported = match &raw.urdf {
            Some(u) => Some(urdf::named::import(u, raw.floating_base.as_ref(), files)?),
            None => {
                if let Some(f) = &raw.floating_base {
                    return Err(ModelError::at(
                        f.span(),
                        "`floating_base` belongs to a model that names a `urdf` file",
                    ));
                }
                None
            }
        };
        if let Some(i) = &imported {
            urdf::named::refuse_clashes(&raw, i)?;
        }
        let mut r = Reader {
            source,
            files,
            pool: Pool::default(),
            coordinates: Vec::new(),
            parameters: Vec::new(),
            inputs: Vec::new(),
            checks: Vec::new(),
        };

        read::coordinates(&mut r, &raw, imported.as_ref())?;
        read::parameters(&mut r, &raw, imported.as_ref(), overrides)?;
        let inputs = read::inputs(&mut r, &raw)?;
        let read::System { gravity, particles, bodies, lagrangian, kinetic, potential, dissipation } =
            read::system(&mut r, &raw, imported.as_ref())?;

        // Forces at points and torques on bodies.
        let dimension = bodies.first().map(|b| b.dimension).unwrap_or(3);
        let loads = load::read_all(&mut r, &raw.loads, &bodies, dimension)?;

        let forces = read::forces(&mut r, &raw)?;
        let initial = read::initial(&mut r, &raw, imported.as_ref())?;
        let constraints = read::constraints(&mut r, &raw, &bodies)?;
        let impacts = impact::read_all(&mut r, &raw.impacts, !constraints.is_empty())?;

        let model = Model {
            pool: r.pool,
            name: raw
                .name
                .or_else(|| imported.as_ref().and_then(|i| i.raw.name.clone()))
                .unwrap_or_else(|| "unnamed model".into()),
            coordinates: r.coordinates,
            parameters: r.parameters,
            particles,
            gravity,
            lagrangian,
            kinetic,
            potential,
            dissipation,
            forces,
            initial,
            bodies,
            constraints,
            impacts,
            loads,
            inputs,
            checks: r.checks,
        };
        columns::refuse_duplicates(&columns::simulate_columns(&model), "simulate's CSV")?;
        Ok(model)
    }

    /// The model a run integrates: every input replaced by its value, an
    /// expression of t, in the forces and loads (and no inputs left). `derive`
    /// and `linearize` keep the inputs as symbols; runs need numbers.
    pub fn with_inputs_applied(mut self) -> Model {
        if self.inputs.is_empty() {
            return self;
        }
        let subst: rustc_hash::FxHashMap<ExprId, ExprId> =
            self.inputs.iter().map(|u| (self.pool.symbol(&u.name), u.value.expr)).collect();
        let pool = &mut self.pool;
        let mut apply = |e: ExprId| pool.substitute(e, &subst);
        for f in self.forces.iter_mut().flatten() {
            f.expr = apply(f.expr);
        }
        for l in &mut self.loads {
            l.vector = l.vector.map(&mut apply);
        }
        self.inputs.clear();
        self
    }

    /// An error at the first input when the model still has its inputs as
    /// symbols, which a run cannot evaluate.
    pub fn check_inputs_applied(&self) -> Result<(), ModelError> {
        match self.inputs.first() {
            None => Ok(()),
            Some(u) => Err(ModelError::at(
                u.span.clone(),
                format!("input '{}' is a symbol in this derivation, and a run needs its value", u.name),
            )
            .with_help("derive `Model::with_inputs_applied()` for runs (the command line does)")),
        }
    }

    /// Parses an expression in the model's names (parameters, coordinates,
    /// velocities, t), e.g. a stop condition from the command line. Spans in the
    /// error are byte offsets into `text`.
    pub fn parse_state_expr(&mut self, text: &str, what: &str) -> Result<ExprId, ModelError> {
        let mut r = Reader {
            source: text,
            files: &no_files,
            pool: std::mem::take(&mut self.pool),
            coordinates: self.coordinates.clone(),
            parameters: self.parameters.clone(),
            inputs: Vec::new(),
            checks: Vec::new(),
        };
        let result = r.expr_str(text, 0..text.len(), Scope::State, what).map(|l| l.expr);
        // The whole text is the expression: spans are offsets into it.
        let result = result.map_err(|mut e| {
            if let Some(span) = &mut e.span {
                if span.start > text.len() {
                    *span = 0..text.len();
                }
            }
            e
        });
        self.pool = r.pool;
        result
    }

    /// Runs the model's checks at numbers ([`ValueCheck`]) at its parameters'
    /// current values, and the start checks too when `start` gives (q, q') at
    /// t = 0: a sweep runs them for each row, as reading the file with `--set`
    /// and a run's start do.
    pub fn check_values(&self, start: Option<(&[f64], &[f64])>) -> Result<(), ModelError> {
        let env = |name: &str| {
            if let Some(v) = self.parameter(name) {
                return Some(v);
            }
            let (q, _) = start?;
            if name == "t" {
                return Some(0.0);
            }
            self.coordinates.iter().position(|c| c.name == name).map(|k| q[k])
        };
        for check in self.checks.iter().filter(|c| start.is_some() || !c.at_start()) {
            check.run(&self.pool, &env)?;
        }
        Ok(())
    }

    /// The initial coordinates and velocities from `[initial]`, evaluated with
    /// the parameters' values. Every coordinate and velocity must be given.
    pub fn initial_state(&self) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
        let n = self.n_coords();
        let mut q = vec![None; n];
        let mut qd = vec![None; n];
        let env = |name: &str| self.parameter(name);
        for iv in &self.initial {
            let v = self
                .pool
                .eval(iv.value.expr, &env)
                .map_err(|e| ModelError::at(iv.value.span.clone(), e.to_string()))?;
            if !v.is_finite() {
                return Err(ModelError::at(iv.value.span.clone(), format!("the initial value evaluates to {v}")));
            }
            let slot = if iv.order == 0 { &mut q } else { &mut qd };
            slot[iv.coord] = Some(v);
        }
        let mut missing = Vec::new();
        for (i, c) in self.coordinates.iter().enumerate() {
            if q[i].is_none() {
                missing.push(c.name.clone());
            }
            if qd[i].is_none() {
                missing.push(format!("{}'", c.name));
            }
        }
        if !missing.is_empty() {
            let list: Vec<String> = missing.iter().map(|m| format!("\"{m}\" = ...")).collect();
            return Err(ModelError::whole(format!("[initial] has no value for {}", missing.join(", ")))
                .with_help(format!("add under [initial]: {}", list.join(", "))));
        }
        Ok((q.into_iter().flatten().collect(), qd.into_iter().flatten().collect()))
    }

    /// The number of degrees of freedom.
    pub fn n_coords(&self) -> usize {
        self.coordinates.len()
    }

    /// The value of a parameter by name.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters.iter().find(|p| p.name == name).map(|p| p.value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reads a model whose `[parameters]` are `m` and `G` and coordinates `r`, `th`
    /// from the top-level lines `head`, and returns the error and the text it points at.
    #[track_caller]
    fn check_err(head: &str, expect: &str, at: &str) {
        let text = format!("coordinates = [\"r\", \"th\"]\n{head}\n[parameters]\nm = 1.0\nG = 1.0\n");
        let err = Model::parse(&text, &[]).expect_err(&text);
        assert_eq!(err.message, expect, "{text}");
        let span = err.span.clone().expect("the error has a place");
        assert_eq!(&text[span], at, "{text}");
    }

    /// Found by fuzzing: a potential with a velocity in a denominator has no
    /// U₀ = U(q, 0, t), and the energy T + U₀ printed as `-0^(-2)*G*m^2 + ...`.
    #[test]
    fn a_potential_must_have_a_value_at_rest() {
        check_err(
            "kinetic = \"m*(r'^2 + r^2*th'^2)/2\"\npotential = \"-G*m^2/r'^2\"",
            "the potential has no value at rest: with every velocity q' = 0 it evaluates to inf",
            "-G*m^2/r'^2",
        );
        check_err(
            "kinetic = \"m*r'^2/2\"\npotential = \"log(r'^2) + th'\"",
            "the potential has no value at rest: with every velocity q' = 0 it evaluates to -inf",
            "log(r'^2) + th'",
        );
        let particle = "[[particles]]\nmass = \"m\"\nposition = [\"r\", \"th\"]\npotential = \"G/(r'*th')\"\n";
        let text = format!("coordinates = [\"r\", \"th\"]\n[parameters]\nm = 1.0\nG = 1.0\n{particle}");
        let err = Model::parse(&text, &[]).expect_err(&text);
        assert!(err.message.starts_with("the particle's potential has no value at rest"), "{}", err.message);
        // A charge in a magnetic field: terms linear in the velocities vanish at rest.
        let text = "coordinates = [\"r\", \"th\"]\nkinetic = \"m*(r'^2 + th'^2)/2\"\npotential = \"G*(r*th' - th*r') + 1/(1 + r'^2)\"\n[parameters]\nm = 1.0\nG = 1.0\n";
        assert!(Model::parse(text, &[]).is_ok());
    }

    /// A table naming a coordinate the model lacks lists those it has.
    #[test]
    fn an_unknown_coordinate_lists_the_coordinates() {
        let help = |coords: &[String], table: &str| {
            let quoted: Vec<String> = coords.iter().map(|c| format!("\"{c}\"")).collect();
            let text = format!(
                "coordinates = [{}]\nkinetic = \"{}'^2\"\n[{table}]\nz = \"1\"\n",
                quoted.join(", "),
                coords[0]
            );
            Model::parse(&text, &[]).expect_err(&text).help.expect("a help")
        };
        let two = ["x".to_string(), "y".to_string()];
        assert_eq!(help(&two, "initial"), "the coordinates are x and y");
        assert_eq!(help(&two, "forces"), "the coordinates are x and y");
        assert_eq!(help(&two[..1], "initial"), "the only coordinate is x");
        let many: Vec<String> = (0..25).map(|k| format!("q{k}")).collect();
        let text = help(&many, "initial");
        assert!(text.starts_with("the coordinates are q0, q1,") && text.ends_with("q19 and 5 more"), "{text}");
    }
}
