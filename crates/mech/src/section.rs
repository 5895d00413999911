//! Poincaré sections: the points where a run crosses a surface g(q, q', t) = 0
//! one way, seen in a plane of two quantities.
//!
//! A section is a crossing condition ([`StopCondition`]) that counts only one
//! way: `x = 0` and `x > 0` count where x − 0 increases through zero, `x < 0`
//! where it decreases. The run locates each crossing as it locates every
//! crossing (root finding on the dense output, then on the method's own
//! states), so a point lies on the surface to round-off. The plane's axes are
//! two expressions of the state; `p_NAME` is the momentum ∂L/∂NAME' where the
//! model has no name `p_NAME`. Without axes, the plane is the first coordinate
//! the condition does not mention and its momentum: (y, p_y) for a section at
//! x = 0, the canonical pair, in which the section map keeps areas.

use crate::derive::{Derivation, Layout};
use crate::error::ModelError;
use crate::run::{Row, StopCondition};
use num::Direction;
use rustc_hash::FxHashMap;
use sym::{ExprId, Tape};

/// A Poincaré section: its condition, and the plane its points are drawn in.
#[derive(Debug, Clone)]
pub struct Section {
    condition: StopCondition,
    axes: [String; 2],
    /// The two axes, compiled over the derivation's [`Layout`].
    tape: Tape,
    layout: Layout,
    values: Vec<f64>,
}

impl Section {
    /// The section of `condition` (read as a crossing: a condition with `=`
    /// counts rising), drawn in the plane of `axes` ("A, B", two expressions
    /// of the state separated by a comma outside parentheses), or in the
    /// default plane (see the module documentation). Errors are about `axes`:
    /// their spans are byte offsets into it.
    pub fn new(d: &Derivation, mut condition: StopCondition, axes: Option<&str>) -> Result<Section, ModelError> {
        if condition.direction == Direction::Both {
            condition.direction = Direction::Rising;
        }
        let mut model = d.model.clone();
        let (names, exprs) = match axes {
            Some(text) => {
                let parts = split_top_level(text);
                if parts.len() != 2 {
                    return Err(ModelError::at(
                        0..text.len(),
                        format!(
                            "the section's plane needs two axes separated by a comma, such as \"y, p_y\", not {} part{}",
                            parts.len(),
                            if parts.len() == 1 { "" } else { "s" }
                        ),
                    ));
                }
                // p_NAME reads as a parameter of the model's copy, then becomes the momentum.
                let stand_ins = momenta_as_parameters(d, &mut model);
                let mut names = Vec::new();
                let mut exprs = Vec::new();
                for span in parts {
                    let raw = &text[span.clone()];
                    let lead = raw.len() - raw.trim_start().len();
                    let part = raw.trim();
                    if part.is_empty() {
                        return Err(ModelError::at(span, "an axis of the section's plane is empty"));
                    }
                    let expr = model.parse_state_expr(part, "an axis of the section's plane").map_err(|mut e| {
                        if let Some(s) = &mut e.span {
                            let start = span.start + lead;
                            *s = s.start + start..s.end + start;
                        }
                        let momenta: Vec<String> = d.coordinate_names().iter().map(|c| format!("p_{c}")).collect();
                        let help = e.help.take().map_or(String::new(), |h| format!("{h}; "));
                        e.with_help(format!("{help}the momenta ∂L/∂q' are {}", momenta.join(", ")))
                    })?;
                    names.push(part.to_string());
                    exprs.push(model.pool.substitute(expr, &stand_ins));
                }
                ([names[0].clone(), names[1].clone()], exprs)
            }
            None => {
                let mentioned = identifiers(&condition.text);
                let coordinates = d.coordinate_names();
                let k = coordinates.iter().position(|c| !mentioned.contains(c)).unwrap_or(0);
                let name = coordinates[k].to_string();
                ([name.clone(), format!("p_{name}")], vec![d.q[k], d.momenta[k]])
            }
        };
        let tape = Tape::compile(&model.pool, &exprs, d.layout.symbols())
            .map_err(|e| ModelError::whole(format!("the section's plane cannot be evaluated: {e}")))?;
        Ok(Section { condition, axes: names, tape, layout: d.layout.clone(), values: d.layout.values() })
    }

