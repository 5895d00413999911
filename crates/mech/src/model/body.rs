//! Rigid bodies in model files (`[[bodies]]`, notes 3.2.4–3.2.6 and appendix A.5):
//! reading a body's table, and turning it into its kinetic energy, its gravity
//! potential and its body-frame angular velocity and angular momentum.
//!
//! A body has a mass M, an inertia tensor `I` about its *reference point* (three
//! principal moments or a symmetric 3×3 tensor, body components; for a body that
//! turns about one axis only, the moment about it), an [`Orientation`] (three
//! coordinates used as Euler angles in any of the twelve sequences, see
//! [`crate::euler`]; one angle about a fixed axis; or none), the reference
//! point's position `x_ref(q, t)`, and the centre of mass `c` relative to the
//! reference point in body components.
//!
//! Bodies form a tree: a body with `parent = "arm"` turns relative to the arm's
//! axes and its `position` is its reference point relative to the arm's, in the
//! arm's components. `derive/body.rs` follows the tree from the roots: with
//! `D` the rotation (space → body components), `D = D_rel·D_parent`,
//! `ω = D_rel·ω_parent + ω_rel` and `x_ref = x_parent + D_parentᵀ·position`.
//! A model whose bodies all turn about z and whose vectors have two components
//! is planar: its positions are (x, y) and `gravity = "g"` pulls along −y.
//!
//! With `r = Dᵀc` the centre of mass relative to the reference point in space,
//!
//! ```text
//! T = ½M|v_ref|² + M v_ref·(ω × r) + ½ωᵀ I ω        (ω, I in body components)
//! U = M g z_cm,   z_cm = x_ref,3 + (Dᵀc)₃
//! L = I ω + M c × (D v_ref)                       (about the reference point, body components)
//! ```
//!
//! For a fixed pivot (v_ref = 0) T = ½ωᵀIω with I about the pivot (the notes'
//! heavy top); for the reference point at the centre of mass (c = 0) T splits
//! into ½Mv² + ½ωᵀIω. The cross term is computed as M (D v_ref)·(ω × c), all in
//! body components.
//!
//! The Euler angles are singular where sin β = 0 (α and γ turn about the same
//! axis; the angles' mass matrix loses rank): `run/body.rs` gives the runs a
//! condition to stop on before the integrator produces garbage there. This file
//! reads the tables; `derive/body.rs` turns a body into T, U, ω and L.

use crate::error::{ModelError, ModelErrorKind};
use crate::model::check::{CheckKind, ValueCheck};
use crate::model::{Located, NumOrText, Reader, Scope};
use crate::probe;
use serde::Deserialize;
use std::ops::Range;
use sym::ExprId;
use toml::Spanned;

/// A rigid body of a model.
#[derive(Debug, Clone)]
pub struct Body {
    /// Its name (`name`, or `body1`, `body2`, … in file order).
    pub name: String,
    /// Where its name is written (the table when the name is the default).
    pub name_span: Range<usize>,
    /// Its mass M (an expression in the parameters).
    pub mass: ExprId,
    /// The inertia tensor about the reference point, body components, symmetric.
    pub inertia: [[ExprId; 3]; 3],
    /// Whether the inertia was given as three principal moments (or one).
    pub principal: bool,
    /// How the body turns, relative to its parent's axes (or space's).
    pub orientation: Orientation,
    /// The body whose axes it turns in and whose reference point its position
    /// starts from (an index into the model's bodies, always an earlier one).
    pub parent: Option<usize>,
    /// The reference point: in space, or relative to the parent's reference
    /// point in the parent's components; functions of (q, t).
    pub position: [ExprId; 3],
    /// 2 for a planar model (vectors written (x, y), turning about z), else 3.
    pub dimension: usize,
    /// The centre of mass relative to the reference point, body components (parameters).
    pub center_of_mass: [ExprId; 3],
    /// Where the body's table is.
    pub span: Range<usize>,
    /// Where its `inertia` is.
    pub inertia_span: Range<usize>,
}

