//! Loads (`[[loads]]`): a force acting at a point, or a torque acting on a
//! body, as an engineer states them, instead of generalized forces projected
//! by hand. `derive/load.rs` turns them into generalized forces by virtual
//! work: `Q_j = F·∂r/∂q_j` for a force at r, `Q_j = τ·∂ω/∂q'_j` for a torque.
//!
//! ```toml
//! [[loads]]                          # a force at a point given in space
//! force = ["0", "-F"]
//! at = ["l*sin(th)", "-l*cos(th)"]
//!
//! [[loads]]                          # at a point of a body, in its axes
//! body = "rod"
//! at = ["0", "-l"]                   # relative to its reference point (default: the point itself)
//! force = ["P", "0"]
//! axes = "body"                      # the force's components: "space" (default) or "body"
//!
//! [[loads]]                          # a torque on a body
//! body = "rod"
//! torque = "tau"                     # planar: about z; else ["tx", "ty", "tz"]
//! ```
//!
//! Forces and torques are expressions of the coordinates, velocities, time,
//! parameters and inputs; points are expressions of the coordinates and time.

use super::{Body, NumOrText, Reader, Scope};
use crate::error::{ModelError, ModelErrorKind};
use serde::Deserialize;
use std::ops::Range;
use sym::ExprId;
use toml::Spanned;

/// What a load is.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadKind {
    /// A force applied at a point: in space, or (with a body) relative to the
    /// body's reference point in its axes.
    Force {
        /// The point, 3 components (a planar model's third is 0).
        at: [ExprId; 3],
    },
    /// A torque on a body.
    Torque,
}

/// One `[[loads]]` table.
#[derive(Debug, Clone)]
pub struct Load {
    /// A force at a point, or a torque.
    pub kind: LoadKind,
    /// The body it acts on (an index into the model's bodies).
    pub body: Option<usize>,
    /// The force or torque, 3 components (a planar model's force has z = 0,
    /// its torque x = y = 0).
    pub vector: [ExprId; 3],
    /// Whether the components are along the body's axes (else space's).
    pub body_axes: bool,
    /// Where the table is.
    pub span: Range<usize>,
}

/// `[[loads]]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLoad {
    force: Option<Spanned<Vec<Spanned<NumOrText>>>>,
    torque: Option<Spanned<toml::Value>>,
    at: Option<Spanned<Vec<Spanned<NumOrText>>>>,
    body: Option<Spanned<String>>,
    axes: Option<Spanned<String>>,
}

/// Reads every `[[loads]]` table; `dimension` is the positions' (2 for a planar model, else 3).
pub(crate) fn read_all(
    r: &mut Reader<'_>,
    raw: &[Spanned<RawLoad>],
    bodies: &[Body],
    dimension: usize,
) -> Result<Vec<Load>, ModelError> {
    let names: Vec<String> = r.coordinates.iter().map(|c| c.name.clone()).collect();
    let q: Vec<ExprId> = names.iter().map(|n| r.pool.var(n, 0)).collect();
    let qd: Vec<ExprId> = names.iter().map(|n| r.pool.var(n, 1)).collect();
    let frames = super::frames::frames(&mut r.pool, bodies, &q, &qd);
    let mut out = Vec::with_capacity(raw.len());
    for l in raw {
        let load = read(r, l, bodies, dimension)?;
        if let LoadKind::Force { at } = load.kind {
            // Virtual work F·∂r/∂q: a force at a point that no coordinate moves
            // would vanish from the equations.
            let point = match load.body {
                None => at,
                Some(b) => {
                    let rel = super::frames::to_space(&mut r.pool, &frames[b].d, &at);
                    std::array::from_fn(|i| r.pool.add2(frames[b].origin[i], rel[i]))
                }
            };
            if point.iter().all(|&x| q.iter().all(|&c| r.pool.free_of(x, c))) {
                let table = l.get_ref();
                let span =
                    table.at.as_ref().map(|a| a.span()).or(table.body.as_ref().map(|b| b.span())).unwrap_or(l.span());
                return Err(ModelError::at(span, "the force acts at a point that no coordinate moves, so it does nothing")
                    .with_help("a force enters the equations through F·∂r/∂q: give a point that moves with the coordinates (`at`, or a `body` that moves)")
                    .with_kind(ModelErrorKind::DoesNothing));
            }
        }
        out.push(load);
    }
    Ok(out)
}

