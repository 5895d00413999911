//! Body files: the TOML text that describes a rigid body as a list of parts,
//! read into expressions and checked (shapes, sizes, signs, names), with every
//! mistake reported at its place in the file.
//!
//! Enter with [`BodyFile::parse`]. A part is a standard shape (`point`, `rod`,
//! `box`, `sphere`, `shell`, `cylinder`, `cone`, `disk`, `ring`, `ellipsoid`)
//! with `mass`, `size`, `center` (where its centre of mass sits) and an
//! optional `orientation` (Euler angles, [`crate::euler`]), or a `density`
//! ρ(x, y, z) over a box `region`. Values are numbers or expressions in
//! `[parameters]`.

use super::shapes::Shape;
use crate::error::ModelError;
use crate::source::Parameter;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use sym::{ExprId, ParseErrorKind, ParseOptions, Pool};
use toml::Spanned;

/// The integration variables of a density part; no parameter may take these names.
pub const DENSITY_VARIABLES: [&str; 3] = ["x", "y", "z"];

/// Names the expression language reserves.
const RESERVED: &[&str] = &[
    "t", "pi", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "ln",
    "sqrt", "abs",
];

/// A parsed body file.
#[derive(Debug, Clone)]
pub struct BodyFile {
    pub(super) pool: Pool,
    /// The body's name.
    pub name: String,
    /// Parameters, in file order, with `--set` overrides applied.
    pub parameters: Vec<Parameter>,
    /// The parts, in file order.
    pub parts: Vec<Part>,
}

/// One part of a body.
#[derive(Debug, Clone)]
pub struct Part {
    /// Its name (`name = "..."`, default `part N`).
    pub name: String,
    /// What it is.
    pub kind: PartKind,
    /// Where its table is in the file.
    pub span: Range<usize>,
}

/// A standard shape or a density.
#[derive(Debug, Clone)]
pub enum PartKind {
    /// A shape with closed-form moments.
    Shape {
        /// Which shape.
        shape: Shape,
        /// Its mass.
        mass: ExprId,
        /// Its dimensions, as the shape's kind lists them (`lagrange inertia` documents each).
        size: Vec<ExprId>,
        /// Its centre of mass in the body's axes.
        center: [ExprId; 3],
        /// Euler angles (α, β, γ) turning the part's axes; `None`: aligned with the body's.
        orientation: Option<[ExprId; 3]>,
    },
    /// A density ρ(x, y, z) over a box.
    Density {
        /// ρ, an expression in the parameters and x, y, z.
        density: ExprId,
        /// Where the density's text is (for errors found while integrating).
        span: Range<usize>,
        /// Per axis [lower, upper], expressions in the parameters.
        region: [[ExprId; 2]; 3],
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBody {
    name: Option<String>,
    #[serde(default)]
    parameters: BTreeMap<Spanned<String>, Spanned<f64>>,
    #[serde(default)]
    parts: Vec<Spanned<RawPart>>,
}

type RawList = Spanned<Vec<Spanned<NumOrText>>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPart {
    name: Option<String>,
    shape: Spanned<String>,
    mass: Option<Spanned<NumOrText>>,
    size: Option<RawList>,
    center: Option<RawList>,
    orientation: Option<RawList>,
    density: Option<Spanned<NumOrText>>,
    region: Option<Spanned<Vec<RawList>>>,
}

#[derive(Deserialize, Clone)]
#[serde(untagged)]
enum NumOrText {
    Num(f64),
    Text(String),
}

/// Reading state: the text, the pool and the parameters.
struct Reader<'a> {
    source: &'a str,
    pool: Pool,
    parameters: Vec<Parameter>,
}

impl Reader<'_> {
    /// Parses a number or an expression; `with_xyz` admits the density variables.
    fn value(&mut self, v: &Spanned<NumOrText>, with_xyz: bool, what: &str) -> Result<ExprId, ModelError> {
        let text = match v.get_ref() {
            NumOrText::Num(x) => {
                if !x.is_finite() {
                    return Err(ModelError::at(v.span(), format!("{what} must be a finite number")));
                }
                let exact = self.source.get(v.span()).and_then(decimal);
                return Ok(match exact {
                    Some(r) => self.pool.number(sym::Number::Rational(r)),
                    None if x.fract() == 0.0 && x.abs() < 1e15 => self.pool.int(*x as i64),
                    None => self.pool.float(*x),
                });
            }
            NumOrText::Text(s) => s,
        };
        let span = v.span();
        let offset = crate::source::content_offset(self.source, &span, text);
        let names: Vec<String> = self.parameters.iter().map(|p| p.name.clone()).collect();
        let known = |name: &str, order: u8| {
            order == 0 && (names.iter().any(|p| p == name) || (with_xyz && DENSITY_VARIABLES.contains(&name)))
        };
        let opts = ParseOptions::default().with_known(&known);
        self.pool.parse_with(text, &opts).map_err(|err| {
            let at = match offset {
                Some(o) => {
                    (o + err.span.start as usize)..(o + (err.span.end as usize).max(err.span.start as usize + 1))
                }
                None => span.clone(),
            };
            let mut e = ModelError::at(at, format!("in {what}: {err}"));
            if let ParseErrorKind::UnknownName { name } = &err.kind {
                let base = name.trim_end_matches('\'');
                e = e.with_help(if !with_xyz && DENSITY_VARIABLES.contains(&base) {
                    format!("{what} may use the parameters only; x, y, z exist only in a density")
                } else {
                    format!("{what} may use the parameters; declare '{base}' under [parameters]")
                });
            }
            e
        })
    }