/// How a body turns relative to its parent's axes (or space's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Orientation {
    /// Three coordinates as Euler or Tait–Bryan angles (α, β, γ) of `sequence`.
    Euler {
        /// The angles' coordinate indices.
        angles: [usize; 3],
        /// The axes they turn about (`sequence = "zxz"`, the notes').
        sequence: crate::euler::Sequence,
    },
    /// One coordinate, the angle about a fixed axis (0 = x, 1 = y, 2 = z).
    Planar {
        /// The angle's coordinate index.
        angle: usize,
        /// The axis.
        axis: usize,
    },
    /// One coordinate, the angle about a fixed unit vector of the parent's
    /// axes (a hinge at any direction: a bicycle's steering head).
    Hinge {
        /// The angle's coordinate index.
        angle: usize,
        /// The unit vector (expressions in the parameters, normalized).
        axis: [ExprId; 3],
    },
    /// No angle of its own: the parent's axes, or space's.
    Fixed,
}

impl Orientation {
    /// The coordinates the body turns with.
    pub fn angles(&self) -> Vec<usize> {
        match *self {
            Orientation::Euler { angles, .. } => angles.to_vec(),
            Orientation::Planar { angle, .. } | Orientation::Hinge { angle, .. } => vec![angle],
            Orientation::Fixed => Vec::new(),
        }
    }

    /// The Euler angles and their sequence, for a body that has them.
    pub fn euler(&self) -> Option<([usize; 3], crate::euler::Sequence)> {
        match *self {
            Orientation::Euler { angles, sequence } => Some((angles, sequence)),
            _ => None,
        }
    }
}

/// How a body's angular velocity can point: along which of its axes, if one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Spin {
    /// It does not turn (no angles up its tree).
    None,
    /// Always along this body axis (every angle up its tree turns about it).
    About(usize),
    /// Any direction.
    Free,
}

/// The `[[bodies]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBody {
    name: Option<Spanned<String>>,
    mass: Option<Spanned<NumOrText>>,
    inertia: Option<Spanned<toml::Value>>,
    angles: Option<Spanned<Vec<Spanned<String>>>>,
    angle: Option<Spanned<String>>,
    axis: Option<Spanned<toml::Value>>,
    sequence: Option<Spanned<String>>,
    parent: Option<Spanned<String>>,
    position: Option<Spanned<Vec<Spanned<NumOrText>>>>,
    center_of_mass: Option<Spanned<Vec<Spanned<NumOrText>>>>,
}

/// Reads every `[[bodies]]` table; a parent comes before its children.
pub(crate) fn read_all(r: &mut Reader<'_>, raw: &[Spanned<RawBody>]) -> Result<Vec<Body>, ModelError> {
    let mut bodies: Vec<Body> = Vec::new();
    let mut spins: Vec<Spin> = Vec::new();
    for (k, b) in raw.iter().enumerate() {
        let (body, spin) = read(r, b, k, &bodies, &spins)?;
        for other in &bodies {
            let own = body.orientation.angles();
            if let Some(&shared) = own.iter().find(|a| other.orientation.angles().contains(a)) {
                return Err(ModelError::at(
                    angles_span(b),
                    format!("coordinate '{}' is already an angle of body '{}'", r.coordinates[shared].name, other.name),
                )
                .with_help("each body turns with its own angles"));
            }
            if other.name == body.name {
                let span = b.get_ref().name.as_ref().map_or(b.span(), |n| n.span());
                return Err(ModelError::at(span, format!("two bodies are named '{}'", body.name)));
            }
        }
        bodies.push(body);
        spins.push(spin);
    }
    // Planar or spatial: one for the whole model.
    let about_z = |b: &Body| match b.orientation {
        Orientation::Euler { .. } | Orientation::Hinge { .. } => false,
        Orientation::Planar { axis, .. } => axis == 2,
        Orientation::Fixed => true,
    };
    for (b, raw_b) in bodies.iter().zip(raw) {
        let table = raw_b.get_ref();
        let flat = [&table.position, &table.center_of_mass].into_iter().flatten().find(|v| v.get_ref().len() == 2);
        if let (Some(v), false) = (flat, about_z(b)) {
            return Err(ModelError::at(v.span(), "this vector has 2 components, not 3 (x, y, z)").with_help(format!(
                "body '{}' turns in space, so its vectors have three components; two are for planar models, whose bodies turn about z",
                b.name
            )));
        }
    }
    let Some(flat) = bodies.iter().position(|b| b.dimension == 2) else { return Ok(bodies) };
    let flat_name = bodies[flat].name.clone();
    for (b, raw_b) in bodies.iter_mut().zip(raw) {
        let table = raw_b.get_ref();
        if let Some(v) = [&table.position, &table.center_of_mass].into_iter().flatten().find(|v| v.get_ref().len() == 3)
        {
            return Err(ModelError::at(v.span(), "this vector has 3 components, not 2 (x, y)").with_help(format!(
                "body '{flat_name}' is written in (x, y), so the model is planar and every body vector has two components"
            )));
        }
        if !about_z(b) {
            return Err(ModelError::at(
                angles_span(raw_b),
                format!("body '{flat_name}' is written in (x, y), so bodies turn about z only; '{}' does not", b.name),
            )
            .with_help("write every body vector with 3 components for bodies that turn in space"));
        }
        b.dimension = 2;
    }
    Ok(bodies)
}

