//! Rigid bodies in model files (`[[bodies]]`, notes 3.2.4–3.2.6 and appendix A.5):
//! reading a body's table, and turning it into its kinetic energy, its gravity
//! potential and its body-frame angular velocity and angular momentum.
//!
//! A body has a mass M, an inertia tensor `I` about its *reference point* (three
//! principal moments or a symmetric 3×3 tensor, body components), three
//! coordinates used as Euler angles (α, β, γ in the notes' convention, see
//! [`crate::euler`]), the reference point's position `x_ref(q, t)` in space, and
//! the centre of mass `c` relative to the reference point in body components.
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

use crate::error::ModelError;
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
    /// Its mass M (an expression in the parameters).
    pub mass: ExprId,
    /// The inertia tensor about the reference point, body components, symmetric.
    pub inertia: [[ExprId; 3]; 3],
    /// Whether the inertia was given as three principal moments.
    pub principal: bool,
    /// The coordinates used as Euler angles (α, β, γ), as coordinate indices.
    pub angles: [usize; 3],
    /// The axes the three angles turn about (`sequence = "zxz"`, the notes').
    pub sequence: crate::euler::Sequence,
    /// The reference point in space, functions of (q, t).
    pub position: [ExprId; 3],
    /// The centre of mass relative to the reference point, body components (parameters).
    pub center_of_mass: [ExprId; 3],
    /// Where the body's table is.
    pub span: Range<usize>,
    /// Where its `inertia` is.
    pub inertia_span: Range<usize>,
}

/// The `[[bodies]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBody {
    name: Option<Spanned<String>>,
    mass: Option<Spanned<NumOrText>>,
    inertia: Spanned<toml::Value>,
    angles: Spanned<Vec<Spanned<String>>>,
    sequence: Option<Spanned<String>>,
    position: Option<Spanned<Vec<Spanned<NumOrText>>>>,
    center_of_mass: Option<Spanned<Vec<Spanned<NumOrText>>>>,
}

/// Reads every `[[bodies]]` table. `gravity` says whether the model has gravity
/// (bodies fall along −z, so particles of the same model need 3-D positions).
pub(crate) fn read_all(r: &mut Reader<'_>, raw: &[Spanned<RawBody>]) -> Result<Vec<Body>, ModelError> {
    let mut bodies: Vec<Body> = Vec::new();
    for (k, b) in raw.iter().enumerate() {
        let body = read(r, b, k)?;
        for other in &bodies {
            if let Some(&shared) = body.angles.iter().find(|a| other.angles.contains(a)) {
                let span = b.get_ref().angles.span();
                return Err(ModelError::at(
                    span,
                    format!(
                        "coordinate '{}' is already an Euler angle of body '{}'",
                        r.coordinates[shared].name, other.name
                    ),
                )
                .with_help("each body turns with its own three angles"));
            }
            if other.name == body.name {
                let span = b.get_ref().name.as_ref().map_or(b.span(), |n| n.span());
                return Err(ModelError::at(span, format!("two bodies are named '{}'", body.name)));
            }
        }
        bodies.push(body);
    }
    Ok(bodies)
}