    /// The crossing condition, one-sided: what the run is given to locate.
    pub fn condition(&self) -> &StopCondition {
        &self.condition
    }

    /// The names of the plane's two axes, as written (or chosen).
    pub fn axes(&self) -> &[String; 2] {
        &self.axes
    }

    /// Whether a row of the run is a point of the section.
    pub fn takes(&self, row: &Row<'_>) -> bool {
        row.event == Some(self.condition.text.as_str())
    }

    /// The point of the plane at the state (t, q, q').
    pub fn point(&mut self, t: f64, q: &[f64], qd: &[f64]) -> [f64; 2] {
        self.layout.set_state(&mut self.values, t, q, qd);
        let mut out = [0.0; 2];
        self.tape.eval(&self.values, &mut out);
        out
    }
}

/// Declares `p_NAME` for every coordinate NAME as a parameter of `model` (a
/// copy of the derivation's), where no name of the model is `p_NAME`; the map
/// takes each such parameter's symbol to the momentum ∂L/∂NAME'.
fn momenta_as_parameters(d: &Derivation, model: &mut crate::Model) -> FxHashMap<ExprId, ExprId> {
    let mut map = FxHashMap::default();
    for (k, c) in d.coordinate_names().iter().enumerate() {
        let name = format!("p_{c}");
        let taken = model.parameters.iter().any(|p| p.name == name) || model.coordinates.iter().any(|c| c.name == name);
        if !taken {
            model.parameters.push(crate::Parameter { name: name.clone(), value: 0.0, span: 0..0 });
            map.insert(model.pool.symbol(&name), d.momenta[k]);
        }
    }
    map
}

/// The byte ranges of `text` between commas outside parentheses.
fn split_top_level(text: &str) -> Vec<std::ops::Range<usize>> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in text.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(start..i);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(start..text.len());
    parts
}

/// The identifiers in an expression's text (`x'` gives `x`).
fn identifiers(text: &str) -> Vec<&str> {
    text.split(|c: char| !(c.is_alphanumeric() || c == '_')).filter(|s| !s.is_empty()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;

    fn henon_heiles() -> Derivation {
        let text = r#"
name = "Henon-Heiles"
coordinates = ["x", "y"]
kinetic = "(x'^2 + y'^2)/2"
potential = "(x^2 + y^2)/2 + x^2*y - y^3/3"
[initial]
x = 0
y = 0.1
"x'" = 0.3
"y'" = 0.2
"#;
        Derivation::new(Model::parse(text, &[]).unwrap()).unwrap()
    }

    #[test]
    fn the_default_plane_is_the_first_coordinate_not_mentioned_and_its_momentum() {
        let d = henon_heiles();
        let c = StopCondition::parse(&d, "x = 0", "the section").unwrap();
        let mut s = Section::new(&d, c, None).unwrap();
        assert_eq!(s.axes(), &["y".to_string(), "p_y".to_string()]);
        assert_eq!(s.condition().direction, Direction::Rising);
        assert_eq!(s.point(0.0, &[0.0, 0.5], &[1.0, -2.0]), [0.5, -2.0]);
    }

    #[test]
    fn axes_are_expressions_split_outside_parentheses() {
        let d = henon_heiles();
        let c = StopCondition::parse(&d, "y < 0", "the section").unwrap();
        let mut s = Section::new(&d, c, Some("atan2(y, x), p_x + 1")).unwrap();
        assert_eq!(s.condition().direction, Direction::Falling);
        let [a, b] = s.point(0.0, &[1.0, 1.0], &[3.0, 0.0]);
        assert!((a - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
        assert_eq!(b, 4.0);
    }

    #[test]
    fn bad_axes_are_refused_with_their_place() {
        let d = henon_heiles();
        let c = || StopCondition::parse(&d, "x = 0", "the section").unwrap();
        let e = Section::new(&d, c(), Some("y")).unwrap_err();
        assert!(e.message.contains("two axes"), "{}", e.message);
        let e = Section::new(&d, c(), Some("y, zz")).unwrap_err();
        assert_eq!(e.span, Some(3..5), "{}", e.message);
        assert!(Section::new(&d, c(), Some("y, ")).is_err());
    }
}