/// Where a body's angles are written (the table when it has none).
fn angles_span(b: &Spanned<RawBody>) -> Range<usize> {
    let raw = b.get_ref();
    raw.angles
        .as_ref()
        .map(|a| a.span())
        .or_else(|| raw.axis.as_ref().map(|a| a.span()))
        .or_else(|| raw.angle.as_ref().map(|a| a.span()))
        .unwrap_or(b.span())
}

/// A coordinate named in a body's angles.
fn angle_coordinate(r: &Reader<'_>, a: &Spanned<String>) -> Result<usize, ModelError> {
    r.coordinates.iter().position(|c| &c.name == a.get_ref()).ok_or_else(|| {
        ModelError::at(a.span(), format!("the angle '{}' is not a coordinate", a.get_ref()))
            .with_help("list it in `coordinates`")
    })
}

/// The body's orientation: `angles` (and `sequence`), `angle` (and `axis`), or neither.
fn read_orientation(r: &mut Reader<'_>, b: &Spanned<RawBody>) -> Result<Orientation, ModelError> {
    let raw = b.get_ref();
    match (&raw.angles, &raw.angle) {
        (Some(_), Some(one)) => {
            Err(ModelError::at(one.span(), "give either `angles` (three) or `angle` (one), not both"))
        }
        (Some(angles_raw), None) => {
            if let Some(axis) = &raw.axis {
                return Err(ModelError::at(
                    axis.span(),
                    "`axis` goes with one `angle`; three `angles` take a `sequence`",
                ));
            }
            let list = angles_raw.get_ref();
            if list.len() != 3 {
                return Err(ModelError::at(
                    angles_raw.span(),
                    format!("`angles` names the three Euler angles (α, β, γ), not {}", list.len()),
                )
                .with_help(
                    "e.g. angles = [\"al\", \"be\", \"ga\"]; a body turning about one axis takes angle = \"th\"",
                ));
            }
            let mut angles = [0usize; 3];
            for (k, a) in list.iter().enumerate() {
                let i = angle_coordinate(r, a)?;
                if angles[..k].contains(&i) {
                    return Err(ModelError::at(a.span(), format!("Euler angle '{}' is listed twice", a.get_ref()))
                        .with_help("α, β and γ are three different coordinates"));
                }
                angles[k] = i;
            }
            let sequence = match &raw.sequence {
                None => crate::euler::Sequence::NOTES,
                Some(s) => crate::euler::Sequence::parse(s.get_ref()).ok_or_else(|| {
                    ModelError::at(s.span(), format!("'{}' is not a sequence of three turns", s.get_ref())).with_help(
                        "three axes, each other than the one before: \"zxz\" (the notes', default), \"zyz\", \"xyx\", …, or Tait–Bryan \"xyz\", \"zyx\", …",
                    )
                })?,
            };
            Ok(Orientation::Euler { angles, sequence })
        }
        (None, Some(one)) => {
            if let Some(s) = &raw.sequence {
                return Err(ModelError::at(
                    s.span(),
                    "`sequence` goes with three `angles`; one `angle` takes an `axis`",
                ));
            }
            let angle = angle_coordinate(r, one)?;
            match raw.axis.as_ref().map(|a| (a.get_ref(), a.span())) {
                None => Ok(Orientation::Planar { angle, axis: 2 }),
                Some((toml::Value::String(name), span)) => match name.as_str() {
                    "x" => Ok(Orientation::Planar { angle, axis: 0 }),
                    "y" => Ok(Orientation::Planar { angle, axis: 1 }),
                    "z" => Ok(Orientation::Planar { angle, axis: 2 }),
                    other => Err(ModelError::at(span, format!("'{other}' is not an axis")).with_help(
                        "axis = \"x\", \"y\" or \"z\" (default z), or a vector [\"ax\", \"ay\", \"az\"], in the parent's axes or space's",
                    )),
                },
                Some((toml::Value::Array(items), span)) if items.len() == 3 => {
                    let mut cursor = span.start;
                    let mut v = [r.pool.zero(); 3];
                    for (k, x) in items.iter().enumerate() {
                        v[k] = entry(r, x, &span, &mut cursor, &format!("component {} of the axis", k + 1))?;
                    }
                    r.check(ValueCheck { kind: CheckKind::Axis(v), span })?;
                    // A vector of length 1 whatever the parameters (sin, 0, −cos
                    // of an angle) is taken as written: dividing by
                    // √(sin² + cos²) only makes every expression longer. One of
                    // length 1 at the file's values only is normalized: a sweep
                    // or --set may give it other lengths.
                    let squares: Vec<ExprId> = v.iter().map(|&c| r.pool.powi(c, 2)).collect();
                    let sum = r.pool.add(&squares);
                    let one = r.pool.one();
                    if probe::decide_equal(&mut r.pool, sum, one) == probe::Decision::Zero {
                        return Ok(Orientation::Hinge { angle, axis: v });
                    }
                    let norm = r.pool.sqrt(sum);
                    let axis = v.map(|c| r.pool.div(c, norm));
                    Ok(Orientation::Hinge { angle, axis })
                }
                Some((_, span)) => Err(ModelError::at(span, "the axis is \"x\", \"y\", \"z\" or three components")),
            }
        }
        (None, None) => {
            let stray = raw.sequence.as_ref().map(|s| s.span()).or(raw.axis.as_ref().map(|a| a.span()));
            if let Some(span) = stray {
                return Err(ModelError::at(span, "the body has no angles for this to apply to")
                    .with_help("give angles = [..] (three) with `sequence`, or angle = \"..\" with `axis`"));
            }
            Ok(Orientation::Fixed)
        }
    }
}

