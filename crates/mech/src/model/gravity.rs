//! Uniform gravity: its two spellings in a model file, and the potential it
//! gives a point mass or a body's centre of mass.
//!
//! `gravity = "g"` (a number or an expression of the parameters) is the
//! strength of a field along −y for 2-D positions and −z for 3-D ones, as the
//! notes draw it: U = m g y (or m g z). `gravity = ["0", "-g", "0"]` is the
//! field vector itself, pointing wherever the model's axes want it (+x, −y in
//! 3-D, …): U = −m g·r, and every particle's position (and, with bodies, the
//! vector) has as many components as the vector.

use super::{Located, NumOrText, Reader, Scope};
use crate::error::ModelError;
use serde::Deserialize;
use std::ops::Range;
use sym::{ExprId, Pool};
use toml::Spanned;

/// A model's gravity (see the module documentation).
#[derive(Debug, Clone)]
pub enum Gravity {
    /// `gravity = "g"`: strength g along −y (2-D positions) or −z (3-D).
    Down(Located),
    /// `gravity = [gx, gy(, gz)]`: the field vector.
    Field {
        /// Its components, in the positions' axes.
        components: Vec<Located>,
        /// Where the vector is written.
        span: Range<usize>,
    },
}

impl Gravity {
    /// Where it is written.
    pub fn span(&self) -> Range<usize> {
        match self {
            Gravity::Down(g) => g.span.clone(),
            Gravity::Field { span, .. } => span.clone(),
        }
    }

    /// The potential of mass `m` at `r`: `m g r_last` for [`Gravity::Down`],
    /// `−m g·r` for a field (its zero components left out).
    pub fn potential(&self, pool: &mut Pool, m: ExprId, r: &[ExprId]) -> ExprId {
        match self {
            Gravity::Down(g) => pool.mul(&[m, g.expr, r[r.len() - 1]]),
            Gravity::Field { components, .. } => {
                let mut terms = Vec::with_capacity(components.len());
                for (g, &x) in components.iter().zip(r) {
                    if !pool.is_zero(g.expr) {
                        terms.push(pool.mul2(g.expr, x));
                    }
                }
                let dot = pool.add(&terms);
                let minus = pool.neg(m);
                pool.mul2(minus, dot)
            }
        }
    }

    /// The strength along −z of a field that points along −z (a top's, a
    /// body's on the notes' axes), as an expression and the sign to multiply
    /// its value by: `(g, 1)` for `Down`, `(g_z, −1)` for a field whose x and
    /// y components are zero; None for any other field.
    pub fn down_z(&self, pool: &Pool) -> Option<(ExprId, f64)> {
        match self {
            Gravity::Down(g) => Some((g.expr, 1.0)),
            Gravity::Field { components, .. } => match components.as_slice() {
                [x, y, z] if pool.is_zero(x.expr) && pool.is_zero(y.expr) => Some((z.expr, -1.0)),
                _ => None,
            },
        }
    }

    /// How many components positions must have: Some(n) for a field of n.
    pub fn dimension(&self) -> Option<usize> {
        match self {
            Gravity::Down(_) => None,
            Gravity::Field { components, .. } => Some(components.len()),
        }
    }
}

/// `gravity` as written: one value, or a list of them.
pub(crate) enum RawGravity {
    One(NumOrText),
    Field(Vec<Spanned<NumOrText>>),
}

impl<'de> Deserialize<'de> for RawGravity {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = RawGravity;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(
                    "a number or an expression string (g along −y or −z), or the field vector [gx, gy] or [gx, gy, gz]",
                )
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<RawGravity, E> {
                Ok(RawGravity::One(NumOrText::Num(v as f64)))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<RawGravity, E> {
                Ok(RawGravity::One(NumOrText::Num(v as f64)))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<RawGravity, E> {
                Ok(RawGravity::One(NumOrText::Num(v)))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<RawGravity, E> {
                Ok(RawGravity::One(NumOrText::Text(v.to_string())))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<RawGravity, A::Error> {
                let mut components = Vec::new();
                while let Some(c) = seq.next_element::<Spanned<NumOrText>>()? {
                    components.push(c);
                }
                Ok(RawGravity::Field(components))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// Reads `gravity` (its expressions in the parameters).
pub(crate) fn read(r: &mut Reader<'_>, raw: &Spanned<RawGravity>) -> Result<Gravity, ModelError> {
    match raw.get_ref() {
        RawGravity::One(v) => {
            let v = Spanned::new(raw.span(), v.clone());
            Ok(Gravity::Down(r.num_or_expr(&v, Scope::Parameters, "gravity")?))
        }
        RawGravity::Field(components) => {
            if !(2..=3).contains(&components.len()) {
                return Err(ModelError::at(
                    raw.span(),
                    format!("the gravity vector has 2 or 3 components, not {}", components.len()),
                )
                .with_help("gravity = \"g\" pulls along −y (2-D) or −z (3-D); gravity = [\"0\", \"-g\", \"0\"] is the field itself"));
            }
            let components = components
                .iter()
                .enumerate()
                .map(|(i, c)| r.num_or_expr(c, Scope::Parameters, &format!("component {} of gravity", i + 1)))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Gravity::Field { components, span: raw.span() })
        }
    }
}
