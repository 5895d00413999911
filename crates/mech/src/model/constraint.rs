//! The `[[constraints]]` tables of a model file, read into specifications:
//! a name, holonomic or velocity, and the expression. What a derivation makes
//! of them is in [`crate::derive`].
//!
//! A table may instead say that a body rolls without slipping on the ground,
//! the plane z = 0 (`rolling = "wheel"`, `radius = "R"`, optional `axle`): a
//! wheel is a disc about its axle e, touching the ground at P = C + R d with
//! d = (−ẑ + (ẑ·e) e)/√(1 − (ẑ·e)²), the lowest point of its rim. Rolling makes
//! the velocity of the wheel's material point at P vanish, v_C + ω × (P − C) = 0:
//! its horizontal components are two velocity constraints `NAME_x`, `NAME_y`
//! (one that vanishes whatever the motion constrains nothing and is left out).
//! A wheel lying flat (e vertical) has no such point: refused when its axle is
//! vertical whatever the coordinates, and at a run's start (`model/check.rs`).
//! With `contact = "constraint"` the contact itself, P_z = 0, is a holonomic
//! constraint `NAME_z` too (the default, `"kept"`, leaves it to the wheel's
//! position, as a centre at height R sin θ keeps a leaning disc on the ground).

use crate::error::{ModelError, ModelErrorKind};
use crate::model::check::{CheckKind, ValueCheck};
use crate::model::{Body, Located, NumOrText, Orientation, Reader, Scope};
use crate::probe;
use serde::Deserialize;
use std::ops::Range;
use sym::{ExprId, Pool};
use toml::Spanned;

/// A `[[constraints]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawConstraint {
    name: Option<Spanned<String>>,
    holonomic: Option<Spanned<String>>,
    velocity: Option<Spanned<String>>,
    rolling: Option<Spanned<String>>,
    radius: Option<Spanned<NumOrText>>,
    axle: Option<Spanned<String>>,
    contact: Option<Spanned<String>>,
}

