//! Extremal problem files: the TOML text of a calculus-of-variations problem
//! (`independent`, `unknown`, `integrand = f(y, y', x)`, `[parameters]`,
//! `[boundary] start/end`), read into expressions with every mistake located.
//!
//! Entry point: [`Problem::parse`].

use crate::error::ModelError;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use sym::{ExprId, ParseErrorKind, ParseOptions, Pool};
use toml::Spanned;

/// Names an extremal problem cannot use for its variables or parameters.
const RESERVED: &[&str] = &[
    "pi", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "ln", "sqrt",
    "abs",
];

/// A parsed extremal problem: find y(x) with y(x0) = y0, y(x1) = y1 that makes
/// `J[y] = ∫ f(y, y', x) dx` stationary.
#[derive(Debug, Clone)]
pub struct Problem {
    /// The arena of the problem's expressions.
    pub pool: Pool,
    /// The problem's name.
    pub name: String,
    /// The independent variable's name (`x`).
    pub independent: String,
    /// The unknown function's name (`y`).
    pub unknown: String,
    /// f(y, y', x).
    pub integrand: ExprId,
    /// Where the integrand's text is.
    pub integrand_span: Range<usize>,
    /// Parameters and their values (file order, after `--set`).
    pub parameters: Vec<(String, f64)>,
    /// (x0, y0).
    pub start: [f64; 2],
    /// (x1, y1).
    pub end: [f64; 2],
    /// The boundary values as written (expressions in the parameters): x0, y0, x1, y1.
    pub boundary_exprs: [ExprId; 4],
    /// Where `start` and `end` are.
    pub boundary_spans: [Range<usize>; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProblem {
    name: Option<String>,
    independent: Option<Spanned<String>>,
    unknown: Option<Spanned<String>>,
    integrand: Option<Spanned<String>>,
    #[serde(default)]
    parameters: BTreeMap<Spanned<String>, Spanned<f64>>,
    boundary: Option<Spanned<RawBoundary>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBoundary {
    start: Option<Spanned<Vec<Spanned<NumOrText>>>>,
    end: Option<Spanned<Vec<Spanned<NumOrText>>>>,
}

#[derive(Deserialize, Clone)]
#[serde(untagged)]
enum NumOrText {
    Num(f64),
    Text(String),
}

fn missing(key: &str, example: &str) -> ModelError {
    ModelError::at(0..0, format!("missing key `{key}`")).with_help(format!("add it, e.g. {example}"))
}

fn check_identifier(name: &Spanned<String>, what: &str) -> Result<(), ModelError> {
    crate::source::check_name_shape(name, what)?;
    let n = name.get_ref();
    if RESERVED.contains(&n.as_str()) {
        return Err(ModelError::at(name.span(), format!("{what} '{n}' uses a reserved name"))
            .with_help("pi is the constant; function names cannot be symbols"));
    }
    Ok(())
}

impl Problem {
    /// Reads a problem file's text. `overrides` are `--set name=value` pairs,
    /// applied to `[parameters]` (an unknown name is an error).
    pub fn parse(source: &str, overrides: &[(String, f64)]) -> Result<Problem, ModelError> {
        let raw: RawProblem = crate::source::read_toml(source, "problem")?;
        let independent = raw.independent.ok_or_else(|| missing("independent", "independent = \"x\""))?;
        let unknown = raw.unknown.ok_or_else(|| missing("unknown", "unknown = \"y\""))?;
        let integrand = raw.integrand.ok_or_else(|| missing("integrand", "integrand = \"sqrt(1 + y'^2)\""))?;
        let boundary = raw
            .boundary
            .ok_or_else(|| missing("boundary", "[boundary] with start = [0.0, 0.0] and end = [1.0, 1.0]"))?;
        check_identifier(&independent, "the independent variable")?;
        check_identifier(&unknown, "the unknown")?;
        if independent.get_ref() == unknown.get_ref() {
            return Err(ModelError::at(
                unknown.span(),
                format!("the unknown '{}' has the name of the independent variable", unknown.get_ref()),
            ));
        }

        let mut parameters: Vec<(String, f64)> = Vec::new();
        for (name, value) in &raw.parameters {
            check_identifier(name, "parameter")?;
            for var in [&independent, &unknown] {
                if name.get_ref() == var.get_ref() {
                    return Err(ModelError::at(
                        name.span(),
                        format!("parameter '{}' has the name of a variable of the problem", name.get_ref()),
                    ));
                }
            }
            if !value.get_ref().is_finite() {
                return Err(ModelError::at(value.span(), format!("parameter '{}' must be finite", name.get_ref())));
            }
            parameters.push((name.get_ref().clone(), *value.get_ref()));
        }
        for (name, value) in overrides {
            match parameters.iter_mut().find(|(n, _)| n == name) {
                Some(p) => p.1 = crate::error::finite_override(name, *value)?,
                None => {
                    return Err(ModelError::setting(
                        crate::error::Setting::Parameter { name: name.clone() },
                        format!("the problem has no parameter '{name}'"),
                    )
                    .with_help(format!(
                        "its parameters are: {}",
                        parameters.iter().map(|p| p.0.as_str()).collect::<Vec<_>>().join(", ")
                    )))
                }
            }
        }

        let mut pool = Pool::default();
        for (name, _) in &parameters {
            pool.set_rank(name, crate::source::RANK_PARAMETER);
        }
        pool.set_rank(independent.get_ref(), crate::source::RANK_TIME);
        pool.set_rank(unknown.get_ref(), crate::source::RANK_COORDINATE);
        let names = Names { x: independent.get_ref(), y: unknown.get_ref(), parameters: &parameters };
        let f = names.expr(&mut pool, source, integrand.get_ref(), integrand.span(), true, "the integrand")?;

        let mut exprs = Vec::new();
        let mut spans = Vec::new();
        for (key, point) in [("start", &boundary.get_ref().start), ("end", &boundary.get_ref().end)] {
            let Some(point) = point else {
                return Err(ModelError::at(boundary.span(), format!("[boundary] is missing `{key}`"))
                    .with_help(format!("add {key} = [x, y]")));
            };
            if point.get_ref().len() != 2 {
                return Err(ModelError::at(
                    point.span(),
                    format!("`{key}` must be a point [x, y], found {} values", point.get_ref().len()),
                ));
            }
            for v in point.get_ref() {
                let what = format!("the boundary `{key}`");
                let e = match v.get_ref() {
                    NumOrText::Num(x) if x.is_finite() => pool.float(*x),
                    NumOrText::Num(_) => return Err(ModelError::at(v.span(), format!("{what} must be finite"))),
                    NumOrText::Text(s) => names.expr(&mut pool, source, s, v.span(), false, &what)?,
                };
                exprs.push((e, v.span()));
            }
            spans.push(point.span());
        }
        let env = |name: &str| parameters.iter().find(|p| p.0 == name).map(|p| p.1);
        let mut values = [0.0; 4];
        for (k, (e, span)) in exprs.iter().enumerate() {
            let v = pool.eval(*e, &env).map_err(|err| ModelError::at(span.clone(), err.to_string()))?;
            if !v.is_finite() {
                return Err(ModelError::at(span.clone(), format!("this boundary value is not finite ({v})")));
            }
            values[k] = v;
        }
        if values[0] >= values[2] {
            return Err(ModelError::at(
                spans[1].clone(),
                format!(
                    "the end's {x} = {} must be greater than the start's {x} = {}",
                    values[2],
                    values[0],
                    x = independent.get_ref()
                ),
            )
            .with_help("give start = [x0, y0] and end = [x1, y1] with x0 < x1"));
        }
        Ok(Problem {
            pool,
            name: raw.name.unwrap_or_else(|| "extremal".into()),
            independent: independent.get_ref().clone(),
            unknown: unknown.get_ref().clone(),
            integrand: f,
            integrand_span: integrand.span(),
            parameters,
            start: [values[0], values[1]],
            end: [values[2], values[3]],
            boundary_exprs: [exprs[0].0, exprs[1].0, exprs[2].0, exprs[3].0],
            boundary_spans: [spans[0].clone(), spans[1].clone()],
        })
    }
}

/// The names a problem declares, for parsing its expressions.
struct Names<'a> {
    x: &'a str,
    y: &'a str,
    parameters: &'a [(String, f64)],
}

impl Names<'_> {
    /// Parses an expression: the integrand (`state`: x, y, y' and parameters) or
    /// a boundary value (parameters only).
    fn expr(
        &self,
        pool: &mut Pool,
        source: &str,
        text: &str,
        span: Range<usize>,
        state: bool,
        what: &str,
    ) -> Result<ExprId, ModelError> {
        let known = |name: &str, order: u8| -> bool {
            if self.parameters.iter().any(|p| p.0 == name) {
                return order == 0;
            }
            state && ((name == self.x && order == 0) || (name == self.y && order <= 1))
        };
        let opts = ParseOptions::default().with_known(&known);
        pool.parse_with(text, &opts).map_err(|err| {
            let at = match crate::source::content_offset(source, &span, text) {
                Some(o) => (o + err.span.start as usize)..(o + (err.span.end as usize).max(err.span.start as usize + 1)),
                None => span.clone(),
            };
            let mut message = format!("in {what}: {err}");
            let mut help = None;
            if let ParseErrorKind::UnknownName { name } = &err.kind {
                let base = name.trim_end_matches('\'');
                let primes = name.len() - base.len();
                let scope = if state {
                    format!("{y}, {y}', {x} and the parameters", x = self.x, y = self.y)
                } else {
                    "numbers and the parameters".to_string()
                };
                if base == self.y || base == self.x {
                    message = format!("in {what}: '{name}' is not allowed here");
                    help = Some(if state && base == self.y && primes >= 2 {
                        format!("the integrand is f({y}, {y}', {x}); {y}'' would make the Euler equation of fourth order, which is not supported", x = self.x, y = self.y)
                    } else {
                        format!("{what} may use {scope}")
                    });
                } else if self.parameters.iter().any(|p| p.0 == base) {
                    message = format!("in {what}: parameter '{base}' cannot be differentiated");
                } else {
                    help = Some(format!("{what} may use {scope}; declare '{base}' under [parameters]"));
                }
            }
            let mut e = ModelError::at(at, message);
            e.help = help;
            e
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[track_caller]
    fn check_err(text: &str, needle: &str, at: &str) {
        let e = Problem::parse(text, &[]).unwrap_err();
        assert!(e.message.contains(needle), "{}", e.message);
        let span = e.span.expect("located");
        assert!(text[span.start..].starts_with(at), "span at {:?}", &text[span.start..]);
    }

    const HEAD: &str = "independent = \"x\"\nunknown = \"y\"\n";

    #[test]
    fn errors_are_located() {
        check_err(
            &format!("{HEAD}integrand = \"sqrt(1 + y''^2)\"\n[boundary]\nstart = [0, 0]\nend = [1, 1]\n"),
            "not allowed",
            "y''",
        );
        check_err(&format!("{HEAD}integrand = \"k*y'^2\"\n[boundary]\nstart = [0, 0]\nend = [1, 1]\n"), "k", "k");
        check_err(
            &format!("{HEAD}integrand = \"y'^2\"\n[boundary]\nstart = [1, 0]\nend = [1, 1]\n"),
            "greater",
            "[1, 1]",
        );
        check_err(&format!("{HEAD}integrand = \"y'^2\"\n[boundary]\nstart = [0, 0]\n"), "missing `end`", "[boundary]");
        check_err(&format!("{HEAD}[boundary]\nstart = [0, 0]\nend = [1, 1]\n"), "integrand", "");
    }

    #[test]
    fn boundary_values_may_be_expressions() {
        let p = Problem::parse(
            &format!("{HEAD}integrand = \"y'^2\"\n[parameters]\nL = 2.0\n[boundary]\nstart = [0, 0]\nend = [\"L/2\", \"pi\"]\n"),
            &[("L".into(), 4.0)],
        )
        .unwrap();
        assert_eq!(p.end, [2.0, std::f64::consts::PI]);
    }
}