    /// The value of an expression in the parameters.
    fn number(&self, e: ExprId, span: Range<usize>, what: &str) -> Result<f64, ModelError> {
        let env = |n: &str| self.parameters.iter().find(|p| p.name == n).map(|p| p.value);
        match self.pool.eval(e, &env) {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(v) => Err(ModelError::at(
                span,
                format!("{what} is {v} with the parameters' values: expected a finite number"),
            )),
            Err(err) => Err(ModelError::at(span, format!("{what} cannot be evaluated: {err}"))),
        }
    }

    /// A list of exactly `n` values (`what` names the list, `items` its
    /// entries), each with its value and its place in the file.
    fn list(
        &mut self,
        v: &RawList,
        n: usize,
        what: &str,
        items: &str,
    ) -> Result<Vec<(ExprId, f64, Range<usize>)>, ModelError> {
        if v.get_ref().len() != n {
            return Err(ModelError::at(
                v.span(),
                format!(
                    "{what} has {n} component{} ({items}), found {}",
                    if n == 1 { "" } else { "s" },
                    v.get_ref().len()
                ),
            ));
        }
        let mut out = Vec::with_capacity(n);
        for x in v.get_ref() {
            let e = self.value(x, false, what)?;
            let value = self.number(e, x.span(), what)?;
            out.push((e, value, x.span()));
        }
        Ok(out)
    }

    fn part(&mut self, index: usize, raw: &Spanned<RawPart>) -> Result<Part, ModelError> {
        let p = raw.get_ref();
        let name = p.name.clone().unwrap_or_else(|| format!("part {}", index + 1));
        let shape_name = p.shape.get_ref().as_str();
        let kind = if shape_name == "density" {
            self.density_part(p, &name)?
        } else {
            let shape = Shape::from_name(shape_name).ok_or_else(|| {
                let known: Vec<&str> = Shape::ALL.iter().map(|s| s.name()).chain(["density"]).collect();
                ModelError::at(p.shape.span(), format!("unknown shape '{shape_name}'"))
                    .with_help(format!("the shapes are: {}", known.join(", ")))
            })?;
            self.shape_part(shape, p, raw.span(), &name)?
        };
        Ok(Part { name, kind, span: raw.span() })
    }