fn read(r: &mut Reader<'_>, b: &Spanned<RawBody>, index: usize) -> Result<Body, ModelError> {
    let raw = b.get_ref();
    let name = match &raw.name {
        Some(n) => {
            crate::source::check_identifier(n, "body name")?;
            n.get_ref().clone()
        }
        None => format!("body{}", index + 1),
    };
    // A body file gives the mass, the centre of mass and the tensor at once.
    let file = match raw.inertia.get_ref() {
        toml::Value::String(s) if s.trim_end().ends_with(".toml") => {
            Some(load_body_file(r, s.trim_end(), raw.inertia.span())?)
        }
        _ => None,
    };
    let mass = match (&raw.mass, &file) {
        (Some(m), _) => r.num_or_expr(m, Scope::Parameters, "the body's mass")?,
        (None, Some(f)) => Located { expr: crate::source::number_expr(&mut r.pool, f.mass), span: raw.inertia.span() },
        (None, None) => {
            return Err(ModelError::at(b.span(), "the body has no `mass`").with_help(
                "give mass = \"M\" (a number or an expression in the parameters), or a body file as `inertia`",
            ))
        }
    };

    // Angles: three distinct coordinates.
    let angles_raw = raw.angles.get_ref();
    if angles_raw.len() != 3 {
        return Err(ModelError::at(
            raw.angles.span(),
            format!("`angles` names the three Euler angles (α, β, γ), not {}", angles_raw.len()),
        )
        .with_help("e.g. angles = [\"al\", \"be\", \"ga\"], each one of the model's coordinates"));
    }
    let mut angles = [0usize; 3];
    for (k, a) in angles_raw.iter().enumerate() {
        let Some(i) = r.coordinates.iter().position(|c| &c.name == a.get_ref()) else {
            return Err(ModelError::at(a.span(), format!("Euler angle '{}' is not a coordinate", a.get_ref()))
                .with_help("list it in `coordinates`"));
        };
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

    // Reference point and centre of mass: three components each.
    let three = |r: &mut Reader<'_>,
                 v: &Option<Spanned<Vec<Spanned<NumOrText>>>>,
                 scope: Scope,
                 what: &str|
     -> Result<[ExprId; 3], ModelError> {
        let Some(v) = v else { return Ok([r.pool.zero(); 3]) };
        if v.get_ref().len() != 3 {
            return Err(ModelError::at(
                v.span(),
                format!("a body's {what} has 3 components (x, y, z), not {}", v.get_ref().len()),
            )
            .with_help("rigid bodies live in three dimensions"));
        }
        let mut out = [r.pool.zero(); 3];
        for (k, x) in v.get_ref().iter().enumerate() {
            out[k] = r.num_or_expr(x, scope, &format!("the body's {what}"))?.expr;
        }
        Ok(out)
    };
    let position = three(r, &raw.position, Scope::Configuration, "position")?;
    let mut center_of_mass = three(r, &raw.center_of_mass, Scope::Parameters, "center_of_mass")?;
    let (inertia, principal) = match &file {
        Some(f) => {
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
            (tensor, diagonal)
        }
        None => read_inertia(r, &raw.inertia)?,
    };

    // Numeric sanity at the parameters' values: M > 0, I a physical tensor
    // (moments ≥ 0, each at most the sum of the other two). A zero moment (a
    // thin rod about its axis, a point mass) is allowed: only a singular
    // total mass matrix is refused, by the derivation, naming the coordinate.
    let values = |r: &Reader<'_>, e: ExprId| {
        let env = |n: &str| r.parameters.iter().find(|p| p.name == n).map(|p| p.value);
        r.pool.eval(e, &env).ok()
    };
    if let Some(m) = values(r, mass.expr) {
        if m.is_nan() || m <= 0.0 {
            return Err(ModelError::at(mass.span.clone(), format!("the body's mass must be positive, not {m}")));
        }
    }
    let mut num = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            num[i][j] = values(r, inertia[i][j]).unwrap_or(f64::NAN);
        }
    }
    if num.iter().flatten().all(|v| v.is_finite()) {
        if let Err(why) = physical(&num) {
            return Err(ModelError::at(
                raw.inertia.span(),
                format!("the inertia tensor {num:?} is not a rigid body's at the parameters' values: {why}"),
            )
            .with_help("principal moments are ≥ 0 and each is at most the sum of the other two (a thin rod has one zero moment)"));
        }
    }
    Ok(Body {
        name,
        mass: mass.expr,
        inertia,
        principal,
        angles,
        sequence,
        position,
        center_of_mass,
        span: b.span(),
        inertia_span: raw.inertia.span(),
    })
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
    let text = (r.files)(name)
        .map_err(|e| ModelError::at(span.clone(), format!("cannot read the body file '{name}': {e}")))?;
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

/// Leading principal minors all positive.
/// Whether `m` is a rigid body's inertia tensor: symmetric, its principal
/// moments ≥ 0 and each at most the sum of the other two (to rounding).
fn physical(m: &[[f64; 3]; 3]) -> Result<(), String> {
    let scale = m.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
    let tol = 1e-12 * scale;
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if (m[i][j] - m[j][i]).abs() > tol {
            return Err(format!("I{}{} ≠ I{}{}", i + 1, j + 1, j + 1, i + 1));
        }
    }
    let moments = nalgebra::Matrix3::from_fn(|i, j| m[i][j]).symmetric_eigenvalues();
    let (a, b, c) = (moments[0], moments[1], moments[2]);
    if let Some(&negative) = [a, b, c].iter().find(|&&x| x < -tol) {
        return Err(format!("a principal moment is negative ({negative})"));
    }
    if scale == 0.0 {
        return Ok(());
    }
    for (x, y, z) in [(a, b, c), (b, c, a), (c, a, b)] {
        if x > y + z + tol {
            return Err(format!("the principal moment {x} exceeds the sum of the other two ({y} + {z})"));
        }
    }
    Ok(())
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
