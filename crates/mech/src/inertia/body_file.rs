//! Body files: the TOML text that describes a rigid body as a list of parts,
//! read into expressions and checked (shapes, sizes, signs, names), with every
//! mistake reported at its place in the file.
//!
//! Enter with [`BodyFile::parse`]. A part is a standard shape (`point`, `rod`,
//! `box`, `sphere`, `shell`, `cylinder`, `cone`, `disk`, `ring`, `ellipsoid`)
//! with `mass`, `size`, `center` (where its centre of mass sits) and an
//! optional `orientation` (Euler angles, [`crate::euler`]), a `density`
//! ρ(x, y, z) over a box `region`, or a `tensor`: a given `inertia` about the
//! part's centre of mass (three principal moments or a symmetric 3×3 tensor,
//! spelled as a model's `[[bodies]]` spell it), checked to be one a mass
//! distribution can have. Values are numbers or expressions in `[parameters]`.

use super::shapes::Shape;
use crate::error::ModelError;
use crate::probe::{self, Decision};
use crate::source::Parameter;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use sym::{ExprId, ParseErrorKind, ParseOptions, Pool};
use toml::Spanned;

/// The integration variables of a density part; no parameter may take these names.
pub const DENSITY_VARIABLES: [&str; 3] = ["x", "y", "z"];

/// How far a given tensor may miss positive semi-definiteness and the
/// triangle inequality of its principal moments, relative to its trace: the
/// rounding of moments written as decimals to about ten digits (a thin disk's
/// I_z = I_x + I_y written as 0.6666666667 = 0.3333333333 + 0.3333333333).
pub const TENSOR_RTOL: f64 = 1e-9;

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

/// A standard shape, a density or a given tensor.
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
    /// A part whose inertia tensor about its centre of mass is given
    /// (`shape = "tensor"`).
    Tensor {
        /// Its mass.
        mass: ExprId,
        /// The tensor about its centre of mass in the part's axes, symmetric
        /// (diagonal when given as principal moments).
        inertia: [[ExprId; 3]; 3],
        /// Whether it was given as three principal moments.
        principal: bool,
        /// Its centre of mass in the body's axes.
        center: [ExprId; 3],
        /// Euler angles (α, β, γ) turning the part's axes; `None`: aligned with the body's.
        orientation: Option<[ExprId; 3]>,
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
    inertia: Option<Spanned<Vec<Spanned<InertiaItem>>>>,
}

/// An entry of a tensor part's `inertia`: a principal moment, or a row of the tensor.
enum InertiaItem {
    Moment(NumOrText),
    Row(Vec<Spanned<NumOrText>>),
}