    fn shape_part(
        &mut self,
        shape: Shape,
        p: &RawPart,
        table: Range<usize>,
        name: &str,
    ) -> Result<PartKind, ModelError> {
        for (key, present) in
            [("density", p.density.as_ref().map(|d| d.span())), ("region", p.region.as_ref().map(|r| r.span()))]
        {
            if let Some(span) = present {
                return Err(ModelError::at(span, format!("a {} has no `{key}`", shape.name()))
                    .with_help("`density` and `region` belong to parts with shape = \"density\""));
            }
        }
        let raw_mass = p.mass.as_ref().ok_or_else(|| {
            ModelError::at(table.clone(), format!("part '{name}' ({}) has no `mass`", shape.name()))
                .with_help("give its mass: mass = \"M\" or a number")
        })?;
        let mass = self.value(raw_mass, false, "the mass")?;
        let m = self.number(mass, raw_mass.span(), "the mass")?;
        if m < 0.0 {
            return Err(ModelError::at(
                raw_mass.span(),
                format!("the mass of part '{name}' is {m}: expected a mass ≥ 0"),
            ));
        }
        let names = shape.size_names();
        let size = match (&p.size, names.len()) {
            (None, 0) => Vec::new(),
            (Some(s), 0) => {
                return Err(
                    ModelError::at(s.span(), format!("a {} has no size", shape.name())).with_help("remove `size`")
                )
            }
            (None, _) => {
                return Err(ModelError::at(
                    table,
                    format!("part '{name}' ({}) has no `size`: expected {}", shape.name(), names.join(", ")),
                ))
            }
            (Some(s), n) => {
                let size = self.list(s, n, &format!("the size of a {}", shape.name()), &names.join(", "))?;
                for (k, (_, v, span)) in size.iter().enumerate() {
                    if *v < 0.0 {
                        return Err(ModelError::at(span.clone(), format!("{} is {v}: expected a size ≥ 0", names[k])));
                    }
                }
                size.into_iter().map(|(e, _, _)| e).collect()
            }
        };
        let center = match &p.center {
            Some(c) => {
                let c = self.list(c, 3, "the centre", "x, y, z of the part's centre of mass")?;
                [c[0].0, c[1].0, c[2].0]
            }
            None => [self.pool.zero(); 3],
        };
        let orientation = match &p.orientation {
            Some(o) => {
                let o = self.list(o, 3, "the orientation", "Euler angles α, β, γ in radians")?;
                Some([o[0].0, o[1].0, o[2].0])
            }
            None => None,
        };
        Ok(PartKind::Shape { shape, mass, size, center, orientation })
    }

    fn density_part(&mut self, p: &RawPart, name: &str) -> Result<PartKind, ModelError> {
        let misplaced = [
            ("mass", p.mass.as_ref().map(|v| v.span()), "its mass is ∫ρ dV over the region"),
            ("size", p.size.as_ref().map(|v| v.span()), "the region gives its extent"),
            ("center", p.center.as_ref().map(|v| v.span()), "x, y, z are the body's own coordinates"),
            ("orientation", p.orientation.as_ref().map(|v| v.span()), "x, y, z are the body's own axes"),
        ];
        for (key, span, why) in misplaced {
            if let Some(span) = span {
                return Err(ModelError::at(span, format!("a density part has no `{key}`: {why}")));
            }
        }
        let raw_density = p.density.as_ref().ok_or_else(|| {
            ModelError::at(p.shape.span(), format!("part '{name}' (density) has no `density`"))
                .with_help("give ρ(x, y, z), e.g. density = \"rho*(1 + x/a)\"")
        })?;
        let density = self.value(raw_density, true, "the density")?;
        let raw_region = p.region.as_ref().ok_or_else(|| {
            ModelError::at(p.shape.span(), format!("part '{name}' (density) has no `region`"))
                .with_help("give the box: region = [[\"0\", \"a\"], [\"0\", \"b\"], [\"0\", \"c\"]]")
        })?;
        if raw_region.get_ref().len() != 3 {
            return Err(ModelError::at(
                raw_region.span(),
                format!("the region has 3 ranges ([lower, upper] of x, y, z), found {}", raw_region.get_ref().len()),
            ));
        }
        let mut region = [[self.pool.zero(); 2]; 3];
        for (axis, range) in raw_region.get_ref().iter().enumerate() {
            let var = DENSITY_VARIABLES[axis];
            let ends = self.list(range, 2, &format!("the range of {var}"), "lower, upper")?;
            let (lo, hi) = (ends[0].1, ends[1].1);
            if lo >= hi {
                return Err(ModelError::at(
                    range.span(),
                    format!("the range of {var} is [{lo}, {hi}]: expected lower < upper"),
                ));
            }
            region[axis] = [ends[0].0, ends[1].0];
        }
        Ok(PartKind::Density { density, span: raw_density.span(), region })
    }
}