fn read(
    r: &mut Reader<'_>,
    b: &Spanned<RawBody>,
    index: usize,
    earlier: &[Body],
    spins: &[Spin],
) -> Result<(Body, Spin), ModelError> {
    let raw = b.get_ref();
    let name = match &raw.name {
        Some(n) => {
            crate::source::check_identifier(n, "body name")?;
            n.get_ref().clone()
        }
        None => format!("body{}", index + 1),
    };
    let parent = match &raw.parent {
        None => None,
        Some(p) => Some(earlier.iter().position(|e| &e.name == p.get_ref()).ok_or_else(|| {
            let known: Vec<&str> = earlier.iter().map(|e| e.name.as_str()).collect();
            ModelError::at(p.span(), format!("no body named '{}' comes before this one", p.get_ref())).with_help(
                if known.is_empty() {
                    "a parent is a body listed earlier in the file, with `name`".to_string()
                } else {
                    format!("a parent is a body listed earlier in the file: {}", known.join(", "))
                },
            )
        })?),
    };
    let orientation = read_orientation(r, b)?;
    let parent_spin = parent.map_or(Spin::None, |p| spins[p]);
    let spin = match (orientation, parent_spin) {
        (Orientation::Euler { .. }, _) => Spin::Free,
        (Orientation::Fixed, s) => s,
        (Orientation::Planar { axis, .. }, Spin::None) => Spin::About(axis),
        (Orientation::Planar { axis, .. }, Spin::About(k)) if k == axis => Spin::About(axis),
        (Orientation::Planar { .. }, _) | (Orientation::Hinge { .. }, _) => Spin::Free,
    };

    // A body file gives the mass, the centre of mass and the tensor at once.
    let file = match raw.inertia.as_ref().map(|i| (i.get_ref(), i.span())) {
        Some((toml::Value::String(s), span)) if s.trim_end().ends_with(".toml") => {
            Some(load_body_file(r, s.trim_end(), span)?)
        }
        _ => None,
    };
    let mass = match (&raw.mass, &file, &raw.inertia) {
        (Some(m), _, _) => r.num_or_expr(m, Scope::Parameters, "the body's mass")?,
        (None, Some(f), Some(i)) => Located { expr: crate::source::number_expr(&mut r.pool, f.mass), span: i.span() },
        _ => {
            return Err(ModelError::at(b.span(), "the body has no `mass`").with_help(
                "give mass = \"M\" (a number or an expression in the parameters), or a body file as `inertia`",
            ))
        }
    };

    // Reference point and centre of mass: two components (planar) or three.
    let mut dimension = 3;
    let mut vector = |r: &mut Reader<'_>,
                      v: &Option<Spanned<Vec<Spanned<NumOrText>>>>,
                      scope: Scope,
                      what: &str|
     -> Result<[ExprId; 3], ModelError> {
        let Some(v) = v else { return Ok([r.pool.zero(); 3]) };
        let n = v.get_ref().len();
        if n != 3 && n != 2 {
            return Err(ModelError::at(v.span(), format!("a body's {what} has 3 components (x, y, z), not {n}"))
                .with_help("or 2, (x, y), in a planar model whose bodies turn about z"));
        }
        if n == 2 {
            dimension = 2;
        }
        let mut out = [r.pool.zero(); 3];
        for (k, x) in v.get_ref().iter().enumerate() {
            out[k] = r.num_or_expr(x, scope, &format!("the body's {what}"))?.expr;
        }
        Ok(out)
    };
    let position = vector(r, &raw.position, Scope::Configuration, "position")?;
    let mut center_of_mass = vector(r, &raw.center_of_mass, Scope::Parameters, "center_of_mass")?;
    let inertia_span = raw.inertia.as_ref().map_or(b.span(), |i| i.span());
    let (inertia, principal, moment_only) = match (&file, &raw.inertia) {
        (Some(f), _) => {
            agree_with_file(r, mass.expr, f.mass, mass.span.clone(), "mass")?;
            match &raw.center_of_mass {
                Some(c) => {
                    for k in 0..3 {
                        let what = format!("centre of mass component {}", k + 1);
                        agree_with_file(r, center_of_mass[k], f.center_of_mass[k], c.span(), &what)?;
                    }
                }
                None => center_of_mass = f.center_of_mass.map(|x| crate::source::number_expr(&mut r.pool, x)),
            }
            let tensor = f.tensor.map(|row| row.map(|x| crate::source::number_expr(&mut r.pool, x)));
            let diagonal = (0..3).all(|i| (0..3).all(|j| i == j || f.tensor[i][j] == 0.0));
            (tensor, diagonal, false)
        }
        (None, Some(i)) if !i.get_ref().is_array() => {
            // One moment: about the only axis the body turns about.
            let Spin::About(axis) = spin else {
                let why = if spin == Spin::None { "does not turn" } else { "turns about more than one axis" };
                return Err(ModelError::at(
                    i.span(),
                    format!("one moment of inertia is for a body that turns about one axis, and '{name}' {why}"),
                )
                .with_help("give three principal moments [\"I1\", \"I2\", \"I3\"] or a 3×3 tensor"));
            };
            let mut cursor = i.span().start;
            let moment = entry(r, i.get_ref(), &i.span(), &mut cursor, "the moment of inertia")?;
            let mut m = [[r.pool.zero(); 3]; 3];
            m[axis][axis] = moment;
            (m, true, true)
        }
        (None, Some(i)) => {
            let (m, principal) = read_inertia(r, i)?;
            (m, principal, false)
        }
        (None, None) if spin == Spin::None => ([[r.pool.zero(); 3]; 3], true, false),
        (None, None) => {
            return Err(ModelError::at(b.span(), format!("body '{name}' turns but has no `inertia`")).with_help(
                "give three principal moments, a 3×3 tensor, a body file, or (turning about one axis) one moment",
            ))
        }
    };

    // Numeric sanity at the parameters' values: M > 0, I a physical tensor
    // (moments ≥ 0, each at most the sum of the other two). A zero moment (a
    // thin rod about its axis, a point mass) is allowed: only a singular
    // total mass matrix is refused, by the derivation, naming the coordinate.
    // The checks are kept for a sweep to run at each row's values.
    let tensor = if moment_only {
        let sum = r.pool.add(&inertia.iter().flatten().copied().collect::<Vec<_>>());
        CheckKind::Moment(sum)
    } else {
        CheckKind::Tensor(inertia)
    };
    r.check(ValueCheck { kind: CheckKind::Mass(mass.expr), span: mass.span.clone() })?;
    r.check(ValueCheck { kind: tensor, span: inertia_span.clone() })?;
    let body = Body {
        name,
        name_span: raw.name.as_ref().map_or(b.span(), |n| n.span()),
        mass: mass.expr,
        inertia,
        principal,
        orientation,
        parent,
        position,
        dimension,
        center_of_mass,
        span: b.span(),
        inertia_span,
    };
    Ok((body, spin))
}