// By hand rather than `#[serde(untagged)]`: an untagged enum buffers its
// input, which loses the places of a row's entries.
impl<'de> Deserialize<'de> for InertiaItem {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Item;
        impl<'de> serde::de::Visitor<'de> for Item {
            type Value = InertiaItem;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a moment (a number or an expression in quotes) or a row of three")
            }
            fn visit_i64<E>(self, v: i64) -> Result<InertiaItem, E> {
                Ok(InertiaItem::Moment(NumOrText::Num(v as f64)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<InertiaItem, E> {
                Ok(InertiaItem::Moment(NumOrText::Num(v as f64)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<InertiaItem, E> {
                Ok(InertiaItem::Moment(NumOrText::Num(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<InertiaItem, E> {
                Ok(InertiaItem::Moment(NumOrText::Text(v.to_string())))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<InertiaItem, A::Error> {
                let mut row = Vec::new();
                while let Some(x) = seq.next_element::<Spanned<NumOrText>>()? {
                    row.push(x);
                }
                Ok(InertiaItem::Row(row))
            }
        }
        d.deserialize_any(Item)
    }
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
        } else if shape_name == "tensor" {
            self.tensor_part(p, raw.span(), &name)?
        } else {
            let shape = Shape::from_name(shape_name).ok_or_else(|| {
                let known: Vec<&str> = Shape::ALL.iter().map(|s| s.name()).chain(["density", "tensor"]).collect();
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
        if let Some(i) = &p.inertia {
            return Err(ModelError::at(i.span(), format!("a {} has no `inertia`: its shape gives it", shape.name()))
                .with_help("a part with a given inertia has shape = \"tensor\""));
        }
        let mass = self.mass(p, table.clone(), name, shape.name())?;
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
        let (center, orientation) = self.placement(p)?;
        Ok(PartKind::Shape { shape, mass, size, center, orientation })
    }

    /// A shape's or a tensor part's `mass` (`kind` names the part's shape).
    fn mass(&mut self, p: &RawPart, table: Range<usize>, name: &str, kind: &str) -> Result<ExprId, ModelError> {
        let raw_mass = p.mass.as_ref().ok_or_else(|| {
            ModelError::at(table, format!("part '{name}' ({kind}) has no `mass`"))
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
        Ok(mass)
    }

    /// A shape's or a tensor part's `center` (default the origin) and `orientation`.
    fn placement(&mut self, p: &RawPart) -> Result<([ExprId; 3], Option<[ExprId; 3]>), ModelError> {
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
        Ok((center, orientation))
    }

    /// A part with a given `inertia` about its centre of mass: three principal
    /// moments or a symmetric 3×3 tensor, checked to be the tensor of some
    /// mass distribution (symmetric, positive semi-definite, each principal
    /// moment at most the sum of the other two).
    fn tensor_part(&mut self, p: &RawPart, table: Range<usize>, name: &str) -> Result<PartKind, ModelError> {
        let misplaced = [
            ("size", p.size.as_ref().map(|v| v.span()), "its `inertia` gives the moments"),
            ("density", p.density.as_ref().map(|v| v.span()), "`density` belongs to parts with shape = \"density\""),
            ("region", p.region.as_ref().map(|v| v.span()), "`region` belongs to parts with shape = \"density\""),
        ];
        for (key, span, why) in misplaced {
            if let Some(span) = span {
                return Err(ModelError::at(span, format!("a tensor part has no `{key}`: {why}")));
            }
        }
        let mass = self.mass(p, table.clone(), name, "tensor")?;
        let raw = p.inertia.as_ref().ok_or_else(|| {
            ModelError::at(table, format!("part '{name}' (tensor) has no `inertia`"))
                .with_help("give its tensor about its centre of mass: inertia = [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]], or principal moments inertia = [A, B, C]")
        })?;
        let span = raw.span();
        let items = raw.get_ref();
        let expected = "expected three principal moments [A, B, C] or a 3×3 tensor [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]]";
        let zero = self.pool.zero();
        let mut inertia = [[zero; 3]; 3];
        // The place of each entry, for the checks below.
        let mut places: [[Range<usize>; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| span.clone()));
        let mut values = [[0.0; 3]; 3];
        let principal = if items.len() == 3 && items.iter().all(|x| matches!(x.get_ref(), InertiaItem::Row(_))) {
            for (i, row) in items.iter().enumerate() {
                let InertiaItem::Row(entries) = row.get_ref() else { unreachable!("checked: every item is a row") };
                if entries.len() != 3 {
                    return Err(ModelError::at(
                        row.span(),
                        format!("row {} of the inertia tensor has {} entries, not 3", i + 1, entries.len()),
                    ));
                }
                for (j, x) in entries.iter().enumerate() {
                    let what = format!("the inertia entry I{}{}", i + 1, j + 1);
                    inertia[i][j] = self.value(x, false, &what)?;
                    values[i][j] = self.number(inertia[i][j], x.span(), &what)?;
                    places[i][j] = x.span();
                }
            }
            false
        } else if items.len() == 3 && items.iter().all(|x| matches!(x.get_ref(), InertiaItem::Moment(_))) {
            for (k, x) in items.iter().enumerate() {
                let InertiaItem::Moment(v) = x.get_ref() else { unreachable!("checked: every item is a moment") };
                let what = format!("the principal moment I{}", k + 1);
                let v = Spanned::new(x.span(), v.clone());
                inertia[k][k] = self.value(&v, false, &what)?;
                values[k][k] = self.number(inertia[k][k], x.span(), &what)?;
                places[k][k] = x.span();
            }
            true
        } else {
            return Err(ModelError::at(span, format!("the inertia has {} entries: {expected}", items.len())));
        };
        for i in 0..3 {
            for j in i + 1..3 {
                // A symmetric tensor is a claim: proven, or the part is refused.
                let problem = match probe::decide_equal(&mut self.pool, inertia[i][j], inertia[j][i]) {
                    Decision::Zero => continue,
                    Decision::NonZero => "the inertia tensor is not symmetric",
                    Decision::Undecided => "could not show that the inertia tensor is symmetric",
                };
                return Err(ModelError::at(
                    places[j][i].clone(),
                    format!(
                        "{problem}: I{}{} = {} but I{}{} = {}",
                        i + 1,
                        j + 1,
                        self.pool.display(inertia[i][j]),
                        j + 1,
                        i + 1,
                        self.pool.display(inertia[j][i])
                    ),
                )
                .with_help("the tensor about the centre of mass is symmetric: I_jk = I_kj"));
            }
        }
        let help = "a mass distribution's tensor has principal moments ≥ 0, each at most the sum of the other two";
        for k in 0..3 {
            if values[k][k] < 0.0 {
                return Err(ModelError::at(
                    places[k][k].clone(),
                    format!("the moment I{0}{0} is {1}: expected a moment ≥ 0", k + 1, values[k][k]),
                )
                .with_help(help));
            }
        }
        check_tensor(&values).map_err(|why| ModelError::at(span, why).with_help(help))?;
        let (center, orientation) = self.placement(p)?;
        Ok(PartKind::Tensor { mass, inertia, principal, center, orientation })
    }

    fn density_part(&mut self, p: &RawPart, name: &str) -> Result<PartKind, ModelError> {
        let misplaced = [
            ("mass", p.mass.as_ref().map(|v| v.span()), "its mass is ∫ρ dV over the region"),
            ("size", p.size.as_ref().map(|v| v.span()), "the region gives its extent"),
            ("center", p.center.as_ref().map(|v| v.span()), "x, y, z are the body's own coordinates"),
            ("orientation", p.orientation.as_ref().map(|v| v.span()), "x, y, z are the body's own axes"),
            ("inertia", p.inertia.as_ref().map(|v| v.span()), "its tensor is integrated from ρ"),
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
                    format!(
                        "the range of {var} is [{}, {}]: expected lower < upper",
                        num::Shortest(lo),
                        num::Shortest(hi)
                    ),
                ));
            }
            region[axis] = [ends[0].0, ends[1].0];
        }
        Ok(PartKind::Density { density, span: raw_density.span(), region })
    }
}

/// Whether a symmetric tensor (its values) is one a mass distribution can
/// have: positive semi-definite with each principal moment at most the sum of
/// the other two, both to [`TENSOR_RTOL`] of its trace; otherwise why not.
fn check_tensor(t: &[[f64; 3]; 3]) -> Result<(), String> {
    let m = nalgebra::Matrix3::from_fn(|j, k| t[j][k]);
    let mut moments: Vec<f64> = nalgebra::SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
    moments.sort_by(f64::total_cmp);
    let slack = TENSOR_RTOL * (t[0][0] + t[1][1] + t[2][2]).abs();
    let shown =
        || format!("({})", moments.iter().map(|&m| num::Shortest(m).to_string()).collect::<Vec<_>>().join(", "));
    if moments[0] < -slack {
        return Err(format!(
            "the inertia tensor is not positive semi-definite: its principal moments are {}, and a moment of inertia is ≥ 0",
            shown()
        ));
    }
    if moments[2] > moments[0] + moments[1] + slack {
        return Err(format!(
            "the principal moments {} break the triangle inequality: I3 = {} exceeds I1 + I2 = {}",
            shown(),
            moments[2],
            moments[0] + moments[1]
        ));
    }
    Ok(())
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
                Some(p) => p.value = crate::error::finite_override(name, *value)?,
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
    fn bad_tensors_are_located() {
        let part = format!("{HEAD}[[parts]]\nshape = \"tensor\"\nmass = \"M\"\n");
        check_error(
            &format!("{part}inertia = [[1, 0.5, 0], [0.25, 1, 0], [0, 0, 1]]\n"),
            "not symmetric: I12 = 1/2 but I21 = 1/4",
            "0.25",
        );
        check_error(
            &format!("{part}inertia = [1, \"-a\", 1]\n"),
            "the moment I22 is -2: expected a moment ≥ 0",
            "\"-a\"",
        );
        // Diagonal entries ≥ 0, yet an eigenvalue 1 − 2 < 0.
        check_error(
            &format!("{part}inertia = [[1, 2, 0], [2, 1, 0], [0, 0, 1]]\n"),
            "not positive semi-definite",
            "[[1, 2, 0], [2, 1, 0], [0, 0, 1]]",
        );
        check_error(&format!("{part}inertia = [1, 1, 3]\n"), "break the triangle inequality", "[1, 1, 3]");
        check_error(&format!("{part}inertia = [1, 1]\n"), "the inertia has 2 entries", "[1, 1]");
        check_error(
            &format!("{part}inertia = [[1, 0, 0], [0, 1], [0, 0, 1]]\n"),
            "row 2 of the inertia tensor",
            "[0, 1]",
        );
        check_error(&format!("{part}inertia = [1, \"1/(a - 2)\", 1]\n"), "expected a finite number", "\"1/(a - 2)\"");
        check_error(&format!("{part}inertia = [1, 1, 1]\nsize = [1]\n"), "a tensor part has no `size`", "[1]");
        check_error(&format!("{part}center = [0, 0, 0]\n"), "(tensor) has no `inertia`", "[[parts]]");
        check_error(
            &format!("{HEAD}[[parts]]\nshape = \"box\"\nmass = 1\nsize = [1, 1, 1]\ninertia = [1, 1, 1]\n"),
            "a box has no `inertia`",
            "[1, 1, 1]",
        );
        // A flat body's moments written to ten digits meet I3 = I1 + I2 within rounding.
        let disk = format!("{part}inertia = [0.3333333333, 0.3333333333, 0.6666666667]\n");
        assert!(BodyFile::parse(&disk, &[]).is_ok());
        // A point-like part (all moments zero) is a tensor too.
        assert!(BodyFile::parse(&format!("{part}inertia = [0, 0, 0]\n"), &[]).is_ok());
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