impl RawConstraint {
    /// Whether the table is a rolling contact (`rolling = "body"`).
    pub(crate) fn is_rolling(&self) -> bool {
        self.rolling.is_some()
    }
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
    for (key, extra) in [("radius", c.radius.as_ref().map(|x| x.span())), ("axle", c.axle.as_ref().map(|x| x.span()))]
        .into_iter()
        .chain([("contact", c.contact.as_ref().map(|x| x.span()))])
    {
        if let Some(span) = extra {
            return Err(ModelError::at(span, format!("`{key}` belongs to a rolling contact"))
                .with_help("add rolling = \"body\" (the wheel), or leave it out"));
        }
    }
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

/// Reads a rolling contact (`rolling = "wheel"`) into its constraints: two
/// velocity constraints, and a holonomic one with `contact = "constraint"`.
pub(crate) fn read_rolling(
    r: &mut Reader<'_>,
    raw: &Spanned<RawConstraint>,
    index: usize,
    previous: &[ConstraintSpec],
    bodies: &[Body],
) -> Result<Vec<ConstraintSpec>, ModelError> {
    let c = raw.get_ref();
    let wheel = c.rolling.as_ref().expect("a rolling table");
    if let Some(x) = c.holonomic.as_ref().or(c.velocity.as_ref()) {
        return Err(ModelError::at(x.span(), "a rolling contact makes its own constraints")
            .with_help("give `holonomic` or `velocity` in a table of its own"));
    }
    let (name, name_span) = match &c.name {
        Some(n) => {
            crate::source::check_identifier(n, "constraint")?;
            (n.get_ref().clone(), n.span())
        }
        None => (format!("c{}", index + 1), raw.span()),
    };
    let Some(b) = bodies.iter().position(|b| &b.name == wheel.get_ref()) else {
        let known: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
        return Err(ModelError::at(wheel.span(), format!("'{}' is not a body of the model", wheel.get_ref()))
            .with_help(if known.is_empty() {
                "a rolling contact names one of the [[bodies]], the wheel".to_string()
            } else {
                format!("its bodies are: {}", known.join(", "))
            }));
    };
    if bodies[b].dimension != 3 {
        return Err(ModelError::at(wheel.span(), "a wheel rolls on the ground z = 0 of a model in 3-D")
            .with_help("write the bodies' vectors with 3 components"));
    }
    let Some(radius) = &c.radius else {
        return Err(ModelError::at(raw.span(), "the rolling contact has no `radius`")
            .with_help("radius = \"R\", the wheel's, a number or an expression in the parameters"));
    };
    let radius = r.num_or_expr(radius, Scope::Parameters, "the wheel's radius")?.expr;
    let zero = r.pool.zero();
    let one = r.pool.one();
    // The axle in body components.
    let unit = |k: usize| -> [ExprId; 3] { std::array::from_fn(|i| if i == k { one } else { zero }) };
    let axle = match (&c.axle, bodies[b].orientation) {
        (Some(a), _) => match a.get_ref().as_str() {
            "x" => unit(0),
            "y" => unit(1),
            "z" => unit(2),
            other => {
                return Err(ModelError::at(a.span(), format!("'{other}' is not a body axis"))
                    .with_help("axle = \"x\", \"y\" or \"z\", the wheel's axis of symmetry in its own axes"))
            }
        },
        (None, Orientation::Planar { axis, .. }) => unit(axis),
        (None, Orientation::Hinge { axis, .. }) => axis,
        (None, Orientation::Euler { sequence, .. }) => unit(sequence.0[2]),
        (None, Orientation::Fixed) => {
            return Err(ModelError::at(wheel.span(), "the wheel has no angle of its own to spin with")
                .with_help("give it angle = \"..\" about its axle, or say axle = \"x\", \"y\" or \"z\""))
        }
    };
    let keep = match &c.contact {
        None => false,
        Some(k) => match k.get_ref().as_str() {
            "kept" => false,
            "constraint" => true,
            other => {
                return Err(ModelError::at(k.span(), format!("'{other}' is not a kind of contact")).with_help(
                    "contact = \"kept\" (default: the wheel's position keeps it on the ground) or \"constraint\"",
                ))
            }
        },
    };
    let names: Vec<String> = r.coordinates.iter().map(|c| c.name.clone()).collect();
    let q: Vec<ExprId> = names.iter().map(|n| r.pool.var(n, 0)).collect();
    let qd: Vec<ExprId> = names.iter().map(|n| r.pool.var(n, 1)).collect();
    let t = r.pool.symbol("t");
    let frames = crate::model::frames::frames(&mut r.pool, bodies, &q, &qd);
    let frame = &frames[b];
    let (v, height, tilt) = contact_velocity(&mut r.pool, frame, axle, radius, &q, &qd, t);
    let span = wheel.span();
    // The contact point divides by √(1 − e_z²): a wheel lying flat (axle
    // vertical) has no lowest rim point, whatever its motion (refused here) or
    // at the start (refused when a run starts, `model/check.rs`).
    if probe::decide_zero(&mut r.pool, tilt) == probe::Decision::Zero {
        return Err(ModelError::at(
            span,
            format!("the wheel '{}' lies flat whatever the coordinates (its axle is identically vertical): its rim has no lowest point to roll on", wheel.get_ref()),
        )
        .with_help("a rolling wheel's axle (axle = \"x\", \"y\" or \"z\", in its own axes) is horizontal or leaning, not along the ground's normal z"));
    }
    r.check(ValueCheck { kind: CheckKind::Axle { name: name.clone(), tilt }, span: span.clone() })?;
    let mut out = Vec::new();
    let mut parts = vec![("x", ConstraintKind::Velocity, v[0]), ("y", ConstraintKind::Velocity, v[1])];
    if keep {
        parts.push(("z", ConstraintKind::Holonomic, height));
    }
    // A component that vanishes whatever the motion (a wheel rolling along y
    // about an axle along x never slips along x) constrains nothing: left out.
    parts.retain(|&(_, _, expr)| probe::decide_zero(&mut r.pool, expr) != probe::Decision::Zero);
    if parts.is_empty() {
        return Err(ModelError::at(
            span,
            "the rolling contact constrains nothing: the contact point's velocity is identically 0",
        )
        .with_help("the wheel's motion already keeps it from slipping; leave the rolling contact out")
        .with_kind(ModelErrorKind::DoesNothing));
    }
    for (axis, kind, expr) in parts {
        let full = format!("{name}_{axis}");
        if previous.iter().chain(&out).any(|p: &ConstraintSpec| p.name == full) {
            return Err(ModelError::at(name_span, format!("constraint '{full}' is named twice"))
                .with_help("a rolling contact NAME makes NAME_x and NAME_y (and NAME_z); give it a name of its own"));
        }
        out.push(ConstraintSpec {
            name: full,
            name_span: name_span.clone(),
            kind,
            expr: Located { expr, span: span.clone() },
        });
    }
    Ok(out)
}

/// The velocity of the wheel's material point at the contact (space
/// components), the contact's height P_z, and 1 − e_z² (e the axle in space).
fn contact_velocity(
    pool: &mut Pool,
    frame: &crate::model::frames::Frame,
    axle: [ExprId; 3],
    radius: ExprId,
    q: &[ExprId],
    qd: &[ExprId],
    t: ExprId,
) -> ([ExprId; 3], ExprId, ExprId) {
    let e = crate::model::frames::to_space(pool, &frame.d, &axle);
    let omega = crate::model::frames::to_space(pool, &frame.d, &frame.omega);
    // s = √(1 − e_z²); R d = R (e_z e_x / s, e_z e_y / s, −s).
    let one = pool.one();
    let ez2 = pool.powi(e[2], 2);
    let rest = pool.sub(one, ez2);
    let s = pool.sqrt(rest);
    let rd: [ExprId; 3] = [
        {
            let x = pool.mul(&[radius, e[2], e[0]]);
            pool.div(x, s)
        },
        {
            let y = pool.mul(&[radius, e[2], e[1]]);
            pool.div(y, s)
        },
        {
            let z = pool.mul2(radius, s);
            pool.neg(z)
        },
    ];
    let v_c = crate::model::frames::velocity(pool, &frame.origin, q, qd, t);
    let v: [ExprId; 3] = std::array::from_fn(|i| {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let a = pool.mul2(omega[j], rd[k]);
        let b = pool.mul2(omega[k], rd[j]);
        let cross = pool.sub(a, b);
        pool.add2(v_c[i], cross)
    });
    let height = pool.add2(frame.origin[2], rd[2]);
    (v, height, rest)
}