/// What a body file says about a body, as numbers at the file's own parameters.
struct FileBody {
    mass: f64,
    center_of_mass: [f64; 3],
    /// The tensor about the file's origin (the body's reference point), body axes.
    tensor: [[f64; 3]; 3],
}

/// Reads and evaluates the body file `name` (see `lagrange inertia`): its
/// origin is the body's reference point and its axes are the body axes.
fn load_body_file(r: &mut Reader<'_>, name: &str, span: Range<usize>) -> Result<FileBody, ModelError> {
    let text = (r.files)(name).map_err(|e| {
        ModelError::at(span.clone(), format!("cannot read the body file '{name}': {e}")).with_kind(ModelErrorKind::File)
    })?;
    let nested = |e: ModelError| {
        let mut err = ModelError::at(span.clone(), format!("in the body file {name}: {}", e.message));
        err.help.clone_from(&e.help);
        err.within = Some(Box::new(crate::error::Within {
            what: "body file".into(),
            name: name.into(),
            text: text.clone(),
            error: e,
        }));
        err
    };
    let body = crate::inertia::BodyFile::parse(&text, &[]).map_err(nested)?;
    let props = body.mass_properties().map_err(nested)?;
    Ok(FileBody {
        mass: props.value(props.mass),
        center_of_mass: props.center_of_mass.map(|c| props.value(c)),
        tensor: props.about_values([0.0; 3]),
    })
}