/// A plain decimal literal (`0.7`, `-12.25`, `3`) as the exact rational it
/// writes, so that a number in a body file stays exact like an expression.
fn decimal(text: &str) -> Option<sym::Rational> {
    let t = text.trim();
    let (neg, digits) = match t.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, t.strip_prefix('+').unwrap_or(t)),
    };
    let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
    let all = || int.chars().chain(frac.chars());
    if int.is_empty() || !all().all(|c| c.is_ascii_digit()) || int.len() + frac.len() > 18 {
        return None;
    }
    let num: i128 = format!("{int}{frac}").parse().ok()?;
    let den = 10i128.checked_pow(frac.len() as u32)?;
    sym::Rational::new(if neg { -num } else { num }, den)
}

fn check_identifier(name: &Spanned<String>) -> Result<(), ModelError> {
    crate::source::check_name_shape(name, "parameter")?;
    let n = name.get_ref();
    if RESERVED.contains(&n.as_str()) {
        return Err(ModelError::at(name.span(), format!("parameter '{n}' uses a reserved name"))
            .with_help("t is the time, pi the constant; function names cannot be symbols"));
    }
    if DENSITY_VARIABLES.contains(&n.as_str()) {
        return Err(ModelError::at(name.span(), format!("parameter '{n}' uses a reserved name"))
            .with_help("x, y, z are the coordinates a density is integrated over"));
    }
    Ok(())
}

impl BodyFile {
    /// Reads a body file's text. `overrides` are `--set name=value` pairs,
    /// applied to `[parameters]` (an unknown name is an error).
    pub fn parse(source: &str, overrides: &[(String, f64)]) -> Result<BodyFile, ModelError> {
        let raw: RawBody = crate::source::read_toml(source, "body")?;
        let mut params: Vec<(&Spanned<String>, &Spanned<f64>)> = raw.parameters.iter().collect();
        params.sort_by_key(|(k, _)| k.span().start);
        let mut parameters: Vec<Parameter> = Vec::new();
        for (k, v) in params {
            check_identifier(k)?;
            if !v.get_ref().is_finite() {
                return Err(ModelError::at(v.span(), format!("parameter '{}' must be finite", k.get_ref())));
            }
            parameters.push(Parameter { name: k.get_ref().clone(), value: *v.get_ref(), span: k.span() });
        }
        for (name, value) in overrides {
            match parameters.iter_mut().find(|p| &p.name == name) {
                Some(p) => p.value = *value,
                None => {
                    let known: Vec<&str> = parameters.iter().map(|p| p.name.as_str()).collect();
                    return Err(ModelError::setting(
                        crate::error::Setting::Parameter { name: name.clone() },
                        format!("the body has no parameter '{name}'"),
                    )
                    .with_help(format!("its parameters are: {}", known.join(", "))));
                }
            }
        }
        let mut pool = Pool::default();
        for p in &parameters {
            pool.set_rank(&p.name, 0);
        }
        for v in DENSITY_VARIABLES {
            pool.set_rank(v, 2);
        }
        let mut r = Reader { source, pool, parameters };
        if raw.parts.is_empty() {
            return Err(ModelError::whole("the body has no parts").with_help(
                "add parts as [[parts]] tables: shape = \"box\", mass = \"M\", size = [\"a\", \"b\", \"c\"]",
            ));
        }
        let mut parts = Vec::with_capacity(raw.parts.len());
        for (i, p) in raw.parts.iter().enumerate() {
            parts.push(r.part(i, p)?);
        }
        Ok(BodyFile { pool: r.pool, name: raw.name.unwrap_or_else(|| "body".into()), parameters: r.parameters, parts })
    }