fn read(r: &mut Reader<'_>, l: &Spanned<RawLoad>, bodies: &[Body], dimension: usize) -> Result<Load, ModelError> {
    let raw = l.get_ref();
    let body = match &raw.body {
        None => None,
        Some(name) => Some(bodies.iter().position(|b| &b.name == name.get_ref()).ok_or_else(|| {
            let known: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
            ModelError::at(
                name.span(),
                format!("the load names body '{}', which the model does not have", name.get_ref()),
            )
            .with_help(if known.is_empty() {
                "the model has no [[bodies]]".to_string()
            } else {
                format!("its bodies are: {}", known.join(", "))
            })
        })?),
    };
    let body_axes = match &raw.axes {
        None => false,
        Some(a) => match a.get_ref().as_str() {
            "space" => false,
            "body" if body.is_some() => true,
            "body" => {
                return Err(ModelError::at(a.span(), "components along a body's axes need the load's `body`")
                    .with_help("add body = \"name\", or leave `axes` out for space components"))
            }
            other => {
                return Err(ModelError::at(a.span(), format!("'{other}' is not a set of axes"))
                    .with_help("axes = \"space\" (default) or \"body\""))
            }
        },
    };
    let zero = r.pool.zero();
    match (&raw.force, &raw.torque) {
        (Some(_), Some(t)) => Err(ModelError::at(t.span(), "a load is a force or a torque, not both")
            .with_help("give each its own [[loads]] table")),
        (None, None) => Err(ModelError::at(l.span(), "the load has no `force` and no `torque`")
            .with_help("force = [\"Fx\", \"Fy\"] with `at`, or torque = \"tau\" with `body`")),
        (Some(force), None) => {
            let n = force.get_ref().len();
            let fits = if bodies.is_empty() { (1..=3).contains(&n) } else { n == dimension };
            if !fits {
                let want = if bodies.is_empty() { "1, 2 or 3".to_string() } else { dimension.to_string() };
                return Err(ModelError::at(force.span(), format!("the force has {n} components, not {want}"))
                    .with_help("as many as the model's positions"));
            }
            let vector = components(r, force, Scope::Driven, "the force")?;
            let at = match (&raw.at, body) {
                (Some(at), _) => {
                    if at.get_ref().len() != n {
                        return Err(ModelError::at(
                            at.span(),
                            format!("the point has {} components and the force {n}", at.get_ref().len()),
                        ));
                    }
                    components(r, at, Scope::Configuration, "the point the force acts at")?
                }
                (None, Some(_)) => [zero; 3],
                (None, None) => return Err(ModelError::at(force.span(), "the force has no point to act at")
                    .with_help(
                    "give at = [..] (in space), or body = \"name\" (at its reference point, or at = [..] in its axes)",
                )),
            };
            Ok(Load { kind: LoadKind::Force { at }, body, vector, body_axes, span: l.span() })
        }
        (None, Some(torque)) => {
            if body.is_none() {
                return Err(ModelError::at(torque.span(), "a torque acts on a body: the load has no `body`")
                    .with_help("add body = \"name\""));
            }
            if let Some(at) = &raw.at {
                return Err(ModelError::at(at.span(), "a torque acts on the whole body, not at a point")
                    .with_help("leave `at` out; a force at a point takes `force`"));
            }
            // A torque does work only through the body's angular velocity: on a
            // body with no angle up its tree it would vanish from the equations.
            if let Some(b) = body.filter(|&b| !turns(bodies, b)) {
                return Err(ModelError::at(
                    torque.span(),
                    format!("body '{}' does not turn (no angle of its own or of a parent), so a torque on it does nothing", bodies[b].name),
                )
                .with_help("a torque acts on a body with `angle` or `angles` (or a parent that has them); a force at a point takes `force` and `at`")
                .with_kind(ModelErrorKind::DoesNothing));
            }
            let vector = match torque.get_ref() {
                toml::Value::Array(_) if dimension == 2 => {
                    return Err(ModelError::at(
                        torque.span(),
                        "a planar model's torque is one value, about z, not a list",
                    )
                    .with_help(
                        "write torque = \"tau\": its bodies turn about z only, so x and y components would do nothing",
                    ));
                }
                toml::Value::Array(_) => {
                    let list: Spanned<Vec<Spanned<NumOrText>>> = torque_list(torque)?;
                    if list.get_ref().len() != 3 {
                        return Err(ModelError::at(
                            torque.span(),
                            format!("the torque has {} components, not 3", list.get_ref().len()),
                        )
                        .with_help("[\"tx\", \"ty\", \"tz\"], or one value about z in a planar model"));
                    }
                    components(r, &list, Scope::Driven, "the torque")?
                }
                one => {
                    if dimension != 2 {
                        return Err(ModelError::at(torque.span(), "one torque value is about z of a planar model")
                            .with_help("in 3-D give its three components [\"tx\", \"ty\", \"tz\"]"));
                    }
                    let value = match one {
                        toml::Value::String(s) => NumOrText::Text(s.clone()),
                        toml::Value::Integer(i) => NumOrText::Num(*i as f64),
                        toml::Value::Float(f) => NumOrText::Num(*f),
                        _ => {
                            return Err(ModelError::at(
                                torque.span(),
                                "the torque is a number, an expression or a list",
                            ))
                        }
                    };
                    let tz = r.num_or_expr(&Spanned::new(torque.span(), value), Scope::Driven, "the torque")?.expr;
                    [zero, zero, tz]
                }
            };
            Ok(Load { kind: LoadKind::Torque, body, vector, body_axes, span: l.span() })
        }
    }
}