/// A value the model gives beside a body file must be the file's (to 1e-9 relative).
fn agree_with_file(r: &Reader<'_>, given: ExprId, want: f64, span: Range<usize>, what: &str) -> Result<(), ModelError> {
    let env = |n: &str| r.parameters.iter().find(|p| p.name == n).map(|p| p.value);
    match r.pool.eval(given, &env) {
        Ok(v) if (v - want).abs() <= 1e-9 * want.abs().max(1.0) => Ok(()),
        Ok(v) => Err(ModelError::at(span, format!("the body's {what} is {v} here but {want} in its body file"))
            .with_help(format!("leave the {what} out to take it from the body file"))),
        Err(e) => Err(ModelError::at(span, e.to_string())),
    }
}

/// The inertia: three principal moments, or a symmetric 3×3 tensor.
fn read_inertia(r: &mut Reader<'_>, v: &Spanned<toml::Value>) -> Result<([[ExprId; 3]; 3], bool), ModelError> {
    let span = v.span();
    let expected = "expected three principal moments [\"I1\", \"I2\", \"I3\"] or a 3×3 tensor [[..], [..], [..]]";
    match v.get_ref() {
        toml::Value::Array(rows) if rows.len() == 3 && rows.iter().all(|x| x.is_array()) => {
            let mut cursor = span.start;
            let mut m = [[r.pool.zero(); 3]; 3];
            for (i, row) in rows.iter().enumerate() {
                let row = row.as_array().expect("checked");
                if row.len() != 3 {
                    return Err(ModelError::at(
                        span.clone(),
                        format!("row {} of the inertia tensor has {} entries, not 3", i + 1, row.len()),
                    ));
                }
                for (j, x) in row.iter().enumerate() {
                    m[i][j] = entry(r, x, &span, &mut cursor, &format!("the inertia entry I{}{}", i + 1, j + 1))?;
                }
            }
            for i in 0..3 {
                for j in i + 1..3 {
                    // A symmetric tensor is a claim: proven, or the model is refused.
                    let problem = match probe::decide_equal(&mut r.pool, m[i][j], m[j][i]) {
                        probe::Decision::Zero => continue,
                        probe::Decision::NonZero => "the inertia tensor is not symmetric",
                        probe::Decision::Undecided => "could not show that the inertia tensor is symmetric",
                    };
                    return Err(ModelError::at(
                        span,
                        format!(
                            "{problem}: I{}{} = {} but I{}{} = {}",
                            i + 1,
                            j + 1,
                            r.pool.display(m[i][j]),
                            j + 1,
                            i + 1,
                            r.pool.display(m[j][i])
                        ),
                    ));
                }
            }
            Ok((m, false))
        }
        toml::Value::Array(items) if items.len() == 3 && items.iter().all(|x| !x.is_array()) => {
            let mut cursor = span.start;
            let zero = r.pool.zero();
            let mut m = [[zero; 3]; 3];
            for (k, x) in items.iter().enumerate() {
                m[k][k] = entry(r, x, &span, &mut cursor, &format!("the principal moment I{}", k + 1))?;
            }
            Ok((m, true))
        }
        toml::Value::Array(items) => {
            Err(ModelError::at(span, format!("the inertia has {} entries: {expected}", items.len())))
        }
        _ => Err(ModelError::at(span, format!("the inertia is not a list: {expected}"))),
    }
}

/// One number or expression of the inertia, located in the file by searching
/// for its text from `cursor` (toml gives the span of the whole array only).
fn entry(
    r: &mut Reader<'_>,
    x: &toml::Value,
    span: &Range<usize>,
    cursor: &mut usize,
    what: &str,
) -> Result<ExprId, ModelError> {
    match x {
        toml::Value::Integer(i) => Ok(crate::source::number_expr(&mut r.pool, *i as f64)),
        toml::Value::Float(f) if f.is_finite() => Ok(crate::source::number_expr(&mut r.pool, *f)),
        toml::Value::String(s) => {
            let hay = r.source.get(*cursor..span.end).unwrap_or("");
            let at = ["\"", "'"].iter().find_map(|q| hay.find(&format!("{q}{s}{q}")).map(|p| (p, q.len())));
            let located = match at {
                Some((p, ql)) => {
                    let start = *cursor + p;
                    *cursor = start + s.len() + 2 * ql;
                    start..*cursor
                }
                None => span.clone(),
            };
            Ok(r.expr_str(s, located, Scope::Parameters, what)?.expr)
        }
        _ => Err(ModelError::at(span.clone(), format!("{what} must be a number or an expression string"))),
    }
}