    /// The arena holding the body's expressions.
    pub fn pool(&self) -> &Pool {
        &self.pool
    }

    /// The value of a parameter.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters.iter().find(|p| p.name == name).map(|p| p.value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error's message and the text its span covers.
    #[track_caller]
    fn check_error(source: &str, message: &str, at: &str) {
        let e = BodyFile::parse(source, &[]).expect_err("an error");
        assert!(e.message.contains(message), "message: {}", e.message);
        let span = e.span.clone().expect("a span");
        assert_eq!(&source[span], at, "{}", e.message);
    }

    #[test]
    fn decimals_stay_exact() {
        let r = |n, d| sym::Rational::new(n, d);
        assert_eq!(decimal("0.7"), r(7, 10));
        assert_eq!(decimal("-12.25"), r(-49, 4));
        assert_eq!(decimal("3"), r(3, 1));
        assert_eq!(decimal("1e-3"), None);
        assert_eq!(decimal("inf"), None);
        assert_eq!(decimal("1_000"), None);
    }

    const HEAD: &str = "[parameters]\nM = 1.0\na = 2.0\n";

    #[test]
    fn bad_parts_are_located() {
        check_error(&format!("{HEAD}[[parts]]\nshape = \"cube\"\nmass = \"M\"\n"), "unknown shape 'cube'", "\"cube\"");
        check_error(
            &format!("{HEAD}[[parts]]\nshape = \"box\"\nmass = \"-M\"\nsize = [1, 1, 1]\n"),
            "expected a mass ≥ 0",
            "\"-M\"",
        );
        check_error(
            &format!("{HEAD}[[parts]]\nshape = \"box\"\nmass = \"M\"\nsize = [1, 1]\n"),
            "has 3 components",
            "[1, 1]",
        );
        check_error(&format!("{HEAD}[[parts]]\nshape = \"sphere\"\nmass = \"M\"\nsize = [\"2*b\"]\n"), "unknown", "b");
        check_error(
            &format!("{HEAD}[[parts]]\nshape = \"sphere\"\nmass = \"M\"\nsize = [\"-a\"]\n"),
            "expected a size ≥ 0",
            "\"-a\"",
        );
        check_error(&format!("{HEAD}[[parts]]\nshape = \"disk\"\nmass = \"x\"\nsize = [1]\n"), "unknown", "x");
        check_error(
            &format!(
                "{HEAD}[[parts]]\nshape = \"density\"\ndensity = \"1\"\nregion = [[\"a\", \"0\"], [0, 1], [0, 1]]\n"
            ),
            "expected lower < upper",
            "[\"a\", \"0\"]",
        );
        check_error("[parameters]\nx = 1.0\n[[parts]]\nshape = \"point\"\nmass = 1\n", "reserved", "x");
    }

    #[test]
    fn a_missing_size_names_the_part() {
        let e = BodyFile::parse(&format!("{HEAD}[[parts]]\nname = \"lid\"\nshape = \"cylinder\"\nmass = \"M\"\n"), &[])
            .err()
            .unwrap();
        assert!(e.message.contains("'lid' (cylinder) has no `size`: expected radius R, height h"), "{}", e.message);
    }

    #[test]
    fn overrides_apply_and_unknown_ones_fail() {
        let src = format!("{HEAD}[[parts]]\nshape = \"point\"\nmass = \"M\"\n");
        let b = BodyFile::parse(&src, &[("a".into(), 3.0)]).unwrap();
        assert_eq!(b.parameter("a"), Some(3.0));
        assert!(BodyFile::parse(&src, &[("q".into(), 3.0)]).is_err());
    }
}