/// Whether body `b` turns: it or a body up its tree has an angle.
fn turns(bodies: &[Body], b: usize) -> bool {
    let mut at = Some(b);
    while let Some(k) = at {
        if !bodies[k].orientation.angles().is_empty() {
            return true;
        }
        at = bodies[k].parent;
    }
    false
}

/// A torque written as a list, its entries located by searching its text.
fn torque_list(torque: &Spanned<toml::Value>) -> Result<Spanned<Vec<Spanned<NumOrText>>>, ModelError> {
    let toml::Value::Array(items) = torque.get_ref() else { unreachable!("called on arrays") };
    let mut out = Vec::with_capacity(items.len());
    for x in items {
        let v = match x {
            toml::Value::String(s) => NumOrText::Text(s.clone()),
            toml::Value::Integer(i) => NumOrText::Num(*i as f64),
            toml::Value::Float(f) => NumOrText::Num(*f),
            _ => return Err(ModelError::at(torque.span(), "a torque component is a number or an expression string")),
        };
        out.push(Spanned::new(torque.span(), v));
    }
    Ok(Spanned::new(torque.span(), out))
}

/// Up to three components, the rest zero.
fn components(
    r: &mut Reader<'_>,
    v: &Spanned<Vec<Spanned<NumOrText>>>,
    scope: Scope,
    what: &str,
) -> Result<[ExprId; 3], ModelError> {
    let mut out = [r.pool.zero(); 3];
    for (k, x) in v.get_ref().iter().enumerate() {
        out[k] = r.num_or_expr(x, scope, &format!("component {} of {what}", k + 1))?.expr;
    }
    Ok(out)
}
